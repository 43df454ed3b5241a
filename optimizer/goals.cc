#include "optimizer/goals.h"

#include <stdexcept>

#include "base/check.h"
#include "contact/rigid.h"

namespace tangent::optimizer {

namespace {

using Matrix37 = Eigen::Matrix<double, 3, 7>;

}  // namespace

OrientationGoalTerm::OrientationGoalTerm(int body, const Eigen::Matrix3d& R,
                                         const Eigen::Vector3d& w)
    : body_(body), initial_R_(R), w_(w) {
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-9) {
    throw std::invalid_argument("orientation goal: target is not a rotation matrix");
  }
}

std::unique_ptr<TermState> OrientationGoalTerm::MakeState() const {
  auto s = std::make_unique<State>();
  s->R_target = initial_R_;
  return s;
}

void OrientationGoalTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                   Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                   Eigen::Ref<Eigen::MatrixXd>) const {
  const BodyPose& p = PoseOf(poses, body_);
  const Eigen::Matrix3d& R_target = static_cast<const State*>(state)->R_target;
  // Fixed-size blocks of the Refs: assigned to a dynamic Ref, the 3 x 7 products took Eigen's
  // generic path (1,100 instructions a call, callgrind on the servo).
  for (int i = 0; i < 3; ++i) {
    r.segment<3>(3 * i) = w_[i] * (p.R_WB.col(i) - R_target.col(i));
    J_a.block<3, 3>(3 * i, 0).setZero();  // ∂(R eᵢ)/∂q: rotation only, −[R eᵢ]× omega_map
    J_a.block<3, 4>(3 * i, 3).noalias() = (-w_[i] * contact::Skew(p.R_WB.col(i))) * p.omega_map;
  }
}

void OrientationGoalTerm::AddWeightedHessian(const std::vector<BodyPose>&, TermState* /*state*/,
                                             const Eigen::Ref<const Eigen::VectorXd>& w,
                                             TermHessian* h) const {
  for (int i = 0; i < 3; ++i) {
    h->W_a.col(i) += w_[i] * w.segment<3>(3 * i);  // y eᵢᵀ
  }
}

namespace {

class Concat final : public Term {
 public:
  struct State final : TermState {
    std::unique_ptr<TermState> a, b;
  };
  Concat(TermPtr a, TermPtr b) : a_(std::move(a)), b_(std::move(b)) {}
  std::string name() const override { return "pose_goal"; }
  int dim() const override { return a_->dim() + b_->dim(); }
  int body_a() const override { return a_->body_a(); }
  std::unique_ptr<TermState> MakeState() const override {
    auto s = std::make_unique<State>();
    s->a = a_->MakeState();
    s->b = b_->MakeState();
    return s;
  }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override {
    auto* s = static_cast<State*>(state);
    const int n = a_->dim();
    a_->Evaluate(poses, s->a.get(), r.head(n), J_a.topRows(n), J_b.topRows(n));
    b_->Evaluate(poses, s->b.get(), r.tail(b_->dim()), J_a.bottomRows(b_->dim()),
                 J_b.bottomRows(b_->dim()));
  }
  bool has_hessian() const override { return a_->has_hessian() && b_->has_hessian(); }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    auto* s = static_cast<State*>(state);
    a_->AddWeightedHessian(poses, s->a.get(), w.head(a_->dim()), h);
    b_->AddWeightedHessian(poses, s->b.get(), w.tail(b_->dim()), h);
  }

 private:
  TermPtr a_, b_;
};

class Aiming final : public Term {
 public:
  Aiming(const Attachment& at, const Eigen::Vector3d& t) : at_(at), t_(t) { at_.axis.normalize(); }
  std::string name() const override { return "aiming_goal"; }
  int dim() const override { return 3; }
  int body_a() const override { return at_.body; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const BodyPose& p = PoseOf(poses, at_.body);
    const Eigen::Vector3d P = p.Point(at_.point);
    const Eigen::Vector3d v = t_ - P;
    const double len = v.norm();
    const Eigen::Vector3d u = v / len;
    r = p.R_WB * at_.axis - u;
    // d(v/|v|) = (I − u uᵀ) dv / |v|, dv = −dP.
    const Eigen::Matrix3d du_dP = -(Eigen::Matrix3d::Identity() - u * u.transpose()) / len;
    J_a = contact::DirectionJacobian(p, at_.axis) - du_dP * contact::PointJacobian(p, at_.point);
  }

 private:
  Attachment at_;
  Eigen::Vector3d t_;
};

class Line final : public Term {
 public:
  Line(const Attachment& at, const Eigen::Vector3d& o, const Eigen::Vector3d& d)
      : at_(at),
        o_(o),
        P_(Eigen::Matrix3d::Identity() - d.normalized() * d.normalized().transpose()) {}
  std::string name() const override { return "line_goal"; }
  int dim() const override { return 3; }
  int body_a() const override { return at_.body; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const BodyPose& p = PoseOf(poses, at_.body);
    // Fixed-size blocks of the Refs: their assignments unroll (a dynamic one loops generically).
    r.head<3>() = P_ * (p.Point(at_.point) - o_);
    J_a.topLeftCorner<3, 7>() = P_ * contact::PointJacobian(p, at_.point);
  }
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>&, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    h->W_a.noalias() += (P_ * w.head<3>()) * at_.point.transpose();
  }

 private:
  Attachment at_;
  Eigen::Vector3d o_;
  Eigen::Matrix3d P_;
};

class Plane final : public Term {
 public:
  Plane(const Attachment& at, const Eigen::Vector3d& o, const Eigen::Vector3d& n, bool half,
        bool one_sided)
      : at_(at), o_(o), n_(n.normalized()), half_(half), one_sided_(one_sided) {}
  std::string name() const override { return half_ ? "half_space_goal" : "plane_goal"; }
  int dim() const override { return 1; }
  int body_a() const override { return at_.body; }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* /*state*/,
                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                Eigen::Ref<Eigen::MatrixXd>) const override {
    const BodyPose& p = PoseOf(poses, at_.body);
    const double s = n_.dot(p.Point(at_.point) - o_);
    if (one_sided_ && s > 0) {
      r[0] = 0.0;
      J_a.setZero();
      return;
    }
    r[0] = s;
    J_a = n_.transpose() * contact::PointJacobian(p, at_.point);
  }
  bool has_hessian() const override { return true; }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* /*state*/,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    const BodyPose& p = PoseOf(poses, at_.body);
    if (one_sided_ && n_.dot(p.Point(at_.point) - o_) > 0) return;
    h->W_a.noalias() += (w[0] * n_) * at_.point.transpose();
  }

 private:
  Attachment at_;
  Eigen::Vector3d o_, n_;
  bool half_, one_sided_;
};

class Disjunction final : public Term {
 public:
  struct State final : TermState {
    std::vector<std::unique_ptr<TermState>> goals;
    // Scratch, sized once: Evaluate stays allocation free.
    Eigen::VectorXd r;
    Eigen::MatrixXd ja, jb;
  };
  explicit Disjunction(std::vector<TermPtr> goals) : goals_(std::move(goals)) {
    if (goals_.empty()) throw std::invalid_argument("disjunction goal: no goals");
    for (const auto& g : goals_) {
      dim_ = std::max(dim_, g->dim());
      if (g->body_a() != goals_[0]->body_a() || g->body_b() != goals_[0]->body_b()) {
        throw std::invalid_argument("disjunction goal: all goals must act on the same bodies");
      }
    }
  }
  std::string name() const override { return "disjunction_goal"; }
  int dim() const override { return dim_; }
  int body_a() const override { return goals_[0]->body_a(); }
  int body_b() const override { return goals_[0]->body_b(); }
  std::unique_ptr<TermState> MakeState() const override {
    auto s = std::make_unique<State>();
    for (const auto& g : goals_) s->goals.push_back(g->MakeState());
    s->r.resize(dim_);
    s->ja.resize(dim_, 7);
    s->jb.resize(dim_, 7);
    return s;
  }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override {
    auto* s = static_cast<State*>(state);
    double best = INFINITY;
    r.setZero();
    J_a.setZero();
    J_b.setZero();
    for (size_t k = 0; k < goals_.size(); ++k) {
      const TermPtr& g = goals_[k];
      const int n = g->dim();
      g->Evaluate(poses, s->goals[k].get(), s->r.head(n), s->ja.topRows(n), s->jb.topRows(n));
      const double v = s->r.head(n).squaredNorm();
      if (v < best) {
        best = v;
        r.setZero();
        J_a.setZero();
        J_b.setZero();
        r.head(n) = s->r.head(n);
        J_a.topRows(n) = s->ja.topRows(n);
        J_b.topRows(n) = s->jb.topRows(n);
      }
    }
  }

 private:
  std::vector<TermPtr> goals_;
  int dim_ = 0;
};

}  // namespace

std::unique_ptr<TermState> PositionGoalTerm::MakeState() const {
  auto s = std::make_unique<State>();
  s->target = initial_target_;
  return s;
}

void PositionGoalTerm::Evaluate(const std::vector<BodyPose>& poses, TermState* state,
                                Eigen::Ref<Eigen::VectorXd> r, Eigen::Ref<Eigen::MatrixXd> J_a,
                                Eigen::Ref<Eigen::MatrixXd>) const {
  const BodyPose& p = PoseOf(poses, at_.body);
  r.head<3>() = p.Point(at_.point) - static_cast<const State*>(state)->target;
  J_a.topLeftCorner<3, 7>() = contact::PointJacobian(p, at_.point);  // (fixed size: see above)
}

void PositionGoalTerm::AddWeightedHessian(const std::vector<BodyPose>&, TermState* /*state*/,
                                          const Eigen::Ref<const Eigen::VectorXd>& w,
                                          TermHessian* h) const {
  h->W_a.noalias() += w.head<3>() * at_.point.transpose();
}

std::shared_ptr<PositionGoalTerm> MakePositionGoal(const Attachment& at, const Eigen::Vector3d& t) {
  return std::make_shared<PositionGoalTerm>(at, t);
}
TermPtr PositionGoal(const Attachment& at, const Eigen::Vector3d& t) {
  return MakePositionGoal(at, t);
}
TermPtr OrientationGoal(int body, const Eigen::Matrix3d& R, const Eigen::Vector3d& w) {
  return std::make_shared<OrientationGoalTerm>(body, R, w);
}
std::shared_ptr<OrientationGoalTerm> MakeOrientationGoal(int body, const Eigen::Matrix3d& R,
                                                         const Eigen::Vector3d& w) {
  return std::make_shared<OrientationGoalTerm>(body, R, w);
}
TermPtr PoseGoal(const Attachment& at, const Eigen::Vector3d& t, const Eigen::Matrix3d& R,
                 const Eigen::Vector3d& w) {
  return std::make_shared<Concat>(PositionGoal(at, t), OrientationGoal(at.body, R, w));
}
TermPtr AimingGoal(const Attachment& at, const Eigen::Vector3d& t) {
  return std::make_shared<Aiming>(at, t);
}
TermPtr LineGoal(const Attachment& at, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  if (!(d.norm() > 0)) throw std::invalid_argument("line goal: zero direction");
  return std::make_shared<Line>(at, o, d);
}
TermPtr PlaneGoal(const Attachment& at, const Eigen::Vector3d& o, const Eigen::Vector3d& n) {
  if (!(n.norm() > 0)) throw std::invalid_argument("plane goal: zero normal");
  return std::make_shared<Plane>(at, o, n, false, false);
}
TermPtr HalfSpaceGoal(const Attachment& at, const Eigen::Vector3d& o, const Eigen::Vector3d& n,
                      bool one_sided) {
  if (!(n.norm() > 0)) throw std::invalid_argument("half-space goal: zero normal");
  return std::make_shared<Plane>(at, o, n, true, one_sided);
}
TermPtr DisjunctionGoal(std::vector<TermPtr> goals) {
  return std::make_shared<Disjunction>(std::move(goals));
}

namespace {

class ShiftedTerm final : public Term {
 public:
  ShiftedTerm(TermPtr term, const Eigen::VectorXd& rhs) : term_(std::move(term)), rhs_(rhs) {}
  std::string name() const override { return term_->name(); }
  int dim() const override { return term_->dim(); }
  int body_a() const override { return term_->body_a(); }
  int body_b() const override { return term_->body_b(); }
  std::unique_ptr<TermState> MakeState() const override {
    auto st = std::make_unique<ShiftedState>();
    st->inner = term_->MakeState();
    st->rhs = rhs_;
    return st;
  }
  void Evaluate(const std::vector<BodyPose>& poses, TermState* state, Eigen::Ref<Eigen::VectorXd> r,
                Eigen::Ref<Eigen::MatrixXd> J_a, Eigen::Ref<Eigen::MatrixXd> J_b) const override {
    auto* st = static_cast<ShiftedState*>(state);
    term_->Evaluate(poses, st->inner.get(), r, J_a, J_b);
    r -= st->rhs;
  }
  bool has_hessian() const override { return term_->has_hessian(); }
  void AddWeightedHessian(const std::vector<BodyPose>& poses, TermState* state,
                          const Eigen::Ref<const Eigen::VectorXd>& w,
                          TermHessian* h) const override {
    term_->AddWeightedHessian(poses, static_cast<ShiftedState*>(state)->inner.get(), w, h);
  }

 private:
  TermPtr term_;
  Eigen::VectorXd rhs_;
};

}  // namespace

TermPtr Shifted(TermPtr term, const Eigen::VectorXd& rhs) {
  TANGENT_REQUIRE(term != nullptr, "shifted term: null term");
  TANGENT_REQUIRE(
      rhs.size() == term->dim() && rhs.allFinite(),
      "shifted term: rhs must have the term's " + std::to_string(term->dim()) + " finite values");
  return std::make_shared<ShiftedTerm>(std::move(term), rhs);
}

}  // namespace tangent::optimizer
