#pragma once

// Finite-difference checks of a one-row two-body term (contact and trim terms): its value and
// gradient at q, its weighted Hessian folded to 14 × 14 over (q_a, q_b), and central differences
// of its analytic gradient to compare that Hessian with.

#include <algorithm>
#include <vector>

#include <Eigen/Core>

#include "optimizer/mechanism.h"
#include "optimizer/term.h"

namespace tangent::testing {

/// β and ∇β (1 × 14 over (q_a, q_b)) at q through the term (which tracks from its last state).
inline double TermValue(const optimizer::Mechanism& m, const optimizer::Term& t,
                        optimizer::TermState* st, const Eigen::VectorXd& q,
                        Eigen::Matrix<double, 1, 14>* grad) {
  std::vector<contact::BodyPose> poses;
  m.Poses(q, &poses);
  Eigen::VectorXd r(1);
  Eigen::MatrixXd Ja(1, 7), Jb(1, 7);
  t.Evaluate(poses, st, r, Ja, Jb);
  if (grad) *grad << Ja, Jb;
  return r[0];
}

/// w ∇²β at q as the solver sees it (AddWeightedHessian, folded with the bodies' quaternions).
inline Eigen::Matrix<double, 14, 14> TermHessianAt(const optimizer::Mechanism& m,
                                                   const optimizer::Term& t,
                                                   optimizer::TermState* st,
                                                   const Eigen::VectorXd& q, double w) {
  TermValue(m, t, st, q, nullptr);
  std::vector<contact::BodyPose> poses;
  m.Poses(q, &poses);
  optimizer::TermHessian h;
  h.SetZero();
  t.AddWeightedHessian(poses, st, Eigen::VectorXd::Constant(1, w), &h);
  h.Fold(q.segment<4>(3), q.segment<4>(10));
  Eigen::Matrix<double, 14, 14> H;
  H << h.aa, h.ab, h.ab.transpose(), h.bb;
  return H;
}

/// Row k: w (∇β(q + h e_k) − ∇β(q − h e_k)) / 2h. Leaves the term at q.
inline Eigen::Matrix<double, 14, 14> GradientDifferences(const optimizer::Mechanism& m,
                                                         const optimizer::Term& t,
                                                         optimizer::TermState* st,
                                                         const Eigen::VectorXd& q, double w,
                                                         double h) {
  Eigen::Matrix<double, 14, 14> fd;
  for (int k = 0; k < 14; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    Eigen::Matrix<double, 1, 14> gp, gm;
    TermValue(m, t, st, qp, &gp);
    TermValue(m, t, st, qm, &gm);
    fd.row(k) = w * (gp - gm) / (2 * h);
  }
  TermValue(m, t, st, q, nullptr);
  return fd;
}

/// Central differences of re-solved values, per coordinate k: (β(q + h e_k) − β(q − h e_k)) / 2h,
/// to compare with ∇β. Leaves the term at q.
inline Eigen::Matrix<double, 1, 14> ValueDifferences(const optimizer::Mechanism& m,
                                                     const optimizer::Term& t,
                                                     optimizer::TermState* st,
                                                     const Eigen::VectorXd& q, double h) {
  Eigen::Matrix<double, 1, 14> fd;
  for (int k = 0; k < 14; ++k) {
    Eigen::VectorXd qp = q, qm = q;
    qp[k] += h;
    qm[k] -= h;
    fd[k] = (TermValue(m, t, st, qp, nullptr) - TermValue(m, t, st, qm, nullptr)) / (2 * h);
  }
  TermValue(m, t, st, q, nullptr);
  return fd;
}

/// Per row k of the weighted Hessian at q: its largest difference from GradientDifferences,
/// relative to the row's size (at least 1). Leaves the term at q.
inline Eigen::Matrix<double, 14, 1> HessianRowErrors(const optimizer::Mechanism& m,
                                                     const optimizer::Term& t,
                                                     optimizer::TermState* st,
                                                     const Eigen::VectorXd& q, double w, double h) {
  const Eigen::Matrix<double, 14, 14> H = TermHessianAt(m, t, st, q, w);
  const Eigen::Matrix<double, 14, 14> fd = GradientDifferences(m, t, st, q, w, h);
  Eigen::Matrix<double, 14, 1> err;
  for (int k = 0; k < 14; ++k) {
    err[k] = (fd.row(k) - H.row(k)).cwiseAbs().maxCoeff() /
             std::max(1.0, H.row(k).cwiseAbs().maxCoeff());
  }
  return err;
}

}  // namespace tangent::testing
