// The simulated device: trajectories (built-in, CSV with bad-input messages), the device model's
// energy bookkeeping, saturation and workspace limits.

#include "server/phantom.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace tangent::server {
namespace {

std::string CsvError(const std::string& text) {
  try {
    HandTrajectory::FromCsv(text, "hand.csv");
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(PhantomTest, TrajectoriesAndTheirErrors) {
  const HandTrajectory drag = HandTrajectory::BuiltIn("drag");
  EXPECT_NEAR(drag.At(0.0).norm(), 0.0, 1e-15);
  EXPECT_NEAR(drag.At(3.0).y(), 6e-3, 1e-9);
  const HandTrajectory csv = HandTrajectory::FromCsv("t,x,y,z\n0,0,0,0\n1,0.01,0,0\n", "hand.csv");
  EXPECT_NEAR(csv.At(0.5).x(), 0.005, 1e-15);
  EXPECT_NEAR(csv.At(7.0).x(), 0.01, 1e-15);
  EXPECT_NE(CsvError("time,x\n").find("hand.csv:1: the header must be \"t,x,y,z\""),
            std::string::npos);
  EXPECT_NE(CsvError("t,x,y,z\n0,0,0\n").find("hand.csv:2: expected four numbers"),
            std::string::npos);
  EXPECT_NE(CsvError("t,x,y,z\n1,0,0,0\n0.5,0,0,0\n").find("hand.csv:3: t must increase"),
            std::string::npos);
  EXPECT_NE(CsvError("t,x,y,z\n").find("hand.csv: no rows"), std::string::npos);
  EXPECT_THROW(HandTrajectory::BuiltIn("wiggle"), std::invalid_argument);
}

TEST(PhantomTest, TheDragLoopsFromItsFirstCircleWithoutAStep) {
  HandTrajectory h = HandTrajectory::BuiltIn("drag");
  EXPECT_TRUE(h.At(70.0).isApprox(h.At(63.0)));  // holds the end by default
  h.LoopFrom(3.0);
  for (double t : {3.0, 4.2, 7.7, 12.5}) {
    EXPECT_LT((h.At(t + 60.0) - h.At(t)).norm(), 1e-12) << t;
    EXPECT_LT((h.At(t + 600.0) - h.At(t)).norm(), 1e-9) << t;
  }
  // Across the seam the hand moves as it does anywhere on the circle (1 ms apart).
  EXPECT_LT((h.At(63.0005) - h.At(62.9995)).norm(), 1e-5);
  EXPECT_THROW(h.LoopFrom(63.0), std::invalid_argument);
}

TEST(PhantomTest, DeviceSaturatesStaysInItsWorkspaceAndCountsEnergy) {
  DeviceModelOptions o;
  DeviceModel d(o);
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  // A spring with damping to the origin, sampled at 1 kHz (b = 1 N s/m > kT/2): after the hand
  // pulls and returns, the server has taken energy, not given it (passive). Without the damping
  // the sampled spring gives energy back: the energy check sees it.
  DeviceModel undamped(o);
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector3d target = k < 1500 ? Eigen::Vector3d(0.01, 0, 0) : zero;
    d.Step(1e-3, target, zero, -300.0 * d.position() - 1.0 * d.velocity());
    undamped.Step(1e-3, target, zero, -300.0 * undamped.position());
  }
  EXPECT_LT(d.energy_from_server(), 0.0);
  EXPECT_GT(undamped.energy_from_server(), 1e-4);
  // Saturation at max_force, whatever the server asks.
  DeviceModel s(o);
  const Eigen::Vector3d f = s.Step(1e-3, zero, zero, Eigen::Vector3d(100, 0, 0));
  EXPECT_NEAR(f.norm(), o.max_force, 1e-12);
  // Workspace: a hand far outside is stopped at the limit.
  DeviceModel w(o);
  for (int k = 0; k < 2000; ++k) w.Step(1e-3, Eigen::Vector3d(1, 0, 0), zero, zero);
  EXPECT_NEAR(w.position().x(), o.workspace.x(), 1e-12);
}

TEST(PhantomTest, TheDriverWatchdogRampsTheForceToZeroWhenWrenchesStop) {
  DriverWatchdog dog(0.02, 500.0);  // 20 ms, 500 N/s
  const double dt = 1e-3;
  const Eigen::Vector3d f(0, 2.0, 0);
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  // Wrenches every ms until t = 0.1 s: rendered as they come (after the first 4 ms' ramp from 0).
  for (int k = 0; k <= 100; ++k) r = dog.Step(k * dt, dt, f, k * dt);
  EXPECT_EQ(r, f);
  EXPECT_EQ(dog.trips(), 0);
  // None after that: held for the watchdog time, then down at 0.5 N per ms, to zero.
  double previous = r.norm();
  int steps_down = 0;
  for (int k = 101; k <= 200; ++k) {
    r = dog.Step(k * dt, dt, f, 0.1);
    if (k * dt <= 0.12 + 1e-12) {
      EXPECT_EQ(r, f) << k;
    }
    EXPECT_LE(previous - r.norm(), 0.5 + 1e-12);
    steps_down += r.norm() < previous;
    previous = r.norm();
  }
  EXPECT_EQ(r.norm(), 0.0);
  EXPECT_EQ(steps_down, 4);  // 2 N at 0.5 N per step
  EXPECT_EQ(dog.trips(), 1);
  EXPECT_TRUE(dog.starved());
  // Wrenches again: rendering resumes, ramping up at the same rate (no step at the hand).
  r = dog.Step(0.3, dt, f, 0.3);
  EXPECT_NEAR(r.norm(), 0.5, 1e-12);
  EXPECT_FALSE(dog.starved());
  // A non-finite wrench is never rendered.
  r = dog.Step(0.301, dt, Eigen::Vector3d(NAN, 0, 0), 0.301);
  EXPECT_TRUE(r.allFinite());
  EXPECT_THROW(DriverWatchdog(0.0, 1.0), std::invalid_argument);
  try {
    DriverWatchdog(0.02, -1.0);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("watchdog: the force rate must be positive, got -1"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace tangent::server
