// Certified clearance between watched bodies (clearance.h).

#include "contact/clearance.h"

#include <fcl/fcl.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace tangent::contact {

BoundingSphere SurfaceSphere(const nurbs::OffsetMesh& mesh) {
  BoundingSphere s;
  const auto& v = mesh.base.vertices;
  if (v.empty()) return s;
  Eigen::Vector3d lo = v.front(), hi = v.front();
  for (const Eigen::Vector3d& x : v) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  s.centre = 0.5 * (lo + hi);
  double r2 = 0.0;
  for (const Eigen::Vector3d& x : v) r2 = std::max(r2, (x - s.centre).squaredNorm());
  s.radius = std::sqrt(r2) + mesh.base.error_bound;
  return s;
}

double SurfaceReach(const nurbs::OffsetMesh& mesh) {
  double r2 = 0.0;
  for (const Eigen::Vector3d& x : mesh.base.vertices) r2 = std::max(r2, x.squaredNorm());
  return std::sqrt(r2) + mesh.base.error_bound;
}

std::vector<std::pair<int, int>> WatchedBodyPairs(
    const std::vector<GlobalSurface>& surfaces, const std::vector<std::pair<int, int>>& pairs,
    const std::vector<std::pair<int, int>>& body_pairs) {
  std::vector<std::pair<int, int>> out;
  const int n = static_cast<int>(surfaces.size());
  for (const auto& [a, b] : pairs) {
    if (a < 0 || b < 0 || a >= n || b >= n) continue;
    const GlobalSurface& sa = surfaces[static_cast<size_t>(a)];
    const GlobalSurface& sb = surfaces[static_cast<size_t>(b)];
    if (!sa.mesh || !sb.mesh || sa.body == sb.body) continue;
    out.emplace_back(std::min(sa.body, sb.body), std::max(sa.body, sb.body));
  }
  for (const auto& [a, b] : body_pairs) {
    if (a != b) out.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

struct ClearanceCertifier::Impl {
  std::vector<GlobalSurface> surfaces;
  std::vector<BoundingSphere> spheres;
  /// Each watched surface's tessellation as an OBBRSS tree (built on first use: a scene's
  /// surfaces that never come near another are never built).
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  std::vector<std::vector<int>> by_body;  ///< watched surfaces of each body
  /// Per body pair: declared as a whole (every watched surface of a against every one of b),
  /// and its declared surface pairs (a < b).
  std::vector<char> whole;
  std::vector<std::vector<std::pair<int, int>>> declared;
  double exact_within = 0.005;
  double standoff = 0.0;
  struct Gap {
    double gap;
    int a, b;
  };
  std::vector<Gap> by_gap;  ///< Certify's workspace
  /// Tessellation distances already measured, by surface pair (a < b), with the poses they were
  /// measured at: at other poses the pair is still at least that less how far either surface
  /// has moved since, so one is measured again only when that has used up a quarter of it. (An
  /// FCL distance between two of the imported peg's 8,000-triangle faces takes 0.1 to 12 ms;
  /// the hand moves them a few per cent of their distance a pass.)
  struct Measured {
    double clearance = 0.0;
    Eigen::Vector3d p_a, p_b;
    Eigen::Matrix3d R_a, R_b;
  };
  std::map<std::pair<int, int>, Measured> measured;
  std::vector<double> reach;  ///< per surface: SurfaceReach

  fcl::CollisionObjectd* Object(int s) {
    auto& o = objects[static_cast<size_t>(s)];
    if (!o) {
      const nurbs::TriangleMesh& m = surfaces[static_cast<size_t>(s)].mesh->base;
      std::vector<fcl::Vector3d> points(m.vertices.begin(), m.vertices.end());
      std::vector<fcl::Triangle> tris;
      tris.reserve(m.triangles.size());
      for (const auto& t : m.triangles) {
        tris.emplace_back(static_cast<size_t>(t[0]), static_cast<size_t>(t[1]),
                          static_cast<size_t>(t[2]));
      }
      auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
      model->beginModel();
      model->addSubModel(points, tris);
      model->endModel();
      o = std::make_unique<fcl::CollisionObjectd>(model);
    }
    return o.get();
  }
};

int ClearanceCertifier::BuildAll() {
  Impl& m = *impl_;
  // The surfaces a certificate may measure: every watched surface of a pair of bodies declared
  // as a whole, and both of each declared surface pair.
  std::vector<char> needed(m.surfaces.size(), 0);
  for (size_t k = 0; k < body_pairs_.size(); ++k) {
    if (m.whole[k]) {
      for (int body : {body_pairs_[k].first, body_pairs_[k].second}) {
        for (int s : m.by_body[static_cast<size_t>(body)]) needed[static_cast<size_t>(s)] = 1;
      }
    }
    for (const auto& [a, b] : m.declared[k]) {
      needed[static_cast<size_t>(a)] = needed[static_cast<size_t>(b)] = 1;
    }
  }
  int built = 0;
  for (size_t s = 0; s < needed.size(); ++s) {
    if (!needed[s] || m.objects[s]) continue;
    m.Object(static_cast<int>(s));
    ++built;
  }
  return built;
}

ClearanceCertifier::ClearanceCertifier(std::vector<GlobalSurface> surfaces,
                                       const std::vector<std::pair<int, int>>& pairs,
                                       const std::vector<std::pair<int, int>>& body_pairs,
                                       double standoff, double exact_within)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.standoff = standoff;
  body_pairs_ = WatchedBodyPairs(surfaces, pairs, body_pairs);
  m.exact_within = exact_within;
  int num_bodies = 0;
  for (const GlobalSurface& s : surfaces) num_bodies = std::max(num_bodies, s.body + 1);
  m.by_body.resize(static_cast<size_t>(num_bodies));
  m.spheres.resize(surfaces.size());
  m.reach.resize(surfaces.size(), 0.0);
  m.objects.resize(surfaces.size());
  for (size_t s = 0; s < surfaces.size(); ++s) {
    if (!surfaces[s].mesh) continue;
    m.spheres[s] = SurfaceSphere(*surfaces[s].mesh);
    m.reach[s] = SurfaceReach(*surfaces[s].mesh);
    m.by_body[static_cast<size_t>(surfaces[s].body)].push_back(static_cast<int>(s));
  }
  m.surfaces = std::move(surfaces);
  auto index = [&](int a, int b) {
    const auto it = std::lower_bound(body_pairs_.begin(), body_pairs_.end(),
                                     std::make_pair(std::min(a, b), std::max(a, b)));
    return static_cast<size_t>(it - body_pairs_.begin());
  };
  m.whole.assign(body_pairs_.size(), 0);
  m.declared.resize(body_pairs_.size());
  for (const auto& [a, b] : body_pairs) {
    if (a != b) m.whole[index(a, b)] = 1;
  }
  const int n = static_cast<int>(m.surfaces.size());
  for (const auto& [a, b] : pairs) {
    if (a < 0 || b < 0 || a >= n || b >= n) continue;
    const GlobalSurface& sa = m.surfaces[static_cast<size_t>(a)];
    const GlobalSurface& sb = m.surfaces[static_cast<size_t>(b)];
    if (!sa.mesh || !sb.mesh || sa.body == sb.body) continue;
    m.declared[index(sa.body, sb.body)].emplace_back(std::min(a, b), std::max(a, b));
  }
}

ClearanceCertifier::~ClearanceCertifier() = default;

double ClearanceCertifier::SphereGap(int a, int b, const std::vector<BodyPose>& poses) const {
  const Impl& m = *impl_;
  const BoundingSphere& ka = m.spheres[static_cast<size_t>(a)];
  const BoundingSphere& kb = m.spheres[static_cast<size_t>(b)];
  const BodyPose& pa = poses[static_cast<size_t>(m.surfaces[static_cast<size_t>(a)].body)];
  const BodyPose& pb = poses[static_cast<size_t>(m.surfaces[static_cast<size_t>(b)].body)];
  return (pa.Point(ka.centre) - pb.Point(kb.centre)).norm() - ka.radius - kb.radius;
}

double ClearanceCertifier::SurfaceClearance(int a, int b, const std::vector<BodyPose>& poses) {
  Impl& m = *impl_;
  const double gap = SphereGap(a, b, poses);
  if (gap >= m.exact_within) return gap;
  const GlobalSurface& sa = m.surfaces[static_cast<size_t>(a)];
  const GlobalSurface& sb = m.surfaces[static_cast<size_t>(b)];
  const BodyPose& pa = poses[static_cast<size_t>(sa.body)];
  const BodyPose& pb = poses[static_cast<size_t>(sb.body)];
  // How far any point of a surface (within `reach` of its body's origin) has moved from pose
  // (p0, R0) to pose: |Δp| + |R − R0|₂ reach, with |R − R0|₂ = 2 sin(θ/2) = √(3 − tr R0ᵀR).
  auto moved = [](const Eigen::Vector3d& p0, const Eigen::Matrix3d& R0, const BodyPose& now,
                  double reach) {
    const double chord = std::sqrt(std::max(0.0, 3.0 - (R0.transpose() * now.R_WB).trace()));
    return (now.q.head<3>() - p0).norm() + chord * reach;
  };
  const auto key = std::make_pair(a, b);
  if (const auto it = m.measured.find(key); it != m.measured.end()) {
    const Impl::Measured& x = it->second;
    const double now = x.clearance - moved(x.p_a, x.R_a, pa, m.reach[static_cast<size_t>(a)]) -
                       moved(x.p_b, x.R_b, pb, m.reach[static_cast<size_t>(b)]);
    if (now >= 0.75 * x.clearance) return std::max(gap, now);
  }
  fcl::CollisionObjectd* oa = m.Object(a);
  fcl::CollisionObjectd* ob = m.Object(b);
  auto place = [](fcl::CollisionObjectd* o, const BodyPose& p) {
    fcl::Transform3d x = fcl::Transform3d::Identity();
    x.linear() = p.R_WB;
    x.translation() = p.q.head<3>();
    o->setTransform(x);
    o->computeAABB();
  };
  place(oa, pa);
  place(ob, pb);
  fcl::DistanceRequestd request(false);
  fcl::DistanceResultd result;
  fcl::distance(oa, ob, request, result);
  // FCL reports a negative distance for meshes that intersect.
  const double d = std::max(0.0, result.min_distance);
  const double c = d - sa.mesh->base.error_bound - sb.mesh->base.error_bound;
  m.measured[key] = {c, pa.q.head<3>(), pb.q.head<3>(), pa.R_WB, pb.R_WB};
  return std::max(gap, c);
}

void ClearanceCertifier::Certify(const std::vector<BodyPose>& poses,
                                 const std::vector<GlobalContact>& tracked,
                                 const GlobalContactStage& stage, std::vector<double>* clearance) {
  in_contact_.clear();
  for (const std::vector<GlobalContact>* contacts : {&tracked, &stage.found()}) {
    for (const GlobalContact& c : *contacts) {
      in_contact_.emplace_back(std::min(c.a, c.b), std::max(c.a, c.b));
    }
  }
  Certify(poses, in_contact_, stage.viewed(), clearance);
}

void ClearanceCertifier::Certify(const std::vector<BodyPose>& poses,
                                 const std::vector<std::pair<int, int>>& in_contact,
                                 const std::vector<GlobalContactStage::Viewed>& viewed,
                                 std::vector<double>* clearance) {
  Impl& m = *impl_;
  const double inf = std::numeric_limits<double>::infinity();
  clearance->assign(body_pairs_.size(), inf);
  for (size_t k = 0; k < body_pairs_.size(); ++k) {
    // A surface pair's bound less the standoff, when positive, lowers the body pair's.
    double c = inf;
    // Certified only beyond twice the standoff (the stage's activation distance): nearer, a
    // facing pair is the stage's next contact, and one it does not take (a face's back, a
    // neighbouring face across a shared edge) would be held still for ever at the standoff.
    auto lower = [&](double s) {
      if (s > 2.0 * m.standoff) c = std::min(c, s - m.standoff);
    };
    // Pairs in the stage's view from its refinements; the others by their spheres' gaps,
    // nearest first, each by its tessellations only while its gap could still lower c.
    m.by_gap.clear();
    auto take = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      if (std::find(in_contact.begin(), in_contact.end(), key) != in_contact.end()) return;
      const auto seen =
          std::find_if(viewed.begin(), viewed.end(), [&](const GlobalContactStage::Viewed& v) {
            return v.a == key.first && v.b == key.second;
          });
      if (seen == viewed.end()) {
        m.by_gap.push_back({SphereGap(key.first, key.second, poses), key.first, key.second});
        return;
      }
      // In the stage's view the tessellations alone may hold a part off for ever (a trimmed
      // face's uncut cells reach past its trim); its refinements' distance, measured on the
      // material, is taken instead, but only while the tessellations say the surfaces do not
      // meet: where they may (closer than their bounds), a refinement can converge to a pair
      // beside the crossing, apart, and nothing is certified.
      const double strict = SurfaceClearance(key.first, key.second, poses);
      if (!(strict > 0.0)) return;
      if (!(seen->nearest < inf)) {
        lower(strict);
        return;
      }
      const nurbs::OffsetMesh& ma = *m.surfaces[static_cast<size_t>(key.first)].mesh;
      const nurbs::OffsetMesh& mb = *m.surfaces[static_cast<size_t>(key.second)].mesh;
      lower(std::max(
          strict, std::min(seen->nearest, ma.offset + mb.offset -
                                              2.0 * (ma.base.error_bound + mb.base.error_bound))));
    };
    if (m.whole[k]) {
      const auto& [ba, bb] = body_pairs_[k];
      for (int a : m.by_body[static_cast<size_t>(ba)]) {
        for (int b : m.by_body[static_cast<size_t>(bb)]) take(a, b);
      }
    } else {
      for (const auto& [a, b] : m.declared[k]) take(a, b);
    }
    std::sort(m.by_gap.begin(), m.by_gap.end(),
              [](const Impl::Gap& x, const Impl::Gap& y) { return x.gap < y.gap; });
    for (const Impl::Gap& g : m.by_gap) {
      // Every pair from here on is at least its gap apart.
      if (g.gap - m.standoff >= c) break;
      if (g.gap >= m.exact_within) {
        lower(g.gap);
        break;
      }
      lower(SurfaceClearance(g.a, g.b, poses));
    }
    (*clearance)[k] = c;
  }
}

}  // namespace tangent::contact
