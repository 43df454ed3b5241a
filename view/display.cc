#include "view/display.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <stdexcept>
#include <utility>

#include <Eigen/Geometry>

#include "nurbs/tessellation.h"
#include "nurbs/trim.h"

namespace tangent::view {
namespace {

/// Trim rims are drawn to 1/8 of a grid cell: the extra triangles lie along the rim only.
constexpr int kRimDepth = 3;

/// FNV-1a 64 over raw bytes: a content hash for caching, not a security measure.
uint64_t Fnv1a(const void* data, size_t size, uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) {
    h ^= p[i];
    h *= 1099511628211ull;
  }
  return h;
}

std::string HashOf(const DisplayMesh& m) {
  uint64_t h = 14695981039346656037ull;
  h = Fnv1a(m.positions.data(), m.positions.size() * sizeof(float), h);
  h = Fnv1a(m.normals.data(), m.normals.size() * sizeof(float), h);
  h = Fnv1a(m.indices.data(), m.indices.size() * sizeof(uint32_t), h);
  h = Fnv1a(m.colour.data(), sizeof(m.colour), h);
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(h));
  return text;
}

/// The mesh's vertices that its kept triangles use, renumbered (a cut mesh keeps all grid
/// vertices; the browser need not receive the dropped ones).
void Compact(const nurbs::TriangleMesh& t, const nurbs::NurbsSurface& s, DisplayMesh* out) {
  std::vector<int> index(t.vertices.size(), -1);
  for (const auto& tri : t.triangles) {
    for (int k : tri) {
      int& slot = index[static_cast<size_t>(k)];
      if (slot < 0) {
        slot = static_cast<int>(out->positions.size() / 3);
        const Eigen::Vector3d& p = t.vertices[static_cast<size_t>(k)];
        const Eigen::Vector2d& uv = t.uv[static_cast<size_t>(k)];
        // At poles and collapsed edges UnitNormal takes the limit from inside the domain, so
        // shading stays smooth where S_u × S_v vanishes.
        const nurbs::SurfacePoint sp = s.Evaluate(uv.x(), uv.y(), 2);
        const Eigen::Vector3d n = nurbs::UnitNormal(s, uv.x(), uv.y(), sp);
        out->uv.push_back(static_cast<float>(uv.x()));
        out->uv.push_back(static_cast<float>(uv.y()));
        for (int i = 0; i < 3; ++i) {
          out->positions.push_back(static_cast<float>(p[i]));
          out->normals.push_back(static_cast<float>(n[i]));
        }
      }
      out->indices.push_back(static_cast<uint32_t>(slot));
    }
  }
}

/// The cells of a tessellation grid that may hold material, with the cells a trim loop crosses
/// split into quarters (recursively, `depth` times), so the rim is drawn to 1/2^depth of a cell
/// instead of by whole cells. Sub-cells that certainly hold no material are dropped; no
/// material is lost (nurbs::TrimmedDomain::MayHoldMaterial). A sub-cell's chords deviate from
/// the surface by at most twice its cell's bound (the bilinear interpolant of a sub-rectangle
/// differs from the cell's by the cell's error at the sub-corners), hence `bound_factor`.
class RimRefiner {
 public:
  RimRefiner(const nurbs::NurbsSurface& s, const nurbs::TrimmedDomain& trim,
             nurbs::TriangleMesh* out)
      : s_(s), trim_(trim), out_(out) {}

  void Cell(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, int depth) {
    if (!trim_.MayHoldMaterial(lo, hi)) return;
    const Eigen::Vector2d mid = 0.5 * (lo + hi);
    // Crossed: a loop passes within the cell's circumscribed circle.
    const bool crossed = std::abs(trim_.Nearest(mid).signed_distance) <= 0.5 * (hi - lo).norm();
    // Not crossed: all of the cell lies on its centre's side of every loop (MayHoldMaterial is
    // conservative near chords and may have kept a cell wholly off the material).
    if (!crossed && !trim_.Contains(mid)) return;
    if (crossed && depth > 0) {
      refined_ = true;
      Cell(lo, mid, depth - 1);
      Cell({mid.x(), lo.y()}, {hi.x(), mid.y()}, depth - 1);
      Cell({lo.x(), mid.y()}, {mid.x(), hi.y()}, depth - 1);
      Cell(mid, hi, depth - 1);
      return;
    }
    // Split along the (0,0)-(1,1) diagonal, counter-clockwise in (u, v), as Tessellate does.
    const int a = Vertex(lo.x(), lo.y()), b = Vertex(hi.x(), lo.y());
    const int c = Vertex(hi.x(), hi.y()), d = Vertex(lo.x(), hi.y());
    out_->triangles.push_back({a, b, c});
    out_->triangles.push_back({a, c, d});
  }
  double bound_factor() const { return refined_ ? 2.0 : 1.0; }

 private:
  int Vertex(double u, double v) {
    const auto [it, added] = index_.try_emplace({u, v}, static_cast<int>(out_->vertices.size()));
    if (added) {
      out_->vertices.push_back(s_.Evaluate(u, v, 0).S);
      out_->uv.emplace_back(u, v);
    }
    return it->second;
  }

  const nurbs::NurbsSurface& s_;
  const nurbs::TrimmedDomain& trim_;
  nurbs::TriangleMesh* out_;
  std::map<std::pair<double, double>, int> index_;
  bool refined_ = false;
};

/// The display mesh of a trimmed surface: the grid's cells that may hold material, the rim's
/// cells refined `depth` times.
nurbs::TriangleMesh CutWithRim(const nurbs::TriangleMesh& grid, const nurbs::NurbsSurface& s,
                               const nurbs::TrimmedDomain& trim, int depth) {
  nurbs::TriangleMesh out;
  RimRefiner refiner(s, trim, &out);
  for (size_t i = 0; i + 1 < grid.u_lines.size(); ++i) {
    for (size_t j = 0; j + 1 < grid.v_lines.size(); ++j) {
      refiner.Cell({grid.u_lines[i], grid.v_lines[j]}, {grid.u_lines[i + 1], grid.v_lines[j + 1]},
                   depth);
    }
  }
  out.u_lines = grid.u_lines;
  out.v_lines = grid.v_lines;
  out.error_bound = refiner.bound_factor() * grid.error_bound;
  return out;
}

}  // namespace

std::array<float, 3> BodyColour(int body) {
  // Distinct, mid-saturation colours that stay readable under shading on a light background.
  static constexpr std::array<std::array<float, 3>, 6> kPalette{{{0.16f, 0.45f, 0.80f},
                                                                 {0.85f, 0.33f, 0.10f},
                                                                 {0.20f, 0.63f, 0.17f},
                                                                 {0.58f, 0.40f, 0.74f},
                                                                 {0.55f, 0.34f, 0.29f},
                                                                 {0.09f, 0.75f, 0.81f}}};
  return kPalette[static_cast<size_t>(body) % kPalette.size()];
}

double DefaultDisplayTolerance(const server::Scene& scene) {
  Eigen::AlignedBox3d box;
  for (const server::SceneSurface& s : scene.surfaces) {
    const optimizer::Vector7d& pose = scene.mechanism.body(s.body).pose;
    const Eigen::Quaterniond q(pose[3], pose[4], pose[5], pose[6]);
    const Eigen::Matrix3d R_WB = q.normalized().toRotationMatrix();
    for (const Eigen::Vector4d& h : s.surface.weighted_points()) {
      box.extend(pose.head<3>() + R_WB * (h.head<3>() / h[3]));
    }
  }
  const double size = box.isEmpty() ? 1.0 : box.diagonal().norm();
  return size > 0.0 ? size / 2000.0 : 1e-3;
}

std::vector<DisplayMesh> BuildDisplayMeshes(const server::Scene& scene, double tolerance,
                                            double trim_cell, int max_lines) {
  if (!(tolerance > 0.0)) {
    throw std::invalid_argument("display tolerance must be positive, got " +
                                std::to_string(tolerance));
  }
  std::vector<DisplayMesh> meshes;
  int index = 0;
  for (const server::SceneSurface& s : scene.surfaces) {
    // A flat plate is one cell at any tolerance: a hole in it needs cells of its own scale.
    const double cell = trim_cell > 0.0 ? trim_cell : 10.0 * tolerance;
    nurbs::TriangleMesh t = nurbs::Tessellate(s.surface, tolerance, max_lines, s.trim ? cell : 0.0);
    if (s.trim) t = CutWithRim(t, s.surface, *s.trim, kRimDepth);
    DisplayMesh m;
    m.surface = s.name;
    m.surface_index = index++;
    m.body = s.body;
    m.colour = BodyColour(s.body);
    m.error_bound = t.error_bound;
    Compact(t, s.surface, &m);
    m.hash = HashOf(m);
    meshes.push_back(std::move(m));
  }
  return meshes;
}

nlohmann::json MeshMessage(const DisplayMesh& m) {
  return {{"type", "mesh"},       {"hash", m.hash},           {"surface", m.surface},
          {"body", m.body},       {"positions", m.positions}, {"normals", m.normals},
          {"indices", m.indices}, {"colour", m.colour},       {"error_bound", m.error_bound}};
}

}  // namespace tangent::view
