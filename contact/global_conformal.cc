// The global stage's finders for pairs the narrow phase cannot see (global.h, steps 4b and 4c):
// nested pairs, whose offsets contain one another and never cross, and pairs of flat faces, whose
// offsets are parallel sheets. Split from global.cc by concept.

#include <algorithm>

#include "contact/face_gap.h"
#include "contact/global.h"
#include "contact/global_minima.h"
#include "contact/global_watched.h"

namespace tangent::contact {

namespace {

bool Tracked(const std::vector<GlobalContact>& tracked, int a, int b) {
  return std::any_of(tracked.begin(), tracked.end(),
                     [&](const GlobalContact& c) { return c.a == a && c.b == b; });
}

}  // namespace

void GlobalContactStage::FindNested(const std::vector<BodyPose>& poses,
                                    const std::vector<GlobalContact>& tracked, GlobalStats* st) {
  Impl& m = *impl_;
  for (const auto& [a, b] : m.surface_pairs) {
    const internal::Watched& wa = m.watched[static_cast<size_t>(a)];
    const internal::Watched& wb = m.watched[static_cast<size_t>(b)];
    if (wa.edges || wb.edges || m.FacePair(a, b) ||
        std::find(m.crossed.begin(), m.crossed.end(), std::make_pair(a, b)) != m.crossed.end() ||
        Tracked(tracked, a, b)) {
      continue;
    }
    const BodyPose& pa = poses[static_cast<size_t>(wa.s.body)];
    const BodyPose& pb = poses[static_cast<size_t>(wb.s.body)];
    if (!internal::Place(pa, wa.centre, wa.half)
             .MostlyShares(internal::Place(pb, wb.centre, wb.half))) {
      continue;
    }
    ++st->seeds_refined;
    internal::NestedPairMinimum(*wa.s.surface, pa, *wb.s.surface, pb, options_, a, b, &found_);
  }
}

void GlobalContactStage::FindFaces(const std::vector<BodyPose>& poses,
                                   const std::vector<GlobalContact>& tracked, GlobalStats* st) {
  Impl& m = *impl_;
  for (const auto& [a, b] : m.surface_pairs) {
    if (!m.FacePair(a, b) || Tracked(tracked, a, b)) continue;
    const internal::Watched& wa = m.watched[static_cast<size_t>(a)];
    const internal::Watched& wb = m.watched[static_cast<size_t>(b)];
    const BodyPose& pa = poses[static_cast<size_t>(wa.s.body)];
    const BodyPose& pb = poses[static_cast<size_t>(wb.s.body)];
    ++st->seeds_refined;
    const FaceCorner low = LowestCorner(*wa.s.surface, *wa.flat, pa, *wb.s.surface, *wb.flat, pb);
    if (low.found && low.beta < options_.activation && low.beta > -options_.max_penetration) {
      found_.push_back({a, b, low.u, low.beta, low.p_f, low.p_g});
    }
  }
}

}  // namespace tangent::contact
