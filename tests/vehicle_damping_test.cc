// VehicleStopped (plugin/vehicles.cc): MuJoCo integrates a vehicle's damping explicitly (it
// comes through mjcb_passive), so on a dof with damping D_l v + D_q |v| v and effective mass M
// a velocity perturbation about the motion is multiplied by 1 - h lambda per Euler step,
// h lambda = h (D_l + 2 D_q |v|) / M, and grows once h lambda > 2 (RK4: 2.785, the real-axis
// limit of its stability region). The scene fuzzer's MuJoCo bad-QACC failures (seeds 1073,
// 1528, 1885, 2431, 4747, 5268, 6154, 7537, 8370) were light vehicles driven past that limit.
// The check stops a vehicle once the perturbation's growth, the product of h lambda - 1 over
// consecutive steps beyond the limit, reaches 100 (kGrowthStop).
//
// Analytic cases: no gravity, no tether, no buoyancy, a free body of mass m with surge damping
// only, moving along x.
//  - Driven: a constant force F = D_l v_s + D_q v_s^2 holds it at v_s exactly (every stage of
//    either integrator sees zero acceleration). Beyond the limit, h lambda is constant, so it
//    stops after exactly ceil(ln 100 / ln(h lambda - 1)) steps, with that h lambda; below it,
//    it runs without a stop, a warning or a change of speed.
//  - Flung: no force, a start beyond the limit. The quadratic law's explicit step slows it by
//    its secant h (D_l + D_q |v|) / M, about half the tangent, so the speed falls at once below
//    the limit's and nothing grows: no stop, no warning (a snap that flings a vehicle is not an
//    instability).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>

#include "mjtether.h"
#include "mjtether_vehicles.h"
#include "warning_handler.h"

namespace mjtether {
namespace {

constexpr double kMass = 2, kDl = 5, kDq = 40, kH = 0.002;  // [kg], [N s/m], [N s^2/m^2], [s]

int g_warnings = 0;
void CountWarning(const char*) { ++g_warnings; }

double Limit(bool rk4) { return rk4 ? 2.785 : 2.0; }
double SpeedAt(double rate) {  // [m/s] the speed at which h lambda = rate
  return (rate * kMass / kH - kDl) / (2 * kDq);
}

std::string Scene(bool rk4) {
  std::ostringstream x;
  x << "<mujoco><option timestep=\"" << kH << "\" gravity=\"0 0 0\""
    << (rk4 ? " integrator=\"RK4\"" : "") << "/><custom>"
    << "<text name=\"water\" data=\"density=1025\"/>"
    << "<text name=\"vehicle:rov\" data=\"linear_damping=" << kDl << ",0,0,0,0,0 "
    << "quadratic_damping=" << kDq << ",0,0,0,0,0\"/>"
    << "</custom><worldbody><body name=\"rov\"><freejoint/><inertial pos=\"0 0 0\" mass=\""
    << kMass << "\" diaginertia=\"0.1 0.1 0.1\"/></body></worldbody></mujoco>";
  return x.str();
}

struct Outcome {
  bool loaded = false, stopped = false;
  std::string message;
  int steps = 0;       // steps taken, the stopping one included
  double speed = 0;    // [m/s] surge speed at the end
  int warnings = 0;    // MuJoCo warnings
};

// Up to 250 steps from `speed` along x, with a constant force `force` [N] along x.
Outcome RunFrom(bool rk4, double speed, double force) {
  Outcome o;
  std::string error;
  mjModel* m = LoadModelFromString(Scene(rk4), "vehicle_damping.xml", &error);
  EXPECT_NE(m, nullptr) << error;
  if (!m) return o;
  o.loaded = true;
  g_warnings = 0;
  const testing::WarningHandler counting(CountWarning);
  mjData* d = mj_makeData(m);
  d->qvel[0] = speed;
  d->xfrc_applied[6 * 1 + 0] = force;  // body 1, the vehicle
  for (int k = 0; k < 250; ++k) {
    Step(m, d);
    ++o.steps;
    if (std::optional<std::string> msg = CheckDivergence(m, d)) {
      o.stopped = true;
      o.message = *msg;
      break;
    }
  }
  o.speed = d->qvel[0];
  o.warnings = g_warnings;
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
  return o;
}

double Force(double v) { return kDl * v + kDq * v * v; }  // [N] that holds the body at v

double FigureAfter(const std::string& message, const std::string& label) {
  const size_t at = message.find(label);
  return at == std::string::npos ? -1 : std::strtod(message.c_str() + at + label.size(), nullptr);
}

class VehicleDamping : public ::testing::TestWithParam<bool> {};

TEST_P(VehicleDamping, DrivenBeyondTheLimitStopsWhenThePerturbationHasGrownAHundredfold) {
  const bool rk4 = GetParam();
  const double rate = 1.25 * Limit(rk4), v = SpeedAt(rate);
  const Outcome o = RunFrom(rk4, v, Force(v));
  EXPECT_EQ(o.warnings, 0);
  ASSERT_TRUE(o.stopped);
  EXPECT_NE(o.message.find("vehicle 'rov' stopped"), std::string::npos) << o.message;
  EXPECT_NE(o.message.find("in surge"), std::string::npos) << o.message;
  // h lambda is the closed form at v (held exactly), to the message's 6 significant digits,
  // and the stop comes at the step the product of h lambda - 1 first reaches 100.
  EXPECT_NEAR(FigureAfter(o.message, "h lambda = "), rate, 1e-5 * rate) << o.message;
  // Counted once per step at the first call a step after the last counted one: with RK4 that is
  // the step's last stage, at t + h, so its first step counts twice (its start and that stage).
  const int counts = static_cast<int>(std::ceil(std::log(100.0) / std::log(rate - 1)));
  EXPECT_EQ(o.steps, rk4 ? counts - 1 : counts) << o.message;
  EXPECT_NEAR(FigureAfter(o.message, "beyond it for "), counts, 0) << o.message;
}

TEST_P(VehicleDamping, DrivenBelowTheLimitRunsAtItsSpeedWithoutAStopOrAWarning) {
  const bool rk4 = GetParam();
  const double v = SpeedAt(0.9 * Limit(rk4));
  const Outcome o = RunFrom(rk4, v, Force(v));
  EXPECT_TRUE(o.loaded);
  EXPECT_EQ(o.warnings, 0);
  EXPECT_FALSE(o.stopped) << o.message;
  EXPECT_NEAR(o.speed, v, 1e-9 * v);
}

TEST_P(VehicleDamping, FlungBeyondTheLimitSlowsDownWithoutAStopOrAWarning) {
  const bool rk4 = GetParam();
  const double v = SpeedAt(1.25 * Limit(rk4));
  const Outcome o = RunFrom(rk4, v, 0);
  EXPECT_TRUE(o.loaded);
  EXPECT_EQ(o.warnings, 0);
  EXPECT_FALSE(o.stopped) << o.message;
  EXPECT_LT(std::abs(o.speed), 0.1 * v);
}

INSTANTIATE_TEST_SUITE_P(Integrators, VehicleDamping, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? "RK4" : "Euler";
                         });

}  // namespace
}  // namespace mjtether
