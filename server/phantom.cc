#include "server/phantom.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace tangent::server {

HandTrajectory HandTrajectory::BuiltIn(const std::string& name) {
  HandTrajectory h;
  h.name_ = name;
  const double mm = 1e-3, pi = std::numbers::pi;
  auto smooth = [](double s) { return s <= 0 ? 0.0 : s >= 1 ? 1.0 : s * s * (3 - 2 * s); };
  std::vector<std::pair<double, Eigen::Vector3d>> pts;
  if (name == "drag") {
    // 1 s still, lift 6 mm in 2 s, then circles of 4 mm radius in the x–y plane, 5 s each
    // (twelve whole circles: it ends where the first began, so it loops from 3 s).
    for (double t = 0; t <= 63.0 + 1e-9; t += 0.01) {
      Eigen::Vector3d x = Eigen::Vector3d::Zero();
      x.y() = 6 * mm * smooth((t - 1.0) / 2.0);
      if (t > 3.0) {
        const double a = 2 * pi * (t - 3.0) / 5.0;
        const double r = 4 * mm * smooth((t - 3.0) / 1.0);
        x.x() += r * std::sin(a);
        x.y() += r * (std::cos(a) - 1.0);
      }
      pts.push_back({t, x});
    }
  } else if (name == "circle") {
    for (double t = 0; t <= 60.0; t += 0.01) {
      const double r = 5 * mm * smooth(t / 1.0), a = 2 * pi * t / 4.0;
      pts.push_back({t, Eigen::Vector3d(r * std::sin(a), r * (1 - std::cos(a)), 0)});
    }
  } else if (name == "pull") {
    for (double t = 0; t <= 60.0; t += 0.01) {
      pts.push_back({t, Eigen::Vector3d(0, 6 * mm * std::sin(2 * pi * t / 3.0) * smooth(t), 0)});
    }
  } else if (name == "hold") {
    pts.push_back({0.0, Eigen::Vector3d::Zero()});
  } else {
    throw std::invalid_argument("unknown trajectory \"" + name +
                                "\" (built in: drag, circle, pull, hold; or a CSV file)");
  }
  for (const auto& [t, x] : pts) {
    h.t_.push_back(t);
    h.x_.push_back(x);
  }
  return h;
}

HandTrajectory HandTrajectory::FromCsv(const std::string& text, const std::string& where) {
  HandTrajectory h;
  h.name_ = where;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (n == 1) {
      if (line.rfind("t,x,y,z", 0) != 0) {
        throw std::invalid_argument(where + ":1: the header must be \"t,x,y,z\", got \"" + line +
                                    "\"");
      }
      continue;
    }
    if (line.empty()) continue;
    std::istringstream row(line);
    double v[4];
    char comma;
    bool ok = static_cast<bool>(row >> v[0]);
    for (int i = 1; i < 4 && ok; ++i) ok = static_cast<bool>(row >> comma >> v[i]) && comma == ',';
    if (!ok) {
      throw std::invalid_argument(where + ":" + std::to_string(n) +
                                  ": expected four numbers t,x,y,z, got \"" + line + "\"");
    }
    for (double x : v) {
      if (!std::isfinite(x)) {
        throw std::invalid_argument(where + ":" + std::to_string(n) + ": non-finite value");
      }
    }
    if (!h.t_.empty() && !(v[0] > h.t_.back())) {
      throw std::invalid_argument(where + ":" + std::to_string(n) + ": t must increase");
    }
    h.t_.push_back(v[0]);
    h.x_.emplace_back(v[1], v[2], v[3]);
  }
  if (h.t_.empty()) throw std::invalid_argument(where + ": no rows");
  return h;
}

void HandTrajectory::LoopFrom(double from) {
  if (from >= 0.0 && !(from < t_.back())) {
    throw std::invalid_argument(name_ + ": cannot loop from " + std::to_string(from) +
                                " s, the trajectory ends at " + std::to_string(t_.back()) + " s");
  }
  loop_from_ = from;
}

Eigen::Vector3d HandTrajectory::At(double t) const {
  if (loop_from_ >= 0.0 && t > t_.back()) {
    t = loop_from_ + std::fmod(t - loop_from_, t_.back() - loop_from_);
  }
  if (t <= t_.front()) return x_.front();
  if (t >= t_.back()) return x_.back();
  const size_t k = static_cast<size_t>(std::upper_bound(t_.begin(), t_.end(), t) - t_.begin());
  const double s = (t - t_[k - 1]) / (t_[k] - t_[k - 1]);
  return (1 - s) * x_[k - 1] + s * x_[k];
}

Eigen::Vector3d DeviceModel::Step(double dt, const Eigen::Vector3d& hand,
                                  const Eigen::Vector3d& hand_velocity,
                                  const Eigen::Vector3d& server_force) {
  Eigen::Vector3d f = server_force;
  if (!f.allFinite()) f.setZero();
  if (f.norm() > o_.max_force) f *= o_.max_force / f.norm();
  max_force_ = std::max(max_force_, f.norm());
  // Semi-implicit Euler with the damping terms implicit (stable at these gains for dt = 1 ms):
  // v⁺ = (v + dt (K_h (hand − x) + B_h v_hand + f) / m) / (1 + dt (B_h + b) / m).
  const Eigen::Vector3d explicit_force =
      o_.hand_stiffness * (hand - x_) + o_.hand_damping * hand_velocity + f;
  v_ = (v_ + dt * explicit_force / o_.mass) / (1.0 + dt * (o_.hand_damping + o_.damping) / o_.mass);
  const Eigen::Vector3d x_next = x_ + dt * v_;
  energy_ += f.dot(v_) * dt;
  x_ = x_next;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(x_[i]) > o_.workspace[i]) {
      x_[i] = std::copysign(o_.workspace[i], x_[i]);
      v_[i] = 0.0;
    }
  }
  return f;
}

Percentiles Percentiles::Of(std::vector<double> v) {
  Percentiles p;
  p.n = v.size();
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  auto at = [&](double q) {
    return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
  };
  p.p50 = at(0.5);
  p.p99 = at(0.99);
  p.p999 = at(0.999);
  p.max = v.back();
  return p;
}

double ForceRoughness(const std::vector<Eigen::Vector3d>& f) {
  if (f.size() < 3) return 0.0;
  double s = 0.0;
  for (size_t k = 2; k < f.size(); ++k) s += (f[k] - 2 * f[k - 1] + f[k - 2]).squaredNorm();
  return std::sqrt(s / static_cast<double>(f.size() - 2));
}

DriverWatchdog::DriverWatchdog(double timeout, double rate) : timeout_(timeout), rate_(rate) {
  if (!(timeout > 0.0)) {
    throw std::invalid_argument("watchdog: the timeout must be positive, got " +
                                std::to_string(timeout));
  }
  if (!(rate > 0.0)) {
    throw std::invalid_argument("watchdog: the force rate must be positive, got " +
                                std::to_string(rate));
  }
}

Eigen::Vector3d DriverWatchdog::Step(double t, double dt, const Eigen::Vector3d& wrench,
                                     double received) {
  const bool starved = received < 0.0 || t - received > timeout_;
  if (starved && !starved_ && received >= 0.0) ++trips_;
  starved_ = starved;
  const Eigen::Vector3d goal = starved || !wrench.allFinite() ? Eigen::Vector3d::Zero() : wrench;
  const Eigen::Vector3d step = goal - rendered_;
  const double max_step = rate_ * dt;
  const double n = step.norm();
  rendered_ += n > max_step ? Eigen::Vector3d(step * (max_step / n)) : step;
  return rendered_;
}

}  // namespace tangent::server
