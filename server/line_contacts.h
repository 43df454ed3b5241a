#pragma once

// Line contacts in the servo (docs/contact.md, "Line contacts"). Where a declared pair's tracked
// contact is nearly conformal along one direction (its relative curvature's smaller eigenvalue
// small against the larger), its extremal point is nearly degenerate: its place along the line
// is ill-conditioned, its exact Hessian grows like the inverse of that eigenvalue, and past a
// pitchfork it is a saddle with a minimum either side. Its distance is well conditioned all the
// same. So while the contact is line-like the pair is held instead by three sections across the
// line (optimizer::SectionContactTerm): one through the contact, one either side. Each is a
// regular curve–surface extremum, each an exact constraint (its points are the surface's), and a
// section off the line's true minimum by δ along it reads the distance high by only ½ λ_min δ².
// After each good tick the sections follow the line (the three move by half their spacing
// toward a side that is nearer), and the point contact comes back, at the middle section, when
// the relative curvature there passes `leave`. Allocation free after construction.

#include <memory>
#include <vector>

#include "contact/extremal.h"
#include "optimizer/problem.h"
#include "optimizer/sections.h"
#include "optimizer/solver.h"

namespace tangent::server {

struct LineContactOptions {
  /// Line mode entered when λ_min < enter · λ_max at a tracked contact (λ the relative
  /// curvature's eigenvalues, contact::RelativeCurvatureOf; λ_min < 0 past the pitchfork), left
  /// when λ_min > leave · λ_max at the middle section.
  double enter = 0.1;
  double leave = 0.25;
  /// The most the gap may dip below two neighbouring sections that both read it (m). Along the
  /// line the gap is β + ½ λ_min δ² about its minimum, so with the minimum midway between
  /// sections a spacing h reads it high by ½ λ_min (h/2)²: the spacing is kept within
  /// 2 √(2 dip / λ_min) (LineSpacing). At entry λ_min is still a tenth of λ_max, and the tight
  /// direction's 1/λ_max alone let the wires through each other by 1.5e-6 m between sections that
  /// all read 0 (chain_soak --lines at 206.298 s: docs/reliability.md, "Soak").
  double dip = 1e-7;
};

/// The spacing (m) of a line's sections for relative curvature eigenvalues λ_min ≤ λ_max (> 0):
/// the tight direction's length scale 1/λ_max, and where λ_min > 0 within 2 √(2 dip / λ_min), so
/// the gap dips at most `dip` below two neighbours. +inf without a positive λ_max.
double LineSpacing(double lambda_min, double lambda_max, double dip);

/// Where a line's gap may dip below its sections: the lowest point of the parabola through three
/// equally spaced sections' distances `below`, `middle` and `above` (at −1, 0 and 1 spacings),
/// in spacings from the middle, when it lies strictly between the outer two and below the least
/// of the three; else false. Along the line the gap is d(δ) = β + ½ λ_min δ² + O(δ³) about its
/// minimum (docs/contact.md, "Line contacts"), so where the sections straddle a minimum the
/// parabola finds it to second order in the spacing.
bool SectionDip(double below, double middle, double above, double* at);

class LineContacts {
 public:
  static constexpr int kSections = 3;  ///< middle, then one either side
  /// Section i's place along the line, in spacings from the middle.
  static constexpr double kOffset[kSections] = {0.0, -1.0, 1.0};

  explicit LineContacts(const LineContactOptions& options = {}) : options_(options) {}

  /// Reserves a pair's section rows in *p (f on body_f, g on body_g, untrimmed); returns the
  /// pair's index here. The surfaces must outlive this.
  int AddPair(optimizer::Problem* p, int body_f, const nurbs::NurbsSurface* f, int body_g,
              const nurbs::NurbsSurface* g);
  /// Whether pair k entered line mode at the last Enter and has not followed since: its point
  /// contacts are still held beside the sections for one solve (the load handed over).
  bool entering(int k) const { return pairs_[static_cast<size_t>(k)].entering; }
  /// Takes the sections' data in the solver (after it is made); all inactive.
  void Bind(optimizer::Solver* solver);

  /// A tracked contact of pair k (not in line mode) at extremum `ext`, evaluation `e` (the pair
  /// order of AddPair): true when it is line-like, and then the pair is in line mode with its
  /// sections placed across the contact (the caller retires the contact's row).
  bool Enter(int k, const contact::SurfaceSurfaceExtremum& ext, const contact::SurfacePairEval& e);
  /// After a good tick in line mode: the sections follow the line. kLeave: the contact is no
  /// longer line-like; *u (pair order) is where the point contact resumes. kRelease: every
  /// section is apart by more than the spacing. Either way the pair has left line mode.
  enum class Next { kStay, kLeave, kRelease };
  Next Follow(int k, const std::vector<contact::BodyPose>& poses, Eigen::Vector4d* u);
  /// Whether a contact of pair k at u (pair order) lies within its line's sections (a global
  /// stage event for it is the line's own).
  bool Covers(int k, const Eigen::Vector4d& u) const;
  /// Leaves line mode (a fault restored the last good state); *u where the point resumes.
  void Leave(int k, Eigen::Vector4d* u);

  int pairs() const { return static_cast<int>(pairs_.size()); }
  bool line(int k) const { return pairs_[static_cast<size_t>(k)].line; }
  const optimizer::SectionContactTerm::State& section(int k, int i) const {
    return *pairs_[static_cast<size_t>(k)].state[i];
  }
  /// Pair k's bodies (mechanism indices; -1 for the world), f's then g's.
  int body_f(int k) const { return pairs_[static_cast<size_t>(k)].term[0]->body_a(); }
  int body_g(int k) const { return pairs_[static_cast<size_t>(k)].term[0]->body_b(); }
  /// Section i's inequality row (its multiplier's index).
  int row(int k, int i) const { return pairs_[static_cast<size_t>(k)].row[i]; }
  /// The middle section's parameters in the pair order.
  Eigen::Vector4d MiddleU(int k) const;
  int64_t placements() const { return placements_; }
  int64_t moves() const { return moves_; }
  /// How many times a line's sections were brought closer about its middle
  /// (LineContactOptions::dip; Follow).
  int64_t respaced() const { return respaced_; }

 private:
  struct Pair {
    std::shared_ptr<optimizer::SectionContactTerm> term[kSections];
    optimizer::SectionContactTerm::State* state[kSections] = {};
    int row[kSections] = {};  ///< inequality rows (multiplier indices)
    bool line = false;
    bool entering = false;  ///< entered, not yet followed (entering())
    int fixed = 0;          ///< f's parameter the sections hold
    double spacing = 0.0;   ///< between neighbours, in that parameter
    double h = 0.0;         ///< the same in metres
    double h_free = 0.0;    ///< h before fitting within the surfaces' domains (Fit)
    Eigen::Vector4d per_metre = Eigen::Vector4d::Zero();  ///< parameters per metre along the line
    Eigen::Vector4d step = Eigen::Vector4d::Zero();       ///< parameters per unit of the held one
    /// A section measured, not held, where the gap dips between the three (SectionDip): how far
    /// below them the gap reaches is the margin they hold (SectionContactTerm::State::margin).
    std::unique_ptr<optimizer::TermState> probe_data;
    optimizer::SectionContactTerm::State* probe = nullptr;
  };
  void Place(Pair* p, const Eigen::Vector4d& middle);
  /// Sets p's spacing for sections centred at `middle`: h_free, within both surfaces' domains.
  /// false when there is no room either side.
  bool Fit(Pair* p, const Eigen::Vector4d& middle) const;
  double Wrap(const Pair& p, double d) const;
  /// The margin pair p's sections hold after a good tick at `poses` (beta: their distances;
  /// middle: the middle section's parameters, pair order): how far the gap reaches below the
  /// least of them where it dips between them (0 where it does not, or the probe there fails).
  double Margin(Pair* p, const std::vector<contact::BodyPose>& poses, const double* beta,
                const Eigen::Vector4d& middle) const;

  LineContactOptions options_;
  std::vector<Pair> pairs_;
  int64_t placements_ = 0, moves_ = 0, respaced_ = 0;
};

}  // namespace tangent::server
