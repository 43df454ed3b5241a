// The stability suite's table (issue 18 item 3; the cases: testing/stability.h): every hard case
// from every start, its outcome against the documented one, the error reached, iterations, and
// for servo cases the largest force against the device's maximum and the largest step between
// answered wrenches against the rate limit. Each row is also a test (tests/server/
// stability_test.cc). Prints a markdown table; exits 1 if any row fails.
//
//   ./build/bench/stability_table [--seconds 4]   (how long each servo case drives its scene)

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "testing/stability.h"

using namespace tangent::testing;

int main(int argc, char** argv) {
  double seconds = 4.0;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--seconds") && i + 1 < argc) {
      seconds = std::atof(argv[++i]);
    } else {
      std::fprintf(stderr, "stability_table: unknown argument \"%s\" (usage: --seconds S)\n",
                   argv[i]);
      return 2;
    }
  }
  if (!(seconds > 0.0)) {
    std::fprintf(stderr, "stability_table: --seconds must be positive\n");
    return 2;
  }
  std::printf("stability_table: servo cases driven %.1f s at 4 kHz, global pass every 4 ms\n\n",
              seconds);
  std::printf(
      "| case | start | outcome (documented) | error reached | iterations | finite | force max / "
      "device max (N) | largest step / rate limit | result | note |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  int failed = 0, rows = 0;
  for (const StabilityCase& c : StabilityCases(TANGENT_SCENES_DIR, seconds)) {
    for (const StabilityRow& r : c.run()) {
      ++rows;
      failed += !r.Passed();
      char error[96], force[64], step[32];
      std::snprintf(error, sizeof error, "%.1e %s", r.error, r.error_what.c_str());
      if (!r.servo && r.path_error > 0.0) {
        std::snprintf(error + std::strlen(error), sizeof error - std::strlen(error), "; path %.1e",
                      r.path_error);
      }
      if (r.servo) {
        std::snprintf(force, sizeof force, "%.2f / %.2f", r.force_max, r.max_force);
        std::snprintf(step, sizeof step, "%.2f", r.step_ratio);
      } else {
        std::snprintf(force, sizeof force, "—");
        std::snprintf(step, sizeof step, "—");
      }
      std::printf("| %s | %s | %s (%s) | %s | %.2f | %s | %s | %s | %s | %s |\n", r.name.c_str(),
                  r.start.c_str(), ToString(r.outcome), ToString(r.expected), error, r.iterations,
                  r.finite ? "yes" : "NO", force, step, r.Passed() ? "pass" : "**FAIL**",
                  r.note.c_str());
    }
  }
  std::printf("\n%d rows, %d failing\n", rows, failed);
  return failed ? 1 : 0;
}
