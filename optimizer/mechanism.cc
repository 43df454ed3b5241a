#include "optimizer/mechanism.h"

#include <sstream>
#include <stdexcept>

#include "contact/rigid.h"

namespace tangent::optimizer {

int Mechanism::AddBody(Body body) {
  auto fail = [&](const std::string& what) {
    throw std::invalid_argument("body \"" + body.name + "\": " + what);
  };
  if (!body.pose.allFinite()) fail("pose has a non-finite coordinate");
  if (!(body.pose.tail<4>().norm() > 0.0)) fail("quaternion is zero");
  if (!body.fixed) {
    if (!(body.mass > 0.0) || !std::isfinite(body.mass)) fail("mass must be positive and finite");
    if (!body.inertia.allFinite() ||
        (body.inertia - body.inertia.transpose()).norm() > 1e-12 * body.inertia.norm()) {
      fail("inertia must be finite and symmetric");
    }
    if (!(body.rigidity >= 0.0)) fail("rigidity must be non-negative");
  }
  body.pose.tail<4>().normalize();
  offsets_.push_back(body.fixed ? -1 : 7 * num_moving_);
  if (!body.fixed) ++num_moving_;
  bodies_.push_back(std::move(body));
  return num_bodies() - 1;
}

Eigen::VectorXd Mechanism::InitialCoordinates() const {
  Eigen::VectorXd q(num_coordinates());
  for (int i = 0; i < num_bodies(); ++i) {
    if (offset(i) >= 0) q.segment<7>(offset(i)) = body(i).pose;
  }
  return q;
}

void Mechanism::Poses(const Eigen::VectorXd& q, std::vector<BodyPose>* poses) const {
  // Fixed bodies' poses never change: written when the vector is sized, kept after (a scene's
  // idle parts then cost nothing per evaluation).
  const bool sized = poses->size() == static_cast<size_t>(num_bodies());
  poses->resize(static_cast<size_t>(num_bodies()));
  for (int i = 0; i < num_bodies(); ++i) {
    if (offset(i) >= 0) {
      (*poses)[static_cast<size_t>(i)] = BodyPose::FromCoordinates(q.segment<7>(offset(i)));
    } else if (!sized) {
      (*poses)[static_cast<size_t>(i)] = BodyPose::FromCoordinates(body(i).pose);
    }
  }
}

void Mechanism::MetricBlocks(const Eigen::VectorXd& q,
                             std::vector<Eigen::Matrix<double, 7, 7>>* blocks) const {
  blocks->resize(static_cast<size_t>(num_moving()));
  for (int i = 0; i < num_bodies(); ++i) {
    const int o = offset(i);
    if (o < 0) continue;
    const Body& b = body(i);
    const Eigen::Vector4d Q = q.segment<4>(o + 3);
    const contact::Matrix34d G = contact::GBody(Q / Q.norm()) / Q.norm();
    Eigen::Matrix<double, 7, 7>& m = (*blocks)[static_cast<size_t>(o / 7)];
    m.setZero();
    m.topLeftCorner<3, 3>().diagonal().setConstant(b.rigidity * b.mass);
    m.bottomRightCorner<4, 4>().noalias() = b.rigidity * G.transpose() * b.inertia * G;
  }
}

void Mechanism::Metric(const Eigen::VectorXd& q, Eigen::MatrixXd* M) const {
  std::vector<Eigen::Matrix<double, 7, 7>> blocks;
  MetricBlocks(q, &blocks);
  M->setZero(num_coordinates(), num_coordinates());
  for (int k = 0; k < num_moving(); ++k)
    M->block<7, 7>(7 * k, 7 * k) = blocks[static_cast<size_t>(k)];
}

}  // namespace tangent::optimizer
