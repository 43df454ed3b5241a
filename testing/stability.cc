#include "testing/stability.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

#include "contact/extremal.h"
#include "nurbs/primitives.h"
#include "optimizer/contacts.h"
#include "server/global_link.h"
#include "server/phantom.h"
#include "server/servo.h"
#include "testing/conformal_scenes.h"
#include "testing/contact_scenes.h"
#include "testing/drag_path.h"

namespace tangent::testing {

const char* ToString(Outcome o) {
  switch (o) {
    case Outcome::kConverged:
      return "converged";
    case Outcome::kFlagged:
      return "flagged";
    case Outcome::kDegraded:
      return "degraded";
    case Outcome::kFailed:
      return "failed";
  }
  return "?";
}

bool StabilityRow::Passed() const {
  const bool bounded = !servo || force_max <= max_force * (1.0 + 1e-12);
  return finite && bounded && outcome == expected;
}

namespace {

using contact::BodyPose;
using contact::ExtremalStatus;
using contact::Vector7d;
using contact::testing::Coordinates;
using contact::testing::Paraboloid;

const Vector7d kIdentity = Coordinates(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());

// ---- Kinematic cases -------------------------------------------------------------------------

struct KinematicSpec {
  KinematicSpec(std::string name_in, nurbs::NurbsSurface f_in, nurbs::NurbsSurface g_in,
                const Vector7d& q_f_in, const Vector7d& q_g_in)
      : name(std::move(name_in)),
        f(std::move(f_in)),
        g(std::move(g_in)),
        q_f(q_f_in),
        q_g(q_g_in) {}
  std::string name;
  nurbs::NurbsSurface f, g;
  Vector7d q_f, q_g;
  std::vector<Eigen::Vector4d> seeds;
  double beta = 0.0;  ///< exact β at q_f, q_g
  Outcome expected = Outcome::kConverged;
  /// Per seed, where a seed's documented outcome differs from `expected` (with its reason).
  std::vector<std::pair<size_t, Outcome>> expected_for_seed;
  std::string seed_note;
  /// The pose of f at step k of the path (k = 1 .. steps); default: seeded small random moves.
  std::function<Vector7d(int)> path;
  int steps = 20;
  std::string note;
};

Outcome OutcomeOf(ExtremalStatus s) {
  switch (s) {
    case ExtremalStatus::kConverged:
      return Outcome::kConverged;
    case ExtremalStatus::kAtBoundary:
    case ExtremalStatus::kSingular:
    case ExtremalStatus::kInvalidInput:
      return Outcome::kFlagged;
    case ExtremalStatus::kNotConverged:
      return Outcome::kDegraded;
  }
  return Outcome::kFailed;
}

std::vector<StabilityRow> RunKinematic(const KinematicSpec& c) {
  std::vector<StabilityRow> rows;
  for (size_t k = 0; k < c.seeds.size(); ++k) {
    StabilityRow row;
    row.name = c.name;
    row.start = "seed " + std::to_string(k + 1);
    row.expected = c.expected;
    row.error_what = "|β − exact| (m)";
    row.note = c.note;
    for (const auto& [seed, outcome] : c.expected_for_seed) {
      if (seed == k) {
        row.expected = outcome;
        row.note = c.seed_note;
      }
    }
    if (!c.seeds[k].allFinite()) {
      // The term refuses a non-finite seed at construction (std::invalid_argument, before the
      // servo runs); the solver behind it reports it as invalid input with finite outputs.
      bool refused = false;
      try {
        optimizer::SurfaceContactTerm term(0, &c.f, 1, &c.g, c.seeds[k]);
      } catch (const std::invalid_argument&) {
        refused = true;
      }
      const contact::SurfaceSurfaceExtremum e = contact::SolveSurfaceSurface(
          c.f, BodyPose::FromCoordinates(c.q_f), c.g, BodyPose::FromCoordinates(c.q_g), c.seeds[k]);
      row.outcome = refused ? OutcomeOf(e.status) : Outcome::kFailed;
      row.finite = e.u.allFinite() && e.p_f.allFinite() && e.p_g.allFinite() && e.n_g.allFinite() &&
                   !std::isnan(e.beta);
      row.error_what = "— (refused by the term; the solver: invalid input)";
      if (!row.finite) row.outcome = Outcome::kFailed;
      rows.push_back(row);
      continue;
    }
    // The servo's contact term: tracker, exactness check, extremal solve (as a slot runs it).
    optimizer::SurfaceContactTerm term(0, &c.f, 1, &c.g, c.seeds[k]);
    auto state = term.MakeState();
    auto* st = static_cast<optimizer::SurfaceContactTerm::State*>(state.get());
    std::vector<BodyPose> poses = {BodyPose::FromCoordinates(c.q_f),
                                   BodyPose::FromCoordinates(c.q_g)};
    Eigen::VectorXd r(1);
    Eigen::MatrixXd J_a(1, 7), J_b(1, 7);
    term.Evaluate(poses, state.get(), r, J_a, J_b);
    const contact::SurfaceSurfaceExtremum first = st->ext;
    row.outcome = OutcomeOf(first.status);
    row.iterations = first.iterations;
    row.finite = first.u.allFinite() && std::isfinite(r[0]) && J_a.allFinite() && J_b.allFinite();
    // A NaN or infinite distance on finite input is a failure, whatever the status says.
    if (first.status != ExtremalStatus::kInvalidInput) {
      row.finite = row.finite && std::isfinite(first.beta);
      row.error = std::abs(first.beta - c.beta);
    } else {
      row.error = 0.0;
      row.error_what = "— (no solve: invalid input reported)";
    }
    // Along the path: each β against a fresh solve from the term's previous parameters.
    std::mt19937_64 rng(1234 + k);
    std::normal_distribution<double> n(0.0, 1.0);
    Vector7d q = c.q_f;
    for (int step = 1; step <= c.steps && first.status != ExtremalStatus::kInvalidInput; ++step) {
      if (c.path) {
        q = c.path(step);
      } else {
        q.head<3>() += 1e-4 * Eigen::Vector3d(n(rng), n(rng), n(rng));
        Eigen::Quaterniond rot(q[3], q[4], q[5], q[6]);
        rot = Eigen::Quaterniond(
                  Eigen::AngleAxisd(1e-3, Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized())) *
              rot;
        q.tail<4>() << rot.w(), rot.x(), rot.y(), rot.z();
      }
      const Eigen::Vector4d before = st->u;
      poses[0] = BodyPose::FromCoordinates(q);
      term.Evaluate(poses, state.get(), r, J_a, J_b);
      const contact::SurfaceSurfaceExtremum fresh = contact::SolveSurfaceSurface(
          c.f, poses[0], c.g, poses[1], before, contact::kContinuation);
      row.finite = row.finite && std::isfinite(r[0]) && J_a.allFinite() && J_b.allFinite() &&
                   st->ext.u.allFinite();
      if (std::isfinite(fresh.beta))
        row.path_error = std::max(row.path_error, std::abs(st->ext.beta - fresh.beta));
      if (st->ext.status == ExtremalStatus::kNotConverged && row.outcome == Outcome::kConverged)
        row.outcome = Outcome::kDegraded;
    }
    if (!row.finite) row.outcome = Outcome::kFailed;
    rows.push_back(row);
  }
  return rows;
}

std::vector<KinematicSpec> KinematicSpecs() {
  std::vector<KinematicSpec> specs;
  const Eigen::Quaterniond quarter_x(
      Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()));
  {
    // A 5 mm sphere centred at the focal point of a paraboloid (vertex radius 2 cm).
    const double k = 50.0;
    KinematicSpec c("focal point", nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.005),
                    Paraboloid(k, 0.02), Coordinates({0, 0, 1.0 / k}, quarter_x), kIdentity);
    c.seeds = {{0.74, 0.52, 0.52, 0.48}, {0.76, 0.49, 0.49, 0.51}, {0.75, 0.5, 0.5, 0.5}};
    c.beta = 1.0 / k - 0.005;
    c.expected = Outcome::kFlagged;
    c.note = "∂F/∂u singular: status singular, u_q refused";
    specs.push_back(std::move(c));
  }
  {
    KinematicSpec c("continuum: concentric spheres",
                    nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.03),
                    nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05), kIdentity, kIdentity);
    c.seeds = {{0.3, 0.45, 0.32, 0.47}, {0.6, 0.55, 0.58, 0.52}, {0.1, 0.3, 0.12, 0.33}};
    c.beta = -0.02;
    c.expected = Outcome::kFlagged;
    c.note = "one pair of the continuum, flagged singular";
    specs.push_back(std::move(c));
  }
  {
    KinematicSpec c("continuum: coaxial cylinders", nurbs::MakeCylinder(0.02, 0.1),
                    nurbs::MakeCylinder(0.05, 0.1), kIdentity, kIdentity);
    c.seeds = {{0.3, 0.4, 0.31, 0.45}, {0.7, 0.6, 0.69, 0.58}};
    c.beta = -0.03;
    c.expected = Outcome::kFlagged;
    c.note = "as above";
    specs.push_back(std::move(c));
  }
  {
    KinematicSpec c(
        "continuum: plane on plane", nurbs::MakePlanePatch({0, 0, 0.01}, {0.1, 0, 0}, {0, -0.1, 0}),
        nurbs::MakePlanePatch({0, -0.1, 0}, {0.1, 0, 0}, {0, 0.1, 0}), kIdentity, kIdentity);
    c.seeds = {{0.3, 0.4, 0.35, 0.5}, {0.6, 0.2, 0.55, 0.75}};
    c.beta = 0.01;
    c.expected = Outcome::kFlagged;
    c.note = "as above";
    specs.push_back(std::move(c));
  }
  {
    // A sphere's south pole (S_u = 0) above a plane.
    KinematicSpec c("pole over a plane", nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05),
                    nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0}),
                    Coordinates({0.01, 0.02, 0.06}, Eigen::Quaterniond::Identity()), kIdentity);
    c.seeds = {{0.3, 0.03, 0.5, 0.5}, {0.8, 0.0, 0.52, 0.55}, {0.1, 0.1, 0.45, 0.5}};
    c.beta = 0.01;
    c.note = "the pole itself returned as the minimum";
    // Moved a little, the contact sits 1e-4 … 1e-3 from the pole in v, where u hardly matters
    // and swings by up to 0.3 a step. Newton in (u, v) was only linear there (4 to 106
    // iterations a step, one at the iteration limit); in the pole's chart (contact/pole_chart.h)
    // each step converges.
    specs.push_back(std::move(c));
  }
  {
    // A ball's pole touching a hole's wall, the ball moved across touching (pole_test.cc).
    const nurbs::NurbsSurface wall =
        nurbs::Transformed(nurbs::ReversedU(nurbs::MakeCylinder(5e-3, 10e-3)),
                           Eigen::Isometry3d(Eigen::Translation3d(0, 0, -10e-3)));
    const nurbs::NurbsSurface ball =
        nurbs::Transformed(nurbs::MakeSphere({0, 0, 0}, 4e-3), Eigen::Isometry3d(quarter_x));
    // f = the ball (moved), g = the wall (fixed).
    KinematicSpec c("pole sliding on a hole's wall", ball, wall,
                    Coordinates({0, 0.9e-3, -6e-3}, Eigen::Quaterniond::Identity()), kIdentity);
    c.seeds = {{0.509, 0.0, 0.75, 0.4}, {0.5, 0.02, 0.76, 0.41}};
    c.beta = 1e-3 - 0.9e-3;
    c.steps = 100;
    c.path = [](int k) {
      return Coordinates({0, 0.9e-3 + 2e-6 * k, -6e-3}, Eigen::Quaterniond::Identity());
    };
    c.note = "the pole's contact through touching (β +0.1 → −0.1 mm)";
    specs.push_back(std::move(c));
  }
  {
    KinematicSpec c(
        "partials at 3°", nurbs::MakeShearedPatch(3 * std::numbers::pi / 180, 0.08, 0.01, false),
        nurbs::MakeTorus(0.04, 0.01),
        Coordinates({-0.03, 0.0, 0.025}, Eigen::Quaterniond(Eigen::AngleAxisd(
                                             std::numbers::pi, Eigen::Vector3d::UnitX()))),
        kIdentity);
    const BodyPose pf = BodyPose::FromCoordinates(c.q_f), pg = BodyPose::FromCoordinates(c.q_g);
    const Eigen::Vector4d s = contact::ClosestSamplePair(c.f, pf, c.g, pg, 60);
    c.seeds = {s, s + Eigen::Vector4d(0.01, -0.01, 0.005, 0.005)};
    // No closed form: the converged solve from the closest samples is the reference.
    c.beta = contact::SolveSurfaceSurface(c.f, pf, c.g, pg, s).beta;
    c.note = "error against the solve from the closest samples";
    specs.push_back(std::move(c));
  }
  {
    // A 5 cm sphere whose centre is 3 cm below a plane: β = −8 cm, a saddle of ½|d|².
    KinematicSpec c("deep interpenetration", nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05),
                    nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0}),
                    Coordinates({0, 0, -0.03}, quarter_x), kIdentity);
    for (double off : {0.0, 0.01, 0.02, 0.04})
      c.seeds.push_back({0.75 + off, 0.5 - off, 0.5 + off, 0.5 - off});
    c.beta = -0.08;
    specs.push_back(std::move(c));
  }
  {
    // A 1 cm sphere beside a 2 cm plane patch: the extremum is on the patch's edge.
    KinematicSpec c("extremum at a domain edge", nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.01),
                    nurbs::MakePlanePatch({0, 0, 0}, {0.02, 0, 0}, {0, 0.02, 0}),
                    Coordinates({0.03, 0.01, 0.02}, Eigen::Quaterniond::Identity()), kIdentity);
    c.seeds = {{0.5, 0.3, 0.5, 0.5}, {0.2, 0.4, 0.9, 0.5}};
    // The sphere's nearest point to the edge x = 0.02 (z = 0): the centre is 0.01 beyond the
    // edge and 0.02 above it.
    c.beta = std::hypot(0.01, 0.02) - 0.01;
    c.expected = Outcome::kFlagged;
    c.note = "held on the edge: status at_boundary";
    specs.push_back(std::move(c));
  }
  {
    // A non-finite seed: reported, never a NaN out.
    KinematicSpec c("non-finite seed", nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05),
                    nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0}),
                    Coordinates({0.01, 0.02, 0.08}, quarter_x), kIdentity);
    c.seeds = {{std::nan(""), 0.5, 0.5, 0.5}};
    c.beta = 0.03;
    c.expected = Outcome::kFlagged;
    c.note = "refused at construction; the solver reports invalid input";
    specs.push_back(std::move(c));
  }
  {
    // A tracking jump: the ball turned 2.5 rad in one step (the tracker reports lost; the term
    // re-solves from its last parameters).
    KinematicSpec c("tracking jump (2.5 rad in one step)",
                    nurbs::MakeSphere(Eigen::Vector3d::Zero(), 0.05),
                    nurbs::MakePlanePatch({-0.2, -0.2, 0}, {0.4, 0, 0}, {0, 0.4, 0}),
                    Coordinates({0.01, 0.02, 0.08}, quarter_x), kIdentity);
    c.seeds = {{0.75, 0.5, 0.5, 0.5}, {0.7, 0.45, 0.55, 0.5}};
    c.beta = 0.03;
    c.steps = 3;
    c.path = [quarter_x](int k) {
      const Eigen::Quaterniond turn(
          Eigen::AngleAxisd(k == 1 ? 2.5 : 2.5 + 0.01 * k, Eigen::Vector3d(1, 1, 0).normalized()));
      return Coordinates({0.01, 0.02, 0.08}, turn * quarter_x);
    };
    c.note = "lost, then a full solve: β equal to a fresh solve's";
    specs.push_back(std::move(c));
  }
  return specs;
}

// ---- Servo cases -----------------------------------------------------------------------------

struct ServoSpec {
  std::string name, start;
  std::function<std::unique_ptr<server::Scene>()> scene;
  std::function<Eigen::Vector3d(double)> hand;
  double seconds = 2.0;
  Outcome expected = Outcome::kConverged;
  std::string note;
  server::ServoOptions options = {};
  /// A whole device state (position and orientation) for device step k at time at_ns, instead
  /// of `hand`'s position on the drag's state; and a run of its own length when > 0 (a case
  /// whose event lies beyond the suite's seconds).
  std::function<server::DeviceSample(int64_t k, int64_t at_ns)> device = {};
  double own_seconds = 0.0;
  /// A case that holds a load: the force at the hand at the end must be at least this (N),
  /// else the parts came apart and the row fails.
  double min_final_force = 0.0;
};

StabilityRow RunServo(const ServoSpec& c) {
  StabilityRow row;
  row.name = c.name;
  row.start = c.start;
  row.expected = c.expected;
  row.servo = true;
  row.error_what = "max constraint violation (m)";
  row.note = c.note;
  const std::unique_ptr<server::Scene> scene = c.scene();
  row.max_force = scene->device.max_force;
  server::ServoLoop servo(*scene, c.options);
  server::GlobalLink link(servo);
  server::TickResult r;
  server::Snapshot snap;
  const int64_t t0 = 1'000'000'000;
  const int ticks = static_cast<int>((c.own_seconds > 0.0 ? c.own_seconds : c.seconds) * 4000.0);
  Eigen::Vector3d last_f = Eigen::Vector3d::Zero();
  int64_t last_ns = 0;
  int64_t faults = 0, iterations = 0, off_tolerance = 0;
  server::DeviceSample s;
  int64_t sample = -1;
  for (int i = 0; i < ticks; ++i) {
    const int64_t now = t0 + 250'000LL * i;
    const int64_t k = (now - t0) / 1'000'000;
    if (k != sample) {
      sample = k;
      if (c.device) {
        s = c.device(k, t0 + k * 1'000'000);
      } else {
        s = bench::DragSample(k + 1, 1e-3 * static_cast<double>(k), t0 + k * 1'000'000);
        const Eigen::Vector3d p = c.hand(1e-3 * static_cast<double>(k));
        for (int j = 0; j < 3; ++j) s.position[j] = p[j];
      }
    }
    servo.Tick(&s, now, &r);
    iterations += r.iterations;
    faults += r.fault;
    row.error = std::max(row.error, r.violation);
    off_tolerance += r.violation > 1e-6;
    const Eigen::Vector3d f(r.wrench.force[0], r.wrench.force[1], r.wrench.force[2]);
    if (!std::isfinite(r.violation) || !f.allFinite()) row.finite = false;
    if (r.answered) {
      row.force_max = std::max(row.force_max, f.norm());
      if (last_ns > 0) {
        const double dt =
            std::min(1e-9 * static_cast<double>(now - last_ns), 2.0 / scene->device.device_rate);
        const double ratio = (f - last_f).norm() / (scene->device.max_force_rate * dt);
        row.step_ratio = std::max(row.step_ratio, ratio);
      }
      last_f = f;
      last_ns = now;
    }
    if (i % 16 == 15) {
      servo.FillSnapshot(&snap);
      link.PassInto(&servo, snap);
    }
  }
  row.iterations = static_cast<double>(iterations) / std::max(1, ticks);
  const bool apart = last_f.norm() < c.min_final_force;
  if (apart) {
    row.note += (row.note.empty() ? "" : "; ") + std::string("apart: ") +
                std::to_string(last_f.norm()) + " N at the end";
  }
  if (!row.finite || faults > 0 || apart || row.force_max > row.max_force * (1 + 1e-12)) {
    row.outcome = Outcome::kFailed;
  } else if (off_tolerance > 0) {
    row.outcome = Outcome::kDegraded;
  } else {
    row.outcome = Outcome::kConverged;
  }
  if (faults > 0) row.note += (row.note.empty() ? "" : "; ") + std::to_string(faults) + " faults";
  return row;
}

std::string Num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

// A planar four-bar (ground 0.3 m, crank 0.1, coupler 0.3, rocker 0.15) with all four revolute
// axes along z: 20 joint equations on 18 coordinates, a rank-deficient closure (rank 17, one
// degree of freedom). The hand holds the coupler's middle; device scale 3 (a 4 cm hand motion is
// 12 cm in the scene, within the Touch's workspace).
std::string PlanarFourBar() {
  // The coupler–rocker joint P: |P − (0, 0.1)| = 0.3, |P − (0.3, 0)| = 0.15, upper branch.
  const double x = (5.025 + std::sqrt(5.025 * 5.025 - 40.0 * 0.61140625)) / 20.0;
  const double y = 3.0 * x - 0.7375;
  std::ostringstream s;
  s << R"({"name": "planar four-bar", "length_unit": "m",
  "bodies": [{"name": "ground", "fixed": true},
    {"name": "crank", "mass": 0.05, "inertia": [2e-4, 1e-5, 2e-4]},
    {"name": "coupler", "position": [0, 0.1, 0], "mass": 0.2, "inertia": [2e-3, 2e-3, 2e-3]},
    {"name": "rocker", "position": [0.3, 0, 0], "mass": 0.08, "inertia": [6e-4, 6e-4, 1e-5]}],
  "surfaces": [],
  "joints": [
    {"name": "crank", "type": "revolute", "a": {"body": "ground", "point": [0, 0, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]},
      "b": {"body": "crank", "point": [0, 0, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]}},
    {"name": "crank-coupler", "type": "revolute", "a": {"body": "crank", "point": [0, 0.1, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]},
      "b": {"body": "coupler", "point": [0, 0, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]}},
    {"name": "coupler-rocker", "type": "revolute", "a": {"body": "coupler", "point": [)"
    << Num(x) << ", " << Num(y - 0.1) << R"(, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]},
      "b": {"body": "rocker", "point": [)"
    << Num(x - 0.3) << ", " << Num(y) << R"(, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]}},
    {"name": "rocker", "type": "revolute", "a": {"body": "ground", "point": [0.3, 0, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]},
      "b": {"body": "rocker", "point": [0, 0, 0], "axis": [0, 0, 1], "reference": [1, 0, 0]}}],
  "grasp": {"body": "coupler", "point": [0.15, 0.025, 0]},
  "device": {"scale": 3.0, "stiffness": 300, "damping": 1.0}})";
  return s.str();
}

std::vector<ServoSpec> ServoSpecs(const std::string& scenes_dir, double seconds) {
  auto load = [scenes_dir](const std::string& name) {
    return [scenes_dir, name] { return server::LoadScene(scenes_dir + "/" + name + ".json"); };
  };
  auto planar = [] { return server::ParseScene(PlanarFourBar(), "planar four-bar"); };
  auto circle = [](double radius, double period) {
    return [radius, period](double t) {
      const double a = 2 * std::numbers::pi * t / period;
      return Eigen::Vector3d(radius * std::sin(a), radius * (std::cos(a) - 1.0), 0.0);
    };
  };
  std::vector<ServoSpec> specs;
  specs.push_back({"rank-deficient closure", "planar four-bar, 2 cm circles", planar,
                   circle(0.02 / 3, 2.0), seconds, Outcome::kConverged,
                   "20 joint equations, rank 17"});
  specs.push_back({"rank-deficient closure", "planar four-bar, 6 cm out of its plane", planar,
                   [](double t) { return Eigen::Vector3d(0, 0, 0.02 * std::min(1.0, t)); }, seconds,
                   Outcome::kConverged, "the hand pulls where no joint can follow"});
  specs.push_back({"near-singular poses", "planar four-bar, 10.5 cm circles (limit positions)",
                   planar, circle(0.035, 2.0), seconds, Outcome::kConverged,
                   "the rocker driven to its limit positions"});
  specs.push_back({"conflicting goals", "spatial four-bar, hand 4 cm off the coupler's path",
                   load("fourbar_point"),
                   [](double t) { return Eigen::Vector3d(0, 0, 0.04 * std::min(1.0, t)); }, seconds,
                   Outcome::kConverged,
                   "grasp goal against the closure: least squares, force saturated"});
  specs.push_back({"conflicting goals", "spatial four-bar, jerk of 5 cm", load("fourbar_point"),
                   [](double t) { return Eigen::Vector3d(t > 0.5 ? 0.05 : 0.0, 0, 0); }, seconds,
                   Outcome::kConverged, "a step the follow speed turns into a path"});
  specs.push_back({"paperclip hooks", "paperclips, the demo's drag", load("paperclips"),
                   bench::DragPath, seconds, Outcome::kConverged,
                   "two hook contacts, near-degenerate as the chain swings"});
  {
    std::ifstream f(scenes_dir + "/peg_in_hole.path.csv");
    std::stringstream text;
    text << f.rdbuf();
    auto path = std::make_shared<server::HandTrajectory>(
        server::HandTrajectory::FromCsv(text.str(), "peg_in_hole.path.csv"));
    // Its path at 10× speed, so even a short run crosses the rim and drops into the hole.
    specs.push_back({"contact over a trim edge", "peg over the rim and into the hole (10× path)",
                     load("peg_in_hole"), [path](double t) { return path->At(10.0 * t); }, seconds,
                     Outcome::kConverged, "face → edge → wall contacts"});
  }
  // Issue 33's canonical conformal contacts (testing/conformal_scenes.h), pressed 2 mm within
  // half a second and then moved (tests/server/conformal_test.cc checks their forces).
  auto press = [](double t) { return -2e-3 * std::min(1.0, 2.0 * t); };
  {
    ServoSpec groove{"conformal contact",
                     "rod in a 1 % larger groove, pressed and slid",
                     [] { return server::ParseScene(kGrooveScene, "groove"); },
                     [press](double t) {
                       return Eigen::Vector3d(t > 0.5 ? 5e-3 * std::sin(3.0 * (t - 0.5)) : 0.0, 0,
                                              press(t));
                     },
                     seconds,
                     Outcome::kConverged,
                     "a line contact: three sections"};
    groove.options.line_contacts = true;
    specs.push_back(std::move(groove));
  }
  specs.push_back({"conformal contact", "ball in a 1 % larger socket, pressed and pushed round",
                   [] { return server::ParseScene(kSocketScene, "socket"); },
                   [press](double t) {
                     const double a = 2 * std::numbers::pi * t, r = t > 0.5 ? 3e-3 : 0.0;
                     return Eigen::Vector3d(r * std::cos(a), r * std::sin(a), press(t));
                   },
                   seconds, Outcome::kConverged, "a patch contact, found nested, on two poles"});
  specs.push_back({"conformal contact", "box's face on a floor, pressed and pushed round",
                   [] { return server::ParseScene(kBoxScene, "box"); },
                   [press](double t) {
                     const double a = 2 * std::numbers::pi * t, r = t > 0.5 ? 5e-3 : 0.0;
                     return Eigen::Vector3d(r * std::cos(a), r * std::sin(a), press(t));
                   },
                   seconds, Outcome::kConverged, "a face contact: held by its four corners"});
  {
    // The fourth: bench/hooks_turn's whole run at the suite's pace (a pass every 4 ms), pulled
    // 2 mm and turned ±40° about the contact normal in a sine of 8 s period (at most 31.4°/s):
    // the one contact point becomes a saddle at 14.5° and the pair is held on the minima either
    // side (tests/server/conformal_test.cc checks the load shared between them).
    ServoSpec hooks{"conformal contact",
                    "two wire hooks turned from crossing towards parallel and back",
                    [] { return server::ParseScene(kHooksScene, "hooks"); },
                    {},
                    seconds,
                    Outcome::kConverged,
                    "through the pitchfork both ways, 11 s whatever the suite's length"};
    hooks.options.dof = 6;
    hooks.device = [](int64_t k, int64_t at_ns) { return bench::HooksHandSample(k + 1, at_ns); };
    hooks.own_seconds = 11.0;
    hooks.min_final_force = 0.3;  // pulled with 0.6 N; apart, the hand feels nothing
    // Twice as fast (4 s period, at most 62.8°/s), held since the solver takes an indefinite
    // matrix's own Newton step (docs/optimizer.md; before, apart at 17° of the turn).
    ServoSpec fast = hooks;
    fast.start = "two wire hooks turned twice as fast (62.8°/s at the peak) and back";
    fast.device = [](int64_t k, int64_t at_ns) {
      return bench::HooksHandSample(k + 1, at_ns, /*period=*/4.0);
    };
    fast.note = "through the pitchfork at twice the bench's rate; 11 s whatever the suite's length";
    specs.push_back(std::move(hooks));
    specs.push_back(std::move(fast));
  }
  return specs;
}

}  // namespace

std::vector<StabilityCase> StabilityCases(const std::string& scenes_dir, double seconds) {
  std::vector<StabilityCase> cases;
  for (KinematicSpec& k : KinematicSpecs()) {
    auto spec = std::make_shared<KinematicSpec>(std::move(k));
    cases.push_back({spec->name, spec->note, [spec] { return RunKinematic(*spec); }});
  }
  for (ServoSpec& s : ServoSpecs(scenes_dir, seconds)) {
    auto spec = std::make_shared<ServoSpec>(std::move(s));
    cases.push_back({spec->name + ": " + spec->start, spec->note,
                     [spec] { return std::vector<StabilityRow>{RunServo(*spec)}; }});
  }
  return cases;
}

}  // namespace tangent::testing
