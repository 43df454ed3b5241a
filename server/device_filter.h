#pragma once

// Which device states the server applies (issue 6 "Safety"): a message with a NaN or infinite
// field, an orientation that is not a unit quaternion, a sequence number not above the last
// accepted one, or an implausible jump is rejected and counted, never applied.

#include <cmath>
#include <cstdint>

namespace tangent::server {

struct DeviceFilterOptions {
  double quaternion_tolerance = 1e-3;  ///< | |Q| − 1 | allowed
  double max_speed = 5.0;              ///< m/s: faster than a hand moves a stylus
  double min_jump = 0.01;              ///< m: jumps below this are never implausible
  double reacquire_after = 0.25;       ///< s of silence after which any position is accepted
};

struct DeviceFilterCounts {
  int64_t accepted = 0;
  int64_t non_finite = 0;
  int64_t quaternion = 0;
  int64_t sequence = 0;
  int64_t jump = 0;
};

class DeviceFilter {
 public:
  enum class Verdict { kAccepted, kNonFinite, kQuaternion, kSequence, kJump };
  explicit DeviceFilter(const DeviceFilterOptions& o = {}) : o_(o) {}

  /// Judges one message (utime in µs, client clock) and counts it.
  Verdict Check(int64_t utime, int64_t seq, const double position[3], const double q[4],
                const double velocity[3]) {
    Verdict v = Judge(utime, seq, position, q, velocity);
    switch (v) {
      case Verdict::kAccepted:
        ++counts_.accepted;
        have_ = true;
        last_seq_ = seq;
        last_utime_ = utime;
        for (int i = 0; i < 3; ++i) last_p_[i] = position[i];
        break;
      case Verdict::kNonFinite:
        ++counts_.non_finite;
        break;
      case Verdict::kQuaternion:
        ++counts_.quaternion;
        break;
      case Verdict::kSequence:
        ++counts_.sequence;
        break;
      case Verdict::kJump:
        ++counts_.jump;
        break;
    }
    return v;
  }
  const DeviceFilterCounts& counts() const { return counts_; }
  static const char* ToString(Verdict v) {
    switch (v) {
      case Verdict::kAccepted:
        return "accepted";
      case Verdict::kNonFinite:
        return "non-finite field";
      case Verdict::kQuaternion:
        return "orientation not a unit quaternion";
      case Verdict::kSequence:
        return "stale or repeated sequence number";
      case Verdict::kJump:
        return "implausible jump";
    }
    return "?";
  }

 private:
  Verdict Judge(int64_t utime, int64_t seq, const double p[3], const double q[4],
                const double v[3]) const {
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(p[i]) || !std::isfinite(v[i])) return Verdict::kNonFinite;
    }
    double n2 = 0.0;
    for (int i = 0; i < 4; ++i) {
      if (!std::isfinite(q[i])) return Verdict::kNonFinite;
      n2 += q[i] * q[i];
    }
    if (std::abs(std::sqrt(n2) - 1.0) > o_.quaternion_tolerance) return Verdict::kQuaternion;
    if (!have_) return Verdict::kAccepted;
    if (seq <= last_seq_) return Verdict::kSequence;
    const double dt = 1e-6 * static_cast<double>(utime - last_utime_);
    if (dt > o_.reacquire_after) return Verdict::kAccepted;
    const double d = std::sqrt((p[0] - last_p_[0]) * (p[0] - last_p_[0]) +
                               (p[1] - last_p_[1]) * (p[1] - last_p_[1]) +
                               (p[2] - last_p_[2]) * (p[2] - last_p_[2]));
    if (d > o_.min_jump && d > o_.max_speed * std::max(dt, 1e-3)) return Verdict::kJump;
    return Verdict::kAccepted;
  }

  DeviceFilterOptions o_;
  DeviceFilterCounts counts_;
  bool have_ = false;
  int64_t last_seq_ = 0, last_utime_ = 0;
  double last_p_[3] = {0, 0, 0};
};

}  // namespace tangent::server
