#pragma once

// Trimmed surfaces (docs/trimming.md): the material of a CAD face is the part of its surface's
// parameter domain inside an outer loop and outside its holes, each loop a closed chain of 2-D
// NURBS curves (lines and polylines as degree-1 curves).
//
// Exact near the boundary. Each curve is cut into Bézier pieces and those subdivided until every
// piece's control polygon lies within a band β of its chord; a rational piece with positive
// weights lies in the convex hull of its control points, and the β-neighbourhood of a segment is
// convex, so the curve lies within β of the polygon made of the chords (certified). A point
// farther than its nearest chord's β from every chord is classified by that polygon with exact
// predicates (CGAL's Epick kernel: the answer is the exact answer for the polygon's double
// vertices); a point within the band is classified by the curve itself: its closest point on the
// loops (Newton on the exact curve from the chord's estimate) and the side of the loop it lies on.
//
// Conventions: the outer loop runs counter-clockwise and holes clockwise, so the material is on
// the left of every loop's direction (a loop given the other way round is reversed, with a
// warning). Without an outer loop the material is the whole domain less the holes.

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "nurbs/curve.h"
#include "nurbs/tessellation.h"

namespace tangent::nurbs {

/// A trimming loop that cannot be used, named: "hole 1: curve 2 ends at (0.5, 0.25) but curve 3
/// starts at (0.5, 0.3): a gap of 0.05 (tolerance 1.4e-09)".
class TrimError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TrimLoop {
  std::vector<NurbsCurve2d> curves;  ///< in order, each starting where the previous ends
};

struct TrimOptions {
  /// Largest gap between one curve's end and the next one's start (and around the loop),
  /// relative to the domain's diagonal.
  double closure_tolerance = 1e-9;
  /// β, the certified band of the polygonization, relative to the domain's diagonal: the curves
  /// lie within β of their chords (pieces are subdivided until they do, and further where two
  /// loops' or a loop's own bands would overlap).
  double band = 1e-4;
};

class TrimmedDomain {
 public:
  /// One chord of the certified polygonization: the piece of curve `curve` of loop `loop`
  /// between parameters t0 and t1 lies within `band` of the segment from a to b.
  struct Chord {
    Eigen::Vector2d a, b;
    int loop = 0, curve = 0;
    double t0 = 0.0, t1 = 0.0;
    double band = 0.0;
  };
  /// The closest point of the loops to a parameter point.
  struct Closest {
    double signed_distance = 0.0;  ///< > 0 on the material, < 0 off it (parametric units)
    int loop = -1, curve = -1;     ///< loop index (0: the outer loop when there is one)
    double t = 0.0;                ///< the curve's parameter there
    Eigen::Vector2d point = Eigen::Vector2d::Zero();
  };

  /// Validates the loops in the domain [lo, hi] of a surface: every loop closed, inside the
  /// domain, not crossing or touching itself or another loop, holes inside the outer loop and
  /// not inside one another; a loop running the wrong way is reversed and *warnings (may be
  /// null) says so. @throws TrimError naming the loop and curve.
  TrimmedDomain(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, std::optional<TrimLoop> outer,
                std::vector<TrimLoop> holes, const TrimOptions& options = {},
                std::vector<std::string>* warnings = nullptr);

  /// Whether (u, v) is on the material (the boundary itself counts as material). Allocation
  /// free, as is Nearest (TrimmedContactTerm calls both inside a solve) — save where CGAL's
  /// filtered predicate falls back to exact arithmetic on a point within rounding of a chord.
  bool Contains(const Eigen::Vector2d& uv) const { return Contains(uv, nullptr); }
  /// Same; when the answer needed the closest loop point (uv within a chord's band), it is left
  /// in *nearest (may be null), else nearest->loop is −1. *clearance (may be null): how far uv
  /// may move (parameter units, Euclidean) with the same answer — farther than every chord's
  /// band and inside the domain, the polygon's verdict cannot change; 0 when uv is within a band.
  /// *excluded_by (may be null): off the material beyond every band, the loop whose polygon
  /// excludes uv (inside a hole, or outside the outer loop), else −1. That loop is then the
  /// nearest one: every path from uv to another loop crosses it.
  bool Contains(const Eigen::Vector2d& uv, Closest* nearest, double* clearance = nullptr,
                int* excluded_by = nullptr) const;
  /// The closest point of the loops to (u, v) and the signed distance to it.
  Closest Nearest(const Eigen::Vector2d& uv) const;
  /// Whether the parameter rectangle [lo, hi] may hold material: false only when it certainly
  /// holds none (no chord's band reaches it, so no loop crosses it, and its centre is off the
  /// material). Cells this rejects can be cut from meshes without losing any material.
  bool MayHoldMaterial(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const;

  bool has_outer() const { return has_outer_; }
  /// Loops in order: the outer loop first when there is one, then the holes.
  const std::vector<TrimLoop>& loops() const { return loops_; }
  const std::vector<Chord>& chords() const { return chords_; }
  const Eigen::Vector2d& lo() const { return lo_; }
  const Eigen::Vector2d& hi() const { return hi_; }
  /// A loop's name in messages: "outer loop" or "hole k".
  std::string LoopName(int loop) const;

 private:
  /// Where uv lies against loop `loop`'s polygon of chords, exactly: CGAL's Bounded_side
  /// (inside, on the boundary or outside) as an int. Allocation free.
  int Side(int loop, const Eigen::Vector2d& uv) const;
  /// The polygon's verdict for a point farther than every chord's band from it.
  /// *excluded_by (may be null): the loop that excludes uv when the answer is false.
  bool PolygonContains(const Eigen::Vector2d& uv, int* excluded_by = nullptr) const;
  /// Newton on curve (loop, curve) for the point closest to uv, from parameter t.
  Closest RefineOn(int loop, int curve, double t, const Eigen::Vector2d& uv) const;
  /// Whether uv lies on the material side of the loop at its closest point c.
  bool OnMaterialSide(const Closest& c, const Eigen::Vector2d& uv) const;

  Eigen::Vector2d lo_, hi_;
  bool has_outer_ = false;
  std::vector<TrimLoop> loops_;
  std::vector<Chord> chords_;
  std::vector<std::vector<int>> loop_chords_;  ///< per loop, its chords in order
  /// Per loop, the box of its chords' ends and their largest band: a point outside the box is
  /// outside the loop's polygon, and one outside it grown by the band is outside every band.
  struct LoopBox {
    Eigen::Vector2d lo, hi;
    double band = 0.0;
    /// The loop's polygon is its box, traversed once (every chord on one of its sides, their
    /// lengths its perimeter): a CAD face's loop round its whole domain. Side and the band test
    /// are then four comparisons, not a pass over the chords.
    bool rectangle = false;
    bool Holds(const Eigen::Vector2d& x, double grow) const {
      return (x.array() >= lo.array() - grow).all() && (x.array() <= hi.array() + grow).all();
    }
  };
  std::vector<LoopBox> loop_box_;
};

/// A tessellation cut along a trim: the grid cells that certainly hold no material
/// (TrimmedDomain::MayHoldMaterial) dropped, cells the trim crosses kept whole, so every point of
/// the material is still within the mesh's certified bound of one of its triangles. The vertices
/// stay (indices unchanged); `cells` holds the kept triangles' grid cells.
TriangleMesh CutAlongTrim(const TriangleMesh& mesh, const TrimmedDomain& trim);

}  // namespace tangent::nurbs
