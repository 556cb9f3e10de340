// Tether-geom contact geometry (docs/contact.md): mesh geoms through their convex hull against
// exact distances, and the rule for an end's own geoms (skipped only near that end).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>

#include "mujoco_fixture.h"
#include "param_name.h"

namespace mjtether::testing {
namespace {


// Euclidean projection of y onto the probability simplex (Duchi et al., ICML 2008, fig. 1).
Eigen::Vector4d ProjectSimplex(const Eigen::Vector4d& y) {
  std::array<double, 4> u = {y[0], y[1], y[2], y[3]};
  std::sort(u.begin(), u.end(), std::greater<double>());
  double sum = 0, tau = 0;
  for (int k = 0; k < 4; ++k) {
    sum += u[k];
    const double t = (sum - 1) / (k + 1);
    if (u[k] - t > 0) tau = t;
  }
  return (y.array() - tau).max(0.0).matrix();
}

// Distance from p to the tetrahedron with corners V (columns), outside it: the closest point
// is V lambda with lambda on the simplex, found by accelerated projected gradient (FISTA, Beck &
// Teboulle 2009) on |V lambda - p|^2, 400 iterations (squared-distance error below
// 2 L/k^2 ~ 1e-5 m^2 with L = 2 |V^T V|: under 0.5 mm of distance at 1 cm). Independent of the
// glue's triangle-by-triangle closest points. Inside: 0 (the test only needs "not inside").
double TetraDistance(const Eigen::Matrix<double, 3, 4>& V, const Vec3& p) {
  const Eigen::Matrix4d G = V.transpose() * V;
  const double L = 2 * G.norm();
  Eigen::Vector4d lam = Eigen::Vector4d::Constant(0.25), y = lam;
  double t = 1;
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector4d grad = 2 * V.transpose() * (V * y - p);
    const Eigen::Vector4d next = ProjectSimplex(y - grad / L);
    const double tn = 0.5 * (1 + std::sqrt(1 + 4 * t * t));
    y = next + ((t - 1) / tn) * (next - lam);
    lam = next;
    t = tn;
  }
  return (V * lam - p).norm();
}

// ---------------------------------------------------------------------------------------------
// Mesh geoms (convex hull): as contact_test's EveryGeomType, a dry 0.6 m tether lowered onto the
// geom by a mocap hand at 0.6 m/s, and no point of its axis (nodes and segment midpoints) comes
// closer to the exact surface than its radius less 5 mm (the same margin: landing at 0.6 m/s,
// the penalty's sink 0.15 mm), and it lands (its lowest node within 5 cm of the surface).
//   box: an off-centre box mesh (corners x in [-0.2, 0.4], y in [-0.25, 0.25], z in [-0.3, 0.1]:
// MuJoCo moves the mesh to its centre of mass, so the geom's frame is checked too) against the
// box's exact signed distance; tetra: a tetrahedron (corners below) against the distance from
// a projected-gradient solve on its barycentric coordinates. Both in the world frame, from the
// vertices as written in the model.
class MeshGeom : public ::testing::TestWithParam<const char*> {};

TEST_P(MeshGeom, TetherStaysOutside) {
  const std::string shape = GetParam();
  Eigen::Matrix<double, 3, 4> T;
  T << -0.3, 0.35, 0.0, 0.05,  //
      -0.25, -0.2, 0.35, 0.0,  //
      -0.2, -0.2, -0.2, 0.25;
  std::string vertex;
  if (shape == "box") {
    for (double x : {-0.2, 0.4})
      for (double y : {-0.25, 0.25})
        for (double z : {-0.3, 0.1}) vertex += Fmt(x) + " " + Fmt(y) + " " + Fmt(z) + "  ";
  } else {
    for (int k = 0; k < 4; ++k)
      vertex += Fmt(T(0, k)) + " " + Fmt(T(1, k)) + " " + Fmt(T(2, k)) + "  ";
  }
  const double top = shape == "box" ? 0.1 : 0.25;
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"/>
  <asset><mesh name="m" vertex=")" +
                          vertex + R"("/></asset>
  <worldbody>
    <geom name="g" type="mesh" mesh="m"/>
    <body name="hand" mocap="true" pos="0.05 0.03 )" +
                          Fmt(top + 0.9) + R"(">
      <site name="a"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,free length=0.6 segments=15 diameter=0.02
      mass_per_length=1 EA=1e5 damping=20 contact=g contact_friction=0.3"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  auto sdf = [&](const Vec3& p) -> double {
    if (shape == "box") {
      const Vec3 q = (p - Vec3(0.1, 0, -0.1)).cwiseAbs() - Vec3(0.3, 0.25, 0.2);
      return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
    }
    return TetraDistance(T, p);
  };
  double closest = INFINITY;
  while (s.d->time < 1.5) {
    s.d->mocap_pos[2] = top + 0.9 - 0.6 * std::min(s.d->time, 1.0);
    ASSERT_TRUE(s.Step());
    // Every 10th step for the tetrahedron (its distance is an iterative solve).
    if (shape != "box" && std::lround(s.d->time / 0.002) % 10 != 0) continue;
    const double* x = NodePositions(s.m, s.d, 0);
    for (int i = 0; i <= 15; ++i) {
      closest = std::min(closest, sdf(Vec3(x + 3 * i)));
      if (i < 15) closest = std::min(closest, sdf(0.5 * (Vec3(x + 3 * i) + Vec3(x + 3 * i + 3))));
    }
  }
  EXPECT_GT(closest, 0.01 - 0.005) << "the tether's axis came closer than its radius";
  const double* x = NodePositions(s.m, s.d, 0);
  double lowest = INFINITY;
  for (int i = 0; i <= 15; ++i) lowest = std::min(lowest, sdf(Vec3(x + 3 * i)));
  EXPECT_LT(lowest, 0.05) << "the tether landed on the mesh";
}

INSTANTIATE_TEST_SUITE_P(Contact, MeshGeom, ::testing::Values("box", "tetra"), StringParamName());

// ---------------------------------------------------------------------------------------------
// An end's own geoms. A geom on the world body 2 m from a world-site end is scenery, not that
// end's own: a weightless tether from the world site a (x = -2) to a mocap hand swept from
// y = +1 to y = -1 past a tall pile (radius 0.3 m, 20 m tall, at the origin) catches on the
// pile. (The former rule skipped every world-body geom within |site - geom centre| + bounding
// radius = 12 m of arc: this 4.3 m tether passed through.) Asserted: no node or segment midpoint
// inside the pile's radius plus the tether's radius less 5 mm (penalty sink at 2 N over
// k L0 = 1e5 N/m: 0.02 mm), and the pile holds it back (the middle node ends on the pile's +y
// side while the hand is at y = -1).
TEST(OwnGeoms, WorldSceneryIsNotAWorldSiteEndsOwn) {
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002" gravity="0 0 0"/>
  <worldbody>
    <geom name="pile" type="cylinder" size="0.3 10"/>
    <site name="a" pos="-2 0 0"/>
    <body name="hand" mocap="true" pos="2 1 0"><site name="b"/></body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=4.3 segments=43 diameter=0.02
      mass_per_length=0.2 EA=1e4 damping=10 contact=all"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  double closest = INFINITY;
  while (s.d->time < 5) {
    s.d->mocap_pos[1] = 1 - 0.5 * std::min(s.d->time, 4.0);
    ASSERT_TRUE(s.Step());
    const double* x = NodePositions(s.m, s.d, 0);
    for (int i = 0; i <= 43; ++i) {
      const Vec3 p(x + 3 * i);
      closest = std::min(closest, std::hypot(p.x(), p.y()) - 0.3);
      if (i < 43) {
        const Vec3 q = 0.5 * (p + Vec3(x + 3 * i + 3));
        closest = std::min(closest, std::hypot(q.x(), q.y()) - 0.3);
      }
    }
  }
  EXPECT_GT(closest, 0.01 - 0.005) << "the tether passed into the pile";
  const double* x = NodePositions(s.m, s.d, 0);
  double ymax = -INFINITY;
  for (int i = 0; i <= 43; ++i) ymax = std::max(ymax, x[3 * i + 1]);
  EXPECT_GT(ymax, 0.25) << "the pile held the tether back";
}

// A geom the end's site is inside is its own: a tether attached at the centre of a box (0.2 m
// half size) on the hand's body hangs out through its bottom without being pushed by it. With
// the box counted, the nodes inside would be pressed out at k = 1e6 N/m^2 over 0.1 m segments
// (10 kN per metre of depth); skipped, the tether hangs straight and the tension at A is its
// weight: 1 kg/m x 1 m x 9.81 = 9.81 N within 1 % (the free end's tension is 0, the drag of
// the settled tether nil; 1 % covers the damping of the last motion).
TEST(OwnGeoms, AGeomAroundTheSiteIsSkippedNearThatEnd) {
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <body name="hand" mocap="true" pos="0 0 2">
      <geom name="box" type="box" size="0.2 0.2 0.2"/>
      <site name="a"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,free length=1 segments=10 diameter=0.02
      mass_per_length=1 EA=1e5 damping=20 contact=all"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  double T = 0;
  int samples = 0;
  while (s.d->time < 3) {
    ASSERT_TRUE(s.Step());
    if (s.d->time > 2.5) T += GetReactions(s.m, s.d, 0).tension_a, ++samples;
  }
  const double* x = NodePositions(s.m, s.d, 0);
  for (int i = 0; i <= 10; ++i) EXPECT_LT(std::hypot(x[3 * i], x[3 * i + 1]), 1e-3) << i;
  EXPECT_NEAR(T / samples, 9.81, 0.01 * 9.81);
}

// ---------------------------------------------------------------------------------------------
// The reaction acts on the geom's body at the contact point: a taut frictionless tether from
// y = 0 to y = 2 on a mocap sled is carried at 0.5 m/s (+x) into the -x face of a free box
// (half sizes 0.2, no gravity) centred on y = 0, so it presses only the face's y > 0 half. The
// normal force (+x) at arms y in (0, 0.2] turns the box about -z: its angular momentum about
// its centre L_z = -sum y F_x dt lies below 0 and above -0.2 times its momentum P_x (taken while
// the box has turned less than 0.1 rad, so the face stays the -x face). A reaction at the
// centre of mass would give L_z = 0.
TEST(Reaction, AtTheContactPointTurnsTheBody) {
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002" gravity="0 0 0" integrator="Euler"/>
  <worldbody>
    <body name="sled" mocap="true" pos="0 0 0">
      <site name="a" pos="0 0 0"/>
      <site name="b" pos="0 2 0"/>
    </body>
    <body name="box" pos="0.5 0 0">
      <freejoint/>
      <geom name="box" type="box" size="0.2 0.2 0.2" mass="2"/>
    </body>
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=1.98 segments=40 diameter=0.02
      mass_per_length=0.3 EA=2e4 damping=20 contact=box"/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  const int box = mj_name2id(s.m, mjOBJ_BODY, "box");
  double ratio = 0, Px = 0;
  while (s.d->time < 3) {
    s.d->mocap_pos[0] = 0.5 * s.d->time;
    ASSERT_TRUE(s.Step());
    // Box angle about z from its quaternion (qpos 3..6: w, x, y, z).
    const double yaw = 2 * std::atan2(s.d->qpos[6], s.d->qpos[3]);
    if (std::abs(yaw) > 0.1) break;
    Px = s.m->body_mass[box] * s.d->qvel[0];
    // Angular velocity of a free joint: qvel 3..5 in the body frame; L_z = I_zz w_z.
    const double Lz = s.m->body_inertia[3 * box + 2] * s.d->qvel[5];
    if (Px > 0.05) ratio = Lz / Px;
  }
  EXPECT_GT(Px, 0.05) << "the box was pushed";
  // Measured -0.011 (the pinned end A at y = 0 takes the stiffest share, so the mean arm is
  // about 1 cm); the centre-of-mass reaction gives 0 to round-off: 3 mm of arm separates them.
  EXPECT_LT(ratio, -0.003) << "the push on the y > 0 half turned the box about -z";
  EXPECT_GT(ratio, -0.2) << "arm at most the half width";
}

// ---------------------------------------------------------------------------------------------
// A start inside a geom (ContactStartWarning, plugin.cc): a straight 2 m tether (length = span,
// 20 segments, d = 2 cm) across a sphere of radius R = 0.3 m centred D below its middle node.
// The sphere's plane under that node is horizontal, so the skin's depth is exactly
// r + R - D; warned with that depth (to 1e-9 m: the closest point is computed in closed form)
// and the geom's name where it exceeds max(1e-3 d, 2 |w|/k), not warned 1 mm clear. With
// gravity, w = 1 kg/m x 9.81 over k = 1e6: a depth of 1.5e-5 m (below 2 w/k = 1.96e-5 m, at
// d = 5 mm above 1e-3 d) is a line resting on the rock, not warned; 2.5e-5 m is.
std::string StartInsideWarning(double depth, double diameter, double gravity) {
  const double R = 0.3, r = 0.5 * diameter, D = R + r - depth;
  std::ostringstream xml;
  xml.precision(17);
  xml << "<mujoco><option timestep=\"0.002\" gravity=\"0 0 " << -gravity << "\"/><worldbody>"
      << "<geom name=\"rock\" type=\"sphere\" size=\"" << R << "\" pos=\"0 0 " << -D << "\"/>"
      << "<site name=\"a\" pos=\"-1 0 0\"/><site name=\"b\" pos=\"1 0 0\"/></worldbody><custom>"
      << "<text name=\"tether:t\" data=\"ends=a,b length=2 segments=20 diameter=" << diameter
      << " mass_per_length=1 EA=1e5 contact=all\"/></custom></mujoco>";
  std::string error;
  mjModel* m = LoadModelFromString(xml.str(), "inside.xml", &error);
  EXPECT_NE(m, nullptr) << error;
  if (!m) return "";
  std::string found;
  for (const std::string& w : Warnings(m)) {
    if (w.find("starts inside a geom") != std::string::npos) found = w;
  }
  Detach(m);
  mj_deleteModel(m);
  return found;
}

double DepthOf(const std::string& warning) {
  const std::string key = "its skin is ";
  const size_t at = warning.find(key);
  return at == std::string::npos ? NAN : std::stod(warning.substr(at + key.size()));
}

TEST(StartInside, IsWarnedWithTheDepthAndTheGeom) {
  const std::string w = StartInsideWarning(0.005, 0.02, 0);
  ASSERT_FALSE(w.empty());
  EXPECT_NEAR(DepthOf(w), 0.005, 1e-9) << w;
  EXPECT_NE(w.find("inside.xml: <text name=\"tether:t\">"), std::string::npos) << w;
  EXPECT_NE(w.find("geom 'rock'"), std::string::npos) << w;
  EXPECT_NE(w.find("depends on <option timestep>"), std::string::npos) << w;
  EXPECT_TRUE(StartInsideWarning(-0.001, 0.02, 0).empty());
}

TEST(StartInside, ALineRestingOnTheRockUnderItsWeightIsNotWarned) {
  EXPECT_TRUE(StartInsideWarning(1.5e-5, 0.005, 9.81).empty());
  EXPECT_NEAR(DepthOf(StartInsideWarning(2.5e-5, 0.005, 9.81)), 2.5e-5, 1e-9);
}

}  // namespace
}  // namespace mjtether::testing
