#pragma once

// A console reporter that also keeps each benchmark's time per iteration (the median when
// repetitions are requested, else the single run), so a benchmark program can print the
// ratios its issue targets after the run.

#include <benchmark/benchmark.h>

#include <map>
#include <string>

namespace tangent::bench {

class MedianReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.error_occurred) continue;
      const bool median = r.run_type == Run::RT_Aggregate && r.aggregate_name == "median";
      if (median || (r.run_type == Run::RT_Iteration && !times_.count(r.run_name.str()))) {
        times_[r.run_name.str()] = r.GetAdjustedRealTime();  // ns per iteration
      }
    }
    ConsoleReporter::ReportRuns(runs);
  }
  /// Time per iteration (ns) of the named benchmark, or −1 when it did not run.
  double Get(const std::string& name) const {
    const auto it = times_.find(name);
    return it == times_.end() ? -1.0 : it->second;
  }

 private:
  std::map<std::string, double> times_;
};

}  // namespace tangent::bench
