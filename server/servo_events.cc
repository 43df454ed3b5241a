// The servo's contact events from the global stage (ServoLoop::Apply): which slot, line or face
// pair an added or removed contact belongs to; and the rows of split pairs between events
// (KeepSplitRowsOffSaddles). Split from servo.cc by concept.

#include "server/servo.h"

#include <cmath>

#include "contact/rigid.h"

namespace tangent::server {

namespace {

// Parameters of one contact, as a fraction of the domains (ParameterDistance): 1e-6 of a
// domain is ~1e-8 m on a part of centimetres, the global stage's own same-point bar.
constexpr double kSameContactParameters = 1e-6;

}  // namespace

bool ServoLoop::Apply(const ContactEventMsg& e) {
  rows_changed_ = true;
  const int lo = std::min(e.surface_a, e.surface_b), hi = std::max(e.surface_a, e.surface_b);
  const Eigen::Vector4d u(e.u[0], e.u[1], e.u[2], e.u[3]);
  if (const int k = faces_.Find(lo, hi); k >= 0) {
    // A pair of flat faces: held by its corners from the first contact found to its release.
    if (!u.allFinite()) return false;
    e.added ? faces_.Hold(k) : faces_.Release(k);
    return true;
  }
  // The pair's slots: its own if it was declared, else its bodies' pool (when they were
  // declared as a pair). Among them: the active one on this face pair nearest to u, and a free
  // one.
  auto on_pair = [&](const Slot& s) { return s.surface_a == lo && s.surface_b == hi; };
  bool declared = false;
  for (const Slot& s : slots_) declared = declared || (!s.body_term && on_pair(s));
  int pool = -1;
  if (!declared && lo >= 0 && hi < static_cast<int>(scene_->surfaces.size())) {
    const int ba = scene_->surfaces[static_cast<size_t>(lo)].body;
    const int bb = scene_->surfaces[static_cast<size_t>(hi)].body;
    for (size_t k = 0; k < scene_->body_pairs.size(); ++k) {
      const BodyPairSpec& bp = scene_->body_pairs[k];
      if ((bp.body_a == ba && bp.body_b == bb) || (bp.body_a == bb && bp.body_b == ba)) {
        pool = static_cast<int>(k);
      }
    }
  }
  if (!declared && pool < 0) return false;  // no slot may hold it
  Slot* nearest = nullptr;
  Slot* free = nullptr;
  double nearest_d = INFINITY;
  for (Slot& s : slots_) {
    const bool mine = declared ? !s.body_term && on_pair(s) : s.body_pair == pool;
    if (s.floating || !mine) continue;
    if (!s.state->active) {
      if (!free) free = &s;
      continue;
    }
    if (!on_pair(s)) continue;  // another face pair of the pool
    const double d =
        contact::ParameterDistance(scene_->surfaces[static_cast<size_t>(lo)].surface,
                                   scene_->surfaces[static_cast<size_t>(hi)].surface, s.U(), u);
    if (d < nearest_d) {
      nearest_d = d;
      nearest = &s;
    }
  }
  if (!u.allFinite()) return false;  // (never from the global stage; a defined answer anyway)
  // A contact along a pair's line is the line's: its sections hold it.
  if (e.added && declared) {
    for (const Slot& s : slots_) {
      if (on_pair(s) && s.line >= 0 && lines_.Covers(s.line, u)) return false;
    }
  }
  if (!e.added) {
    // Only the contact the event names: a slot elsewhere on the pair is another contact (the
    // named one may be gone already, e.g. freed by an earlier event).
    if (!nearest || nearest_d > 0.05) return false;
    nearest->state->Deactivate();
    return true;
  }
  // Already tracked: the same contact added twice. The engine runs a pass only on a snapshot
  // that has taken every earlier event, so this is a second line of defence; it must not merge
  // distinct contacts close together (the minima either side of a split saddle start a few
  // 1e-3 of a domain apart), hence a bar at the stage's own same-point resolution.
  if (nearest && nearest_d < kSameContactParameters) return true;
  if (!free) return false;
  if (free->body_term && !free->Target(lo, hi)) return false;
  free->Activate(u);
  return true;
}

void ServoLoop::KeepSplitRowsOffSaddles() {
  if (!rows_changed_ && !split_rows_) return;
  rows_changed_ = false;
  split_rows_ = false;
  for (const Slot& s : slots_) {
    if (!s.plain) continue;
    int rows = 0;
    for (const Slot& o : slots_) {
      rows +=
          o.plain && o.state->active && o.surface_a == s.surface_a && o.surface_b == s.surface_b;
    }
    static_cast<optimizer::SurfaceContactTerm::State&>(*s.state).keep_off_saddles = rows > 1;
    split_rows_ = split_rows_ || rows > 1;
  }
}

}  // namespace tangent::server
