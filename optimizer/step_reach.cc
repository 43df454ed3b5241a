#include "optimizer/step_reach.h"

#include <algorithm>

#include <Eigen/Geometry>

namespace tangent::optimizer {

double ReachFraction(const Problem& problem, const ProblemData& data, const Eigen::VectorXd& q,
                     const Eigen::VectorXd& step) {
  const Mechanism& m = problem.mechanism();
  // The displacement of world point p fixed on body b by the full step.
  auto moved = [&](int b, const Eigen::Vector3d& p) -> Eigen::Vector3d {
    const int o = b >= 0 ? m.offset(b) : -1;
    if (o < 0) return Eigen::Vector3d::Zero();
    const Eigen::Quaterniond Q0(q[o + 3], q[o + 4], q[o + 5], q[o + 6]);
    const Eigen::Vector4d q1 = q.segment<4>(o + 3) + step.segment<4>(o + 3);
    const Eigen::Quaterniond Q1(q1[0], q1[1], q1[2], q1[3]);
    const Eigen::Vector3d p_B = Q0.normalized().conjugate() * (p - q.segment<3>(o));
    return q.segment<3>(o) + step.segment<3>(o) + Q1.normalized() * p_B - p;
  };
  double alpha = 1.0;
  const auto& rows = problem.inequalities();
  for (size_t i = 0; i < rows.size(); ++i) {
    const Term& t = *rows[i].term;
    Eigen::Vector3d p;
    double reach = 0.0;
    if (!t.Reach(data.state(1, static_cast<int>(i)), &p, &reach)) continue;
    const double d = (moved(t.body_a(), p) - moved(t.body_b(), p)).norm();
    if (d > reach) alpha = std::min(alpha, reach / d);
  }
  return alpha;
}

}  // namespace tangent::optimizer
