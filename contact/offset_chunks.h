#pragma once

// The global stage's blocks of an offset mesh (contact/global.h, docs/contact.md "FCL"): grid
// cells grouped into chunks, each with its box and, built the first time the narrow phase needs
// it, its own OBBRSS tree. Internal to tangent_contact (it includes FCL).
//
// A part of hundreds of faces has hundreds of thousands of chunks, and the global stage
// collides only those whose boxes overlap another surface's: building every tree at load took
// 2.5 s and 800 MB for a 375-face part (1.4 million triangles) whose ball touched none.

#include <fcl/fcl.h>

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "nurbs/offset.h"

namespace tangent::contact {

class Chunk {
 public:
  std::vector<int> triangles;    ///< chunk triangle k is surface triangle triangles[k]
  Eigen::Vector2d uv_lo, uv_hi;  ///< parameter box of its vertices
  Eigen::Vector3d centre, half;  ///< box of its offset vertices, surface frame

  /// Its collision object: an OBBRSS tree over its triangles in the surface frame, built on the
  /// first call (not thread-safe: the global stage's own thread asks).
  fcl::CollisionObjectd* Object() const;
  bool built() const { return object_ != nullptr; }

 private:
  friend std::vector<Chunk> BuildChunks(const nurbs::OffsetMesh&, int, int);
  mutable std::vector<fcl::Vector3d> points_;  // until the tree is built
  mutable std::vector<fcl::Triangle> tris_;
  mutable std::unique_ptr<fcl::CollisionObjectd> object_;
};

/// The chunks of an offset mesh: blocks of `v_cells` grid cells across v and `u_cells` along u.
std::vector<Chunk> BuildChunks(const nurbs::OffsetMesh& mesh, int u_cells, int v_cells);

}  // namespace tangent::contact
