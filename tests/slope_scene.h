// The resting/sliding scene of the contact tests (contact_test.cc's Resting on a plane or a
// tilted box, contact_hfield_test.cc's HfieldRamp on a ramp height field): a heavy tether lying
// down a slope of angle alpha, held only by friction mu, its upper end on a 200 g frictionless
// slider along the slope (the slider runs ahead under its own weight and the first segment goes
// slack, so the tether below is held by nothing else). Coulomb: it stays when tan(alpha) < mu
// and slides with acceleration g (sin(alpha) - mu cos(alpha)) when tan(alpha) > mu. Staying is
// "within the regularisation": friction mu N tanh(v/eps) holds the slope at the creep speed
// v = eps atanh(tan(alpha)/mu), so after 1 s the tether has moved at most about that far
// (bounded here by 3 eps atanh x 1 s). Sliding: the distance after 1 s is 1/2 a t^2 within 10 %
// (the first instants of settling on the penalty, and the creep scale, are small against 0.3 m).
#pragma once

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "mujoco_fixture.h"

namespace mjtether::testing {

struct Slope {
  double alpha;   // [rad] the slope's angle, downhill along +x
  double mu = 0.3;     // [-] Coulomb friction
  double eps = 0.01;   // [m/s] the friction's regularisation speed
  Vec3 down() const { return Vec3(std::cos(alpha), 0, -std::sin(alpha)); }
  Vec3 normal() const { return Vec3(std::sin(alpha), 0, std::cos(alpha)); }
};

// Runs the scene for 1 s on the surface given as MJCF (`asset` inside <asset>, `surface` in the
// worldbody: a geom named "ground" whose surface passes through the origin with the slope's
// normal) and returns how far the middle of the tether went down the slope [m].
inline double SlideDownSlope(const Slope& sl, const std::string& asset, const std::string& surface,
                             const char* integrator) {
  const double g = 9.81, r = 0.01;
  const double M = 0.2;  // [kg] slider (rk4: coupling omega h = 0.45, below its limit 0.5; 0.1 kg until session 29)
  const Vec3 down = sl.down(), normal = sl.normal();
  const Vec3 start = -1.0 * down + r * normal;  // the upper end, on the surface
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002" gravity="0 0 -9.81"/>
  <compiler angle="radian"/>
  <asset>)" + asset + R"(</asset>
  <worldbody>
    )" + surface + R"(
    <body name="slider" pos=")" +
                          Fmt(start.x()) + " 0 " + Fmt(start.z()) + R"(">
      <joint name="s" type="slide" axis=")" +
                          Fmt(down.x()) + " 0 " + Fmt(down.z()) + R"("/>
      <geom type="sphere" size="0.005" mass=")" +
                          Fmt(M) + R"(" contype="0" conaffinity="0"/>
      <site name="a"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,free length=2 segments=20 diameter=0.02
      mass_per_length=2 EA=1e3 damping=1 integrator=)" +
                          std::string(integrator) + R"( contact=ground contact_friction=)" +
                          Fmt(sl.mu) + " contact_friction_speed=" + Fmt(sl.eps) + R"("/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  EXPECT_NE(s.d, nullptr);
  if (!s.d) return NAN;
  mj_forward(s.m, s.d);
  // Lying straight down the slope, touching it (its axis r above the surface, less the
  // static penetration).
  const double k = GetTether(s.m, 0)->params().contact_stiffness;
  const double sink = 2 * g * std::cos(sl.alpha) / k;  // [m] weight per length / stiffness
  Eigen::Matrix3Xd x(3, 21);
  for (int i = 0; i <= 20; ++i) x.col(i) = start + 0.1 * i * down - sink * normal;
  SetNodes(s.m, s.d, x);
  while (s.d->time < 1.0) {
    if (!s.Step()) {
      ADD_FAILURE() << "the step failed at t = " << s.d->time;
      return NAN;
    }
  }
  return down.dot(Vec3(NodePositions(s.m, s.d, 0) + 30) - x.col(10));
}

// Coulomb's verdict on `moved` (above).
inline void ExpectCoulomb(const Slope& sl, double moved) {
  const double g = 9.81, tan_alpha = std::tan(sl.alpha);
  if (tan_alpha < sl.mu) {
    const double creep = sl.eps * std::atanh(tan_alpha / sl.mu);
    EXPECT_LT(std::abs(moved), 3 * creep * 1.0) << "tan(alpha) < mu: it should stay";
  } else {
    const double a = g * (std::sin(sl.alpha) - sl.mu * std::cos(sl.alpha));
    EXPECT_NEAR(moved, 0.5 * a, 0.1 * 0.5 * a) << "tan(alpha) > mu: it should slide";
  }
}

}  // namespace mjtether::testing
