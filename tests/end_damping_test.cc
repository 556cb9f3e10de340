// CheckEndDamping (plugin/plugin.cc; docs/scene_fuzzer.md, failure class open-thrust-qacc):
// the velocity-dependent force of a tether end on a free body enters MuJoCo's step explicitly,
// and a body velocity mode grows once h lambda > 2, lambda the largest eigenvalue of
// W^1/2 D W^1/2 (D = -sym(dF/dv) at the site, W the body's inverse mass there).
//
// Analytic case: no gravity, a straight unstretched tether of N segments from a fixed site to
// a free body of mass m (no vehicle declaration, so W = I/m exactly), the body moving at v
// perpendicular to the line. The only velocity-dependent end force is the end node's normal
// drag kn l |v_n| v_n over its drag length l = L0/2 (kn = rho Cdn d / 2; the tangential part
// vanishes at v_t = 0), whose derivative has eigenvalues 2 kn l |v| (along v), kn l |v| (across)
// and 0: h lambda = 2 h kn (L0/2) |v| / m, so the limit 2 is reached at v* = 2 m / (h kn L0).
// Drag only slows the body, so a start above v* must stop at the first step and one below it
// must run without a stop and without a MuJoCo warning.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>

#include "mjtether.h"
#include "mjtether_vehicles.h"

namespace mjtether {
namespace {

constexpr double kRho = 1025, kCdn = 1.2, kD = 0.05;  // [kg/m^3], [-], [m]
constexpr double kL0 = 1, kMass = 0.5, kH = 0.002;     // [m], [kg], [s]
constexpr int kSegments = 4;

int g_warnings = 0;
void CountWarning(const char*) { ++g_warnings; }

double LimitSpeed() {  // [m/s] v* = 2 m / (h kn L0)
  const double kn = 0.5 * kRho * kCdn * kD;
  return 2 * kMass / (kH * kn * kL0);
}

std::string Scene(const char* integrator) {
  std::ostringstream x;
  x << "<mujoco><option timestep=\"" << kH << "\" gravity=\"0 0 0\"/><custom>"
    << "<text name=\"water\" data=\"density=" << kRho << "\"/>"
    << "<text name=\"tether:t\" data=\"ends=a,b length=" << kSegments * kL0
    << " segments=" << kSegments << " diameter=" << kD
    << " mass_per_length=2 EA=1000 Cdn=" << kCdn << " Cdt=0 integrator=" << integrator << "\"/>"
    << "</custom><worldbody><site name=\"a\"/><body name=\"rov\" pos=\"" << kSegments * kL0
    << " 0 0\"><freejoint/><inertial pos=\"0 0 0\" mass=\"" << kMass
    << "\" diaginertia=\"0.01 0.01 0.01\"/><site name=\"b\"/></body></worldbody></mujoco>";
  return x.str();
}

struct Outcome {
  bool stopped = false;
  std::string message;
  double time = 0;  // [s] when stopped
};

// Runs 0.5 s with the body starting at `speed` along y (perpendicular to the line along x).
Outcome RunFrom(const char* integrator, double speed) {
  std::string error;
  mjModel* m = LoadModelFromString(Scene(integrator), "end_damping.xml", &error);
  EXPECT_NE(m, nullptr) << error;
  Outcome o;
  if (!m) return o;
  mjData* d = mj_makeData(m);
  d->qvel[1] = speed;
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

// The figure after "h lambda = " in the message.
double RateIn(const std::string& message) {
  const size_t at = message.find("h lambda = ");
  return at == std::string::npos ? -1 : std::strtod(message.c_str() + at + 11, nullptr);
}

class EndDamping : public ::testing::TestWithParam<const char*> {};

TEST_P(EndDamping, AboveTheLimitSpeedStopsAtOnceWithTheAnalyticRate) {
  g_warnings = 0;
  void (*previous)(const char*) = mju_user_warning;
  mju_user_warning = CountWarning;
  const Outcome o = RunFrom(GetParam(), 1.25 * LimitSpeed());
  mju_user_warning = previous;
  EXPECT_EQ(g_warnings, 0);
  ASSERT_TRUE(o.stopped);
  EXPECT_NE(o.message.find("damping too stiff for the step of body 'rov'"), std::string::npos)
      << o.message;
  // The check runs in the first step's callback, on the initial state (l = L0/2 exactly,
  // v_n = the start speed): it stops there, at h lambda = 2 x 1.25 = 2.5. The tolerance 1% is
  // the central difference's error on a quadratic law, far below (none in exact arithmetic).
  EXPECT_LE(o.time, kH + 1e-12);
  EXPECT_NEAR(RateIn(o.message), 2.5, 0.01 * 2.5) << o.message;
}

TEST_P(EndDamping, BelowTheLimitSpeedRunsWithoutAStopOrAWarning) {
  g_warnings = 0;
  void (*previous)(const char*) = mju_user_warning;
  mju_user_warning = CountWarning;
  const Outcome o = RunFrom(GetParam(), 0.8 * LimitSpeed());
  mju_user_warning = previous;
  EXPECT_EQ(g_warnings, 0);
  EXPECT_FALSE(o.stopped) << o.message;
}

INSTANTIATE_TEST_SUITE_P(Integrators, EndDamping,
                         ::testing::Values("explicit", "implicit", "implicit2", "rk4", "bdf2"));

}  // namespace
}  // namespace mjtether
