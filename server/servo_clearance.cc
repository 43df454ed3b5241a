// The servo's clearance guard (optimizer/clearance_guard.h; docs/stability.md "No
// tunnelling"): its body pairs and reaches, the first certificate at the settled initial poses,
// and the certificates the global stage sends after each pass. Split from servo.cc by concept.

#include <algorithm>
#include <utility>
#include <vector>

#include "contact/clearance.h"
#include "contact/relative_curvature.h"
#include "server/servo.h"

namespace tangent::server {

void ServoLoop::StartClearanceGuard(const contact::GlobalContactStage& stage,
                                    const std::vector<contact::BodyPose>& pass_poses) {
  const std::vector<contact::GlobalSurface> surfaces = GlobalSurfaces();
  const std::vector<std::pair<int, int>> pairs = GlobalPairs();
  const std::vector<std::pair<int, int>> body_pairs = GlobalBodyPairs();
  const optimizer::Mechanism& m = problem_->mechanism();
  std::vector<double> reach(static_cast<size_t>(m.num_bodies()), 0.0);
  for (const contact::GlobalSurface& s : surfaces) {
    if (!s.mesh) continue;
    double& r = reach[static_cast<size_t>(s.body)];
    r = std::max(r, contact::SurfaceReach(*s.mesh));
  }
  guard_.Configure(m, contact::WatchedBodyPairs(surfaces, pairs, body_pairs), std::move(reach));
  // The guard also measures the tick motion bound (its bodies' reaches), armed or not.
  if (options_.clearance_guard || options_.max_part_speed > 0.0) {
    solver_->set_clearance_guard(&guard_);
  }
  solver_->set_motion_marker(
      [](void* servo) { return static_cast<ServoLoop*>(servo)->BoundSnappingParts(); }, this);
  if (!options_.clearance_guard) return;
  // The first certificate, from the cold pass at the initial poses. The pass found the touching
  // pairs; the active slots (floating pairs seeded from samples among them) are left out too.
  // Taken only if the settled configuration lies within it; else the first pass's is.
  std::vector<contact::GlobalContact> tracked;
  for (const Slot& s : slots_) {
    if (!s.state->active) continue;
    contact::GlobalContact c;
    c.a = s.surface_a;
    c.b = s.surface_b;
    tracked.push_back(c);
  }
  contact::ClearanceCertifier certifier(surfaces, pairs, body_pairs,
                                        0.5 * GlobalStageOptions().activation);
  std::vector<double> clearance;
  certifier.Certify(pass_poses, tracked, stage, &clearance);
  guard_.Adopt(
      q_, [&](int b) { return pass_poses[static_cast<size_t>(b)].q; }, clearance.data());
}

bool ServoLoop::AdoptClearances(const ClearanceMsg& m) {
  if (!options_.clearance_guard || m.num_bodies != static_cast<int32_t>(poses_.size()) ||
      m.num_pairs != static_cast<int32_t>(guard_.pairs().size())) {
    return false;
  }
  return guard_.Adopt(
      q_, [&](int b) { return Eigen::Map<const contact::Vector7d>(m.q[b]); }, m.clearance);
}

bool ServoLoop::BoundSnappingParts() {
  // (Asked only by a solve with a motion bound: max_part_speed > 0.)
  if (!bound_lagging_) guard_.ClearBounds();
  bool any = bound_lagging_;
  // Parts held by a line: their steps are free (bounded, they jam: docs/reliability.md), but an
  // unconverged solve returns no iterate that carried them past the bound.
  guard_.ClearReturnBounds();
  for (int k = 0; k < lines_.pairs(); ++k) {
    if (!lines_.line(k)) continue;
    if (lines_.body_f(k) >= 0) guard_.BoundReturn(lines_.body_f(k), true);
    if (lines_.body_g(k) >= 0) guard_.BoundReturn(lines_.body_g(k), true);
  }
  for (const Slot& s : slots_) {
    if (!s.plain || !s.state->active) continue;
    const auto& st = static_cast<const optimizer::SurfaceContactTerm::State&>(*s.state);
    if (!st.valid || st.ext.status != contact::ExtremalStatus::kConverged) continue;
    const contact::RelativeCurvature rc = contact::RelativeCurvatureOf(st.eval);
    if (!rc.valid || !(rc.eigenvalues[0] < kSnapCurvature * rc.eigenvalues[1])) continue;
    const auto& term = *s.term;
    if (term.body_a() >= 0) guard_.Bound(term.body_a(), true);
    if (term.body_b() >= 0) guard_.Bound(term.body_b(), true);
    any = true;
  }
  return any;
}

}  // namespace tangent::server
