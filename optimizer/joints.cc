#include "optimizer/joints.h"

#include <cmath>
#include <stdexcept>

#include "contact/rigid.h"

namespace tangent::optimizer {

namespace {

using Matrix37 = Eigen::Matrix<double, 3, 7>;

// World point of an attachment and ∂/∂q_B.
Eigen::Vector3d Point(const std::vector<BodyPose>& poses, const Attachment& at, Matrix37* J) {
  const BodyPose& p = PoseOf(poses, at.body);
  *J = contact::PointJacobian(p, at.point);
  return p.Point(at.point);
}

// World image of a body-fixed direction and ∂/∂q_B.
Eigen::Vector3d Direction(const std::vector<BodyPose>& poses, int body, const Eigen::Vector3d& v,
                          Matrix37* J) {
  const BodyPose& p = PoseOf(poses, body);
  *J = contact::DirectionJacobian(p, v);
  return p.R_WB * v;
}

// Two unit vectors perpendicular to a (and to each other).
void Perpendiculars(const Eigen::Vector3d& a, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  const Eigen::Vector3d n = a.normalized();
  *e1 = (std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY())
            .cross(n)
            .normalized();
  *e2 = n.cross(*e1);
}

Attachment Normalized(Attachment at, const char* joint) {
  if (!(at.axis.norm() > 0) || !(at.reference.norm() > 0)) {
    throw std::invalid_argument(std::string(joint) +
                                ": attachment axis and reference must be non-zero");
  }
  at.axis.normalize();
  at.reference = (at.reference - at.axis * at.axis.dot(at.reference));
  if (!(at.reference.norm() > 1e-9)) {
    throw std::invalid_argument(std::string(joint) +
                                ": attachment reference is parallel to its axis");
  }
  at.reference.normalize();
  return at;
}

// cos of the angle between the two axes, (R_a axis_a)·(R_b axis_b).
double AxisCosine(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b) {
  return (PoseOf(poses, a.body).R_WB * a.axis).dot(PoseOf(poses, b.body).R_WB * b.axis);
}

// cos φ of the turn about the axis, (R_a ref_a)·(R_b ref_b).
double ReferenceCosine(const std::vector<BodyPose>& poses, const Attachment& a,
                       const Attachment& b) {
  return (PoseOf(poses, a.body).R_WB * a.reference).dot(PoseOf(poses, b.body).R_WB * b.reference);
}

// "Axes parallel" with the sense kept. The two rows v = (A·B1, A·B2) (A a's axis, B1, B2 two
// directions perpendicular to b's axis B) are sin θ times a unit vector, θ the angle between A
// and B, and vanish for A = −B too: a joint mounted reversed would be a solution. No two
// smooth functions on the sphere vanish at one point only, so the rows are mapped in the far
// hemisphere (A·B < 0): r = v (2/|v| − 1), whose size 2 − sin θ grows on to 2 at the flip.
// The map is the identity for A·B ≥ 0 (the joint near its solution is untouched) and C¹ at
// θ = π/2, where |v| = 1. At the exact flip (|v| = 0) r = (2, 0), the one-sided limit along B1.
struct SameSenseMap {
  Eigen::Vector2d value;
  Eigen::Matrix2d T = Eigen::Matrix2d::Identity();  // ∂r/∂v
  bool far = false;
  Eigen::Vector2d v;
  double n = 0.0;
  SameSenseMap(const Eigen::Vector2d& v_in, double cosine) : value(v_in), v(v_in) {
    if (cosine >= 0.0) return;
    far = true;
    n = v.norm();
    if (n < 1e-300) {
      value = Eigen::Vector2d(2.0, 0.0);
      T = -Eigen::Matrix2d::Identity();
      return;
    }
    value = v * (2.0 / n - 1.0);
    T = (2.0 / n - 1.0) * Eigen::Matrix2d::Identity() - (2.0 / (n * n * n)) * v * v.transpose();
  }
  // Σ_i w_i ∂²r_i/∂v∂v = −2 (w vᵀ + v wᵀ + (w·v) I)/n³ + 6 (w·v) v vᵀ/n⁵.
  Eigen::Matrix2d Curvature(const Eigen::Vector2d& w) const {
    if (!far || n < 1e-300) return Eigen::Matrix2d::Zero();
    const double n3 = n * n * n, wv = w.dot(v);
    return -2.0 * (w * v.transpose() + v * w.transpose() + wv * Eigen::Matrix2d::Identity()) / n3 +
           6.0 * wv * v * v.transpose() / (n3 * n * n);
  }
};

// The rows a joint is built from. Each appends to r at `row` and to the Jacobian blocks.
struct Rows {
  Eigen::Ref<Eigen::VectorXd> r;
  Eigen::Ref<Eigen::MatrixXd> Ja, Jb;
  int row = 0;

  // P_a − P_b (3 rows).
  void Coincide(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b) {
    Matrix37 ja, jb;
    r.segment<3>(row) = Point(poses, a, &ja) - Point(poses, b, &jb);
    // (Fixed-size blocks of the Refs throughout: a product assigned to a dynamic Ref row takes
    // Eigen's generic path, ~2,000 instructions for a 1 x 7 row; callgrind, issue 35.)
    Ja.block<3, 7>(row, 0) = ja;
    Jb.block<3, 7>(row, 0) = -jb;
    row += 3;
  }
  // (R_a u)·(R_b v) (1 row).
  void Dot(const std::vector<BodyPose>& poses, int ba, const Eigen::Vector3d& u, int bb,
           const Eigen::Vector3d& v) {
    const BodyPose& pa = PoseOf(poses, ba);
    const BodyPose& pb = PoseOf(poses, bb);
    const Eigen::Vector3d U = pa.R_WB * u, V = pb.R_WB * v;
    r[row] = U.dot(V);
    // ∂(U·V)/∂q_a = Vᵀ ∂U/∂q_a: rotational only (contact::DirectionGradient), and likewise for b.
    Ja.block<1, 3>(row, 0).setZero();
    Ja.block<1, 4>(row, 3) = contact::DirectionGradient(pa, U, V);
    Jb.block<1, 3>(row, 0).setZero();
    Jb.block<1, 4>(row, 3) = contact::DirectionGradient(pb, V, U);
    ++row;
  }
  // a's axis against b's two perpendiculars (2 rows), same sense only (SameSenseMap).
  void ParallelAxes(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b,
                    const Eigen::Vector3d& b1, const Eigen::Vector3d& b2) {
    const int r0 = row;
    Dot(poses, a.body, a.axis, b.body, b1);
    Dot(poses, a.body, a.axis, b.body, b2);
    const SameSenseMap m(r.segment<2>(r0), AxisCosine(poses, a, b));
    r.segment<2>(r0) = m.value;
    const Eigen::Matrix<double, 2, 7> ja = Ja.block<2, 7>(r0, 0), jb = Jb.block<2, 7>(r0, 0);
    Ja.block<2, 7>(r0, 0).noalias() = m.T * ja;
    Jb.block<2, 7>(r0, 0).noalias() = m.T * jb;
  }
  // No turn about the axis (1 row): s = (R_a ref_a)·(R_b (axis_b × ref_b)) = sin φ, same sense
  // only: for cos φ = ref_a·ref_b < 0 the row is 2 sgn(s) − s (a half turn is not a solution).
  void NoTurn(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b) {
    const int r0 = row;
    Dot(poses, a.body, a.reference, b.body, b.axis.cross(b.reference));
    if (ReferenceCosine(poses, a, b) >= 0.0) return;
    r[r0] = (r[r0] >= 0.0 ? 2.0 : -2.0) - r[r0];
    Ja.block<1, 7>(r0, 0) *= -1.0;
    Jb.block<1, 7>(r0, 0) *= -1.0;
  }
  // (P_b − P_a)·(R_a e) (1 row): b's point in a's plane through P_a normal to e.
  void Offset(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b,
              const Eigen::Vector3d& e) {
    Matrix37 jpa, jpb, je;
    const Eigen::Vector3d d = Point(poses, b, &jpb) - Point(poses, a, &jpa);
    const Eigen::Vector3d E = Direction(poses, a.body, e, &je);
    r[row] = d.dot(E);
    Ja.block<1, 7>(row, 0).noalias() = -E.transpose() * jpa + d.transpose() * je;
    Jb.block<1, 7>(row, 0).noalias() = E.transpose() * jpb;
    ++row;
  }
};

// The same rows' weighted second derivatives (weights w, one per row, consumed in order). Curvature
// of rotated vectors goes to the rotation weights (TermHessian); only cross-body and
// position–rotation products are written as blocks.
struct HessianRows {
  const Eigen::Ref<const Eigen::VectorXd>& w;
  TermHessian* h;
  int row = 0;

  // Σ w_k (P_a − P_b)_k: only the rotations curve.
  void Coincide(const std::vector<BodyPose>&, const Attachment& a, const Attachment& b) {
    const Eigen::Vector3d y = w.segment<3>(row);
    h->W_a.noalias() += y * a.point.transpose();
    h->W_b.noalias() -= y * b.point.transpose();
    row += 3;
  }
  // w (R_a u)·(R_b v).
  void Dot(const std::vector<BodyPose>& poses, int ba, const Eigen::Vector3d& u, int bb,
           const Eigen::Vector3d& v) {
    WeightedDot(w[row++], poses, ba, u, bb, v);
  }
  // Σ_i w_i ∇²r_i of SameSenseMap's rows: the dot rows' curvature with the weights Tᵀw, plus
  // the map's own second derivatives along the dot rows' gradients, Σ_jk M_jk ∇v_j ∇v_kᵀ.
  void ParallelAxes(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b,
                    const Eigen::Vector3d& b1, const Eigen::Vector3d& b2) {
    const Eigen::Vector2d wk = w.segment<2>(row);
    row += 2;
    Matrix37 ju, j1, j2;
    const Eigen::Vector3d U = Direction(poses, a.body, a.axis, &ju);
    const Eigen::Vector3d B1 = Direction(poses, b.body, b1, &j1);
    const Eigen::Vector3d B2 = Direction(poses, b.body, b2, &j2);
    const SameSenseMap m(Eigen::Vector2d(U.dot(B1), U.dot(B2)), AxisCosine(poses, a, b));
    const Eigen::Vector2d wt = m.T.transpose() * wk;
    WeightedDot(wt[0], poses, a.body, a.axis, b.body, b1);
    WeightedDot(wt[1], poses, a.body, a.axis, b.body, b2);
    if (!m.far) return;
    Eigen::Matrix<double, 2, 7> ga, gb;  // ∇v: rows (U·B1, U·B2) over q_a and q_b
    ga << B1.transpose() * ju, B2.transpose() * ju;
    gb << U.transpose() * j1, U.transpose() * j2;
    const Eigen::Matrix2d M = m.Curvature(wk);
    h->aa.noalias() += ga.transpose() * M * ga;
    h->ab.noalias() += ga.transpose() * M * gb;
    h->bb.noalias() += gb.transpose() * M * gb;
  }
  void NoTurn(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b) {
    const double wk = w[row++];
    const double sign = ReferenceCosine(poses, a, b) >= 0.0 ? 1.0 : -1.0;  // r = 2 sgn s − s
    WeightedDot(sign * wk, poses, a.body, a.reference, b.body, b.axis.cross(b.reference));
  }
  void WeightedDot(double wk, const std::vector<BodyPose>& poses, int ba, const Eigen::Vector3d& u,
                   int bb, const Eigen::Vector3d& v) {
    const BodyPose& pa = PoseOf(poses, ba);
    const BodyPose& pb = PoseOf(poses, bb);
    const Eigen::Vector3d U = pa.R_WB * u, V = pb.R_WB * v;
    h->W_a.noalias() += (wk * V) * u.transpose();
    h->W_b.noalias() += (wk * U) * v.transpose();
    // ∂U/∂Q_a = −[U]× Ω_a, ∂V/∂Q_b = −[V]× Ω_b, and [U]×ᵀ[V]× = (U·V) I − V Uᵀ:
    // Ω_aᵀ[U]×ᵀ[V]×Ω_b = (U·V) Ω_aᵀΩ_b − (Ω_aᵀV)(Ω_bᵀU)ᵀ.
    const Eigen::Vector4d x = pa.omega_map.transpose() * V, y = pb.omega_map.transpose() * U;
    h->ab.block<4, 4>(3, 3).noalias() +=
        (wk * U.dot(V)) * (pa.omega_map.transpose() * pb.omega_map) - (wk * x) * y.transpose();
  }
  // w (P_b − P_a)·E_a with E_a = R_a e.
  void Offset(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b,
              const Eigen::Vector3d& e) {
    const double wk = w[row++];
    const BodyPose& pa = PoseOf(poses, a.body);
    const BodyPose& pb = PoseOf(poses, b.body);
    const Eigen::Vector3d d = pb.Point(b.point) - pa.Point(a.point);
    const Eigen::Vector3d E = pa.R_WB * e;
    const Matrix37 JPa = contact::PointJacobian(pa, a.point);
    const Matrix37 JPb = contact::PointJacobian(pb, b.point);
    const Matrix37 JE = contact::DirectionJacobian(pa, e);
    h->aa.noalias() -= wk * (JE.transpose() * JPa + JPa.transpose() * JE);
    h->W_a.noalias() += (wk * d) * e.transpose() - (wk * E) * a.point.transpose();
    h->ab.noalias() += wk * JE.transpose() * JPb;
    h->W_b.noalias() += (wk * E) * b.point.transpose();
  }
};

enum class Kind { kSpherical, kRevolute, kUniversal, kCylindrical, kPrismatic, kFixed };

class Joint final : public Term {
 public:
  Joint(Kind kind, const char* name, const Attachment& a, const Attachment& b)
      : kind_(kind), name_(name), a_(Normalized(a, name)), b_(Normalized(b, name)) {
    Perpendiculars(b_.axis, &b1_, &b2_);
    Perpendiculars(a_.axis, &a1_, &a2_);
  }
  std::string name() const override { return name_; }
  int dim() const override {
    switch (kind_) {
      case Kind::kSpherical:
        return 3;
      case Kind::kRevolute:
        return 5;
      case Kind::kUniversal:
        return 4;
      case Kind::kCylindrical:
        return 4;
      case Kind::kPrismatic:
        return 5;
      case Kind::kFixed:
        return 6;
    }
    return 0;
  }
  int body_a() const override { return a_.body; }
  int body_b() const override { return b_.body; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd> J_b) const override {
    Rows rows{r, J_a, J_b};
    Visit(poses, &rows);
  }
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    HessianRows rows{w, h};
    Visit(poses, &rows);
  }

 private:
  // The joint's rows, in order, for a value/Jacobian or a Hessian visitor.
  template <class V>
  void Visit(const std::vector<BodyPose>& poses, V* rows) const {
    const bool coincide = kind_ == Kind::kSpherical || kind_ == Kind::kRevolute ||
                          kind_ == Kind::kUniversal || kind_ == Kind::kFixed;
    if (coincide) rows->Coincide(poses, a_, b_);
    if (kind_ == Kind::kUniversal) rows->Dot(poses, a_.body, a_.axis, b_.body, b_.axis);
    const bool parallel = kind_ == Kind::kRevolute || kind_ == Kind::kCylindrical ||
                          kind_ == Kind::kPrismatic || kind_ == Kind::kFixed;
    if (parallel) rows->ParallelAxes(poses, a_, b_, b1_, b2_);       // same sense
    if (kind_ == Kind::kCylindrical || kind_ == Kind::kPrismatic) {  // b's point on a's axis.
      rows->Offset(poses, a_, b_, a1_);
      rows->Offset(poses, a_, b_, a2_);
    }
    if (kind_ == Kind::kPrismatic || kind_ == Kind::kFixed) rows->NoTurn(poses, a_, b_);
  }
  Kind kind_;
  const char* name_;
  Attachment a_, b_;
  Eigen::Vector3d a1_, a2_, b1_, b2_;
};

class UnitQuaternionTerm final : public Term {
 public:
  explicit UnitQuaternionTerm(int body) : body_(body) {}
  std::string name() const override { return "unit_quaternion"; }
  int dim() const override { return 1; }
  int body_a() const override { return body_; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const Eigen::Vector4d Q = PoseOf(poses, body_).q.tail<4>();
    r[0] = Q.squaredNorm() - 1.0;
    J_a.topLeftCorner<1, 3>().setZero();  // fixed-size blocks: no memset
    J_a.block<1, 4>(0, 3) = 2.0 * Q.transpose();
  }
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>&, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    h->aa.block<4, 4>(3, 3).diagonal().array() += 2.0 * w[0];
  }

 private:
  int body_;
};

// θ = atan2(s, c) with s = (R_a ref_a × R_b ref_b)·(R_a axis), c = (R_a ref_a)·(R_b ref_b).
// s = (R_a (axis × ref_a))·(R_b ref_b) too (rotations keep cross products): both are dot
// products of one vector on each body, so their second derivatives are HessianRows::Dot's.
struct AngleParts {
  double theta, s, c;
  Eigen::Matrix<double, 1, 14> ds, dc;  // [∂/∂q_a, ∂/∂q_b]
};

AngleParts AngleWithParts(const std::vector<BodyPose>& poses, const Attachment& a,
                          const Attachment& b) {
  Matrix37 jra, jrb, jax;
  const Eigen::Vector3d ra = Direction(poses, a.body, a.reference, &jra);
  const Eigen::Vector3d rb = Direction(poses, b.body, b.reference, &jrb);
  const Eigen::Vector3d ax = Direction(poses, a.body, a.axis, &jax);
  AngleParts p;
  p.s = ra.cross(rb).dot(ax);
  p.c = ra.dot(rb);
  // ds = (dra × rb)·ax + (ra × drb)·ax + (ra × rb)·dax = (rb × ax)·dra + (ax × ra)·drb + ...
  p.ds << rb.cross(ax).transpose() * jra + ra.cross(rb).transpose() * jax,
      ax.cross(ra).transpose() * jrb;
  p.dc << rb.transpose() * jra, ra.transpose() * jrb;
  p.theta = std::atan2(p.s, p.c);
  return p;
}

double Angle(const std::vector<BodyPose>& poses, const Attachment& a, const Attachment& b,
             Eigen::Matrix<double, 1, 7>* dJa, Eigen::Matrix<double, 1, 7>* dJb) {
  const AngleParts p = AngleWithParts(poses, a, b);
  if (dJa) {
    const double inv = 1.0 / (p.s * p.s + p.c * p.c);
    const Eigen::Matrix<double, 1, 14> d = (p.c * p.ds - p.s * p.dc) * inv;
    *dJa = d.head<7>();
    *dJb = d.tail<7>();
  }
  return p.theta;
}

class RevoluteLimitsTerm final : public Term {
 public:
  RevoluteLimitsTerm(const Attachment& a, const Attachment& b, double lo, double hi)
      : a_(Normalized(a, "revolute limits")),
        b_(Normalized(b, "revolute limits")),
        lo_(lo),
        hi_(hi) {
    if (!(lo < hi)) throw std::invalid_argument("revolute limits: need lo < hi");
  }
  std::string name() const override { return "revolute_limits"; }
  int dim() const override { return 2; }
  int body_a() const override { return a_.body; }
  int body_b() const override { return b_.body; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd> J_b) const override {
    Eigen::Matrix<double, 1, 7> da, db;
    const double theta = Angle(poses, a_, b_, &da, &db);
    r[0] = theta - lo_;
    r[1] = hi_ - theta;
    J_a.row(0) = da;
    J_a.row(1) = -da;
    J_b.row(0) = db;
    J_b.row(1) = -db;
  }
  bool has_hessian() const override { return true; }
  // ω ∇²θ with ω = w_0 − w_1 (the rows are θ − lo and hi − θ). With ρ² = s² + c² and
  // g = ∇θ = (c∇s − s∇c)/ρ²:
  //   ∇²θ = (c∇²s − s∇²c)/ρ² + (∇c∇sᵀ − ∇s∇cᵀ)/ρ² − 2 g (s∇s + c∇c)ᵀ/ρ²   (symmetrized).
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    const double omega = w[0] - w[1];
    const AngleParts p = AngleWithParts(poses, a_, b_);
    const double rho2 = p.s * p.s + p.c * p.c;
    const Eigen::Vector2d dot_weights(omega * p.c / rho2, -omega * p.s / rho2);
    const Eigen::Ref<const Eigen::VectorXd> weights(dot_weights);
    HessianRows rows{weights, h};
    rows.Dot(poses, a_.body, a_.axis.cross(a_.reference), b_.body, b_.reference);
    rows.Dot(poses, a_.body, a_.reference, b_.body, b_.reference);
    const Eigen::Matrix<double, 1, 14> g = (p.c * p.ds - p.s * p.dc) / rho2;
    Eigen::Matrix<double, 14, 14> R = p.dc.transpose() * p.ds - p.ds.transpose() * p.dc -
                                      2.0 * g.transpose() * (p.s * p.ds + p.c * p.dc);
    R = (0.5 * omega / rho2) * (R + R.transpose()).eval();
    h->aa += R.topLeftCorner<7, 7>();
    h->ab += R.topRightCorner<7, 7>();
    h->bb += R.bottomRightCorner<7, 7>();
  }

 private:
  Attachment a_, b_;
  double lo_, hi_;
};

// A prismatic joint's displacement d = (P_b − P_a)·(R_a axis_a) (the Offset row along a's axis):
// limits d − lo ≥ 0 and hi − d ≥ 0, or (one row) d itself.
class PrismaticCoordinateTerm final : public Term {
 public:
  PrismaticCoordinateTerm(const Attachment& a, const Attachment& b, bool limits, double lo,
                          double hi)
      : a_(Normalized(a, "prismatic limits")),
        b_(Normalized(b, "prismatic limits")),
        limits_(limits),
        lo_(lo),
        hi_(hi) {
    if (limits && !(lo < hi)) throw std::invalid_argument("prismatic limits: need lo < hi");
  }
  std::string name() const override { return limits_ ? "prismatic_limits" : "joint_coordinate"; }
  int dim() const override { return limits_ ? 2 : 1; }
  int body_a() const override { return a_.body; }
  int body_b() const override { return b_.body; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd> J_b) const override {
    Rows rows{r, J_a, J_b, 0};
    rows.Offset(poses, a_, b_, a_.axis);
    if (!limits_) return;
    r[1] = hi_ - r[0];
    r[0] -= lo_;
    J_a.row(1) = -J_a.row(0);
    J_b.row(1) = -J_b.row(0);
  }
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    const Eigen::Matrix<double, 1, 1> omega(limits_ ? w[0] - w[1] : w[0]);
    const Eigen::Ref<const Eigen::VectorXd> weights(omega);
    HessianRows rows{weights, h};
    rows.Offset(poses, a_, b_, a_.axis);
  }

 private:
  Attachment a_, b_;
  bool limits_;
  double lo_, hi_;
};

// A revolute joint's angle θ as one row (RevoluteLimits' first row without its bound).
class RevoluteCoordinateTerm final : public Term {
 public:
  RevoluteCoordinateTerm(const Attachment& a, const Attachment& b)
      : limits_(a, b, -4.0, 4.0), a_(a), b_(b) {}
  std::string name() const override { return "joint_coordinate"; }
  int dim() const override { return 1; }
  int body_a() const override { return limits_.body_a(); }
  int body_b() const override { return limits_.body_b(); }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override {
    Eigen::Vector2d r2;
    Eigen::Matrix<double, 2, 7> ja, jb;
    limits_.Evaluate(poses, state, r2, ja, jb);
    r[0] = r2[0] - 4.0;
    J_a.row(0) = ja.row(0);
    J_b.row(0) = jb.row(0);
  }
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    const Eigen::Vector2d w2(w[0], 0.0);
    limits_.AddWeightedHessian(poses, state, w2, h);
  }

 private:
  RevoluteLimitsTerm limits_;
  Attachment a_, b_;
};

}  // namespace

TermPtr PrismaticLimits(const Attachment& a, const Attachment& b, double lo, double hi) {
  return std::make_shared<PrismaticCoordinateTerm>(a, b, true, lo, hi);
}
TermPtr JointCoordinate(const std::string& type, const Attachment& a, const Attachment& b) {
  if (type == "prismatic") return std::make_shared<PrismaticCoordinateTerm>(a, b, false, 0, 0);
  if (type == "revolute") return std::make_shared<RevoluteCoordinateTerm>(a, b);
  throw std::invalid_argument("joint coordinate: a " + type +
                              " joint has no single coordinate (revolute or prismatic)");
}
double PrismaticDisplacement(const Attachment& a, const Attachment& b,
                             const std::vector<BodyPose>& poses) {
  const Attachment an = Normalized(a, "prismatic displacement");
  const Attachment bn = Normalized(b, "prismatic displacement");
  return (PoseOf(poses, bn.body).Point(bn.point) - PoseOf(poses, an.body).Point(an.point))
      .dot(PoseOf(poses, an.body).R_WB * an.axis);
}

TermPtr MakeJoint(const std::string& type, const Attachment& a, const Attachment& b) {
  if (type == "spherical") return SphericalJoint(a, b);
  if (type == "revolute") return RevoluteJoint(a, b);
  if (type == "universal") return UniversalJoint(a, b);
  if (type == "cylindrical") return CylindricalJoint(a, b);
  if (type == "prismatic") return PrismaticJoint(a, b);
  if (type == "fixed") return FixedJoint(a, b);
  throw std::invalid_argument("unknown joint type \"" + type +
                              "\" (spherical, revolute, universal, cylindrical, prismatic, fixed)");
}

TermPtr SphericalJoint(const Attachment& a, const Attachment& b) {
  return std::make_shared<Joint>(Kind::kSpherical, "spherical", a, b);
}
TermPtr RevoluteJoint(const Attachment& a, const Attachment& b) {
  return std::make_shared<Joint>(Kind::kRevolute, "revolute", a, b);
}
TermPtr UniversalJoint(const Attachment& a, const Attachment& b) {
  return std::make_shared<Joint>(Kind::kUniversal, "universal", a, b);
}
TermPtr CylindricalJoint(const Attachment& a, const Attachment& b) {
  return std::make_shared<Joint>(Kind::kCylindrical, "cylindrical", a, b);
}
TermPtr PrismaticJoint(const Attachment& a, const Attachment& b) {
  return std::make_shared<Joint>(Kind::kPrismatic, "prismatic", a, b);
}
TermPtr FixedJoint(const Attachment& a, const Attachment& b) {
  return std::make_shared<Joint>(Kind::kFixed, "fixed", a, b);
}
TermPtr UnitQuaternion(int body) { return std::make_shared<UnitQuaternionTerm>(body); }
TermPtr RevoluteLimits(const Attachment& a, const Attachment& b, double lo, double hi) {
  return std::make_shared<RevoluteLimitsTerm>(a, b, lo, hi);
}
double RevoluteAngle(const Attachment& a, const Attachment& b, const std::vector<BodyPose>& poses) {
  return Angle(poses, Normalized(a, "revolute angle"), Normalized(b, "revolute angle"), nullptr,
               nullptr);
}

}  // namespace tangent::optimizer
