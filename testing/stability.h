#pragma once

// The stability suite (issue 18 item 3): the hard cases of design.md §4.3 and docs/stability.md,
// plus rank-deficient closures, conflicting goals, near-singular mechanism poses and contacts
// sliding over a trim edge and along a pole, each run from several starts.
//
// Two kinds of case:
//   - kinematic: a surface pair through the servo's own contact term (optimizer::
//     SurfaceContactTerm: the tracker, the exactness check and the extremal solver behind it),
//     from several seeds, then moved along a path; each step's β is compared with a fresh
//     extremal solve from the term's previous parameters.
//   - servo: a scene driven by a scripted hand through server::ServoLoop at 4 kHz with a global
//     pass every 4 ms; the wrench is checked against the device's maximum and the rate limit.
// Every row has a documented expected outcome; tests/server/stability_test.cc makes each row a
// test, bench/stability_table prints the table for docs/benchmarks.md.

#include <functional>
#include <string>
#include <vector>

namespace tangent::testing {

enum class Outcome {
  kConverged,  ///< the solver's own tolerance met at every step
  kFlagged,    ///< a defined degenerate state reported (singular, invalid input, at a bound)
  kDegraded,   ///< finite and bounded, but the solve did not reach its tolerance everywhere
  kFailed,     ///< a NaN, an unbounded force, or a fault
};
const char* ToString(Outcome o);

struct StabilityRow {
  std::string name;   ///< the case
  std::string start;  ///< which start (seed, hand path)
  Outcome outcome = Outcome::kFailed;
  Outcome expected = Outcome::kConverged;
  /// The error reached and what it measures (against a closed form, a fresh solve, or the
  /// constraint violation of a servo run).
  double error = 0.0;
  std::string error_what;
  double iterations = 0.0;  ///< the solve's (kinematic) or mean per tick (servo)
  bool finite = true;       ///< no NaN or infinity anywhere in the outputs
  /// Servo rows: the largest force (N) against the device's maximum, and the largest step
  /// between answered wrenches as a fraction of the rate limit's step (1: the limiter acted).
  bool servo = false;
  double force_max = 0.0, max_force = 0.0, step_ratio = 0.0;
  /// Kinematic rows: the largest |β − a fresh solve's| along the path (m).
  double path_error = 0.0;
  std::string note;
  /// Finite, bounded, and the outcome the case documents.
  bool Passed() const;
};

struct StabilityCase {
  std::string name;
  std::string what;  ///< the configuration, one line
  std::function<std::vector<StabilityRow>()> run;
};

/// Every case. `scenes_dir`: the repository's scenes/ (servo cases load the example scenes).
/// `seconds`: how long each servo case drives its scene (the tests use a short run).
std::vector<StabilityCase> StabilityCases(const std::string& scenes_dir, double seconds);

}  // namespace tangent::testing
