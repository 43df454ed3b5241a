#pragma once

// Running a study's cases: on a pool of threads over the one shared problem, journalled as they
// finish (one JSON line per case) so that an interrupted run resumes without redoing them, and
// assembled into the result file in case order whatever the order they finished in.

#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "design/study.h"

namespace tangent::design {

struct RunnerOptions {
  int threads = 1;
  /// Finished cases are appended here as JSON lines ("": no journal).
  std::string journal;
  /// Cases found in these journals (a line per case; a torn last line is ignored) are taken as
  /// done and not solved again.
  std::vector<std::string> resume_from;
  /// Called after each case (under a lock): cases done, cases in this share.
  std::function<void(int, int, const nlohmann::json&)> progress;
};

/// Solves the cases `share` (indices) and returns their results by index, resumed ones included.
std::map<int, nlohmann::json> RunCases(const Study& study, const std::vector<int>& share,
                                       const RunnerOptions& options);

/// The result file: the study's header, every case in order, and the best optimum.
nlohmann::json ResultFile(const Study& study, const std::map<int, nlohmann::json>& cases);

/// Results compared without their timings (the one field that differs between runs).
nlohmann::json WithoutTimings(nlohmann::json result);

}  // namespace tangent::design
