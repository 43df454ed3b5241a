#pragma once

// A recorded run (an lcm-logger log) as a sequence of view states, for replay with a time slider
// and for snapshots at a time. Built once when the log is opened.

#include <stdexcept>
#include <string>
#include <vector>

#include "server/bridge.h"
#include "view/model.h"

namespace tangent::view {

class TimelineError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Timeline {
 public:
  /// Reads every event of `path` on the scene, contact, wrench, device and statistics channels;
  /// one state per scene_state_t (the poses), carrying the latest of the others. Messages that
  /// do not decode or do not fit the scene are skipped and counted.
  /// @throws TimelineError when the file cannot be opened or holds no scene_state_t for `scene`.
  Timeline(const std::string& path, const server::Scene& scene, const server::Channels& channels);

  /// Seconds from the first state to the last.
  double duration() const;
  /// The last state at or before t seconds from the start (t clamped to [0, duration]).
  const ViewState& At(double t) const;
  size_t size() const { return states_.size(); }
  int64_t skipped() const { return skipped_; }

 private:
  std::vector<double> times_;  ///< seconds from the first state, increasing
  std::vector<ViewState> states_;
  int64_t skipped_ = 0;
};

}  // namespace tangent::view
