// The three tiers of base/check.h: a user error throws with its message, a broken invariant
// aborts naming the condition, a hot-loop check costs nothing in release.

#include "base/check.h"

#include <gtest/gtest.h>

namespace tangent::base {
namespace {

TEST(CheckTest, RequireThrowsTheMessage) {
  const int n = 3;
  try {
    TANGENT_REQUIRE(n < 2, "widget: n must be below 2, got " + std::to_string(n));
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "widget: n must be below 2, got 3");
  }
  EXPECT_NO_THROW(TANGENT_REQUIRE(n > 2, "unused"));
}

TEST(CheckDeathTest, CheckAbortsNamingTheCondition) {
  const int index = 7, size = 4;
  EXPECT_DEATH(TANGENT_CHECK(index < size), "internal check failed: index < size");
  TANGENT_CHECK(size < index);  // holds: nothing happens
}

TEST(CheckDeathTest, DebugChecksFollowTheBuild) {
  int evaluated = 0;
  auto cond = [&] {
    ++evaluated;
    return false;
  };
#if defined(NDEBUG) && !defined(TANGENT_DEBUG_CHECKS)
  TANGENT_DCHECK(cond());  // compiled out: never evaluated, never aborts
  EXPECT_EQ(evaluated, 0);
#else
  EXPECT_DEATH(TANGENT_DCHECK(cond()), "internal check failed");
#endif
}

}  // namespace
}  // namespace tangent::base
