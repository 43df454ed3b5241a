// The servo's line contacts (server/line_contacts.h): entering, following and leaving line mode
// after each good tick, and a line's report in the snapshot. Split from servo.cc by concept.

#include "server/servo.h"

namespace tangent::server {

void ServoLoop::FollowLines() {
  if (lines_.pairs() == 0) return;  // (no declared pair may hold a line: nothing to visit)
  // Pairs in line mode: the sections follow the line, or the point contact resumes.
  for (int k = 0; k < lines_.pairs(); ++k) {
    if (!lines_.line(k)) continue;
    const bool entered = lines_.entering(k);
    Eigen::Vector4d u;
    const LineContacts::Next next = lines_.Follow(k, poses_, &u);
    if (next == LineContacts::Next::kLeave && !entered) ResumePoint(k, u);
    if (next != LineContacts::Next::kStay || !entered) continue;
    // Entered a tick ago: the sections have taken the load beside the point contacts along the
    // line (one solve with both), which are retired now.
    for (Slot& o : slots_) {
      if (o.line == k && o.state->active && lines_.Covers(k, o.U())) {
        o.state->Deactivate();
        rows_changed_ = true;
      }
    }
  }
  // A line-like point contact: the pair goes to line mode; its contacts along the line stay for
  // one more solve, so that the sections take the load from them, and are retired after it.
  for (Slot& s : slots_) {
    if (s.line < 0 || !s.state->active || lines_.line(s.line)) continue;
    const auto& st = static_cast<const optimizer::SurfaceContactTerm::State&>(*s.state);
    if (!st.valid || (st.ext.status != contact::ExtremalStatus::kConverged &&
                      st.ext.status != contact::ExtremalStatus::kSingular))
      continue;
    lines_.Enter(s.line, st.ext, st.eval);
  }
}

void ServoLoop::ResumePoint(int line, const Eigen::Vector4d& u) {
  for (Slot& s : slots_) {
    if (s.line == line && !s.state->active) {
      s.Activate(u);
      rows_changed_ = true;
      return;
    }
  }
}

void ServoLoop::FillLineContacts(Snapshot* s, int* count) const {
  int n = *count;
  // A pair in line mode: its middle section, carrying the three sections' load (once per pair:
  // at its first slot, slots of a pair being consecutive).
  for (size_t j = 0; j < slots_.size(); ++j) {
    const Slot& slot = slots_[j];
    const int k = slot.line;
    if (k < 0 || !lines_.line(k) || n >= kMaxContacts) continue;
    if (j > 0 && slots_[j - 1].line == k) continue;
    TrackedContact& c = s->contacts[n++];
    c.surface_a = slot.surface_a;
    c.surface_b = slot.surface_b;
    c.body_a = scene_->surfaces[static_cast<size_t>(c.surface_a)].body;
    c.body_b = scene_->surfaces[static_cast<size_t>(c.surface_b)].body;
    const Eigen::Vector4d u = lines_.MiddleU(k);
    const optimizer::SectionContactTerm::State& m = lines_.section(k, 0);
    for (int i = 0; i < 4; ++i) c.u[i] = u[i];
    c.beta = m.ext.beta;
    for (int i = 0; i < 3; ++i) {
      c.p_a[i] = m.ext.p_g[i];  // (the section is on a, the solver's curve)
      c.p_b[i] = m.ext.p_f[i];
    }
    c.force = LineLoads(k).sum();
  }
  *count = n;
}

}  // namespace tangent::server
