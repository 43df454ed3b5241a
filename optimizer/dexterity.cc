#include "optimizer/dexterity.h"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <array>
#include <atomic>
#include <stdexcept>

#include "optimizer/goals.h"

namespace tangent::optimizer {

namespace {

std::atomic<std::uint64_t> next_dexterity_id{1};

}  // namespace

// What the measures and every gradient at q share.
struct Dexterity::Point {
  std::uint64_t owner = 0;
  Eigen::VectorXd q;
  std::unique_ptr<ProblemEvaluator> main, aux;  // evaluated at q (equality rows)
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;      // of B
  Eigen::MatrixXd X, S, U, V;
  Eigen::VectorXd sigma;
  Measures measures;  // without gradients
};

Dexterity::Dexterity(const Problem& problem, const Attachment& end_effector,
                     const std::vector<std::pair<Attachment, Attachment>>& joints)
    : id_(next_dexterity_id.fetch_add(1, std::memory_order_relaxed)),
      problem_(problem),
      aux_(problem.mechanism()) {
  if (joints.empty()) throw std::invalid_argument("dexterity: no joint chosen");
  m_ = static_cast<int>(joints.size());
  x_row_ = aux_.num_equality_rows();  // after the unit-quaternion rows aux_ made itself
  aux_.AddEquality(PositionGoal(end_effector, Eigen::Vector3d::Zero()));
  a_row_ = aux_.num_equality_rows();
  // θ through RevoluteLimits' first row θ − lo (its Jacobian and Hessian are θ's).
  for (const auto& [a, b] : joints) aux_.AddEquality(RevoluteLimits(a, b, -4.0, 4.0));
}

Dexterity::Measures Dexterity::Evaluate(const Eigen::VectorXd& q, bool gradients) const {
  return Evaluate(q, gradients ? kAllGradients : 0);
}

const Dexterity::Point& Dexterity::At(const Eigen::VectorXd& q) const {
  // A few points per thread: a worst case over configurations evaluates one Dexterity at one
  // point per configuration (seven for the four-bar) before asking their gradients.
  constexpr int kPoints = 16;
  thread_local std::array<std::unique_ptr<Point>, kPoints> points;
  thread_local int next = 0;
  for (const std::unique_ptr<Point>& p : points) {
    if (p && p->owner == id_ && p->q.size() == q.size() && p->q == q) return *p;
  }
  const int n = problem_.mechanism().num_coordinates();
  const int mc = problem_.num_equality_rows();
  if (mc + m_ != n) {
    throw std::runtime_error("dexterity: " + std::to_string(m_) + " chosen joints, but the " +
                             "mechanism has " + std::to_string(n - mc) +
                             " degrees of freedom by its equality rows");
  }
  auto p = std::make_unique<Point>();
  p->main = std::make_unique<ProblemEvaluator>(problem_);
  p->aux = std::make_unique<ProblemEvaluator>(aux_);
  p->main->EvaluateEqualities(q);  // (only the equality rows make B and X)
  p->aux->EvaluateEqualities(q);
  Eigen::MatrixXd B(n, n);
  B.topRows(mc) = p->main->J_e();
  for (int k = 0; k < m_; ++k) B.row(mc + k) = p->aux->J_e().row(a_row_ + 2 * k);
  p->lu.compute(B);
  p->X = p->aux->J_e().middleRows(x_row_, 3);
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(n, m_);
  E.bottomRows(m_).setIdentity();
  p->S = p->lu.solve(E);
  if (!p->S.allFinite() ||
      (B * p->S - E).cwiseAbs().maxCoeff() > 1e-8 * (1.0 + p->S.cwiseAbs().maxCoeff())) {
    throw std::runtime_error(
        "dexterity: the chosen joints do not parameterize the mechanism's motion here");
  }
  Measures& out = p->measures;
  out.J = p->X * p->S;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(out.J, Eigen::ComputeThinU | Eigen::ComputeThinV);
  p->sigma = svd.singularValues();
  p->U = svd.matrixU();
  p->V = svd.matrixV();
  const int r = static_cast<int>(p->sigma.size());
  const double s_max = p->sigma[0], s_min = p->sigma[r - 1];
  out.dexterity = p->sigma.prod();
  out.inverse_condition = s_max > 0 ? s_min / s_max : 0.0;
  out.force_transmission = s_max > 0 ? 1.0 / s_max : 0.0;
  p->owner = id_;
  p->q = q;
  std::unique_ptr<Point>& slot = points[static_cast<size_t>(next)];
  next = (next + 1) % kPoints;
  slot = std::move(p);
  return *slot;
}

Dexterity::Measures Dexterity::Evaluate(const Eigen::VectorXd& q, int gradients) const {
  const Point& p = At(q);
  Measures out = p.measures;
  if (!gradients) return out;
  const int n = problem_.mechanism().num_coordinates();
  const int mc = problem_.num_equality_rows();
  const Eigen::MatrixXd &U = p.U, &V = p.V, &S = p.S;
  const Eigen::VectorXd& sigma = p.sigma;
  const int r = static_cast<int>(sigma.size());
  const double s_max = sigma[0], s_min = sigma[r - 1];
  // G = ∂f/∂J for each measure (∂σ_i = u_iᵀ ∂J v_i).
  Eigen::MatrixXd G_dex = Eigen::MatrixXd::Zero(3, m_);
  for (int i = 0; i < r; ++i) G_dex += (out.dexterity / sigma[i]) * U.col(i) * V.col(i).transpose();
  const Eigen::MatrixXd G_max = U.col(0) * V.col(0).transpose();
  const Eigen::MatrixXd G_min = U.col(r - 1) * V.col(r - 1).transpose();
  const Eigen::MatrixXd G_inv = G_min / s_max - (s_min / (s_max * s_max)) * G_max;
  const Eigen::MatrixXd G_force = -G_max / (s_max * s_max);

  // B⁻ᵀ Xᵀ (n × 3) once for every measure: Y2 below is this times Y1, so the solve has 3
  // right-hand sides instead of n.
  const Eigen::MatrixXd Xt = p.X.transpose();
  const Eigen::MatrixXd Z = p.lu.transpose().solve(Xt);
  auto gradient = [&](const Eigen::MatrixXd& G) {
    // ∂f/∂q_k = ⟨Y1, ∂X/∂q_k⟩ + ⟨Y2, ∂B/∂q_k⟩, Y1 = G Sᵀ, Y2 = −B⁻ᵀ Xᵀ Y1. X's and B's rows are
    // constraint rows' gradients, so this is Σ_r ∇²c_r W(r, :)ᵀ with W the rows of Y1 and Y2
    // that weigh row r: one Hessian per row, not one per coordinate (it used to assemble an
    // n × n Hessian per coordinate for its one column: two thirds of a design solve's time).
    const Eigen::MatrixXd Y1 = G * S.transpose();
    const Eigen::MatrixXd Y2 = -Z * Y1;
    Eigen::VectorXd grad = Eigen::VectorXd::Zero(n);
    p.main->AddRowHessiansTimes(ProblemEvaluator::kEquality, Y2.topRows(mc), &grad);
    Eigen::MatrixXd W_aux = Eigen::MatrixXd::Zero(aux_.num_equality_rows(), n);
    W_aux.middleRows(x_row_, 3) = Y1;
    for (int k = 0; k < m_; ++k) W_aux.row(a_row_ + 2 * k) = Y2.row(mc + k);
    p.aux->AddRowHessiansTimes(ProblemEvaluator::kEquality, W_aux, &grad);
    return grad;
  };
  if (gradients & GradientBit(DexterityMeasure::kDexterity)) {
    out.grad_dexterity = gradient(G_dex);
  }
  if (gradients & GradientBit(DexterityMeasure::kInverseCondition)) {
    out.grad_inverse_condition = gradient(G_inv);
  }
  if (gradients & GradientBit(DexterityMeasure::kForceTransmission)) {
    out.grad_force_transmission = gradient(G_force);
  }
  return out;
}

namespace {

class DexterityObjective final : public DesignObjective {
 public:
  DexterityObjective(std::shared_ptr<const Dexterity> d, DexterityMeasure m)
      : d_(std::move(d)), m_(m) {}
  std::string name() const override {
    switch (m_) {
      case DexterityMeasure::kDexterity:
        return "dexterity";
      case DexterityMeasure::kInverseCondition:
        return "inverse_condition";
      case DexterityMeasure::kForceTransmission:
        break;
    }
    return "force_transmission";
  }
  double Value(const Eigen::VectorXd& q) const override {
    const Dexterity::Measures r = d_->Evaluate(q, false);
    return Pick(r.dexterity, r.inverse_condition, r.force_transmission);
  }
  void Gradient(const Eigen::VectorXd& q, Eigen::VectorXd* g) const override {
    const Dexterity::Measures r = d_->Evaluate(q, Dexterity::GradientBit(m_));
    *g = m_ == DexterityMeasure::kDexterity          ? r.grad_dexterity
         : m_ == DexterityMeasure::kInverseCondition ? r.grad_inverse_condition
                                                     : r.grad_force_transmission;
  }

 private:
  double Pick(double a, double b, double c) const {
    return m_ == DexterityMeasure::kDexterity          ? a
           : m_ == DexterityMeasure::kInverseCondition ? b
                                                       : c;
  }
  std::shared_ptr<const Dexterity> d_;
  DexterityMeasure m_;
};

}  // namespace

std::shared_ptr<DesignObjective> MakeDexterityObjective(std::shared_ptr<const Dexterity> d,
                                                        DexterityMeasure measure) {
  return std::make_shared<DexterityObjective>(std::move(d), measure);
}

}  // namespace tangent::optimizer
