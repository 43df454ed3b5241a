#include "view/timeline.h"

#include <algorithm>

#include <lcm/lcm-cpp.hpp>

namespace tangent::view {
namespace {

/// Decodes `event` as T and applies it; false (and counted by the caller) if it does not decode
/// or the model rejects it.
template <typename T>
bool DecodeApply(const lcm::LogEvent& event, ViewModel* model) {
  T m;
  if (m.decode(event.data, 0, event.datalen) != event.datalen) return false;
  return model->Apply(m, nullptr);
}

}  // namespace

Timeline::Timeline(const std::string& path, const server::Scene& scene,
                   const server::Channels& ch) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw TimelineError(path + ": cannot open the LCM log for reading");
  ViewModel model(scene);
  int64_t first_utime = -1;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->datalen < 0) continue;
    bool ok = true;
    if (e->channel == ch.scene) {
      ok = DecodeApply<scene_state_t>(*e, &model);
      if (ok) {
        const int64_t u = model.state().utime;
        if (first_utime < 0) first_utime = u;
        const double t = 1e-6 * static_cast<double>(u - first_utime);
        if (!times_.empty() && t < times_.back()) {
          ok = false;  // Out of order (another server's run in the same log): not replayable.
        } else {
          times_.push_back(t);
          states_.push_back(model.state());
        }
      }
    } else if (e->channel == ch.contacts) {
      ok = DecodeApply<contact_states_t>(*e, &model);
    } else if (e->channel == ch.wrench) {
      ok = DecodeApply<wrench_t>(*e, &model);
    } else if (e->channel == ch.device) {
      ok = DecodeApply<device_state_t>(*e, &model);
    } else if (e->channel == ch.stats) {
      ok = DecodeApply<loop_stats_t>(*e, &model);
    }
    if (!ok) ++skipped_;
  }
  if (states_.empty()) {
    throw TimelineError(path + ": no scene_state_t of scene \"" + scene.name + "\" on channel " +
                        ch.scene + " (" + std::to_string(skipped_) + " messages skipped)");
  }
}

double Timeline::duration() const { return times_.back(); }

const ViewState& Timeline::At(double t) const {
  const auto it = std::upper_bound(times_.begin(), times_.end(), t);
  const size_t k = it == times_.begin() ? 0 : static_cast<size_t>(it - times_.begin()) - 1;
  return states_[k];
}

}  // namespace tangent::view
