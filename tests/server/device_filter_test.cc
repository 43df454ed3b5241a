// Device messages the server must never apply: NaN/inf, a non-unit quaternion, a stale or
// repeated sequence number, an implausible jump. Each is rejected and counted by reason.

#include "server/device_filter.h"

#include <gtest/gtest.h>

#include <cmath>

namespace tangent::server {
namespace {

using V = DeviceFilter::Verdict;

struct Msg {
  int64_t utime = 1000, seq = 1;
  double p[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0}, v[3] = {0, 0, 0};
};

TEST(DeviceFilterTest, RejectsAndCountsEachKindOfBadMessage) {
  DeviceFilter f;
  Msg m;
  EXPECT_EQ(f.Check(m.utime, m.seq, m.p, m.q, m.v), V::kAccepted);
  Msg nan = m;
  nan.seq = 2;
  nan.p[1] = NAN;
  EXPECT_EQ(f.Check(nan.utime, nan.seq, nan.p, nan.q, nan.v), V::kNonFinite);
  Msg inf = m;
  inf.seq = 2;
  inf.v[2] = INFINITY;
  EXPECT_EQ(f.Check(inf.utime, inf.seq, inf.p, inf.q, inf.v), V::kNonFinite);
  Msg quat = m;
  quat.seq = 2;
  quat.q[0] = 0.9;
  EXPECT_EQ(f.Check(quat.utime, quat.seq, quat.p, quat.q, quat.v), V::kQuaternion);
  EXPECT_EQ(f.Check(m.utime + 1000, 1, m.p, m.q, m.v), V::kSequence);  // repeated
  EXPECT_EQ(f.Check(m.utime + 1000, 0, m.p, m.q, m.v), V::kSequence);  // stale
  Msg jump = m;
  jump.seq = 3;
  jump.utime += 1000;
  jump.p[0] = 0.2;  // 20 cm in 1 ms
  EXPECT_EQ(f.Check(jump.utime, jump.seq, jump.p, jump.q, jump.v), V::kJump);
  Msg ok = m;
  ok.seq = 4;
  ok.utime += 2000;
  ok.p[0] = 0.002;  // 2 mm in 2 ms: a fast hand, plausible
  EXPECT_EQ(f.Check(ok.utime, ok.seq, ok.p, ok.q, ok.v), V::kAccepted);
  // After a silence longer than reacquire_after, any position is accepted.
  Msg back = ok;
  back.seq = 5;
  back.utime += 500000;
  back.p[0] = 0.05;
  EXPECT_EQ(f.Check(back.utime, back.seq, back.p, back.q, back.v), V::kAccepted);
  const DeviceFilterCounts& c = f.counts();
  EXPECT_EQ(c.accepted, 3);
  EXPECT_EQ(c.non_finite, 2);
  EXPECT_EQ(c.quaternion, 1);
  EXPECT_EQ(c.sequence, 2);
  EXPECT_EQ(c.jump, 1);
  EXPECT_STREQ(DeviceFilter::ToString(V::kJump), "implausible jump");
}

}  // namespace
}  // namespace tangent::server
