#include "optimizer/evaluator.h"

#include <algorithm>

#include "contact/rigid.h"

namespace tangent::optimizer {

ProblemEvaluator::ProblemEvaluator(const Problem& problem, bool dense_jacobians)
    : problem_(problem), data_(problem), dense_jacobians_(dense_jacobians) {
  const Mechanism& m = problem.mechanism();
  const int n = m.num_coordinates();
  m.Poses(m.InitialCoordinates(), &poses_);
  const int rows[3] = {problem.num_equality_rows(), problem.num_inequality_rows(),
                       problem.num_objective_rows()};
  for (int k = 0; k < 3; ++k) {
    values_[k].setZero(rows[k]);
    J_a_[k].setZero(rows[k], 7);
    J_b_[k].setZero(rows[k], 7);
    kept_a_[k].setZero(rows[k], 7);
    kept_b_[k].setZero(rows[k], 7);
    if (dense_jacobians_) dense_[k].setZero(rows[k], n);
    int index = 0;
    for (const Problem::Entry& e : List(static_cast<Kind>(k))) {
      Item it;
      it.term = e.term.get();
      it.state = data_.state(k, index++);
      it.weight = e.weight;
      it.row = e.row;
      it.dim = e.term->dim();
      it.body_a = e.term->body_a();
      it.body_b = e.term->body_b();
      it.block_a = m.offset(it.body_a) >= 0 ? m.offset(it.body_a) / 7 : -1;
      it.block_b = it.body_b >= 0 && m.offset(it.body_b) >= 0 ? m.offset(it.body_b) / 7 : -1;
      items_[k].push_back(it);
    }
  }
  rotation_weights_.assign(static_cast<size_t>(m.num_moving()), Eigen::Matrix3d::Zero());
}

const std::vector<Problem::Entry>& ProblemEvaluator::List(Kind kind) const {
  switch (kind) {
    case kEquality:
      return problem_.equalities();
    case kInequality:
      return problem_.inequalities();
    case kObjective:
      break;
  }
  return problem_.objectives();
}

std::vector<std::pair<int, int>> ProblemEvaluator::CoupledBlocks() const {
  std::vector<std::pair<int, int>> pairs;
  for (const auto& items : items_) {
    for (const Item& it : items) {
      if (it.block_a >= 0 && it.block_b >= 0) pairs.emplace_back(it.block_a, it.block_b);
    }
  }
  return pairs;
}

void ProblemEvaluator::Evaluate(const Eigen::VectorXd& q) { EvaluateKinds(q, 0, 2); }

void ProblemEvaluator::EvaluateEqualities(const Eigen::VectorXd& q) {
  EvaluateKinds(q, kEquality, kEquality);
}

void ProblemEvaluator::EvaluateKinds(const Eigen::VectorXd& q, int first, int last) {
  const Mechanism& m = problem_.mechanism();
  for (int i = 0; i < m.num_bodies(); ++i) {
    if (m.offset(i) >= 0) {
      poses_[static_cast<size_t>(i)] = BodyPose::FromCoordinates(q.segment<7>(m.offset(i)));
    }
  }
  for (int k = first; k <= last; ++k) {
    for (Item& it : items_[k]) {
      // An idle row (a free contact slot) is written once: its value and Jacobian stay.
      const bool idle = it.term->Idle(it.state);
      if (idle && it.idle) continue;
      it.idle = idle;
      auto ja = J_a_[k].middleRows(it.row, it.dim);
      auto jb = J_b_[k].middleRows(it.row, it.dim);
      it.term->Evaluate(poses_, it.state, values_[k].segment(it.row, it.dim), ja, jb);
      // A fixed or absent body's block is ignored; zeroed row by row (fixed-size 7-vectors: a
      // dynamic block's setZero calls memset, ~20 % of an evaluation here).
      for (int r = it.row; r < it.row + it.dim; ++r) {
        if (it.block_b < 0) J_b_[k].row(r).setZero();
        if (it.block_a < 0) J_a_[k].row(r).setZero();
      }
    }
    if (dense_jacobians_) DenseJacobian(static_cast<Kind>(k), &dense_[k]);
  }
}

void ProblemEvaluator::DenseJacobian(Kind kind, Eigen::MatrixXd* J) const {
  // (Sized once: no allocation when J already has the shape.)
  J->setZero(values_[kind].size(), problem_.mechanism().num_coordinates());
  for (const Item& it : items_[kind]) {
    if (it.block_a >= 0)
      J->block(it.row, 7 * it.block_a, it.dim, 7) = J_a_[kind].middleRows(it.row, it.dim);
    // += : a term may name one body twice.
    if (it.block_b >= 0)
      J->block(it.row, 7 * it.block_b, it.dim, 7) += J_b_[kind].middleRows(it.row, it.dim);
  }
}

double ProblemEvaluator::Objective(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                                   const std::vector<Matrix7d>& M) const {
  double e = 0.0;
  for (size_t b = 0; b < M.size(); ++b) {
    const Eigen::Matrix<double, 7, 1> d =
        q.segment<7>(7 * static_cast<int>(b)) - q_ref.segment<7>(7 * static_cast<int>(b));
    e += d.dot(M[b] * d);
  }
  e *= 0.5 * problem_.least_astonishment();
  for (const Item& it : items_[kObjective]) {
    e += 0.5 * it.weight * values_[kObjective].segment(it.row, it.dim).squaredNorm();
  }
  for (const Problem::DesignEntry& d : problem_.design_objectives()) e -= d.weight * d.f->Value(q);
  return e;
}

void ProblemEvaluator::ObjectiveGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                                         const std::vector<Matrix7d>& M, Eigen::VectorXd* g,
                                         Eigen::VectorXd* design) const {
  const double w = problem_.least_astonishment();
  for (size_t b = 0; b < M.size(); ++b) {
    const int o = 7 * static_cast<int>(b);
    g->segment<7>(o).noalias() = w * (M[b] * (q.segment<7>(o) - q_ref.segment<7>(o)));
  }
  if (design) design->setZero(q.size());
  for (const Problem::DesignEntry& d : problem_.design_objectives()) {
    Eigen::VectorXd gd;
    d.f->Gradient(q, &gd);
    *g -= d.weight * gd;
    if (design) *design -= d.weight * gd;
  }
  // Row by row with fixed-size 7-vectors, as AddJacobianTransposeTimes (a dynamic d x 7
  // transpose product takes Eigen's generic path: 5 % of the peg's tick).
  const Eigen::VectorXd& r = values_[kObjective];
  for (const Item& it : items_[kObjective]) {
    if (it.block_a >= 0) {
      Vector7d ga = Vector7d::Zero();
      for (int k = it.row; k < it.row + it.dim; ++k) {
        ga.noalias() += r[k] * J_a_[kObjective].row(k).transpose();
      }
      g->segment<7>(7 * it.block_a) += it.weight * ga;
    }
    if (it.block_b >= 0) {
      Vector7d gb = Vector7d::Zero();
      for (int k = it.row; k < it.row + it.dim; ++k) {
        gb.noalias() += r[k] * J_b_[kObjective].row(k).transpose();
      }
      g->segment<7>(7 * it.block_b) += it.weight * gb;
    }
  }
}

namespace {

// g += scale · Jᵀ v over the items `skip` does not skip, row by row with fixed-size 7-vectors
// (a dynamic d x 7 transpose product costs 3x more here).
template <class Items, class Rows, class Skip>
[[gnu::always_inline]] inline void TransposeTimes(const Items& items, const Rows& Ja,
                                                  const Rows& Jb, const Eigen::VectorXd& v,
                                                  double scale, Eigen::VectorXd* g, Skip skip) {
  for (const auto& it : items) {
    if (skip(it)) continue;
    if (it.block_a >= 0) {
      Vector7d ga = Vector7d::Zero();
      for (int r = it.row; r < it.row + it.dim; ++r) ga.noalias() += v[r] * Ja.row(r).transpose();
      g->segment<7>(7 * it.block_a) += scale * ga;
    }
    if (it.block_b >= 0) {
      Vector7d gb = Vector7d::Zero();
      for (int r = it.row; r < it.row + it.dim; ++r) gb.noalias() += v[r] * Jb.row(r).transpose();
      g->segment<7>(7 * it.block_b) += scale * gb;
    }
  }
}

}  // namespace

void ProblemEvaluator::AddJacobianTransposeTimes(Kind kind, const Eigen::VectorXd& v, double scale,
                                                 Eigen::VectorXd* g) const {
  // (An idle term's rows are zero.)
  TransposeTimes(items_[kind], J_a_[kind], J_b_[kind], v, scale, g,
                 [](const Item& it) { return it.idle; });
}

void ProblemEvaluator::KeepJacobians() {
  for (const Kind k : {kEquality, kInequality}) {
    std::copy_n(J_a_[k].data(), J_a_[k].size(), kept_a_[k].data());  // (sized at construction)
    std::copy_n(J_b_[k].data(), J_b_[k].size(), kept_b_[k].data());
    for (Item& it : items_[k]) it.kept_idle = it.idle;
  }
}

void ProblemEvaluator::AddKeptJacobianTransposeTimes(Kind kind, const Eigen::VectorXd& v,
                                                     double scale, Eigen::VectorXd* g) const {
  TransposeTimes(items_[kind], kept_a_[kind], kept_b_[kind], v, scale, g,
                 [](const Item& it) { return it.kept_idle; });
}

void ProblemEvaluator::JacobianTimes(Kind kind, const Eigen::VectorXd& x,
                                     Eigen::VectorXd* out) const {
  const JacobianRows& Ja = J_a_[kind];
  const JacobianRows& Jb = J_b_[kind];
  for (const Item& it : items_[kind]) {
    if (it.idle) {  // zero rows
      for (int r = it.row; r < it.row + it.dim; ++r) (*out)[r] = 0.0;
      continue;
    }
    const Vector7d xa = it.block_a >= 0 ? Vector7d(x.segment<7>(7 * it.block_a)) : Vector7d::Zero();
    const Vector7d xb = it.block_b >= 0 ? Vector7d(x.segment<7>(7 * it.block_b)) : Vector7d::Zero();
    for (int r = it.row; r < it.row + it.dim; ++r) {
      (*out)[r] = Ja.row(r).dot(xa.transpose()) + Jb.row(r).dot(xb.transpose());
    }
  }
}

namespace {

// out += Σ_k wx_k y_kᵀ (wx_k = w_k x_k), column by column: each column's seven sums stay in
// registers over the rows instead of a 7 x 7 accumulator loaded and stored for every row. The
// products and their order are those of row-by-row rank-one updates (the same bits).
template <class Block>
void AddOuterProducts(const Vector7d* wx, const Vector7d* y, int m, Block&& out) {
  for (int j = 0; j < 7; ++j) {
    Vector7d column = wx[0] * y[0][j];
    for (int k = 1; k < m; ++k) column.noalias() += wx[k] * y[k][j];
    out.col(j) += column;
  }
}

}  // namespace

void ProblemEvaluator::AddGaussNewton(Kind kind, const Eigen::VectorXd& row_weights,
                                      BlockMatrix* H) const {
  // Per term, Σ_rows w a aᵀ (and b bᵀ, a bᵀ) over its rows with nonzero weight, gathered into
  // fixed-size 7-vectors; only the upper block triangle is written (the factorizations read
  // the upper triangle).
  constexpr int kMaxRows = 8;
  Vector7d a[kMaxRows], b[kMaxRows], wa[kMaxRows], wb[kMaxRows];
  const JacobianRows& Ja = J_a_[kind];
  const JacobianRows& Jb = J_b_[kind];
  for (const Item& it : items_[kind]) {
    if (it.idle) continue;  // zero rows
    // Only the blocks of moving bodies (a contact against a fixed part has one).
    const bool has_a = it.block_a >= 0, has_b = it.block_b >= 0;
    for (int r0 = it.row; r0 < it.row + it.dim; r0 += kMaxRows) {  // (wider terms: in parts)
      int m = 0;
      for (int r = r0; r < std::min(r0 + kMaxRows, it.row + it.dim); ++r) {
        const double w = row_weights[r];
        if (w == 0.0) continue;
        a[m] = Ja.row(r).transpose();
        b[m] = Jb.row(r).transpose();
        wa[m] = w * a[m];
        wb[m] = w * b[m];
        ++m;
      }
      if (m == 0) continue;
      if (has_a) AddOuterProducts(wa, a, m, H->Block(it.block_a, it.block_a));
      if (has_b) AddOuterProducts(wb, b, m, H->Block(it.block_b, it.block_b));
      if (has_a && has_b) {
        if (it.block_a < it.block_b) {
          AddOuterProducts(wa, b, m, H->Block(it.block_a, it.block_b));
        } else {
          Matrix7d ab = Matrix7d::Zero();
          AddOuterProducts(wa, b, m, ab);
          H->AddOffDiagonal(it.block_a, it.block_b, ab);
        }
      }
    }
  }
}

void ProblemEvaluator::AddCurvature(Kind kind, const Eigen::VectorXd& weights, BlockMatrix* H) {
  TermHessian h;
  for (const Item& it : items_[kind]) {
    if (it.idle || !it.term->has_hessian()) continue;
    const auto w = weights.segment(it.row, it.dim);
    if (!(w.array() != 0.0).any()) continue;
    h.SetZero();
    it.term->AddWeightedHessian(poses_, it.state, w, &h);
    if (it.block_a >= 0) {
      H->Block(it.block_a, it.block_a) += h.aa;
      rotation_weights_[static_cast<size_t>(it.block_a)] += h.W_a;
    }
    if (it.block_b >= 0) {
      H->Block(it.block_b, it.block_b) += h.bb;
      rotation_weights_[static_cast<size_t>(it.block_b)] += h.W_b;
    }
    if (it.block_a >= 0 && it.block_b >= 0) H->AddOffDiagonal(it.block_a, it.block_b, h.ab);
  }
  rotations_pending_ = true;
}

void ProblemEvaluator::AddRowHessiansTimes(Kind kind, const Eigen::MatrixXd& Y,
                                           Eigen::VectorXd* g) {
  TermHessian h;
  Eigen::VectorXd w;
  const Eigen::Vector4d identity(1.0, 0.0, 0.0, 0.0);
  for (const Item& it : items_[kind]) {
    if (!it.term->has_hessian()) continue;
    w.setZero(it.dim);
    for (int r = 0; r < it.dim; ++r) {
      if (Y.row(it.row + r).isZero(0.0)) continue;
      w[r] = 1.0;
      h.SetZero();
      it.term->AddWeightedHessian(poses_, it.state, w, &h);
      w[r] = 0.0;
      h.Fold(it.block_a >= 0 ? poses_[static_cast<size_t>(it.body_a)].q.tail<4>() : identity,
             it.block_b >= 0 ? poses_[static_cast<size_t>(it.body_b)].q.tail<4>() : identity);
      // The row's Hessian has the blocks [aa ab; abᵀ bb] on the two bodies' coordinates.
      const int a = 7 * it.block_a, b = 7 * it.block_b;
      if (it.block_a >= 0) {
        const auto y_a = Y.row(it.row + r).segment<7>(a).transpose();
        g->segment<7>(a) += h.aa * y_a;
        if (it.block_b >= 0) g->segment<7>(b) += h.ab.transpose() * y_a;
      }
      if (it.block_b >= 0) {
        const auto y_b = Y.row(it.row + r).segment<7>(b).transpose();
        g->segment<7>(b) += h.bb * y_b;
        if (it.block_a >= 0) g->segment<7>(a) += h.ab * y_b;
      }
    }
  }
}

void ProblemEvaluator::FoldRotations(BlockMatrix* H) {
  if (!rotations_pending_) return;
  const Mechanism& m = problem_.mechanism();
  for (int i = 0; i < m.num_bodies(); ++i) {
    const int o = m.offset(i);
    if (o < 0) continue;
    Eigen::Matrix3d& W = rotation_weights_[static_cast<size_t>(o / 7)];
    if (!W.isZero(0.0)) {
      H->Block(o / 7, o / 7).bottomRightCorner<4, 4>() +=
          contact::RotateHessianWeighted(poses_[static_cast<size_t>(i)].q.tail<4>(), W);
      W.setZero();
    }
  }
  rotations_pending_ = false;
}

double ProblemEvaluator::Objective(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                                   const Eigen::MatrixXd& M) const {
  double e = 0.5 * problem_.least_astonishment() * (q - q_ref).dot(M * (q - q_ref));
  for (const Item& it : items_[kObjective]) {
    e += 0.5 * it.weight * values_[kObjective].segment(it.row, it.dim).squaredNorm();
  }
  for (const Problem::DesignEntry& d : problem_.design_objectives()) e -= d.weight * d.f->Value(q);
  return e;
}

void ProblemEvaluator::ObjectiveGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& q_ref,
                                         const Eigen::MatrixXd& M, Eigen::VectorXd* g) const {
  g->noalias() = problem_.least_astonishment() * (M * (q - q_ref));
  Eigen::VectorXd wr = values_[kObjective];
  for (const Item& it : items_[kObjective]) wr.segment(it.row, it.dim) *= it.weight;
  AddJacobianTransposeTimes(kObjective, wr, 1.0, g);
  for (const Problem::DesignEntry& d : problem_.design_objectives()) {
    Eigen::VectorXd gd;
    d.f->Gradient(q, &gd);
    *g -= d.weight * gd;
  }
}

void ProblemEvaluator::AddCurvature(const std::vector<Problem::Entry>& list,
                                    const Eigen::VectorXd& weights, Eigen::MatrixXd* H) {
  const Kind kind = &list == &problem_.equalities()     ? kEquality
                    : &list == &problem_.inequalities() ? kInequality
                                                        : kObjective;
  BlockMatrix dense(problem_.mechanism().num_moving(), {}, false);
  AddCurvature(kind, weights, &dense);
  FoldRotations(&dense);
  *H += Eigen::MatrixXd(dense.dense().selfadjointView<Eigen::Upper>());
}

void TermHessian::Fold(const Eigen::Vector4d& Q_a, const Eigen::Vector4d& Q_b) {
  aa.bottomRightCorner<4, 4>() += contact::RotateHessianWeighted(Q_a, W_a);
  bb.bottomRightCorner<4, 4>() += contact::RotateHessianWeighted(Q_b, W_b);
  W_a.setZero();
  W_b.setZero();
}

void ProblemEvaluator::ForEachBusyState(void (TermState::*f)(int), int slot) {
  // (An idle row, a free contact slot, stays idle through a solve: nothing to keep.)
  for (const auto& kind : items_) {
    for (const Item& it : kind) {
      if (it.state && !it.idle) (it.state->*f)(slot);
    }
  }
}

}  // namespace tangent::optimizer
