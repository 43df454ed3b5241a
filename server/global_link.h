#pragma once

// The servo ↔ global-stage link, written once: a pass of the global contact stage on a servo
// snapshot, its events converted to the messages the servo applies, and the clearance
// certificate of the pairs it left apart (contact/clearance.h). The engine's global thread, the
// servo tests and the servo benchmark all drive the stage through it.

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

#include "contact/clearance.h"
#include "contact/global.h"
#include "server/messages.h"
#include "server/servo.h"

namespace tangent::server {

class GlobalLink {
 public:
  /// The stage over the servo's scene (its surfaces, declared pairs and global_stage settings).
  explicit GlobalLink(const ServoLoop& servo) : GlobalLink(servo, servo.GlobalStageOptions()) {}
  GlobalLink(const ServoLoop& servo, const contact::GlobalOptions& options)
      : stage_(servo.GlobalSurfaces(), servo.GlobalPairs(), servo.GlobalBodyPairs(), options),
        certifier_(servo.GlobalSurfaces(), servo.GlobalPairs(), servo.GlobalBodyPairs(),
                   0.5 * options.activation) {}

  /// Builds the certifier's tessellation trees up front (contact::ClearanceCertifier::BuildAll):
  /// what a server does before it serves. @return how many were built.
  int Prepare() { return certifier_.BuildAll(); }

  /// One pass on `snapshot`: emit(const ContactEventMsg&) for each event, in order; then the
  /// certificate of the pairs apart (clearances()). @return the number of events.
  template <class Emit>
  int Pass(const Snapshot& snapshot, Emit&& emit) {
    ToGlobalInput(snapshot, &poses_, &tracked_);
    stage_.Run(poses_, tracked_, &events_);
    for (const contact::ContactEvent& e : events_) {
      if (e.kind == contact::ContactEvent::Kind::kAdded) {
        deepest_added_ = std::min(deepest_added_, e.contact.beta);
      }
      emit(ToEventMsg(e));
    }
    Certify(snapshot);
    return static_cast<int>(events_.size());
  }
  /// One pass on `snapshot` (the servo's own) applied to `servo` in this thread, as the tests and
  /// benchmarks drive it: each event (observe(msg, applied) sees it), then the certificate
  /// (ServoLoop::AdoptClearances), which a servo left without moves no farther from the first
  /// pass's poses than that certificate allows. The engine hands both across threads instead
  /// (server/engine.cc). @return the number of events.
  template <class Observe>
  int PassInto(ServoLoop* servo, const Snapshot& snapshot, Observe&& observe) {
    const int n = Pass(snapshot, [&](const ContactEventMsg& m) { observe(m, servo->Apply(m)); });
    servo->AdoptClearances(clearances_);
    return n;
  }
  int PassInto(ServoLoop* servo, const Snapshot& snapshot) {
    return PassInto(servo, snapshot, [](const ContactEventMsg&, bool) {});
  }
  /// The last pass's certificate (for ServoLoop::AdoptClearances).
  const ClearanceMsg& clearances() const { return clearances_; }
  /// The smallest β of any contact the stage added, measured at its pass's snapshot (+∞ before
  /// the first). The servo's rows report their own β, and a row held off its extremum can read
  /// ~0 while its pair interpenetrates beside it; a contact added this deep is that penetration,
  /// found (docs/reliability.md, "Soak").
  double deepest_added() const { return deepest_added_; }

 private:
  /// The certificate at the snapshot's poses, leaving out the surface pairs in contact: those
  /// the servo tracks and those the pass found.
  void Certify(const Snapshot& snapshot);

  contact::GlobalContactStage stage_;
  contact::ClearanceCertifier certifier_;
  std::vector<contact::BodyPose> poses_;
  std::vector<contact::GlobalContact> tracked_;
  std::vector<contact::ContactEvent> events_;
  std::vector<double> clearance_;
  ClearanceMsg clearances_;
  double deepest_added_ = std::numeric_limits<double>::infinity();
};

}  // namespace tangent::server
