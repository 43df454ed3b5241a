// The global stage's blocks of an offset mesh (offset_chunks.h).

#include "contact/offset_chunks.h"

#include <algorithm>
#include <map>
#include <utility>

namespace tangent::contact {

fcl::CollisionObjectd* Chunk::Object() const {
  if (!object_) {
    auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    model->beginModel();
    model->addSubModel(points_, tris_);
    model->endModel();
    object_ = std::make_unique<fcl::CollisionObjectd>(model);
    std::vector<fcl::Vector3d>().swap(points_);  // the model holds its own copies
    std::vector<fcl::Triangle>().swap(tris_);
  }
  return object_.get();
}

std::vector<Chunk> BuildChunks(const nurbs::OffsetMesh& mesh, int u_cells, int v_cells) {
  const int nt = static_cast<int>(mesh.base.triangles.size());
  const int nvc = std::max(1, static_cast<int>(mesh.base.v_lines.size()) - 1);
  const int bv = std::min(nvc, std::max(1, v_cells));
  const int bu = std::max(1, u_cells);
  std::map<std::pair<int, int>, std::vector<int>> blocks;
  for (int t = 0; t < nt; ++t) {
    const int cell = mesh.base.CellOf(t);
    blocks[{(cell / nvc) / bu, (cell % nvc) / bv}].push_back(t);
  }
  std::vector<Chunk> chunks;
  chunks.reserve(blocks.size());
  std::vector<int> local(mesh.vertices.size(), -1);  // mesh vertex -> chunk vertex, per chunk
  for (auto& [block, triangles] : blocks) {
    Chunk c;
    c.triangles = std::move(triangles);
    c.uv_lo = Eigen::Vector2d::Constant(1e300);
    c.uv_hi = Eigen::Vector2d::Constant(-1e300);
    std::vector<int> used;
    for (int t : c.triangles) {
      size_t idx[3];
      for (int k = 0; k < 3; ++k) {
        const int v = mesh.base.triangles[static_cast<size_t>(t)][static_cast<size_t>(k)];
        int& l = local[static_cast<size_t>(v)];
        if (l < 0) {
          l = static_cast<int>(c.points_.size());
          c.points_.push_back(mesh.vertices[static_cast<size_t>(v)]);
          used.push_back(v);
        }
        idx[k] = static_cast<size_t>(l);
        c.uv_lo = c.uv_lo.cwiseMin(mesh.base.uv[static_cast<size_t>(v)]);
        c.uv_hi = c.uv_hi.cwiseMax(mesh.base.uv[static_cast<size_t>(v)]);
      }
      c.tris_.emplace_back(idx[0], idx[1], idx[2]);
    }
    for (int v : used) local[static_cast<size_t>(v)] = -1;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (const fcl::Vector3d& x : c.points_) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
    c.centre = 0.5 * (lo + hi);
    c.half = 0.5 * (hi - lo);
    chunks.push_back(std::move(c));
  }
  return chunks;
}

}  // namespace tangent::contact
