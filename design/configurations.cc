#include "design/configurations.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "optimizer/joints.h"

namespace tangent::design {

Eigen::VectorXd ConfigurationsSpec::Gather(int k, const Eigen::VectorXd& q) const {
  const std::vector<int>& map = gather[static_cast<size_t>(k)];
  Eigen::VectorXd q_k(static_cast<Eigen::Index>(map.size()));
  for (size_t i = 0; i < map.size(); ++i) q_k[static_cast<Eigen::Index>(i)] = q[map[i]];
  return q_k;
}

void ConfigurationsSpec::ScatterAdd(int k, const Eigen::VectorXd& g_k, Eigen::VectorXd* g) const {
  const std::vector<int>& map = gather[static_cast<size_t>(k)];
  for (size_t i = 0; i < map.size(); ++i) (*g)[map[i]] += g_k[static_cast<Eigen::Index>(i)];
}

std::unique_ptr<server::Scene> Replicate(ConfigurationsSpec* c) {
  const server::Scene& base = *c->base;
  const optimizer::Mechanism& mech = base.mechanism;
  const int K = c->size();
  // The design side: fixed bodies and whatever design and fixed joints join to them.
  auto is_design = [&](int j) {
    return std::find(c->design_joints.begin(), c->design_joints.end(), j) != c->design_joints.end();
  };
  c->shared_body.assign(static_cast<size_t>(mech.num_bodies()), false);
  for (int b = 0; b < mech.num_bodies(); ++b)
    c->shared_body[static_cast<size_t>(b)] = mech.body(b).fixed;
  for (bool grew = true; grew;) {
    grew = false;
    for (size_t j = 0; j < base.joints.size(); ++j) {
      const server::JointSpec& js = base.joints[j];
      if (!is_design(static_cast<int>(j)) && js.type != "fixed") continue;
      auto a = c->shared_body.begin() + js.a.body, b = c->shared_body.begin() + js.b.body;
      if (*a != *b) {
        *a = *b = true;
        grew = true;
      }
    }
  }
  auto shared = [&](int body) {
    return static_cast<bool>(c->shared_body[static_cast<size_t>(body)]);
  };
  for (int j : c->design_joints) {
    const server::JointSpec& js = base.joints[static_cast<size_t>(j)];
    if (!shared(js.a.body) || !shared(js.b.body)) {
      throw std::invalid_argument(
          "design joint \"" + js.name +
          "\" would move with the configurations: with configurations, a design joint must join "
          "bodies held to the ground by design and fixed joints only (an adjustable pivot's "
          "slider on the ground side), so that one design serves every configuration");
    }
  }
  const server::JointSpec& cj = base.joints[static_cast<size_t>(c->joint)];
  if (shared(cj.a.body) && shared(cj.b.body)) {
    throw std::invalid_argument("the configuration joint \"" + cj.name +
                                "\" joins two bodies on the design side: it moves nothing");
  }

  auto out = std::make_unique<server::Scene>();
  server::Scene& s = *out;
  s.name = base.name + " at " + std::to_string(K) + " configurations";
  s.path = base.path;
  c->bodies.assign(static_cast<size_t>(K),
                   std::vector<int>(static_cast<size_t>(mech.num_bodies())));
  // Each copy's bodies first, in order, then the shared ones: the Newton matrix is then block
  // diagonal with a border (an arrow), which the sparse solver's natural ordering factorizes
  // without fill. (Shared bodies first, every copy couples through them on the first pivots and
  // the factor filled in completely: measured, 463k instructions per factorization of the
  // four-bar at seven angles, 44 % of its run in the starts' settling solves.)
  for (int k = 0; k < K; ++k) {
    for (int b = 0; b < mech.num_bodies(); ++b) {
      if (shared(b)) continue;
      optimizer::Body copy = mech.body(b);
      copy.name += "@" + std::to_string(k + 1);
      c->bodies[static_cast<size_t>(k)][static_cast<size_t>(b)] = s.mechanism.AddBody(copy);
    }
  }
  for (int b = 0; b < mech.num_bodies(); ++b) {
    if (!shared(b)) continue;
    const int r = s.mechanism.AddBody(mech.body(b));
    for (int k = 0; k < K; ++k) c->bodies[static_cast<size_t>(k)][static_cast<size_t>(b)] = r;
  }
  c->joints.assign(static_cast<size_t>(K), std::vector<int>(base.joints.size()));
  for (size_t j = 0; j < base.joints.size(); ++j) {
    const server::JointSpec& js = base.joints[j];
    const bool one = shared(js.a.body) && shared(js.b.body);
    for (int k = 0; k < (one ? 1 : K); ++k) {
      server::JointSpec r = js;
      r.a.body = c->Body(k, js.a.body);
      r.b.body = c->Body(k, js.b.body);
      if (!one) r.name += "@" + std::to_string(k + 1);
      r.term = optimizer::MakeJoint(r.type, r.a, r.b);
      if (js.limits) r.limits = optimizer::RevoluteLimits(r.a, r.b, js.limit_lo, js.limit_hi);
      const int index = static_cast<int>(s.joints.size());
      s.joints.push_back(std::move(r));
      for (int m = k; m < (one ? K : k + 1); ++m) {
        c->joints[static_cast<size_t>(m)][j] = index;
      }
    }
  }
  c->gather.assign(static_cast<size_t>(K),
                   std::vector<int>(static_cast<size_t>(mech.num_coordinates())));
  for (int k = 0; k < K; ++k) {
    for (int b = 0; b < mech.num_bodies(); ++b) {
      if (mech.offset(b) < 0) continue;
      const int r = s.mechanism.offset(c->Body(k, b));
      for (int i = 0; i < 7; ++i) {
        c->gather[static_cast<size_t>(k)][static_cast<size_t>(mech.offset(b) + i)] = r + i;
      }
    }
  }
  s.device = base.device;
  s.least_astonishment = base.least_astonishment;
  return out;
}

WorstCase::WorstCase(Terms terms, const ConfigurationsSpec* c, bool lowest)
    : terms_(std::move(terms)), c_(c), lowest_(lowest) {
  if (c_->size() < 1) throw std::invalid_argument("worst case: no configuration");
  if (!(c_->tolerance > 0.0)) throw std::invalid_argument("worst case: tolerance must be > 0");
  // ρ = log(K)/δ; with one configuration the aggregate is F itself (any ρ).
  rho_ = c_->size() > 1 ? std::log(static_cast<double>(c_->size())) / c_->tolerance : 1.0;
}

Eigen::VectorXd WorstCase::PerCopy(const Eigen::VectorXd& q) const {
  Eigen::VectorXd F = Eigen::VectorXd::Zero(c_->size());
  for (int k = 0; k < c_->size(); ++k) {
    const Eigen::VectorXd q_k = c_->Gather(k, q);
    for (const auto& [f, w] : terms_) F[k] += w * f->Value(q_k);
  }
  return F;
}

double WorstCase::Aggregate(const Eigen::VectorXd& F) const {
  // e + (σ/ρ) log((1/K) Σ exp(σρ(F_k − e))), e the extreme: no overflow, exact when all agree.
  const double sigma = lowest_ ? -1.0 : 1.0;
  const double e = lowest_ ? F.minCoeff() : F.maxCoeff();
  const double mean = (sigma * rho_ * (F.array() - e)).exp().mean();
  return e + sigma / rho_ * std::log(mean);
}

double WorstCase::Value(const Eigen::VectorXd& q) const { return Aggregate(PerCopy(q)); }

void WorstCase::Gradient(const Eigen::VectorXd& q, Eigen::VectorXd* g) const {
  const Eigen::VectorXd F = PerCopy(q);
  const double sigma = lowest_ ? -1.0 : 1.0;
  const double e = lowest_ ? F.minCoeff() : F.maxCoeff();
  const Eigen::ArrayXd w = (sigma * rho_ * (F.array() - e)).exp();
  const Eigen::ArrayXd pi = w / w.sum();  // ∂KS/∂F_k
  g->setZero(q.size());
  Eigen::VectorXd g_k;
  for (int k = 0; k < c_->size(); ++k) {
    const Eigen::VectorXd q_k = c_->Gather(k, q);
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(q_k.size());
    for (const auto& [f, weight] : terms_) {
      f->Gradient(q_k, &g_k);
      sum += weight * g_k;
    }
    c_->ScatterAdd(k, pi[k] * sum, g);
  }
}

}  // namespace tangent::design
