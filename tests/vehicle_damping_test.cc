// VehicleStopped (plugin/vehicles.cc): MuJoCo integrates a vehicle's damping explicitly (it
// comes through mjcb_passive), so on a dof with damping D_l v + D_q |v| v and effective mass M
// a velocity perturbation is multiplied by 1 - h lambda per Euler step, h lambda =
// h (D_l + 2 D_q |v|) / M, and grows once h lambda > 2 (RK4: 2.785, the real-axis limit of its
// stability region). The scene fuzzer's MuJoCo bad-QACC failures (seeds 1073, 1528, 1885, 2431,
// 4747, 5268, 6154, 7537, 8370) were light vehicles driven at hundreds of m/s past that limit.
//
// Analytic case: no gravity, no tether, no buoyancy, a free body of mass m with surge damping
// only, moving along x. The limit speed is v* = (2 M / h - D_l) / (2 D_q). Damping only slows
// the body, so a start above v* must stop in the first step's callback at h lambda =
// h (D_l + 2 D_q v0) / m, and a start below it must run without a stop and without a MuJoCo
// warning.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>

#include "mjtether.h"
#include "mjtether_vehicles.h"

namespace mjtether {
namespace {

constexpr double kMass = 2, kDl = 5, kDq = 40, kH = 0.002;  // [kg], [N s/m], [N s^2/m^2], [s]

int g_warnings = 0;
void CountWarning(const char*) { ++g_warnings; }

double Limit(bool rk4) { return rk4 ? 2.785 : 2.0; }
double LimitSpeed(bool rk4) {  // [m/s] v*
  return (Limit(rk4) * kMass / kH - kDl) / (2 * kDq);
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
  double time = 0;  // [s] when stopped
};

Outcome RunFrom(bool rk4, double speed) {
  Outcome o;
  std::string error;
  mjModel* m = LoadModelFromString(Scene(rk4), "vehicle_damping.xml", &error);
  EXPECT_NE(m, nullptr) << error;
  if (!m) return o;
  o.loaded = true;
  mjData* d = mj_makeData(m);
  d->qvel[0] = speed;
  for (int k = 0; k < 250; ++k) {
    Step(m, d);
    if (std::optional<std::string> msg = CheckDivergence(m, d)) {
      o.stopped = true;
      o.message = *msg;
      o.time = d->time;
      break;
    }
  }
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
  return o;
}

double RateIn(const std::string& message) {
  const size_t at = message.find("h lambda = ");
  return at == std::string::npos ? -1 : std::strtod(message.c_str() + at + 11, nullptr);
}

class VehicleDamping : public ::testing::TestWithParam<bool> {};

TEST_P(VehicleDamping, AboveTheLimitSpeedStopsAtOnceWithTheAnalyticRate) {
  const bool rk4 = GetParam();
  g_warnings = 0;
  void (*previous)(const char*) = mju_user_warning;
  mju_user_warning = CountWarning;
  const double v0 = 1.25 * LimitSpeed(rk4);
  const Outcome o = RunFrom(rk4, v0);
  mju_user_warning = previous;
  EXPECT_EQ(g_warnings, 0);
  ASSERT_TRUE(o.stopped);
  EXPECT_NE(o.message.find("vehicle 'rov' stopped"), std::string::npos) << o.message;
  EXPECT_NE(o.message.find("in surge"), std::string::npos) << o.message;
  // The first callback sees the initial state exactly: the rate is the closed form, to the
  // message's 6 significant digits.
  EXPECT_LE(o.time, kH + 1e-12);
  EXPECT_NEAR(RateIn(o.message), kH * (kDl + 2 * kDq * v0) / kMass, 1e-5 * Limit(rk4))
      << o.message;
}

TEST_P(VehicleDamping, BelowTheLimitSpeedRunsWithoutAStopOrAWarning) {
  const bool rk4 = GetParam();
  g_warnings = 0;
  void (*previous)(const char*) = mju_user_warning;
  mju_user_warning = CountWarning;
  const Outcome o = RunFrom(rk4, 0.9 * LimitSpeed(rk4));
  mju_user_warning = previous;
  EXPECT_TRUE(o.loaded);
  EXPECT_EQ(g_warnings, 0);
  EXPECT_FALSE(o.stopped) << o.message;
}

INSTANTIATE_TEST_SUITE_P(Integrators, VehicleDamping, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? "RK4" : "Euler";
                         });

}  // namespace
}  // namespace mjtether
