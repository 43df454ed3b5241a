#pragma once

// Three tiers of checks (../shared/style.md):
//   TANGENT_REQUIRE(cond, message)  bad input from a user, a file or a caller at an API
//       boundary: throws std::invalid_argument with the message (build it with the offending
//       values). Never on the servo path.
//   TANGENT_CHECK(cond)  a broken invariant of our own code (an index the construction
//       guaranteed, a size that must match): prints where and aborts, in every build. Cheap
//       enough for set-up code and once-per-tick code, not for inner loops.
//   TANGENT_DCHECK(cond)  the same check in hot loops (per evaluation, per row): compiled only
//       in debug builds (NDEBUG unset) and in the sanitizer build, free in release.

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace tangent::base {

[[noreturn]] inline void CheckFailed(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "%s:%d: internal check failed: %s\n", file, line, condition);
  std::abort();
}

}  // namespace tangent::base

#define TANGENT_REQUIRE(cond, message)                              \
  do {                                                              \
    if (!(cond)) throw std::invalid_argument(std::string(message)); \
  } while (false)

#define TANGENT_CHECK(cond)                                               \
  do {                                                                    \
    if (!(cond)) ::tangent::base::CheckFailed(#cond, __FILE__, __LINE__); \
  } while (false)

#if defined(NDEBUG) && !defined(TANGENT_DEBUG_CHECKS)
#define TANGENT_DCHECK(cond) \
  do {                       \
  } while (false && (cond))
#else
#define TANGENT_DCHECK(cond) TANGENT_CHECK(cond)
#endif
