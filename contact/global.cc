#include "contact/global.h"

#include <fcl/fcl.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

#include "contact/box_newton.h"
#include "contact/face_gap.h"
#include "contact/global_minima.h"
#include "contact/global_watched.h"
#include "contact/offset_chunks.h"
#include "contact/relative_curvature.h"
#include "contact/solver_inputs.h"
#include "contact/trimmed.h"

namespace tangent::contact {

const char* ToString(ContactEvent::Reason r) {
  switch (r) {
    case ContactEvent::Reason::kApproached:
      return "approached";
    case ContactEvent::Reason::kSeparated:
      return "separated";
    case ContactEvent::Reason::kLeftDomain:
      return "left_domain";
    case ContactEvent::Reason::kLost:
      return "lost";
    case ContactEvent::Reason::kSplit:
      return "split";
    case ContactEvent::Reason::kMerged:
      return "merged";
  }
  return "?";
}

namespace {

using internal::AddFound;
using internal::MinimaBeside;
using internal::SamePoints;
using internal::WorldBox;

using internal::Place;

using internal::Watched;

using internal::Seed;

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

}  // namespace

namespace {

bool BroadPhaseCallback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data) {
  auto* impl = static_cast<GlobalContactStage::Impl*>(data);
  int a = static_cast<int>(reinterpret_cast<intptr_t>(o1->getUserData()));
  int b = static_cast<int>(reinterpret_cast<intptr_t>(o2->getUserData()));
  if (a == b || !impl->Allowed(a, b)) return false;
  if (impl->watched[static_cast<size_t>(a)].s.body ==
      impl->watched[static_cast<size_t>(b)].s.body) {
    return false;
  }
  impl->surface_pairs.emplace_back(std::min(a, b), std::max(a, b));
  return false;  // keep going
}

}  // namespace

namespace {

// A surface with an offset mesh, as the global stage watches it: its chunks, the whole mesh's
// box as the broad phase's object (user data: the surface's index), and its metres per
// parameter unit (mean |S_u|, |S_v| over the mesh's vertices) for distances along it.
Watched WatchSurface(int index, const GlobalSurface& s, const GlobalOptions& options) {
  Watched w;
  w.s = s;
  if (s.trim) {
    w.edges = std::make_unique<TrimEdges>(s.surface, s.trim);
  } else if (options.face_pairs) {
    w.flat = nurbs::FlatQuadOf(*s.surface);
  }
  w.chunks = BuildChunks(*s.mesh, options.chunk_u_cells, options.chunk_v_cells);
  w.placed.resize(w.chunks.size());
  w.placed_at.assign(w.chunks.size(), -1);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const Eigen::Vector3d& x : s.mesh->vertices) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  // A flat face's offset is a sheet parallel to it, and two faces resting on each other have
  // sheets on either side of both: its box also holds the face itself (its corners), so that the
  // broad phase reports the pair.
  if (w.flat) {
    for (const Eigen::Vector3d& x : w.flat->points) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
  }
  w.centre = 0.5 * (lo + hi);
  w.half = 0.5 * (hi - lo);
  w.object = std::make_unique<fcl::CollisionObjectd>(
      std::make_shared<fcl::Boxd>(2.0 * w.half + Eigen::Vector3d::Constant(1e-9)));
  w.object->setUserData(reinterpret_cast<void*>(static_cast<intptr_t>(index)));
  double su = 0.0, sv = 0.0;
  for (const Eigen::Vector2d& uv : s.mesh->base.uv) {
    const nurbs::SurfacePoint p = s.surface->Evaluate(uv[0], uv[1], 1);
    su += p.S_u.norm();
    sv += p.S_v.norm();
  }
  const double count = std::max<double>(1.0, static_cast<double>(s.mesh->base.uv.size()));
  w.L_u = su / count;
  w.L_v = sv / count;
  w.w_u = s.surface->knots_u().domain_end() - s.surface->knots_u().domain_begin();
  w.w_v = s.surface->knots_v().domain_end() - s.surface->knots_v().domain_begin();
  w.periodic_u = s.surface->periodic_u();
  w.periodic_v = s.surface->periodic_v();
  w.u_lo = s.surface->knots_u().domain_begin();
  w.v_lo = s.surface->knots_v().domain_begin();
  // Pole rows: the partial along the edge vanishes at every sample of it.
  for (int k = 0; k < 4; ++k) {
    const int across = k < 2 ? 0 : 1;
    const double bound =
        across == 0 ? (k == 0 ? w.u_lo : w.u_lo + w.w_u) : (k == 2 ? w.v_lo : w.v_lo + w.w_v);
    bool collapsed = true;
    for (int i = 0; i <= 8 && collapsed; ++i) {
      const double t = (across == 0 ? w.v_lo + w.w_v * i / 8.0 : w.u_lo + w.w_u * i / 8.0);
      const nurbs::SurfacePoint p =
          across == 0 ? s.surface->Evaluate(bound, t, 1) : s.surface->Evaluate(t, bound, 1);
      const Eigen::Vector3d& along = across == 0 ? p.S_v : p.S_u;
      const Eigen::Vector3d& off = across == 0 ? p.S_u : p.S_v;
      collapsed = off.norm() > 0.0 && along.norm() <= nurbs::kDegenerateRatio * off.norm();
    }
    w.pole[static_cast<size_t>(k)] = collapsed;
  }
  return w;
}

}  // namespace

GlobalContactStage::GlobalContactStage(std::vector<GlobalSurface> surfaces,
                                       const std::vector<std::pair<int, int>>& pairs,
                                       const GlobalOptions& options)
    : GlobalContactStage(std::move(surfaces), pairs, {}, options) {}

GlobalContactStage::GlobalContactStage(std::vector<GlobalSurface> surfaces,
                                       const std::vector<std::pair<int, int>>& pairs,
                                       const std::vector<std::pair<int, int>>& body_pairs,
                                       const GlobalOptions& options)
    : impl_(std::make_unique<Impl>()), options_(options) {
  if (!(options.release > options.activation)) {
    throw std::invalid_argument("global contact: release must exceed activation (hysteresis)");
  }
  Impl& m = *impl_;
  m.n = static_cast<int>(surfaces.size());
  for (const GlobalSurface& s : surfaces) {
    if (s.body < 0) throw std::invalid_argument("global contact: a surface on body -1");
    m.num_bodies = std::max(m.num_bodies, s.body + 1);
  }
  for (const auto& [a, b] : body_pairs) m.num_bodies = std::max({m.num_bodies, a + 1, b + 1});
  m.body_declared.assign(static_cast<size_t>(m.num_bodies * m.num_bodies), 0);
  std::vector<char> declared(surfaces.size(), 0);
  for (const auto& [a, b] : pairs) {
    if (a < 0 || b < 0 || a >= m.n || b >= m.n || a == b) {
      throw std::invalid_argument("global contact: pair (" + std::to_string(a) + ", " +
                                  std::to_string(b) + ") does not name two of the " +
                                  std::to_string(m.n) + " surfaces");
    }
    m.surface_declared.emplace_back(std::min(a, b), std::max(a, b));
    declared[static_cast<size_t>(a)] = declared[static_cast<size_t>(b)] = 1;
  }
  std::sort(m.surface_declared.begin(), m.surface_declared.end());
  for (const auto& [a, b] : body_pairs) {
    if (a < 0 || b < 0 || a == b) {
      throw std::invalid_argument("global contact: body pair (" + std::to_string(a) + ", " +
                                  std::to_string(b) + ") does not name two bodies");
    }
    m.body_declared[static_cast<size_t>(a * m.num_bodies + b)] = 1;
    m.body_declared[static_cast<size_t>(b * m.num_bodies + a)] = 1;
    for (size_t i = 0; i < surfaces.size(); ++i) {
      if (surfaces[i].body == a || surfaces[i].body == b) declared[i] = 1;
    }
  }
  if (options.broad_phase == GlobalOptions::BroadPhase::kSweepAndPrune) {
    m.manager = std::make_unique<fcl::SaPCollisionManagerd>();
  } else {
    m.manager = std::make_unique<fcl::DynamicAABBTreeCollisionManagerd>();
  }
  for (int i = 0; i < m.n; ++i) {
    const GlobalSurface& s = surfaces[static_cast<size_t>(i)];
    const std::string name = "global contact: surface " + std::to_string(i);
    if (!s.surface) throw std::invalid_argument(name + " is null");
    if (!s.mesh) {
      // A surface in no declared pair needs no mesh: it is never tested (model only what the
      // scene asks for).
      if (declared[static_cast<size_t>(i)]) {
        throw std::invalid_argument(name + " is in a declared pair but has no offset mesh");
      }
      Watched w;
      w.s = s;
      m.watched.push_back(std::move(w));
      continue;
    }
    m.watched.push_back(WatchSurface(i, s, options));
  }
  // A declared pair's offsets together must reach twice the release distance, so that it is
  // seen until it is released (a face's offset may be reduced below a concave radius of its).
  auto offset = [&](int i) { return surfaces[static_cast<size_t>(i)].mesh->offset; };
  std::vector<double> body_min(static_cast<size_t>(m.num_bodies), 1e300);
  for (int i = 0; i < m.n; ++i) {
    if (surfaces[static_cast<size_t>(i)].mesh) {
      double& b = body_min[static_cast<size_t>(surfaces[static_cast<size_t>(i)].body)];
      b = std::min(b, offset(i));
    }
  }
  for (int a = 0; a < m.num_bodies; ++a) {
    for (int b = a + 1; b < m.num_bodies; ++b) {
      if (m.body_declared[static_cast<size_t>(a * m.num_bodies + b)] &&
          body_min[static_cast<size_t>(a)] + body_min[static_cast<size_t>(b)] <
              2.0 * options.release) {
        throw std::invalid_argument("global contact: bodies " + std::to_string(a) + " and " +
                                    std::to_string(b) +
                                    ": their smallest offsets together are below twice the "
                                    "release distance");
      }
    }
  }
  for (const auto& [a, b] : m.surface_declared) {
    if (offset(a) + offset(b) < 2.0 * options.release) {
      throw std::invalid_argument("global contact: surfaces " + std::to_string(a) + " and " +
                                  std::to_string(b) +
                                  ": offsets together below twice the release distance");
    }
  }
  for (Watched& w : m.watched) {
    if (w.object) m.manager->registerObject(w.object.get());
  }
  m.manager->setup();
}

GlobalContactStage::~GlobalContactStage() = default;

void GlobalContactStage::BroadPhase(const std::vector<BodyPose>& poses, GlobalStats* st_out) {
  Impl& m = *impl_;
  GlobalStats& st = *st_out;
  // Broad phase on the snapshot, in two levels: FCL's manager over the surfaces' boxes, then,
  //    for each declared pair it reports, the blocks of each surface that overlap the other
  //    surface's box, paired where their own boxes overlap. (One manager over all blocks was
  //    measured first: with 20 clips, ~2000 blocks, its tree dominated the pass.)
  for (Watched& w : m.watched) {
    if (!w.object) continue;
    const BodyPose& p = poses[static_cast<size_t>(w.s.body)];
    w.object->setTransform(p.R_WB, p.Point(w.centre));
    w.object->computeAABB();
  }
  if (options_.broad_phase == GlobalOptions::BroadPhase::kSweepAndPrune) {
    // FCL 0.7's incremental SaP update (update_) corrupts its endpoint lists when boxes move and
    // then loops forever (measured: three clip boxes, first jiggled pass). The manager is rebuilt
    // from the sorted boxes instead: a full sort per pass, not seed 004's coherent insertion sort.
    m.manager->clear();
    for (Watched& w : m.watched) {
      if (w.object) m.manager->registerObject(w.object.get());
    }
    m.manager->setup();
  } else {
    m.manager->update();
  }
  m.surface_pairs.clear();
  m.candidates.clear();
  m.manager->collide(&m, BroadPhaseCallback);
  std::sort(m.surface_pairs.begin(), m.surface_pairs.end());
  m.surface_pairs.erase(std::unique(m.surface_pairs.begin(), m.surface_pairs.end()),
                        m.surface_pairs.end());
  st.candidate_pairs = static_cast<int>(m.surface_pairs.size());
  // A chunk is near the other surface when its box, in its own surface's frame, overlaps the
  // other surface's world box seen in that frame (bounded by an axis-aligned box there): no
  // chunk is rotated into the world for the test, and only the near ones are placed, once a
  // pass. (Placing every chunk of every surface in a candidate pair was a tenth of a pass over
  // 20 clips.) A chunk this rejects lies wholly outside the other surface's box, so its
  // triangles meet none of the other's: the candidates the narrow phase finds are unchanged.
  auto near = [&](Watched& w, const BodyPose& p, const WorldBox& other, std::vector<int>* out) {
    const Eigen::Vector3d c = p.R_WB.transpose() * (0.5 * (other.lo + other.hi) - p.q.head<3>());
    const Eigen::Vector3d h = p.R_WB.transpose().cwiseAbs() * (0.5 * (other.hi - other.lo));
    for (size_t k = 0; k < w.chunks.size(); ++k) {
      const Chunk& ch = w.chunks[k];
      if (((ch.centre - c).cwiseAbs().array() > (ch.half + h).array()).any()) continue;
      if (w.placed_at[k] != m.pass) {
        w.placed[k] = Place(p, ch.centre, ch.half);
        w.placed_at[k] = m.pass;
      }
      out->push_back(static_cast<int>(k));
    }
  };
  for (const auto& [a, b] : m.surface_pairs) {
    if (m.FacePair(a, b)) continue;  // (their corners are measured instead: FindFaces)
    Watched& wa = m.watched[static_cast<size_t>(a)];
    Watched& wb = m.watched[static_cast<size_t>(b)];
    const BodyPose& pa = poses[static_cast<size_t>(wa.s.body)];
    const BodyPose& pb = poses[static_cast<size_t>(wb.s.body)];
    const WorldBox box_a = Place(pa, wa.centre, wa.half);
    const WorldBox box_b = Place(pb, wb.centre, wb.half);
    m.near_a.clear();
    m.near_b.clear();
    near(wa, pa, box_b, &m.near_a);
    near(wb, pb, box_a, &m.near_b);
    for (int ka : m.near_a) {
      for (int kb : m.near_b) {
        if (wa.placed[static_cast<size_t>(ka)].Overlaps(wb.placed[static_cast<size_t>(kb)])) {
          m.candidates.push_back({a, b, ka, kb});
        }
      }
    }
  }
}

namespace {

// Narrow phase on the chunk pairs candidates[first, last) of surfaces a, b whose boxes overlap:
// the intersecting offset triangles (primitive pairs only, enable_contact = false: seeds are
// placed from the triangles) into m.triangle_pairs. A chunk pair lying, on both surfaces,
// within far_factor·ρ along the surface of a tracked contact is skipped: every seed it could
// give would fall in that contact's sphere of neglect.
void NarrowPhase(GlobalContactStage::Impl& m, const GlobalOptions& options, int a, int b,
                 size_t first, size_t last, const BodyPose& pa, const BodyPose& pb,
                 const std::vector<GlobalContact>& tracked, GlobalStats* st) {
  const double far = options.far_factor * options.neglect_radius;
  const Watched& wa = m.watched[static_cast<size_t>(a)];
  const Watched& wb = m.watched[static_cast<size_t>(b)];
  m.triangle_pairs.clear();
  for (size_t k = first; k < last; ++k) {
    const Chunk& ca = wa.chunks[static_cast<size_t>(m.candidates[k][2])];
    const Chunk& cb = wb.chunks[static_cast<size_t>(m.candidates[k][3])];
    bool skip = false;
    for (const GlobalContact& c : tracked) {
      if (c.a == a && c.b == b && wa.FarthestAlong(c.u.head<2>(), ca) <= far &&
          wb.FarthestAlong(c.u.tail<2>(), cb) <= far) {
        skip = true;
        break;
      }
    }
    if (skip) {
      ++st->chunk_pairs_skipped;
      continue;
    }
    ++st->chunk_pairs_tested;
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
  st->triangle_pairs += static_cast<int>(m.triangle_pairs.size());
}

// Seeds from m.triangle_pairs, clustered by spheres of neglect into m.accepted: the pair's
// tracked contacts first (where they are now, as neglect centres; returns how many), then one
// cluster per seed not within ρ (and topologically near on both surfaces) of an earlier one.
size_t ClusterSeeds(GlobalContactStage::Impl& m, const GlobalOptions& options, int a, int b,
                    const BodyPose& pa, const BodyPose& pb,
                    const std::vector<GlobalContact>& tracked, const Box& domains,
                    GlobalStats* st) {
  const double rho = options.neglect_radius, far = options.far_factor * rho;
  const Watched& wa = m.watched[static_cast<size_t>(a)];
  const Watched& wb = m.watched[static_cast<size_t>(b)];
  std::vector<Seed>& accepted = m.accepted;
  accepted.clear();
  for (const GlobalContact& c : tracked) {
    if (c.a != a || c.b != b) continue;
    const Eigen::Vector3d xa = pa.Point(wa.s.surface->Evaluate(c.u[0], c.u[1], 0).S);
    const Eigen::Vector3d xb = pb.Point(wb.s.surface->Evaluate(c.u[2], c.u[3], 0).S);
    Seed t;
    t.u = c.u;
    t.x = 0.5 * (xa + xb);
    accepted.push_back(t);
  }
  const size_t n_tracked = accepted.size();
  for (const auto& [ta, tb] : m.triangle_pairs) {
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
      if ((o.x - s.x).norm() < rho && wa.Along(o.u.head<2>(), s.u.head<2>()) <= far &&
          wb.Along(o.u.tail<2>(), s.u.tail<2>()) <= far) {
        owner = k >= n_tracked ? &accepted[k] : nullptr;
        ++st->seeds_neglected;
        s.count = -1;  // neglected
        break;
      }
    }
    if (s.count < 0 && !owner) continue;
    Seed& cluster = owner ? *owner : (accepted.push_back(s), accepted.back());
    AddToCluster(s.u, domains, &cluster);
  }
  return n_tracked;
}

// A tracked contact is held to the servo's tracking residual (the contact equations' scaled
// residual, optimizer::SurfaceContactTerm::kTrackedResidual); 1e-9 accepts what a snapshot
// carries and stops short of a point one Newton step would move by more than ~1e-18.
constexpr double kTrackedResidual = 1e-9;

// What a face extremum e of surfaces a, b stands for when either is trimmed: itself while its
// points lie on both materials, else the edge contact of the surface it leaves, or with both
// trimmed the two edges' (contact/trimmed.h), with its distance and points in (a, b) order.
struct OnMaterial {
  bool on_edge = false;
  /// Where the points lie (PointParameters): with both surfaces trimmed, what the contact is
  /// tracked by; else the face extremum's parameters.
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
  double beta = 0.0;
  Eigen::Vector3d p_a = Eigen::Vector3d::Zero(), p_b = Eigen::Vector3d::Zero();
  ExtremalStatus status = ExtremalStatus::kNotConverged;
};
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

// A face extremum on the material held on its surface's border (ExtremalStatus::kAtBoundary,
// every held parameter on a trimmed surface): where a face's material reaches its surface's
// border (an imported cylinder wall's top at a hole's rim), the border is the material's edge and
// the held extremum its contact with the other surface, as a trim edge's is. The servo's
// trimmed term measures it so (a face contact held on a bound, with its boundary Hessian); the
// stage keeps and finds it alike, rather than calling it gone from the domain and finding it
// again every pass. `on`: its MeasureOnMaterial.
bool HeldOnMaterialBorder(const Watched& wa, const Watched& wb, const SurfaceSurfaceExtremum& e,
                          const OnMaterial& on) {
  if (e.status != ExtremalStatus::kAtBoundary || on.on_edge) return false;
  for (int i = 0; i < 4; ++i) {
    if (e.at_bound[static_cast<size_t>(i)] && !(i < 2 ? wa.edges : wb.edges)) return false;
  }
  return true;
}

// Refines each new cluster m.accepted[n_tracked...] by the extremal Newton solver: from the mean
// of its seeds (the middle of where the offsets overlap, near the closest or deepest pair), then
// from its first seed and a few other members while that fails. (Measured: from the first seed
// alone, 2.4 % of deep contacts, whose seeds ring the overlap, converged to the far sides' pair
// instead.) Contacts not already in *found are added to it.
void RefineClusters(const GlobalContactStage::Impl& m, const GlobalOptions& options, int a, int b,
                    size_t n_tracked, const BodyPose& pa, const BodyPose& pb, const Box& domains,
                    GlobalStats* st, std::vector<GlobalContact>* found, double* nearest) {
  const Watched& wa = m.watched[static_cast<size_t>(a)];
  const Watched& wb = m.watched[static_cast<size_t>(b)];
  for (size_t k = n_tracked; k < m.accepted.size(); ++k) {
    SurfaceSurfaceExtremum e;
    SurfacePairEval at;
    bool ok = false;
    const Seed& cl = m.accepted[k];
    OnMaterial on;
    for (int attempt = 0; attempt < 2 + cl.n_members && !ok; ++attempt) {
      ++st->seeds_refined;
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
      if (on.on_edge) {
        ok = (e.status == ExtremalStatus::kConverged || e.status == ExtremalStatus::kAtBoundary) &&
             on.status == ExtremalStatus::kConverged && on.beta < options.activation &&
             on.beta > -options.max_penetration;
      } else {
        ok = (e.status == ExtremalStatus::kConverged || HeldOnMaterialBorder(wa, wb, e, on) ||
              (options.accept_continuum && e.status == ExtremalStatus::kSingular)) &&
             e.beta < options.activation && e.beta > -options.max_penetration && e.alignment < 0.0;
      }
      // The cluster's own minimum, apart by more than the activation distance where the offsets
      // met (its points within ρ of there): no contact here, and the other seeds would only find
      // it again. (The retries are for seeds that reach another region's pair, such as a deep
      // contact's far sides, which lie below −max_penetration. Measured on twenty clips' cold
      // pass: 380 of 2,035 clusters ended so, each retried three times.)
      if (!ok && !on.on_edge && e.status == ExtremalStatus::kConverged &&
          e.kind == ExtremumKind::kMinimum && e.beta >= options.activation &&
          (0.5 * (e.p_f + e.p_g) - cl.x).norm() < options.neglect_radius) {
        break;
      }
    }
    if (!ok) continue;
    // A saddle of the distance is not a contact: the minima beside it are. (Held on a border,
    // the surfaces' curvature across it says nothing.)
    if (const RelativeCurvature rc = RelativeCurvatureOf(at);
        !on.on_edge && e.status == ExtremalStatus::kConverged && rc.crossing) {
      MinimaBeside(*wa.s.surface, pa, *wb.s.surface, pb, e, at, rc, options, a, b, found);
      continue;
    }
    AddFound({a, b, on.u, on.beta, on.p_a, on.p_b}, found);
  }
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
  NarrowPhase(m, options_, a, b, first, last, pa, pb, tracked, st);
  const size_t n_tracked = ClusterSeeds(m, options_, a, b, pa, pb, tracked, domains, st);
  double nearest = std::numeric_limits<double>::infinity();
  RefineClusters(m, options_, a, b, n_tracked, pa, pb, domains, st, &found_, &nearest);
  if (!m.triangle_pairs.empty()) {
    m.crossed.emplace_back(a, b);
    viewed_.push_back({a, b, nearest});
  }
}

void GlobalContactStage::Events(const std::vector<BodyPose>& poses,
                                const std::vector<GlobalContact>& tracked,
                                std::vector<ContactEvent>* events) {
  const Impl& m = *impl_;
  const double far = options_.far_factor * options_.neglect_radius;
  split_.clear();
  removed_.assign(tracked.size(), 0);
  // Whether tracked contact k re-solved to the points of an earlier one of its pair still kept.
  auto same_as_earlier = [&](size_t k, const SurfaceSurfaceExtremum& e) {
    const GlobalContact now{tracked[k].a, tracked[k].b, e.u, e.beta, e.p_f, e.p_g};
    for (size_t j = 0; j < k; ++j) {
      if (!removed_[j] && SamePoints(tracked[j], now)) return true;
    }
    return false;
  };
  // Tracked contacts re-solved from their parameters (removals, splits, merges); found ones not
  // tracked are added.
  for (size_t k = 0; k < tracked.size(); ++k) {
    const GlobalContact& c = tracked[k];
    const Watched& wa = m.watched[static_cast<size_t>(c.a)];
    const Watched& wb = m.watched[static_cast<size_t>(c.b)];
    const BodyPose& pa = poses[static_cast<size_t>(wa.s.body)];
    const BodyPose& pb = poses[static_cast<size_t>(wb.s.body)];
    if (m.FacePair(c.a, c.b)) {
      // Two flat faces: held by their corners while some corner lies over the other face
      // within the release distance.
      const FaceCorner low = LowestCorner(*wa.s.surface, *wa.flat, pa, *wb.s.surface, *wb.flat, pb);
      const GlobalContact now{c.a, c.b, c.u, low.beta, low.p_f, low.p_g};
      if (!low.found || low.beta > options_.release) {
        events->push_back(
            {ContactEvent::Kind::kRemoved,
             low.found ? ContactEvent::Reason::kSeparated : ContactEvent::Reason::kLeftDomain,
             now});
        removed_[k] = 1;
      }
      continue;
    }
    // The servo holds its contacts at extremal parameters (the snapshot's u and poses are one
    // tick's): taken as they are when they still solve the contact equations, else re-solved.
    // (Newton from an extremum that is nearly degenerate, as where two wires turn parallel,
    // can take one step far away.)
    SurfacePairEval at;
    SurfaceSurfaceExtremum e;
    bool jumped = false;
    OnMaterial on;
    TrimmedMeasure edge;
    if (wa.edges && wb.edges && MeasureTrimmedPairAt(*wa.edges, pa, *wb.edges, pb, c.u, &edge)) {
      // Two trimmed faces tracked at an edge contact's points: re-measured in its own form.
      e.u = c.u;
      e.status = ExtremalStatus::kConverged;
      on = {true, c.u, edge.beta, edge.p_f, edge.p_g, edge.status};
    } else {
      e = ExtremumAt(*wa.s.surface, pa, *wb.s.surface, pb, c.u, kTrackedResidual, &at);
      if (e.status != ExtremalStatus::kConverged) {
        const double held_distance = at.d.norm();
        e = SolveSurfaceSurface(*wa.s.surface, pa, *wb.s.surface, pb, c.u, kContinuation, &at);
        jumped = FoundAnotherExtremum(*wa.s.surface, *wb.s.surface, c.u, e, held_distance);
      }
      // On trimmed surfaces: the edge contact where the face's point lies off the material.
      on = MeasureOnMaterial(wa, pa, wb, pb, e);
    }
    if (on.on_edge && !jumped && e.status != ExtremalStatus::kNotConverged) {
      e.status = on.status;
      e.beta = on.beta;
      e.p_f = on.p_a;
      e.p_g = on.p_b;
    }
    // A removal names the contact by the parameters it is tracked at (what the owner of the
    // contact matches it by), with the distance and points re-solved now.
    GlobalContact now{c.a, c.b, c.u, e.beta, e.p_f, e.p_g};
    auto remove = [&](ContactEvent::Reason reason) {
      events->push_back({ContactEvent::Kind::kRemoved, reason, now});
      removed_[k] = 1;
    };
    // kSingular is not a loss: a pair held at β ≈ 0 (every active contact, within the servo's
    // 1e-10 m) makes the Newton matrix nearly rank deficient, the more so at a pole, and the
    // re-solve ends converged-but-singular on the same pair. Removing it there made contacts
    // at domes' poles chatter (removed and found again every pass: scripts/faults.sh
    // contact_burst); the servo's tracker holds them exactly, and separation still removes them.
    const bool border = !jumped && HeldOnMaterialBorder(wa, wb, e, on);
    if (e.status == ExtremalStatus::kAtBoundary && !border) {
      remove(ContactEvent::Reason::kLeftDomain);
    } else if ((e.status != ExtremalStatus::kConverged && e.status != ExtremalStatus::kSingular &&
                !border) ||
               jumped) {
      remove(ContactEvent::Reason::kLost);
    } else if (e.beta > options_.release) {
      remove(ContactEvent::Reason::kSeparated);
    } else if (same_as_earlier(k, e)) {
      // Two tracked contacts on one point (the minima of a split came back together).
      remove(ContactEvent::Reason::kMerged);
    } else if (const RelativeCurvature rc = RelativeCurvatureOf(at);
               !on.on_edge && !border && rc.crossing) {
      // The pair the contact follows turned from a minimum into a saddle (a pitchfork: e.g.
      // two interlocked wires turned until one lies in the other's bend, tighter than itself);
      // β ≥ 0 there no longer keeps the surfaces apart. The minima either side replace it.
      remove(ContactEvent::Reason::kSplit);
      MinimaBeside(*wa.s.surface, pa, *wb.s.surface, pb, e, at, rc, options_, c.a, c.b, &split_);
    }
  }
  for (const GlobalContact& f : found_) {
    bool known = false;
    for (size_t k = 0; k < tracked.size() && !known; ++k) {
      const GlobalContact& c = tracked[k];
      if (removed_[k] || c.a != f.a || c.b != f.b) continue;
      const Watched& wa = m.watched[static_cast<size_t>(f.a)];
      const Watched& wb = m.watched[static_cast<size_t>(f.b)];
      known = wa.Along(c.u.head<2>(), f.u.head<2>()) <= far &&
              wb.Along(c.u.tail<2>(), f.u.tail<2>()) <= far;
    }
    for (const GlobalContact& s : split_) known = known || SamePoints(s, f);
    if (!known)
      events->push_back({ContactEvent::Kind::kAdded, ContactEvent::Reason::kApproached, f});
  }
  for (const GlobalContact& s : split_)
    events->push_back({ContactEvent::Kind::kAdded, ContactEvent::Reason::kSplit, s});
}

void GlobalContactStage::Run(const std::vector<BodyPose>& poses,
                             const std::vector<GlobalContact>& tracked,
                             std::vector<ContactEvent>* events, GlobalStats* stats) {
  Impl& m = *impl_;
  GlobalStats st;
  events->clear();
  found_.clear();
  viewed_.clear();
  m.crossed.clear();
  ++m.pass;
  BroadPhase(poses, &st);
  // Candidates are grouped by surface pair (a, b): one FindContacts per pair.
  for (size_t first = 0; first < m.candidates.size();) {
    const int a = m.candidates[first][0], b = m.candidates[first][1];
    size_t last = first;
    while (last < m.candidates.size() && m.candidates[last][0] == a && m.candidates[last][1] == b) {
      ++last;
    }
    FindContacts(a, b, first, last, poses, tracked, &st);
    first = last;
  }
  FindNested(poses, tracked, &st);
  FindFaces(poses, tracked, &st);
  st.found = static_cast<int>(found_.size());
  Events(poses, tracked, events);
  std::sort(found_.begin(), found_.end(), [](const GlobalContact& x, const GlobalContact& y) {
    return std::tie(x.a, x.b, x.u[0], x.u[1]) < std::tie(y.a, y.b, y.u[0], y.u[1]);
  });
  if (stats) *stats = st;
}

}  // namespace tangent::contact
