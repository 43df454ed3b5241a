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

using internal::HeldOnMaterialBorder;
using internal::IsNearMiss;
using internal::MeasureOnMaterial;
using internal::MinimaBeside;
using internal::OnMaterial;
using internal::Place;
using internal::SamePoints;
using internal::Watched;
using internal::WorldBox;

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
  w.near_mask.assign(w.chunks.size(), 0);
  w.near_search.assign(w.chunks.size(), -1);
  w.near_upto.assign(w.chunks.size(), 0);
  {
    std::vector<int> ids(w.chunks.size());
    std::vector<Eigen::AlignedBox3d> boxes(w.chunks.size());
    for (size_t k = 0; k < w.chunks.size(); ++k) {
      ids[k] = static_cast<int>(k);
      boxes[k] = Eigen::AlignedBox3d(w.chunks[k].centre - w.chunks[k].half,
                                     w.chunks[k].centre + w.chunks[k].half);
    }
    w.chunk_tree = std::make_unique<Eigen::KdBVH<double, 3, int>>(ids.begin(), ids.end(),
                                                                  boxes.begin(), boxes.end());
  }
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
    // The chunks' tree, not every chunk: a part's face has thousands.
    struct Query {
      const Eigen::AlignedBox3d box;
      std::vector<int>* out;
      bool intersectVolume(const Eigen::AlignedBox3d& v) const { return v.intersects(box); }
      bool intersectObject(int k) {
        out->push_back(k);
        return false;  // (keep going)
      }
    } query{Eigen::AlignedBox3d(c - h, c + h), out};
    Eigen::BVIntersect(*w.chunk_tree, query);
    std::sort(out->begin(), out->end());  // (the order the chunks are stored in, as a scan's)
    size_t kept = 0;
    for (int k : *out) {
      const Chunk& ch = w.chunks[static_cast<size_t>(k)];
      if (((ch.centre - c).cwiseAbs().array() > (ch.half + h).array()).any()) continue;
      if (w.placed_at[static_cast<size_t>(k)] != m.pass) {
        w.placed[static_cast<size_t>(k)] = Place(p, ch.centre, ch.half);
        w.placed_at[static_cast<size_t>(k)] = m.pass;
      }
      (*out)[kept++] = k;
    }
    out->resize(kept);
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
    const size_t na = m.near_a.size(), nb = m.near_b.size();
    if (na * nb <= static_cast<size_t>(std::max(0, options_.sweep_above))) {
      for (int ka : m.near_a) {
        for (int kb : m.near_b) {
          if (wa.placed[static_cast<size_t>(ka)].Overlaps(wb.placed[static_cast<size_t>(kb)])) {
            m.candidates.push_back({a, b, ka, kb});
          }
        }
      }
      continue;
    }
    // Many near blocks (nested or conformal surfaces, large faces): their pairs whose world
    // boxes overlap, by a sweep along the axis where the two surfaces' common box is longest:
    // both lists sorted by their boxes' low ends, each box tested against the other list's boxes
    // that start before it ends. (Every block against every other was 1.5 ms a pass for a ball
    // in a socket, ~1,800 x 960 blocks.)
    const WorldBox common{box_a.lo.cwiseMax(box_b.lo), box_a.hi.cwiseMin(box_b.hi)};
    int axis = 0;
    (common.hi - common.lo).maxCoeff(&axis);
    auto lo = [axis](const Watched& w, int k) { return w.placed[static_cast<size_t>(k)].lo[axis]; };
    std::sort(m.near_a.begin(), m.near_a.end(),
              [&](int x, int y) { return lo(wa, x) < lo(wa, y); });
    std::sort(m.near_b.begin(), m.near_b.end(),
              [&](int x, int y) { return lo(wb, x) < lo(wb, y); });
    for (size_t i = 0, j = 0; i < na && j < nb;) {
      const WorldBox& box_i = wa.placed[static_cast<size_t>(m.near_a[i])];
      const WorldBox& box_j = wb.placed[static_cast<size_t>(m.near_b[j])];
      if (box_i.lo[axis] <= box_j.lo[axis]) {
        for (size_t k = j; k < nb && lo(wb, m.near_b[k]) <= box_i.hi[axis]; ++k) {
          if (box_i.Overlaps(wb.placed[static_cast<size_t>(m.near_b[k])])) {
            m.candidates.push_back({a, b, m.near_a[i], m.near_b[k]});
          }
        }
        ++i;
      } else {
        for (size_t k = i; k < na && lo(wa, m.near_a[k]) <= box_j.hi[axis]; ++k) {
          if (wa.placed[static_cast<size_t>(m.near_a[k])].Overlaps(box_j)) {
            m.candidates.push_back({a, b, m.near_a[k], m.near_b[j]});
          }
        }
        ++j;
      }
    }
  }
}

namespace {

// A tracked contact is held to the servo's tracking residual (the contact equations' scaled
// residual, optimizer::SurfaceContactTerm::kTrackedResidual); 1e-9 accepts what a snapshot
// carries and stops short of a point one Newton step would move by more than ~1e-18.
constexpr double kTrackedResidual = 1e-9;

}  // namespace

void GlobalContactStage::Events(const std::vector<BodyPose>& poses,
                                const std::vector<GlobalContact>& tracked,
                                std::vector<ContactEvent>* events) {
  Impl& m = *impl_;
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
      // Still within the offsets' reach: the next pass re-solves it as a near miss.
      if (options_.near_misses && IsNearMiss(m, options_, c.a, c.b, e)) {
        m.next_misses.push_back({c.a, c.b, e.u});
      }
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
  std::swap(m.misses, m.next_misses);
  m.next_misses.clear();
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
