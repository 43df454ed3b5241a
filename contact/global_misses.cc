// Near misses of the global stage (global_watched.h; docs/contact.md, "Near misses"): minima of a
// surface pair's distance, apart within the offsets' reach, carried from one pass to the next
// and used, like tracked contacts, as centres of the spheres of neglect. Split from global.cc by
// concept.

#include <algorithm>

#include "contact/extremal.h"
#include "contact/global_watched.h"

namespace tangent::contact::internal {

bool IsNearMiss(const GlobalContactStage::Impl& m, const GlobalOptions& options, int a, int b,
                const SurfaceSurfaceExtremum& e) {
  const Watched& wa = m.watched[static_cast<size_t>(a)];
  const Watched& wb = m.watched[static_cast<size_t>(b)];
  // On a trimmed surface the face's minimum may lie off the material, where the contact is an
  // edge's: those pairs keep the narrow phase every pass.
  if (wa.edges || wb.edges) return false;
  const double reach = wa.s.mesh->offset + wb.s.mesh->offset;
  return e.status == ExtremalStatus::kConverged && e.kind == ExtremumKind::kMinimum &&
         e.alignment < 0.0 && e.beta >= options.activation && e.beta < reach;
}

void ReviveNearMisses(GlobalContactStage::Impl& m, int a, int b, const BodyPose& pa,
                      const BodyPose& pb) {
  const nurbs::NurbsSurface& f = *m.watched[static_cast<size_t>(a)].s.surface;
  const nurbs::NurbsSurface& g = *m.watched[static_cast<size_t>(b)].s.surface;
  m.revived.clear();
  for (const NearMiss& miss : m.misses) {
    if (miss.a != a || miss.b != b) continue;
    const double held_distance = (pa.Point(f.Evaluate(miss.u[0], miss.u[1], 0).S) -
                                  pb.Point(g.Evaluate(miss.u[2], miss.u[3], 0).S))
                                     .norm();
    Revived r;
    r.e = SolveSurfaceSurface(f, pa, g, pb, miss.u, kContinuation, &r.at);
    // Another extremum than this one moved (a far side, a branch beyond a saddle) says nothing
    // of the region the near miss stood for.
    if (r.e.status != ExtremalStatus::kConverged ||
        FoundAnotherExtremum(f, g, miss.u, r.e, held_distance)) {
      continue;
    }
    // Two near misses re-solved to one pair: one.
    const bool repeated = std::any_of(m.revived.begin(), m.revived.end(), [&](const Revived& o) {
      return (o.e.p_f - r.e.p_f).norm() < kSamePoint && (o.e.p_g - r.e.p_g).norm() < kSamePoint;
    });
    if (!repeated) m.revived.push_back(r);
  }
}

}  // namespace tangent::contact::internal
