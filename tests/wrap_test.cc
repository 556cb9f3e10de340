// Tether-geom contact against statics (docs/contact.md): a tether draped over a frictionless
// cylinder with a mass on one end, and a tether wound twice round a pile by an end orbiting
// it, whose tensions obey the capstan law along the wrap.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "mujoco_fixture.h"

namespace mjtether::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string Fmt(double x) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.10g", x);
  return buf;
}

void SetNodes(const mjModel* m, const mjData* d, const Eigen::Matrix3Xd& x) {
  double* xp = const_cast<double*>(NodePositions(m, d, 0));
  ASSERT_NE(xp, nullptr);
  const int n = GetTether(m, 0)->nodes();
  ASSERT_EQ(x.cols(), n);
  for (int i = 0; i < 3 * n; ++i) xp[i] = x.data()[i], xp[3 * n + i] = 0;
}

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
// weight left out, fails).
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
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"><flag contact="disable"/></option>
  <worldbody>
    <geom name="drum" type="cylinder" size=")" + Fmt(R) + R"( 0.3" zaxis="0 1 0"/>
    <site name="a" pos=")" + Fmt(A.x()) + " 0 " + Fmt(A.z()) + R"("/>
    <body name="mass" pos=")" + Fmt(Ra) + " 0 " + Fmt(-hang0) + R"(">
      <joint name="x" type="slide" axis="1 0 0" damping="20"/>
      <joint name="z" type="slide" axis="0 0 1" damping="20"/>
      <geom type="sphere" size="0.05" mass=")" + Fmt(M) + R"("/>
      <site name="b"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=)" + Fmt(L) + " segments=" + std::to_string(N) +
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
  EXPECT_NEAR(TA / expected, 1, 0.01) << "T_A " << TA << " expected " << expected;
}

INSTANTIATE_TEST_SUITE_P(Integrators, Drape,
                         ::testing::Values("implicit", "implicit2", "explicit", "rk4"));

// ---------------------------------------------------------------------------------------------
// Wrap: in a horizontal plane (no gravity), end B (mocap) orbits a vertical pile twice at
// radius 1.5 m; end A is on a slider pulled away from the pile by F = 10 N. The tether cannot
// pass through the pile, so it winds round it: its winding number about the pile's axis, from
// the nodes' angles, is the initial quarter turn plus the two orbits, 2.25 turns (to 0.02
// turn, the angle spanned by the end nodes' positions jitter). While it winds, the slider is
// drawn in and the tether slips over the pile all along the wrap, so the capstan law holds
// across the contact: T_B / T_A = exp(mu theta_c), theta_c the angle the tether turns while in
// contact (from the nodes within 2 mm of the pile's surface), within 5 % (each end of the
// contact is uncertain by one segment, 0.16 rad, i.e. +-1.6 % in exp(mu theta) at mu = 0.1,
// plus the 3 % of the capstan test).
class Wrap : public ::testing::TestWithParam<const char*> {};

TEST_P(Wrap, OrbitingTwiceWrapsTwiceAndTensionsFollowCapstan) {
  const double r = 0.3, d = 0.02, ra = r + d / 2, Ro = 1.5, F = 10, mu = 0.1;
  const double period = 10, ramp = 1;
  const Vec3 A0(-6, 0, 0), B0(0, -Ro, 0);
  const double L = (B0 - A0).norm();
  const int N = static_cast<int>(std::round(L / 0.05));
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002" gravity="0 0 0"><flag contact="disable"/></option>
  <worldbody>
    <geom name="pile" type="cylinder" size=")" + Fmt(r) + R"( 1"/>
    <body name="slider" pos=")" + Fmt(A0.x()) + R"( 0 0">
      <joint name="s" type="slide" axis="1 0 0"/>
      <geom type="sphere" size="0.02" mass="0.1"/>
      <site name="a"/>
    </body>
    <body name="orbiter" mocap="true" pos=")" + Fmt(B0.x()) + " " + Fmt(B0.y()) + R"( 0">
      <site name="b"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=)" + Fmt(L) + " segments=" + std::to_string(N) +
                          R"( diameter=0.02 mass_per_length=0.1 EA=1e5 damping=20 integrator=)" +
                          GetParam() + R"( contact=pile contact_friction=)" + Fmt(mu) +
                          R"( contact_friction_speed=0.002"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  const double omega = 2 * kPi / period;
  // Orbit angle: ramped up over `ramp` seconds, then uniform; 2 turns at t_end.
  auto phi = [&](double t) {
    return t < ramp ? omega * t * t / (2 * ramp) : omega * (t - ramp / 2);
  };
  const double t_end = 2 * period + ramp / 2;
  double ratio = 0, theta_mean = 0;
  int samples = 0;
  double winding = 0, theta_c = 0;
  while (s.d->time < t_end) {
    const double p = -kPi / 2 + phi(s.d->time + s.m->opt.timestep);
    s.d->mocap_pos[0] = Ro * std::cos(p);
    s.d->mocap_pos[1] = Ro * std::sin(p);
    s.d->xfrc_applied[6 * 1 + 0] = -F;  // the slider (body 1), away from the pile
    ASSERT_TRUE(s.Step());
    // Winding and contact angle from the nodes' angles about the pile's axis (z).
    const double* x = NodePositions(s.m, s.d, 0);
    winding = theta_c = 0;
    for (int i = 0; i < N; ++i) {
      const double a0 = std::atan2(x[3 * i + 1], x[3 * i]);
      const double a1 = std::atan2(x[3 * i + 4], x[3 * i + 3]);
      const double da = std::remainder(a1 - a0, 2 * kPi);
      winding += da;
      if (std::hypot(x[3 * i], x[3 * i + 1]) < ra + 2e-3 &&
          std::hypot(x[3 * i + 3], x[3 * i + 4]) < ra + 2e-3) {
        theta_c += da;
      }
    }
    if (s.d->time > t_end - 2) {
      const EndReactions re = GetReactions(s.m, s.d, 0);
      ratio += re.tension_b / re.tension_a;
      theta_mean += theta_c;
      ++samples;
    }
  }
  ratio /= samples;
  theta_mean /= samples;
  const double turns = winding / (2 * kPi);
  RecordProperty("turns", Fmt(turns));
  RecordProperty("theta_c", Fmt(theta_mean));
  RecordProperty("ratio", Fmt(ratio));
  EXPECT_NEAR(turns, 2.25, 0.02);
  // Most of the winding is in contact (the two free legs turn less than a half turn).
  EXPECT_GT(theta_mean, 2 * 2 * kPi - kPi);
  EXPECT_NEAR(ratio / std::exp(mu * theta_mean), 1, 0.05)
      << "T_B/T_A " << ratio << " exp(mu theta_c) " << std::exp(mu * theta_mean);
  // The slider was drawn in by the wrapped length (about 2 pi ra per orbit).
  EXPECT_GT(s.d->qpos[0], 0.8 * 2 * 2 * kPi * ra);
}

INSTANTIATE_TEST_SUITE_P(Integrators, Wrap,
                         ::testing::Values("implicit", "implicit2", "explicit", "rk4"));

}  // namespace
}  // namespace mjtether::testing
