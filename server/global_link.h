#pragma once

// The servo ↔ global-stage link, written once: a pass of the global contact stage on a servo
// snapshot, its events converted to the messages the servo applies. The engine's global thread,
// the servo tests and the servo benchmark all drive the stage through it.

#include <vector>

#include "contact/global.h"
#include "server/messages.h"
#include "server/servo.h"

namespace tangent::server {

class GlobalLink {
 public:
  /// The stage over the servo's scene (its surfaces, declared pairs and global_stage settings).
  explicit GlobalLink(const ServoLoop& servo) : GlobalLink(servo, servo.GlobalStageOptions()) {}
  GlobalLink(const ServoLoop& servo, const contact::GlobalOptions& options)
      : stage_(servo.GlobalSurfaces(), servo.GlobalPairs(), servo.GlobalBodyPairs(), options) {}

  /// One pass on `snapshot`: emit(const ContactEventMsg&) for each event, in order.
  /// @return the number of events.
  template <class Emit>
  int Pass(const Snapshot& snapshot, Emit&& emit) {
    ToGlobalInput(snapshot, &poses_, &tracked_);
    stage_.Run(poses_, tracked_, &events_);
    for (const contact::ContactEvent& e : events_) emit(ToEventMsg(e));
    return static_cast<int>(events_.size());
  }

 private:
  contact::GlobalContactStage stage_;
  std::vector<contact::BodyPose> poses_;
  std::vector<contact::GlobalContact> tracked_;
  std::vector<contact::ContactEvent> events_;
};

}  // namespace tangent::server
