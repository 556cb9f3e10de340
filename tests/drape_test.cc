// Tether-geom contact against statics (docs/contact.md): a tether draped over a frictionless
// cylinder with a mass on one end, implicit and explicit (each at a MuJoCo step its coupling
// limit accepts).
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "mujoco_fixture.h"
#include "param_name.h"

namespace mjtether::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;



// ---------------------------------------------------------------------------------------------
// Drape: a heavy tether (w = 4.9 N/m) from a fixed site A, up and over a frictionless
// horizontal cylinder (radius R, axis y), hanging down on the other side to a 5 kg mass (on
// damped x and z slides). Statics of a cable on a frictionless support (e.g. Irvine, Cable
// Structures, 1981, ch. 1): the contact passes no tangential force, so along the whole cable
// T - w z is constant; the mass hangs straight below the cylinder's side (x = R + d/2), at the
// depth the length leaves: z_B = -(L - t_A - (R + d/2) theta), t_A the tangent from A and
// theta the wrap angle; and the tension at A is T_A = M g + w (z_A - z_B). Tolerances: z_B
// within 5 mm (the A leg's sag shortens its reach by ~1.5 mm, the polygon round the drum
// lengthens the wrap by ~0.6 mm, the stretch T/EA L ~0.4 mm, the penalty's sink ~0.3 mm),
// x_B within 2 mm (the polygon's nodes stand 0.6 mm off the circle), T_A within 1 % (its
// difference from M g, w (z_A - z_B) = 2.5 N, is 5 % of it: a drum passing friction, or the
// weight left out, fails). Site A is in a body of its own (on the world body it would do as
// well: the drum is 2 m from it, not end A's own geom, docs/contact.md).
class Drape : public ::testing::TestWithParam<const char*> {};

TEST_P(Drape, EquilibriumAsStaticsPredicts) {
  const double R = 0.5, d = 0.02, Ra = R + d / 2, M = 5, g = 9.81, mu_l = 0.5, w = mu_l * g;
  const Vec3 A(-1.5, 0, -2);
  const double hang0 = 1.5;  // [m] initial hanging length
  // Tangent from A to the circle of radius Ra, on its upper left (angle phiA), wrap to angle 0.
  const double OA = A.norm(), tA = std::sqrt(OA * OA - Ra * Ra);
  const double phiA = std::atan2(A.z(), A.x()) - std::acos(Ra / OA) + 2 * kPi;
  const Vec3 PA(Ra * std::cos(phiA), 0, Ra * std::sin(phiA));
  const double theta = phiA;  // from phiA down to 0, over the top
  const double L = tA + Ra * theta + hang0;
  const int N = static_cast<int>(std::round(L / 0.05));
  // The MuJoCo step each integrator's coupling limit with the 5 kg mass on the stiff tether
  // (omega = 2000 rad/s) accepts: omega h < 2 explicit, 0.8 rk4, 4 implicit2 (docs/coupling.md).
  // rk4 passes too (T_A 46.574 N for 46.587) but takes 28 600 steps (minutes under load): not
  // in the suite. implicit2 is refused on this scene (contact with an end on a moving body):
  // it settled at the right place but its end tensions read 19, 25 and 67 N at 2, 1 and
  // 0.5 ms for 46.6 N (docs/contact.md).
  const std::string integrator = GetParam();
  const double timestep = integrator == "explicit"    ? 0.0008
                          : integrator == "rk4"       ? 0.00035
                          : integrator == "implicit2" ? 0.001
                                                      : 0.002;
  const std::string xml = R"(
<mujoco>
  <option timestep=")" + Fmt(timestep) +
                          R"("><flag contact="disable"/></option>
  <worldbody>
    <geom name="drum" type="cylinder" size=")" +
                          Fmt(R) + R"( 0.3" zaxis="0 1 0"/>
    <body name="anchor" pos=")" +
                          Fmt(A.x()) + " 0 " + Fmt(A.z()) + R"(">
      <site name="a"/>
    </body>
    <body name="mass" pos=")" +
                          Fmt(Ra) + " 0 " + Fmt(-hang0) + R"(">
      <joint name="x" type="slide" axis="1 0 0" damping="20"/>
      <joint name="z" type="slide" axis="0 0 1" damping="20"/>
      <geom type="sphere" size="0.05" mass=")" +
                          Fmt(M) + R"("/>
      <site name="b"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=)" +
                          Fmt(L) + " segments=" + std::to_string(N) +
                          R"( diameter=0.02 mass_per_length=)" + Fmt(mu_l) +
                          R"( EA=1e6 damping=500 integrator=)" + GetParam() +
                          R"( contact=drum"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  mj_forward(s.m, s.d);
  // The draped shape: leg A, the arc, the hanging leg.
  Eigen::Matrix3Xd x(3, N + 1);
  const double L0 = L / N;
  for (int i = 0; i <= N; ++i) {
    const double a = i * L0;  // from A
    if (a <= tA) {
      x.col(i) = A + (PA - A) * (a / tA);
    } else if (a <= tA + Ra * theta) {
      const double phi = phiA - (a - tA) / Ra;
      x.col(i) = Vec3(Ra * std::cos(phi), 0, Ra * std::sin(phi));
    } else {
      x.col(i) = Vec3(Ra, 0, -(a - tA - Ra * theta));
    }
  }
  SetNodes(s.m, s.d, x);
  double TA = 0;
  int samples = 0;
  while (s.d->time < 10) {
    ASSERT_TRUE(s.Step());
    if (s.d->time > 9) TA += GetReactions(s.m, s.d, 0).tension_a, ++samples;
  }
  TA /= samples;
  const Vec3 B(s.d->site_xpos + 3 * 1);  // site b (site a is 0)
  const double zB = -(L - tA - Ra * theta);
  RecordProperty("xB", Fmt(B.x()));
  RecordProperty("zB", Fmt(B.z()));
  RecordProperty("TA", Fmt(TA));
  EXPECT_NEAR(B.x(), Ra, 2e-3);
  EXPECT_NEAR(B.z(), zB, 5e-3);
  const double expected = M * g + w * (A.z() - B.z());
  std::printf("drape %s: xB %.5f (%.5f) zB %.5f (%.5f) T_A %.3f (%.3f)\n", GetParam(), B.x(), Ra,
              B.z(), zB, TA, expected);
  EXPECT_NEAR(TA / expected, 1, 0.01) << "T_A " << TA << " expected " << expected;
}

INSTANTIATE_TEST_SUITE_P(Integrators, Drape, ::testing::Values("implicit", "explicit"),
                         StringParamName());

}  // namespace
}  // namespace mjtether::testing
