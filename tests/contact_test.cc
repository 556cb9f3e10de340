// Tether-geom contact (docs/contact.md) against closed forms: the capstan equation, Newton's
// third law between the tether and a free body, no tunnelling of a fast pipe through a
// segment, and a tether resting on or sliding down a slope (Coulomb: tan(alpha) vs mu).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <string>

#include "mujoco_fixture.h"
#include "param_name.h"
#include "slope_scene.h"

namespace mjtether::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;



// ---------------------------------------------------------------------------------------------
// Capstan: a dry, weightless tether wrapped by theta over a fixed cylinder of radius R, slipping
// slowly towards end A (pulled down at 2 cm/s by a mocap body) against a load on end B (a
// body on a vertical slide pulled down by 50 N). In steady slip the tensions at the two ends
// obey T_A / T_B = exp(mu theta) (Euler 1762; e.g. Johnson, Contact Mechanics, 1985, eq. 7.10).
// The segments (5 cm, a turn of 0.1 rad per node) make the polygon's ratio differ from the
// exponential by O((mu dtheta)^3) per node, and the regularised friction (tanh(v/eps), slip
// 10 eps) saturates to 1 - 4e-9: both far below the 3 % asked; the penalty's penetration
// (T/(k R) ~ 0.5 mm) changes the wrap radius, not the angle.
struct CapstanCase {
  double mu;
  double theta;
};
void PrintTo(const CapstanCase& c, std::ostream* os) {
  *os << "mu " << c.mu << ", theta " << c.theta / kPi << " pi";
}

class Capstan : public ::testing::TestWithParam<std::tuple<CapstanCase, const char*>> {};

TEST_P(Capstan, TensionRatioIsExpMuTheta) {
  const auto [cc, integrator] = GetParam();
  const double R = 0.5, d = 0.02, Ra = R + d / 2, leg = 1.0, L0 = 0.05;
  // Leg B hangs straight down from the tangent point (Ra, 0, 0); the wrap runs over the top
  // (+z) from angle 0 to theta (measured from +x towards +z); leg A leaves tangentially.
  const double th = cc.theta;
  const Vec3 tB(Ra, 0, 0), tA(Ra * std::cos(th), 0, Ra * std::sin(th));
  const Vec3 dirA(-std::sin(th), 0, std::cos(th));  // tangent, leaving the wrap
  const Vec3 endB = tB + Vec3(0, 0, -leg), endA = tA + leg * dirA;
  const double length = 2 * leg + Ra * th;
  const int N = static_cast<int>(std::round(length / L0));
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    <geom name="drum" type="cylinder" size=")" +
                          Fmt(R) + R"( 0.3" zaxis="0 1 0"/>
    <body name="puller" mocap="true" pos=")" +
                          Fmt(endA.x()) + " 0 " + Fmt(endA.z()) + R"(">
      <site name="a"/>
    </body>
    <body name="load" pos=")" +
                          Fmt(endB.x()) + " 0 " + Fmt(endB.z()) + R"(">
      <joint name="slide" type="slide" axis="0 0 1"/>
      <geom type="sphere" size="0.01" mass="1" contype="0" conaffinity="0"/>
      <site name="b"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=)" +
                          Fmt(length) + " segments=" + std::to_string(N) +
                          R"( diameter=0.02 mass_per_length=0.5 EA=1e5 damping=50
      integrator=)" + integrator +
                          R"( contact=drum contact_friction=)" + Fmt(cc.mu) + R"(
      contact_friction_speed=0.002"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  mj_forward(s.m, s.d);
  // The wrapped shape at rest length: leg B up, the arc, leg A out.
  Eigen::Matrix3Xd x(3, N + 1);
  const double L = length / N;
  for (int i = 0; i <= N; ++i) {
    const double a = (N - i) * L;  // arc length from end B
    Vec3 p;
    if (a <= leg) {
      p = endB + Vec3(0, 0, a);
    } else if (a <= leg + Ra * th) {
      const double phi = (a - leg) / Ra;
      p = Vec3(Ra * std::cos(phi), 0, Ra * std::sin(phi));
    } else {
      p = tA + (a - leg - Ra * th) * dirA;
    }
    x.col(i) = p;
  }
  SetNodes(s.m, s.d, x);
  const double v = 0.02;  // [m/s] pulling speed of end A along its leg
  const Vec3 a0 = endA;
  double sum_a = 0, sum_b = 0;
  int samples = 0;
  while (s.d->time < 2.0) {
    s.d->xfrc_applied[6 * 2 + 2] = -50;  // the load on body 2 (load)
    const Vec3 pa = a0 + v * s.d->time * dirA;
    for (int k = 0; k < 3; ++k) s.d->mocap_pos[k] = pa[k];
    ASSERT_TRUE(s.Step());
    if (s.d->time > 1.5) {
      const EndReactions r = GetReactions(s.m, s.d, 0);
      sum_a += r.tension_a;
      sum_b += r.tension_b;
      ++samples;
    }
  }
  const double ratio = sum_a / sum_b;
  const double expected = std::exp(cc.mu * th);
  std::printf("capstan mu=%g theta=%g: T_A/T_B = %.4f, exp(mu theta) = %.4f\n", cc.mu, th, ratio,
              expected);
  if (cc.mu == 0) {
    EXPECT_NEAR(ratio, 1.0, 0.005) << "frictionless: equal tensions";
  } else {
    EXPECT_NEAR(ratio / expected, 1.0, 0.03)
        << "T_A/T_B = " << ratio << ", exp(mu theta) = " << expected;
  }
  // The load moved up: the tether really slipped round the drum.
  EXPECT_GT(s.d->qpos[0], 0.01);
}

INSTANTIATE_TEST_SUITE_P(
    Contact, Capstan,
    ::testing::Combine(::testing::Values(CapstanCase{0, kPi}, CapstanCase{0.1, kPi / 2},
                                         CapstanCase{0.3, kPi / 2}, CapstanCase{0.5, kPi / 2},
                                         CapstanCase{0.1, kPi}, CapstanCase{0.3, kPi},
                                         CapstanCase{0.5, kPi}),
                       ::testing::Values("implicit")),
    [](const auto& info) {
      const CapstanCase& c = std::get<0>(info.param);
      return "mu" + NumberName(c.mu) + "_theta" + NumberName(c.theta / kPi) + "pi_" +
             std::get<1>(info.param);
    });

// ---------------------------------------------------------------------------------------------
// Two-way: a taut tether (stretched 1 %) carried broadside by a mocap sled at 0.5 m/s sweeps
// into a free box (no gravity, no water) and pushes it. Newton's third law: the box's momentum is,
// at every step, minus the sum of the contact impulses the tether received (to round-off: the glue
// returns each impulse as a constant force over the next MuJoCo step, and MuJoCo's Euler step adds
// h F / m to a free body's linear velocity exactly). And the box does move.
class TwoWay : public ::testing::TestWithParam<const char*> {};

TEST_P(TwoWay, BoxMomentumIsMinusTetherContactImpulse) {
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002" gravity="0 0 0" integrator="Euler"/>
  <worldbody>
    <body name="sled" mocap="true" pos="0 0 0">
      <site name="a" pos="0 -1 0"/>
      <site name="b" pos="0 1 0"/>
    </body>
    <body name="box" pos="1.0 0 0">
      <freejoint/>
      <geom name="box" type="box" size="0.2 0.2 0.2" mass="2"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=1.98 segments=20 diameter=0.02
      mass_per_length=0.3 EA=2e4 damping=20 integrator=)" +
                          std::string(GetParam()) + R"( contact=box contact_friction=)" +
                          (std::string(GetParam()) == "implicit2" ? "0" : "0.3") + R"("/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  const int box = mj_name2id(s.m, mjOBJ_BODY, "box");
  const double mass = s.m->body_mass[box];
  Vec3 impulse = Vec3::Zero();  // [N s] summed contact impulses on the tether
  double largest = 0;
  while (s.d->time < 3.0) {
    s.d->mocap_pos[0] = 0.5 * s.d->time;
    ASSERT_TRUE(s.Step());
    const Vec3 P = mass * Vec3(s.d->qvel[0], s.d->qvel[1], s.d->qvel[2]);
    // The impulse of the tether's advance to the start of a MuJoCo step acts on the box
    // during that step.
    impulse += ContactImpulse(s.m, s.d, 0);
    EXPECT_LT((P + impulse).norm(), 1e-9 * std::max(1.0, P.norm())) << "t = " << s.d->time;
    largest = std::max(largest, P.norm());
    if (::testing::Test::HasFailure()) break;
  }
  // It was pushed: at least a tenth of the sled's speed given to the box at some point.
  EXPECT_GT(largest, 0.1 * 0.5 * mass);
  EXPECT_GT(s.d->qpos[0], 1.05);
}

INSTANTIATE_TEST_SUITE_P(Contact, TwoWay,
                         ::testing::Values("explicit", "rk4", "implicit", "implicit2"),
                         StringParamName());

// ---------------------------------------------------------------------------------------------
// No tunnelling: a 0.1 m-radius pipe moving at 3 m/s (a 1e4 kg body on a slide, so its speed
// holds) hits the middle of a tether of 1 m segments (12 m over a 10 m span, slack) at a 2 ms
// MuJoCo step, and carries it 2.5 m on. At every step the tether's crossing of the pipe's
// plane stays ahead of the pipe's axis: it never passes through.
class NoTunnelling : public ::testing::TestWithParam<const char*> {};

TEST_P(NoTunnelling, PipeAtThreeMetresPerSecond) {
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    <site name="a" pos="2 -5 0"/>
    <site name="b" pos="2 5 0"/>
    <body name="pipe" pos="0 0 0">
      <joint name="x" type="slide" axis="1 0 0"/>
      <geom name="pipe" type="capsule" size="0.1 6" mass="10000"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=12 segments=12 diameter=0.03
      mass_per_length=1 EA=1e6 damping=1e3 integrator=)" +
                          std::string(GetParam()) + R"( contact=pipe"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  s.d->qvel[0] = 3;
  double ahead_min = INFINITY;
  while (s.d->time < 1.5) {
    ASSERT_TRUE(s.Step());
    const double* x = NodePositions(s.m, s.d, 0);
    const double xp = s.d->qpos[0];
    // The pipe is vertical (a capsule along z) at y = 0: compare its x with the tether's at
    // the node nearest y = 0.
    int mid = 0;
    for (int i = 0; i <= 12; ++i) {
      if (std::abs(x[3 * i + 1]) < std::abs(x[3 * mid + 1])) mid = i;
    }
    ahead_min = std::min(ahead_min, x[3 * mid] - xp);
  }
  // The middle node ends ahead of the pipe's axis by about the two radii (a penetration of
  // a few mm at most), never behind it.
  EXPECT_GT(ahead_min, 0.0) << "the pipe passed through the tether";
  EXPECT_GT(NodePositions(s.m, s.d, 0)[3 * 6] - s.d->qpos[0], 0.1);
  EXPECT_GT(s.d->qpos[0], 4.0);
}

INSTANTIATE_TEST_SUITE_P(Contact, NoTunnelling,
                         ::testing::Values("explicit", "rk4", "implicit", "implicit2"),
                         StringParamName());

// ---------------------------------------------------------------------------------------------
// Resting: a heavy tether lying down a slope of angle alpha, a plane or the top of a tilted
// box, held only by friction (the scene and Coulomb's bounds: slope_scene.h).
struct SlopeCase {
  const char* geom;
  double tan_alpha;
};
void PrintTo(const SlopeCase& c, std::ostream* os) {
  *os << c.geom << ", tan alpha " << c.tan_alpha;
}

class Resting : public ::testing::TestWithParam<std::tuple<SlopeCase, const char*>> {};

TEST_P(Resting, SlidesWhenTanAlphaExceedsMu) {
  const auto [sc, integrator] = GetParam();
  const Slope sl{std::atan(sc.tan_alpha)};
  const Vec3 normal = sl.normal();
  const std::string euler = "0 " + Fmt(sl.alpha) + " 0";
  const std::string surface =
      std::string(sc.geom) == "plane"
          ? R"(<geom name="ground" type="plane" size="10 10 0.1" euler=")" + euler + R"("/>)"
          : R"(<geom name="ground" type="box" size="4 1 0.5" pos=")" + Fmt(-0.5 * normal.x()) +
                " 0 " + Fmt(-0.5 * normal.z()) + R"(" euler=")" + euler + R"("/>)";
  ExpectCoulomb(sl, SlideDownSlope(sl, "", surface, integrator));
}

INSTANTIATE_TEST_SUITE_P(
    Contact, Resting,
    ::testing::Combine(::testing::Values(SlopeCase{"plane", 0.2}, SlopeCase{"plane", 0.45},
                                         SlopeCase{"box", 0.2}, SlopeCase{"box", 0.45}),
                       ::testing::Values("explicit", "rk4", "implicit")),
    [](const auto& info) {
      const SlopeCase& c = std::get<0>(info.param);
      return std::string(c.geom) + "_tan" + NumberName(c.tan_alpha) + "_" + std::get<1>(info.param);
    });

// ---------------------------------------------------------------------------------------------
// Every supported geom type: a dry 0.6 m tether lowered onto it at 0.6 m/s until its end is
// 0.3 m above the top piles up on it or slides off it, and no point of its axis (nodes and
// segment midpoints) gets closer to the geom's surface than the tether's radius less the
// penalty's sink (the whole tether's weight, 6 N, on one segment: 6 N over k L0 = 4e4 N/m,
// 0.15 mm; 5 mm allowed for the landing at 0.6 m/s and the pile falling on it). Tension
// only: a column that pushes back would be driven into the geom by the mocap hand. The
// distance is the geom's exact signed distance, written here independently of the glue
// (the ellipsoid: only "not inside", its distance having no closed form).
class EveryGeomType : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryGeomType, TetherStaysOutside) {
  const std::string type = GetParam();
  const std::string size = type == "sphere"     ? "0.3"
                           : type == "capsule"  ? "0.2 0.3"
                           : type == "cylinder" ? "0.3 0.2"
                           : type == "box"      ? "0.3 0.25 0.2"
                           : type == "plane"    ? "2 2 0.1"
                                                : "0.3 0.4 0.25";
  // [m] highest point of the geom
  const double top = type == "sphere"      ? 0.3
                     : type == "capsule"   ? 0.5
                     : type == "plane"     ? 0.0
                     : type == "ellipsoid" ? 0.25
                                           : 0.2;
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="g" type=")" +
                          type + R"(" size=")" + size + R"("/>
    <body name="hand" mocap="true" pos="0.05 0.03 )" +
                          Fmt(top + 0.9) + R"(">
      <site name="a"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,free length=0.6 segments=15 diameter=0.02
      mass_per_length=1 EA=1e5 damping=20 contact=g contact_friction=0.3 integrator=implicit"/>
  </custom>
</mujoco>)";
  // Backward Euler declared (issue 17): the contact mode, sqrt(k L0/m) h = 2 at this step, is not
  // resolved, and backward Euler damps it; with bdf2 the tether's axis came to 2.4 mm of the
  // sphere (7.6 mm into its radius) where the check allows 5 mm. Which is nearer the converged
  // penetration is not measured yet (open, docs/numerics.md).
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  auto sdf = [&](const Vec3& p) -> double {
    if (type == "sphere") return p.norm() - 0.3;
    if (type == "capsule") {
      return (p - Vec3(0, 0, std::clamp(p.z(), -0.3, 0.3))).norm() - 0.2;
    }
    if (type == "cylinder") {
      const double dr = std::hypot(p.x(), p.y()) - 0.3, dz = std::abs(p.z()) - 0.2;
      return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0)) + std::min(std::max(dr, dz), 0.0);
    }
    if (type == "box") {
      const Vec3 q = p.cwiseAbs() - Vec3(0.3, 0.25, 0.2);
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    if (type == "plane") return p.z();
    // Ellipsoid: positive outside, no distance.
    const double e =
        std::pow(p.x() / 0.3, 2) + std::pow(p.y() / 0.4, 2) + std::pow(p.z() / 0.25, 2);
    return e > 1 ? 0.01 : -1;
  };
  double closest = INFINITY;
  while (s.d->time < 1.5) {
    // Lowered at 0.6 m/s until its end is 0.3 m above the top, then held.
    s.d->mocap_pos[2] = top + 0.9 - 0.6 * std::min(s.d->time, 1.0);
    ASSERT_TRUE(s.Step());
    const double* x = NodePositions(s.m, s.d, 0);
    for (int i = 0; i <= 15; ++i) {
      closest = std::min(closest, sdf(Vec3(x + 3 * i)));
      if (i < 15) closest = std::min(closest, sdf(0.5 * (Vec3(x + 3 * i) + Vec3(x + 3 * i + 3))));
    }
  }
  EXPECT_GT(closest, 0.01 - 0.005) << "the tether's axis came closer than its radius";
  // It did land on the geom (the ellipsoid: somewhere near its top).
  const double* x = NodePositions(s.m, s.d, 0);
  double lowest = INFINITY;
  for (int i = 0; i <= 15; ++i) lowest = std::min(lowest, sdf(Vec3(x + 3 * i)));
  if (type != "ellipsoid") {
    EXPECT_LT(lowest, 0.05);
  }
}

INSTANTIATE_TEST_SUITE_P(Contact, EveryGeomType,
                         ::testing::Values("plane", "sphere", "capsule", "cylinder", "box",
                                           "ellipsoid"),
                         StringParamName());

// ---------------------------------------------------------------------------------------------
// Declarations: every key range-checked, unknown names refused with the file, element and key.
std::string LoadError(const std::string& tether_keys, const std::string& extra = "") {
  const std::string xml = R"(
<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <body name="rock" pos="0 0 1"><geom name="stone" type="sphere" size="0.2"/></body>
    )" + extra + R"(
    <site name="a" pos="0 0 2"/>
    <site name="b" pos="1 0 2"/>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=2 segments=4 diameter=0.02
      mass_per_length=1 EA=1e5 )" +
                          tether_keys + R"("/>
  </custom>
</mujoco>)";
  std::string error;
  mjModel* m = LoadModelFromString(xml, "scene.xml", &error);
  if (m) {
    Detach(m);
    mj_deleteModel(m);
    return "";
  }
  return error;
}

TEST(ContactDeclaration, RangesAndNames) {
  EXPECT_EQ(LoadError("contact=all"), "");
  EXPECT_EQ(LoadError("contact=floor,rock"), "");
  struct Bad {
    const char* keys;
    const char* expect;
  };
  const Bad bad[] = {
      {"contact=boulder", "no geom or body named 'boulder'"},
      {"contact=floor,,rock", "has an empty name"},
      {"contact=all contact_stiffness=0",
       "key 'contact_stiffness' = 0 is out of range; "
       "allowed: (0, 1e+10]"},
      {"contact=all contact_damping=-1", "key 'contact_damping' = -1 is out of range"},
      {"contact=all contact_friction=11",
       "key 'contact_friction' = 11 is out of range; "
       "allowed: [0, 10]"},
      {"contact=all contact_friction_speed=0",
       "key 'contact_friction_speed' = 0 is out of "
       "range; allowed: (0, 10]"},
      {"contact_friction=0.3", "contact_* keys are given but no 'contact'"},
      {"contact=all contact_stiffness=nan",
       "key 'contact_stiffness': 'nan' is not a finite number"},
      {"contact=all contact_friction=0.2 integrator=implicit2",
       "not supported with "
       "integrator=implicit2"},
  };
  for (const Bad& b : bad) {
    const std::string e = LoadError(b.keys);
    EXPECT_NE(e.find("scene.xml: <text name=\"tether:t\">: "), std::string::npos) << e;
    EXPECT_NE(e.find(b.expect), std::string::npos) << b.keys << " -> " << e;
  }
}

// implicit2 with contact and an end on a body with degrees of freedom is refused at load: its
// end tensions were measured wrong there (a static drape read 19-67 N for 46.6 N, depending on
// the step; docs/contact.md). The same scene with the end on a fixed body loads.
TEST(ContactDeclaration, Implicit2WithContactOnAMovingBodyIsRefused) {
  auto load = [](const std::string& joint) {
    const std::string xml = R"(
<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <site name="a" pos="0 0 2"/>
    <body name="slider" pos="1 0 2">)" + joint + R"(<geom type="sphere" size="0.05" mass="1"/>
      <site name="b"/></body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=2 segments=4 diameter=0.02
      mass_per_length=1 EA=1e5 contact=all integrator=implicit2"/>
  </custom>
</mujoco>)";
    std::string error;
    mjModel* m = LoadModelFromString(xml, "scene.xml", &error);
    if (m) {
      Detach(m);
      mj_deleteModel(m);
    }
    return error;
  };
  EXPECT_EQ(load(""), "");
  const std::string e = load(R"(<joint type="slide" axis="1 0 0"/>)");
  EXPECT_NE(e.find("scene.xml: <text name=\"tether:t\">: key 'integrator' = implicit2 is not "
                   "supported with 'contact' and end B on body 'slider'"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("use integrator=bdf2"), std::string::npos) << e;
}

// Without `contact=` nothing is computed: the contact effect is off and the tether passes
// through the geoms as before (here: it falls through a floor plane).
TEST(ContactDeclaration, AbsentMeansNoContact) {
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 0.1"/>
    <site name="a" pos="0 0 0.5"/>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,free length=2 segments=10 diameter=0.02
      mass_per_length=1 EA=1e5 damping=10"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  EXPECT_EQ(GetTether(s.m, 0)->params().effects & kContact, 0u);
  while (s.d->time < 0.5) ASSERT_TRUE(s.Step());
  EXPECT_LT(NodePositions(s.m, s.d, 0)[3 * 10 + 2], -1.0);  // hangs 1.5 m below the floor
}

}  // namespace
}  // namespace mjtether::testing
