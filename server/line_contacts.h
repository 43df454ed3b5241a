#pragma once

// Line contacts in the servo (docs/contact.md, "Line contacts"): where a declared pair's tracked
// contact is nearly conformal along one direction (its relative curvature's smaller eigenvalue
// small against the larger), the pair is also held by two sections across that direction, one
// either side of the contact (optimizer::SectionContactTerm), so that it stays held when the
// contact's own extremum turns into a saddle with a minimum either side (a pitchfork). The
// sections are placed with hysteresis and moved when the contact slides past the middle half
// between them; a crossing contact costs nothing beyond one relative-curvature evaluation per
// tick. Allocation free after construction.

#include <vector>

#include "contact/extremal.h"
#include "optimizer/problem.h"
#include "optimizer/sections.h"
#include "optimizer/solver.h"

namespace tangent::server {

struct LineContactOptions {
  /// Sections placed when λ_min < enter · λ_max (λ the relative curvature's eigenvalues,
  /// contact::RelativeCurvatureOf; λ_min < 0 past the pitchfork), taken away when
  /// λ_min > leave · λ_max on every contact of the pair.
  double enter = 0.1;
  double leave = 0.25;
};

class LineContacts {
 public:
  explicit LineContacts(const LineContactOptions& options = {}) : options_(options) {}

  /// Reserves a pair's two section rows in *p (f on body_f, g on body_g, untrimmed); returns the
  /// pair's index here. A pair with sections keeps them while it has no tracked contact (the
  /// global stage re-seeding it), until both are farther apart than their half spacing. The
  /// surfaces must outlive this.
  int AddPair(optimizer::Problem* p, int body_f, const nurbs::NurbsSurface* f, int body_g,
              const nurbs::NurbsSurface* g);
  /// Takes the sections' data in the solver (after it is made); all inactive.
  void Bind(optimizer::Solver* solver);

  /// After a good tick: pair k's contacts, each an active slot's extremum and its evaluation
  /// (the pair order (f, g) of AddPair), and whether any is in use. Places, moves or takes away
  /// the pair's sections.
  void BeginPair(int k);
  void Consider(int k, const contact::SurfaceSurfaceExtremum& ext,
                const contact::SurfacePairEval& e);
  void EndPair(int k);
  /// Takes every section away (a fault restored the last good state).
  void Clear();

  int pairs() const { return static_cast<int>(pairs_.size()); }
  bool line(int k) const { return pairs_[static_cast<size_t>(k)].line; }
  const optimizer::SectionContactTerm::State& section(int k, int side) const {
    return *pairs_[static_cast<size_t>(k)].state[side];
  }
  int64_t placements() const { return placements_; }

 private:
  struct Pair {
    std::shared_ptr<optimizer::SectionContactTerm> term[2];
    optimizer::SectionContactTerm::State* state[2] = {nullptr, nullptr};
    bool line = false;
    // This tick's most line-like contact: its curvature ratio and where it lies.
    double ratio = 1e300;
    bool seen = false, want = false;
    Eigen::Vector4d u = Eigen::Vector4d::Zero();
    Eigen::Vector4d step = Eigen::Vector4d::Zero();  ///< parameters per metre along the line
    double h = 0.0;                                  ///< half the sections' spacing, m
    int fixed = 0;                                   ///< f's parameter the sections hold
  };
  void Place(Pair* p);

  LineContactOptions options_;
  std::vector<Pair> pairs_;
  int64_t placements_ = 0;
};

}  // namespace tangent::server
