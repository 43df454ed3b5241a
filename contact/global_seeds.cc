// The global stage's search of one surface pair (GlobalContactStage::FindContacts; docs/contact.md,
// "Global stage"): its block pairs through FCL's narrow phase, the offset triangles' seeds
// clustered by spheres of neglect, each cluster refined into a contact or a near miss as soon as
// it appears, and every block pair and cluster round what was found skipped. Split from
// global.cc by concept.

#include <fcl/fcl.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "contact/global.h"
#include "contact/global_minima.h"
#include "contact/global_watched.h"
#include "contact/relative_curvature.h"
#include "contact/solver_inputs.h"
#include "contact/trimmed.h"

namespace tangent::contact {

namespace internal {

OnMaterial MeasureOnMaterial(const Watched& wa, const BodyPose& pa, const Watched& wb,
                             const BodyPose& pb, const SurfaceSurfaceExtremum& e) {
  if (wa.edges && wb.edges) {
    const TrimmedMeasure t = MeasureTrimmedPair(*wa.edges, pa, *wb.s.surface, wb.edges.get(), pb,
                                                &e, nullptr, nullptr, nullptr);
    return {t.on_edge, PointParameters(*wa.edges, *wb.edges, t, e.u), t.beta, t.p_f, t.p_g,
            t.status};
  }
  if (wa.edges) {
    const TrimmedMeasure t = MeasureTrimmed(*wa.edges, pa, *wb.s.surface, pb, e);
    if (t.on_edge) return {true, e.u, t.beta, t.p_f, t.p_g, t.status};
  }
  if (wb.edges) {
    SurfaceSurfaceExtremum swapped = e;
    swapped.u << e.u.tail<2>(), e.u.head<2>();
    const TrimmedMeasure t = MeasureTrimmed(*wb.edges, pb, *wa.s.surface, pa, swapped);
    if (t.on_edge) return {true, e.u, t.beta, t.p_g, t.p_f, t.status};
  }
  return {false, e.u, e.beta, e.p_f, e.p_g, e.status};
}

bool HeldOnMaterialBorder(const Watched& wa, const Watched& wb, const SurfaceSurfaceExtremum& e,
                          const OnMaterial& on) {
  if (e.status != ExtremalStatus::kAtBoundary || on.on_edge) return false;
  for (int i = 0; i < 4; ++i) {
    if (e.at_bound[static_cast<size_t>(i)] && !(i < 2 ? wa.edges : wb.edges)) return false;
  }
  return true;
}

}  // namespace internal

namespace {

using internal::AddFound;
using internal::Centre;
using internal::HeldOnMaterialBorder;
using internal::IsNearMiss;
using internal::MeasureOnMaterial;
using internal::MinimaBeside;
using internal::OnMaterial;
using internal::Seed;
using internal::Watched;

// Parameters of world point x on offset triangle t of a watched surface: barycentric
// coordinates of x projected on the triangle (clamped inside), applied to the vertices' (u, v).
Eigen::Vector2d ParametersAt(const Watched& w, const BodyPose& pose, int t,
                             const Eigen::Vector3d& x) {
  const auto& tri = w.s.mesh->base.triangles[static_cast<size_t>(t)];
  const Eigen::Vector3d a = pose.Point(w.s.mesh->vertices[static_cast<size_t>(tri[0])]);
  const Eigen::Vector3d b = pose.Point(w.s.mesh->vertices[static_cast<size_t>(tri[1])]);
  const Eigen::Vector3d c = pose.Point(w.s.mesh->vertices[static_cast<size_t>(tri[2])]);
  const Eigen::Vector3d e0 = b - a, e1 = c - a, d = x - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
  const double d20 = d.dot(e0), d21 = d.dot(e1);
  const double den = d00 * d11 - d01 * d01;
  double l1 = 1.0 / 3, l2 = 1.0 / 3;
  if (den > 0.0) {
    l1 = std::clamp((d11 * d20 - d01 * d21) / den, 0.0, 1.0);
    l2 = std::clamp((d00 * d21 - d01 * d20) / den, 0.0, 1.0);
    if (l1 + l2 > 1.0) {
      const double s = l1 + l2;
      l1 /= s;
      l2 /= s;
    }
  }
  const auto& uv = w.s.mesh->base.uv;
  return (1.0 - l1 - l2) * uv[static_cast<size_t>(tri[0])] + l1 * uv[static_cast<size_t>(tri[1])] +
         l2 * uv[static_cast<size_t>(tri[2])];
}

// Domain bounds and periodicity of a pair's four parameters.
using Box = internal::PairBox;

// Whether the point (u, x) of surfaces wa, wb (parameters, world midpoint) lies in the sphere of
// neglect centred at (c_u, c_x): within ρ in space and within far_factor·ρ along both surfaces.
bool InSphere(const Watched& wa, const Watched& wb, const GlobalOptions& options,
              const Eigen::Vector4d& c_u, const Eigen::Vector3d& c_x, const Eigen::Vector4d& u,
              const Eigen::Vector3d& x) {
  const double far = options.far_factor * options.neglect_radius;
  return (c_x - x).norm() < options.neglect_radius && wa.Along(c_u.head<2>(), u.head<2>()) <= far &&
         wb.Along(c_u.tail<2>(), u.tail<2>()) <= far;
}

void AddToCluster(const Eigen::Vector4d& u, const Box& box, Seed* c) {
  for (int i = 0; i < 4; ++i) {
    if (box.periodic[static_cast<size_t>(i)]) {
      const double angle = 2.0 * M_PI * (u[i] - box.lo[i]) / (box.hi[i] - box.lo[i]);
      c->sum_cos[i] += std::cos(angle);
      c->sum_sin[i] += std::sin(angle);
    } else {
      c->sum[i] += u[i];
    }
  }
  c->count = std::max(c->count, 0) + 1;
  if ((c->count == 2 || c->count == 8 || c->count == 32 || c->count == 128) && c->n_members < 4) {
    c->members[static_cast<size_t>(c->n_members++)] = u;
  }
}

Eigen::Vector4d ClusterMean(const Seed& c, const Box& box) {
  if (c.count <= 0) return c.u;
  Eigen::Vector4d m;
  for (int i = 0; i < 4; ++i) {
    if (box.periodic[static_cast<size_t>(i)]) {
      double angle = std::atan2(c.sum_sin[i], c.sum_cos[i]);
      if (angle < 0) angle += 2.0 * M_PI;
      m[i] = box.lo[i] + (box.hi[i] - box.lo[i]) * angle / (2.0 * M_PI);
    } else {
      m[i] = c.sum[i] / c.count;
    }
  }
  return m;
}

Eigen::Vector3d Centroid(const Watched& w, const BodyPose& pose, int t) {
  const auto& tri = w.s.mesh->base.triangles[static_cast<size_t>(t)];
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int k : tri) c += w.s.mesh->vertices[static_cast<size_t>(k)];
  return pose.Point(c / 3.0);
}

// Which of the pair's centres (bit i: m.centres[i], the first 64) lie within far_factor·ρ along
// surface w of all of its chunk k; `side` 0 for the pair's first surface, 1 for its second.
// Kept per chunk for this search (a chunk is in many block pairs), extended as centres come.
uint64_t CentresNear(const GlobalContactStage::Impl& m, const GlobalOptions& options, Watched& w,
                     int k, int side) {
  const double far = options.far_factor * options.neglect_radius;
  const size_t i = static_cast<size_t>(k);
  if (w.near_search[i] != m.search) {
    w.near_search[i] = m.search;
    w.near_mask[i] = 0;
    w.near_upto[i] = 0;
  }
  const int n = static_cast<int>(std::min<size_t>(m.centres.size(), 64));
  const Chunk& chunk = w.chunks[i];
  for (int c = w.near_upto[i]; c < n; ++c) {
    const Eigen::Vector4d& u = m.centres[static_cast<size_t>(c)].u;
    const Eigen::Vector2d x =
        side == 0 ? Eigen::Vector2d(u.head<2>()) : Eigen::Vector2d(u.tail<2>());
    if (w.FarthestAlong(x, chunk) <= far) w.near_mask[i] |= uint64_t{1} << c;
  }
  w.near_upto[i] = n;
  return w.near_mask[i];
}

// Whether block pair (ka, kb) lies, on both surfaces, within far_factor·ρ along the surface of a
// centre of neglect (m.centres: a tracked contact, a near miss, or what a cluster of this pass
// reached): every seed it could give would fall in that centre's sphere.
bool NearACentre(GlobalContactStage::Impl& m, const GlobalOptions& options, Watched& wa,
                 Watched& wb, int ka, int kb) {
  if (CentresNear(m, options, wa, ka, 0) & CentresNear(m, options, wb, kb, 1)) return true;
  // (Beyond 64 centres, one by one.)
  const double far = options.far_factor * options.neglect_radius;
  const Chunk& ca = wa.chunks[static_cast<size_t>(ka)];
  const Chunk& cb = wb.chunks[static_cast<size_t>(kb)];
  return std::any_of(m.centres.begin() + std::min<long>(64, static_cast<long>(m.centres.size())),
                     m.centres.end(), [&](const Centre& c) {
                       return wa.FarthestAlong(c.u.head<2>(), ca) <= far &&
                              wb.FarthestAlong(c.u.tail<2>(), cb) <= far;
                     });
}

// Narrow phase on one block pair of surfaces a, b: its intersecting offset triangles (primitive
// pairs only, enable_contact = false: seeds are placed from the triangles) appended to
// m.triangle_pairs.
void CollideBlocks(GlobalContactStage::Impl& m, const GlobalOptions& options, const Chunk& ca,
                   const Chunk& cb, const BodyPose& pa, const BodyPose& pb) {
  fcl::CollisionObjectd* oa = ca.Object();
  fcl::CollisionObjectd* ob = cb.Object();
  oa->setTransform(pa.R_WB, pa.q.head<3>());
  ob->setTransform(pb.R_WB, pb.q.head<3>());
  fcl::CollisionRequestd request(static_cast<size_t>(options.max_triangle_pairs), false);
  fcl::CollisionResultd result;
  fcl::collide(oa, ob, request, result);
  for (size_t r = 0; r < result.numContacts(); ++r) {
    const fcl::Contactd& c = result.getContact(r);
    const bool swapped = c.o1 != oa->collisionGeometry().get();
    m.triangle_pairs.emplace_back(ca.triangles[static_cast<size_t>(swapped ? c.b2 : c.b1)],
                                  cb.triangles[static_cast<size_t>(swapped ? c.b1 : c.b2)]);
  }
}

// Seeds from m.triangle_pairs[from...], clustered by spheres of neglect into m.accepted (whose
// first n_centres are the pair's centres): one cluster per seed not within ρ (and topologically
// near on both surfaces) of an earlier one.
void ClusterSeeds(GlobalContactStage::Impl& m, const GlobalOptions& options, const Watched& wa,
                  const Watched& wb, const BodyPose& pa, const BodyPose& pb, const Box& domains,
                  size_t from, size_t n_centres, GlobalStats* st) {
  std::vector<Seed>& accepted = m.accepted;
  for (size_t t = from; t < m.triangle_pairs.size(); ++t) {
    const auto [ta, tb] = m.triangle_pairs[t];
    // Where the triangles meet: the midpoint of their centroids, projected on each. (FCL's
    // contact positions, with enable_contact, measured centimetres off for mesh pairs in 0.7
    // and cost a triangle–triangle intersection each.)
    Seed s;
    s.x = 0.5 * (Centroid(wa, pa, ta) + Centroid(wb, pb, tb));
    s.u << ParametersAt(wa, pa, ta, s.x), ParametersAt(wb, pb, tb, s.x);
    // Spheres of neglect, unless topologically far on either surface.
    Seed* owner = nullptr;
    for (size_t k = 0; k < accepted.size(); ++k) {
      const Seed& o = accepted[k];
      if (InSphere(wa, wb, options, o.u, o.x, s.u, s.x)) {
        owner = k >= n_centres ? &accepted[k] : nullptr;
        ++st->seeds_neglected;
        s.count = -1;  // neglected
        break;
      }
    }
    if (s.count < 0 && !owner) continue;
    Seed& cluster = owner ? *owner : (accepted.push_back(s), accepted.back());
    AddToCluster(s.u, domains, &cluster);
  }
}

// Whether a refinement's answer e (on the material: on) is a contact of surfaces a, b: an
// interior extremum (or one held on a trimmed face's border, or a continuum when line contacts
// take them) with facing normals, or an edge's, with −max_penetration < β < activation.
bool IsContact(const Watched& wa, const Watched& wb, const GlobalOptions& options,
               const SurfaceSurfaceExtremum& e, const SurfacePairEval& at, const OnMaterial& on) {
  if (on.on_edge) {
    return (e.status == ExtremalStatus::kConverged || e.status == ExtremalStatus::kAtBoundary) &&
           on.status == ExtremalStatus::kConverged && on.beta < options.activation &&
           on.beta > -options.max_penetration;
  }
  return (e.status == ExtremalStatus::kConverged || HeldOnMaterialBorder(wa, wb, e, on) ||
          internal::LineContinuum(options, e, at)) &&
         e.beta < options.activation && e.beta > -options.max_penetration && e.alignment < 0.0;
}

// Adds contact e of surfaces a, b (IsContact; `at`: the pair's evaluation there) to *found:
// a saddle of the distance is not a contact, the minima beside it are. (Held on a border, the
// surfaces' curvature across it says nothing.)
void AddContact(const Watched& wa, const Watched& wb, const GlobalOptions& options, int a, int b,
                const BodyPose& pa, const BodyPose& pb, const SurfaceSurfaceExtremum& e,
                const SurfacePairEval& at, const OnMaterial& on,
                std::vector<GlobalContact>* found) {
  if (const RelativeCurvature rc = RelativeCurvatureOf(at);
      !on.on_edge && e.status == ExtremalStatus::kConverged && rc.crossing) {
    MinimaBeside(*wa.s.surface, pa, *wb.s.surface, pb, e, at, rc, options, a, b, found);
    return;
  }
  AddFound({a, b, on.u, on.beta, on.p_a, on.p_b}, found);
}

// Refines cluster m.accepted[k] of surfaces a, b by the extremal Newton solver: from the mean of
// its seeds (the middle of where the offsets overlap, near the closest or deepest pair), then,
// when `last_chance`, from its first seed and a few other members while that fails. (Measured:
// from the first seed alone, 2.4 % of deep contacts, whose seeds ring the overlap, converged to
// the far sides' pair instead.) A contact is added to *found; a contact or a near miss becomes a
// centre of neglect (m.centres). A cluster whose first seed lies in a centre's sphere is not
// refined: it would reach the same pair (a deep contact's overlap, several ρ wide, gave up to
// seven clusters that all did).
void RefineCluster(GlobalContactStage::Impl& m, const GlobalOptions& options, int a, int b,
                   size_t k, bool last_chance, const BodyPose& pa, const BodyPose& pb,
                   const Box& domains, GlobalStats* st, std::vector<GlobalContact>* found,
                   double* nearest) {
  const Watched& wa = m.watched[static_cast<size_t>(a)];
  const Watched& wb = m.watched[static_cast<size_t>(b)];
  const double rho = options.neglect_radius;
  Seed& cl = m.accepted[k];
  if (cl.done) return;
  const bool covered = std::any_of(m.centres.begin(), m.centres.end(), [&](const Centre& c) {
    return InSphere(wa, wb, options, c.u, c.x, cl.u, cl.x);
  });
  if (covered) {
    ++st->seeds_neglected;
    cl.done = true;
    return;
  }
  SurfaceSurfaceExtremum e;
  SurfacePairEval at;
  OnMaterial on;
  bool ok = false, near_miss = false, apart = false;
  // The mean again only when seeds have joined since it was solved from.
  const int first = cl.tried == cl.count ? 1 : 0;
  const int end = last_chance ? 2 + cl.n_members : 1;
  for (int attempt = first; attempt < end && !ok && !apart; ++attempt) {
    ++st->seeds_refined;
    if (attempt == 0) cl.tried = cl.count;
    const Eigen::Vector4d seed = attempt == 0   ? ClusterMean(cl, domains)
                                 : attempt == 1 ? cl.u
                                                : cl.members[static_cast<size_t>(attempt - 2)];
    e = SolveSurfaceSurface(*wa.s.surface, pa, *wb.s.surface, pb, seed, kContinuation, &at);
    // On trimmed surfaces the face's extremal point may lie off the material (over a hole,
    // beyond a face's border): the contact is then the nearest trim edge's.
    on = MeasureOnMaterial(wa, pa, wb, pb, e);
    // The nearest pair measured on the material (GlobalContactStage::viewed): a converged
    // minimum of the faces, or an edge's.
    if (on.on_edge ? on.status == ExtremalStatus::kConverged
                   : e.status == ExtremalStatus::kConverged && e.kind == ExtremumKind::kMinimum) {
      *nearest = std::min(*nearest, on.on_edge ? on.beta : e.beta);
    }
    ok = IsContact(wa, wb, options, e, at, on);
    // The cluster's own minimum, apart by more than the activation distance where the offsets
    // met (its points within ρ of there): no contact here, and the other seeds would only find
    // it again. (The retries are for seeds that reach another region's pair, such as a deep
    // contact's far sides, which lie below −max_penetration. Measured on twenty clips' cold
    // pass: 380 of 2,035 clusters ended so, each retried three times.) Within the offsets'
    // reach, it is a near miss, which the next pass re-solves (ReviveNearMisses).
    apart = !ok && !on.on_edge && e.status == ExtremalStatus::kConverged &&
            e.kind == ExtremumKind::kMinimum && e.beta >= options.activation &&
            (0.5 * (e.p_f + e.p_g) - cl.x).norm() < rho;
    near_miss = apart && IsNearMiss(m, options, a, b, e);
  }
  if (near_miss && options.near_misses) m.next_misses.push_back({a, b, e.u});
  if (ok || near_miss) m.centres.push_back({e.u, 0.5 * (on.p_a + on.p_b)});
  if (ok) AddContact(wa, wb, options, a, b, pa, pb, e, at, on, found);
  cl.done = ok || apart || last_chance;
}

}  // namespace

void GlobalContactStage::FindContacts(int a, int b, size_t first, size_t last,
                                      const std::vector<BodyPose>& poses,
                                      const std::vector<GlobalContact>& tracked, GlobalStats* st) {
  Impl& m = *impl_;
  const Watched& wa = m.watched[static_cast<size_t>(a)];
  const Watched& wb = m.watched[static_cast<size_t>(b)];
  const BodyPose& pa = poses[static_cast<size_t>(wa.s.body)];
  const BodyPose& pb = poses[static_cast<size_t>(wb.s.body)];
  const Box domains = internal::PairBoxOf(*wa.s.surface, *wb.s.surface);
  ++m.search;  // (the chunks' centre masks are this search's: CentresNear)
  // Centres of neglect: the pair's tracked contacts where they are now, then its near misses.
  m.centres.clear();
  for (const GlobalContact& c : tracked) {
    if (c.a != a || c.b != b) continue;
    const Eigen::Vector3d xa = pa.Point(wa.s.surface->Evaluate(c.u[0], c.u[1], 0).S);
    const Eigen::Vector3d xb = pb.Point(wb.s.surface->Evaluate(c.u[2], c.u[3], 0).S);
    m.centres.push_back({c.u, 0.5 * (xa + xb)});
  }
  // The last pass's near misses, re-solved: each now a contact, a near miss again (kept for the
  // next pass), or neither (dropped); the first two become centres. One that came within the
  // sphere of neglect of a tracked contact is that contact.
  const size_t n_tracked = m.centres.size();
  double nearest = std::numeric_limits<double>::infinity();
  bool revived = false;
  internal::ReviveNearMisses(m, a, b, pa, pb);
  for (const internal::Revived& r : m.revived) {
    const OnMaterial on{false, r.e.u, r.e.beta, r.e.p_f, r.e.p_g, r.e.status};
    const bool contact = IsContact(wa, wb, options_, r.e, r.at, on);
    if (!contact && !IsNearMiss(m, options_, a, b, r.e)) continue;
    const Eigen::Vector3d x = 0.5 * (r.e.p_f + r.e.p_g);
    const bool tracked_here = std::any_of(
        m.centres.begin(), m.centres.begin() + static_cast<long>(n_tracked),
        [&](const Centre& c) { return InSphere(wa, wb, options_, c.u, c.x, r.e.u, x); });
    if (tracked_here) continue;
    if (r.e.kind == ExtremumKind::kMinimum) nearest = std::min(nearest, r.e.beta);
    m.centres.push_back({r.e.u, x});
    ++st->near_misses;
    revived = true;
    if (contact) {
      AddContact(wa, wb, options_, a, b, pa, pb, r.e, r.at, on, &found_);
    } else {
      m.next_misses.push_back({a, b, r.e.u});
    }
  }
  m.accepted.clear();
  for (const Centre& c : m.centres) {
    Seed t;
    t.u = c.u;
    t.x = c.x;
    t.done = true;
    m.accepted.push_back(t);
  }
  const size_t n_centres = m.accepted.size();
  // Block pairs nearest first (their world boxes' centres): where the offsets overlap most, so
  // that the first found there skips the rest round it.
  m.order.clear();
  for (size_t k = first; k < last; ++k) {
    const internal::WorldBox& ba = wa.placed[static_cast<size_t>(m.candidates[k][2])];
    const internal::WorldBox& bb = wb.placed[static_cast<size_t>(m.candidates[k][3])];
    m.order.emplace_back(((ba.lo + ba.hi) - (bb.lo + bb.hi)).squaredNorm(), k);
  }
  std::sort(m.order.begin(), m.order.end());
  m.triangle_pairs.clear();
  for (const auto& [distance, k] : m.order) {
    const Chunk& ca = wa.chunks[static_cast<size_t>(m.candidates[k][2])];
    const Chunk& cb = wb.chunks[static_cast<size_t>(m.candidates[k][3])];
    if (NearACentre(m, options_, m.watched[static_cast<size_t>(a)],
                    m.watched[static_cast<size_t>(b)], m.candidates[k][2], m.candidates[k][3])) {
      ++st->chunk_pairs_skipped;
      continue;
    }
    ++st->chunk_pairs_tested;
    const size_t from = m.triangle_pairs.size(), clusters = m.accepted.size();
    CollideBlocks(m, options_, ca, cb, pa, pb);
    ClusterSeeds(m, options_, wa, wb, pa, pb, domains, from, n_centres, st);
    // New clusters are refined at once from their seeds so far: what they reach skips the
    // block pairs round it. One that fails waits for the rest of its seeds.
    for (size_t c = clusters; c < m.accepted.size(); ++c) {
      RefineCluster(m, options_, a, b, c, false, pa, pb, domains, st, &found_, &nearest);
    }
  }
  for (size_t c = n_centres; c < m.accepted.size(); ++c) {
    RefineCluster(m, options_, a, b, c, true, pa, pb, domains, st, &found_, &nearest);
  }
  st->triangle_pairs += static_cast<int>(m.triangle_pairs.size());
  // (A near miss is a minimum within the offsets' reach: they cross there.)
  if (!m.triangle_pairs.empty() || revived) {
    m.crossed.emplace_back(a, b);
    viewed_.push_back({a, b, nearest});
  }
}

}  // namespace tangent::contact
