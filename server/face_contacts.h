#pragma once

// Face contacts in the servo (docs/contact.md, "Face contacts"). A declared pair of two
// untrimmed flat faces (nurbs/flat.h: a box's face on a plane) has no extremal point that holds
// it: parallel, its extremal pair is a continuum; tilted, it is a corner of one face. The height
// of one face above the other's plane is affine along it, so the pair is held exactly by the
// corners of each face that lie over the other (optimizer::CornerContactTerm), except where
// their edges cross (a face overhanging the other's edge), which is not measured. The rows are
// reserved when the scene loads and evaluate nothing until the global stage finds the pair
// (contact/face_gap.h, GlobalContactStage::FindFaces); the pair is released when the stage
// reports it apart or no corner lies over the other face. Allocation free after construction.

#include <vector>

#include "nurbs/flat.h"
#include "optimizer/corners.h"
#include "optimizer/problem.h"
#include "optimizer/solver.h"

namespace tangent::server {

class FaceContacts {
 public:
  static constexpr int kCorners = 8;  ///< f's four against g, then g's four against f

  /// Reserves the corner rows of the pair of flat faces f (scene surface `surface_f`, on body_f,
  /// corners qf) and g in *p; returns the pair's index here. The surfaces must outlive this.
  int AddPair(optimizer::Problem* p, int surface_f, int body_f, const nurbs::NurbsSurface* f,
              const nurbs::FlatQuad& qf, int surface_g, int body_g, const nurbs::NurbsSurface* g,
              const nurbs::FlatQuad& qg);
  /// Takes the rows' data in the solver (after it is made); all unused.
  void Bind(optimizer::Solver* solver);

  /// The pair of scene surfaces (a, b) in either order, or −1.
  int Find(int surface_a, int surface_b) const;
  /// Holds pair k by its corners (the global stage found it); no change when held.
  void Hold(int k);
  /// Releases pair k (apart): its rows read inactive and evaluate nothing.
  void Release(int k);
  /// After a good tick: a held pair none of whose corners lies over the other face is released.
  void Follow();

  int pairs() const { return static_cast<int>(pairs_.size()); }
  bool held(int k) const { return pairs_[static_cast<size_t>(k)].held; }
  int surface_f(int k) const { return pairs_[static_cast<size_t>(k)].surface_f; }
  int surface_g(int k) const { return pairs_[static_cast<size_t>(k)].surface_g; }
  const optimizer::CornerContactTerm::State& corner(int k, int i) const {
    return *pairs_[static_cast<size_t>(k)].state[i];
  }
  /// Corner i's inequality row (its multiplier's index).
  int row(int k, int i) const { return pairs_[static_cast<size_t>(k)].row[i]; }
  /// The corner of held pair k lying over the other face nearest to it, or −1.
  int Lowest(int k) const;
  /// Corner i of pair k as a contact in the pair's order: parameters (f's, then g's) and the
  /// points on f and on g (world). It must lie over the other face (state.over()).
  void Contact(int k, int i, Eigen::Vector4d* u, Eigen::Vector3d* p_f, Eigen::Vector3d* p_g) const;

 private:
  struct Pair {
    int surface_f = -1, surface_g = -1;
    std::shared_ptr<optimizer::CornerContactTerm> term[kCorners];
    optimizer::CornerContactTerm::State* state[kCorners] = {};
    int row[kCorners] = {};
    Eigen::Vector2d corner_u[kCorners];  ///< the corner's parameters on its own face
    Eigen::Vector2d seed[kCorners];      ///< the middle of the other face's domain
    bool held = false;
  };
  std::vector<Pair> pairs_;
};

}  // namespace tangent::server
