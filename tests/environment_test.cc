// The water a tether is in, beyond a uniform current and a flat seabed (docs/environment.md):
// a current that varies with depth (current_profile=FILE.csv), checked against an independent
// integration of the static equilibrium of a cable, and against the uniform current it must
// reduce to.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>
#include <ostream>
#include <string>

#include "mujoco_fixture.h"
#include "param_name.h"

namespace mjtether::testing {
namespace {


std::string WriteFile(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

// ---------------------------------------------------------------------------------------------
// A vertical tether in a linearly sheared current u_x(z) = u0 + s (z - z0), with a weight (a
// vehicle) at its lower end, at rest.
//
// The reference is the static equilibrium ODE of an extensible cable with no bending
// (e.g. Irvine, Cable Structures, 1981, ch. 1; the same as MoorDyn's quasi-static line), in the
// unstretched arclength s0 from the lower end up, with F the force that the part above exerts
// on the part below:
//   dF/ds0 = -[ w + (1 + T/EA) f_drag(u(z), t) ],   dx/ds0 = (1 + T/EA) t,   t = F/T, T = |F|,
//   w = -(mu - rho A) g e_z (net weight per rest length),
//   f_drag = 1/2 rho Cdn d |u_n| u_n + 1/2 rho Cdt pi d |u_t| u_t  (per stretched length),
// and F(0) = minus the other forces on the vehicle: its net weight and its damping in the
// current at its own depth, (D_l + D_q |u|) u. The lower end's position is found by shooting
// (Newton on x(L) = top) with RK4 at 40 steps per segment, whose error (~1e-12 m) is nothing
// beside the lumped model's.
struct Sheared {
  double L = 20, d = 0.03, mu = 1.0, EA = 1e5, Cdn = 1.2, Cdt = 0.01;
  double rho = 1025, g = 9.81;
  double M = 100, V = 0.02;             // vehicle [kg], [m^3]
  double Dl = 20, Dq = 100;             // vehicle surge damping [N s/m], [N s^2/m^2]
  double z0 = -25, u0 = 0.1, u1 = 0.7;  // profile rows (z0, u0) and (0, u1)
  double Ux(double z) const {
    if (z <= z0) return u0;
    if (z >= 0) return u1;
    return u0 + (u1 - u0) * (z - z0) / (0 - z0);
  }
};

// Integrates from the lower end at xb (x, z) up the whole length; returns the positions at
// every node of an N-segment tether, from the lower end (index 0) up.
std::vector<Eigen::Vector2d> Integrate(const Sheared& c, const Eigen::Vector2d& xb, int N) {
  const double A = M_PI * c.d * c.d / 4, w = (c.mu - c.rho * A) * c.g;
  const double kn = 0.5 * c.rho * c.Cdn * c.d, kt = 0.5 * c.rho * c.Cdt * M_PI * c.d;
  using State = Eigen::Vector4d;  // x, z, Fx, Fz
  auto rhs = [&](const State& y) {
    const Eigen::Vector2d F = y.tail<2>();
    const double T = F.norm(), stretch = 1 + T / c.EA;
    const Eigen::Vector2d t = F / T, u(c.Ux(y[1]), 0);
    const double ut = u.dot(t);
    const Eigen::Vector2d un = u - ut * t;
    const Eigen::Vector2d fd = kn * un.norm() * un + kt * std::abs(ut) * ut * t;
    State dy;
    dy.head<2>() = stretch * t;
    dy.tail<2>() = -(Eigen::Vector2d(0, -w) + stretch * fd);
    return dy;
  };
  const double ub = c.Ux(xb[1]);
  State y;
  y << xb, -(c.Dl + c.Dq * std::abs(ub)) * ub, (c.M - c.rho * c.V) * c.g;
  std::vector<Eigen::Vector2d> out = {xb};
  const int sub = 40;
  const double h = c.L / N / sub;
  for (int i = 0; i < N; ++i) {
    for (int k = 0; k < sub; ++k) {
      const State k1 = rhs(y), k2 = rhs(y + 0.5 * h * k1), k3 = rhs(y + 0.5 * h * k2),
                  k4 = rhs(y + h * k3);
      y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    out.push_back(y.head<2>());
  }
  return out;
}

// Shooting: the lower end such that the upper end lands at the origin (the top site).
std::vector<Eigen::Vector2d> Equilibrium(const Sheared& c, int N) {
  Eigen::Vector2d xb(0, -c.L);
  for (int it = 0; it < 30; ++it) {
    const Eigen::Vector2d r = Integrate(c, xb, N).back();
    if (r.norm() < 1e-11) break;
    Eigen::Matrix2d J;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d e = xb;
      e[k] += 1e-6;
      J.col(k) = (Integrate(c, e, N).back() - r) / 1e-6;
    }
    xb -= J.inverse() * r;
  }
  return Integrate(c, xb, N);
}

std::string ShearedScene(const Sheared& c, int N, const std::string& integrator,
                         const std::string& water, double x0 = 0, double z0 = 0) {
  return R"(
<mujoco>
  <option timestep="0.002"><flag contact="disable"/></option>
  <custom>
    <text name="water" data=")" +
         water + R"("/>
    <text name="tether:t" data="ends=top,rov length=)" +
         Fmt(c.L) + " segments=" + std::to_string(N) + " diameter=" + Fmt(c.d) +
         " mass_per_length=" + Fmt(c.mu) + " EA=" + Fmt(c.EA) + " damping=2000 Cdn=" + Fmt(c.Cdn) +
         " Cdt=" + Fmt(c.Cdt) + " integrator=" + integrator + R"("/>
    <text name="vehicle:rov" data="volume=)" +
         Fmt(c.V) + " linear_damping=" + Fmt(c.Dl) + "," + Fmt(c.Dl) +
         R"(,2000,50,50,50 quadratic_damping=)" + Fmt(c.Dq) + "," + Fmt(c.Dq) +
         R"(,100,10,10,10"/>
  </custom>
  <worldbody>
    <site name="top" pos="0 0 0"/>
    <body name="rov" pos=")" +
         Fmt(x0) + " 0 " + Fmt(z0 == 0 ? -c.L : z0) + R"(">
      <freejoint/>
      <geom type="box" size="0.3 0.3 0.3" mass=")" +
         Fmt(c.M) + R"("/>
      <site name="rov"/>
    </body>
  </worldbody>
</mujoco>)";
}

// Largest distance [m] between the settled tether's nodes (top = node 0) and the reference
// (lower end = index 0), after `seconds` of simulation.
double ShapeError(const Sheared& c, int N, const std::string& integrator, double seconds,
                  double* offset) {
  const std::string csv =
      WriteFile("profile_sheared.csv",
                "z,ux,uy,uz\n" + Fmt(c.z0) + "," + Fmt(c.u0) + ",0,0\n0," + Fmt(c.u1) + ",0,0\n");
  // The vehicle starts at the reference's lower end (the tether straight to it): the slowest
  // mode, the line swinging against drag and the vehicle's damping (time constant ~6 s),
  // then starts from centimetres, not metres, away.
  const std::vector<Eigen::Vector2d> ref = Equilibrium(c, N);
  LoadedScene s(ShearedScene(c, N, integrator, "density=1025 current_profile=" + csv, ref[0].x(),
                             ref[0].y()));
  if (!s.m) return 1e9;
  const int steps = static_cast<int>(seconds / s.m->opt.timestep);
  for (int k = 0; k < steps; ++k) {
    if (!s.Step()) return 1e9;
  }
  EXPECT_LT(Vec3(s.d->qvel).norm(), 1e-5) << "not at rest";
  const double* x = NodePositions(s.m, s.d, 0);
  double err = 0;
  for (int i = 0; i <= N; ++i) {
    const Eigen::Vector2d sim(x[3 * i], x[3 * i + 2]);
    err = std::max(err, (sim - ref[N - i]).norm());
    EXPECT_NEAR(x[3 * i + 1], 0, 1e-9);  // the current is along x: nothing moves along y
  }
  *offset = ref[0].x();
  return err;
}

class ShearedCurrent : public ::testing::TestWithParam<const char*> {};

// The settled shape matches the integrated equilibrium. The lumped-mass tether is a second-
// order discretisation of the ODE (loads lumped at nodes by the trapezoid rule, tension
// constant along a segment), so its error falls as L0^2: the test asserts it at 20 segments
// (L0 = 1 m) below 0.5 % of the vehicle's offset (measured: 1.2 mm of 0.94 m, 0.13 %), and
// that 40 segments cut it by more than 2.5 (4 for exact second order, measured 4.0; 2.5 leaves
// room for what has not settled after 60 s: the vehicle moves at < 1e-5 m/s, also asserted).
TEST_P(ShearedCurrent, StaticShapeMatchesIntegratedEquilibrium) {
  const Sheared c;
  double offset = 0, offset2 = 0;
  const double e20 = ShapeError(c, 20, GetParam(), 60, &offset);
  const double e40 = ShapeError(c, 40, GetParam(), 60, &offset2);
  RecordProperty("offset_m", Fmt(offset));
  RecordProperty("error20_m", Fmt(e20));
  RecordProperty("error40_m", Fmt(e40));
  // The current pushes the vehicle about 0.9 m down-stream (with the uniform mean current the
  // offset differs by more than 5 %, see below).
  EXPECT_GT(offset, 0.5);
  EXPECT_LT(e20, 0.005 * offset) << "offset " << offset;
  EXPECT_GT(e20 / e40, 2.5) << "e20 " << e20 << " e40 " << e40;
}

INSTANTIATE_TEST_SUITE_P(Integrators, ShearedCurrent,
                         ::testing::Values("implicit", "implicit2", "explicit", "rk4"),
                         StringParamName());

// The reference is sensitive to the profile: the same ODE with the depth-averaged current
// taken uniform moves the lower end by more than the tolerance above, so a tether that saw
// one current everywhere (or the vehicle's current at the wrong depth) would fail.
TEST(ShearedCurrentReference, DiffersFromUniformMeanCurrent) {
  Sheared c;
  const double offset = Equilibrium(c, 40)[0].x();
  Sheared mean = c;
  mean.u0 = mean.u1 = 0.5 * (c.Ux(-c.L) + c.Ux(0));
  const double offset_mean = Equilibrium(mean, 40)[0].x();
  EXPECT_GT(std::abs(offset - offset_mean), 0.05 * offset);
}

// A profile whose rows all hold the same current is that uniform current: the same state, bit
// for bit, for every integrator (the interpolation adds zero).
class UniformProfile : public ::testing::TestWithParam<const char*> {};

TEST_P(UniformProfile, EqualsUniformCurrent) {
  const Sheared c;
  const std::string csv =
      WriteFile("profile_uniform.csv", "-50,0.3,-0.1,0.02\n-10,0.3,-0.1,0.02\n");
  LoadedScene a(ShearedScene(c, 10, GetParam(), "density=1025 current=0.3,-0.1,0.02"));
  LoadedScene b(ShearedScene(c, 10, GetParam(), "density=1025 current_profile=" + csv));
  ASSERT_TRUE(a.m && b.m);
  for (int k = 0; k < 500; ++k) {
    ASSERT_TRUE(a.Step());
    ASSERT_TRUE(b.Step());
  }
  const double *xa = NodePositions(a.m, a.d, 0), *xb = NodePositions(b.m, b.d, 0);
  for (int i = 0; i < 6 * 11; ++i) ASSERT_EQ(xa[i], xb[i]) << i;  // positions and velocities
  for (int i = 0; i < a.m->nq; ++i) ASSERT_EQ(a.d->qpos[i], b.d->qpos[i]) << i;
  // And the current acted: the vehicle drifted along it.
  EXPECT_GT(a.d->qpos[0], 0.01);
}

INSTANTIATE_TEST_SUITE_P(Integrators, UniformProfile,
                         ::testing::Values("implicit", "implicit2", "explicit", "rk4"),
                         StringParamName());

// Declaration errors: exclusive with a non-zero current; the file is named.
TEST(CurrentProfileDeclaration, Refusals) {
  const Sheared c;
  const std::string csv = WriteFile("profile_ok.csv", "0,0.1,0,0\n");
  std::string error;
  mjModel* m =
      LoadModelFromString(ShearedScene(c, 5, "implicit", "current=0.1,0,0 current_profile=" + csv),
                          "scene.xml", &error);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(error.find("scene.xml: <text name=\"water\">"), std::string::npos) << error;
  EXPECT_NE(error.find("'current' and 'current_profile' exclude each other"), std::string::npos)
      << error;
  const std::string bad = WriteFile("profile_bad.csv", "z,ux,uy,uz\n0,0,0,0\n-1,0,0,0\n");
  m = LoadModelFromString(ShearedScene(c, 5, "implicit", "current_profile=" + bad), "scene.xml",
                          &error);
  EXPECT_EQ(m, nullptr);
  EXPECT_NE(error.find(bad + " line 3: z must increase strictly"), std::string::npos) << error;
}

// ---------------------------------------------------------------------------------------------
// Seabed geoms (seabed=GEOMNAME).
//
// Tilted plane: a heavy tether lying straight down a plane geom tilted by alpha, held only by
// seabed friction mu (its upper end on a 200 g frictionless slider along the slope, which runs
// ahead so the first segment goes slack; 200 g keeps rk4's coupling omega h, 0.45, below its
// limit 0.5, docs/coupling.md (100 g, 0.63, until session 29 lowered it from 0.8); as
// tests/contact_test.cc's Resting, here with the
// seabed law). No drag (Cdn = Cdt = 0), so the closed form is Coulomb's: it stays when
// tan(alpha) < mu, within the regularisation (creep at eps atanh(tan(alpha)/mu), bounded by 3
// times that over 1 s), and slides with a = g' (sin(alpha) - mu cos(alpha)) otherwise, g' =
// g (1 - rho A / m) the net weight over the dry mass per length; distance after 1 s within
// 10 % of a/2 (settling onto the penalty in the first instants).
struct PlaneCase {
  double tan_alpha;
  const char* integrator;
};
void PrintTo(const PlaneCase& c, std::ostream* os) {
  *os << "tan alpha " << c.tan_alpha << ", " << c.integrator;
}

class SeabedPlane : public ::testing::TestWithParam<PlaneCase> {};

TEST_P(SeabedPlane, SlidesWhenTanAlphaExceedsMu) {
  const PlaneCase pc = GetParam();
  const double mu = 0.3, eps = 0.01, alpha = std::atan(pc.tan_alpha), g = 9.81;
  const double m = 2, d = 0.02, rho = 1025, A = M_PI * d * d / 4;
  const double gp = g * (1 - rho * A / m);
  const Vec3 down(std::cos(alpha), 0, -std::sin(alpha)),
      normal(std::sin(alpha), 0, std::cos(alpha));
  const Vec3 start = -1.0 * down + 0.001 * normal;
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"><flag contact="disable"/></option>
  <compiler angle="radian"/>
  <custom>
    <text name="water" data="density=1025 seabed=ground seabed_friction=)" +
                          Fmt(mu) + " seabed_friction_speed=" + Fmt(eps) + R"("/>
    <text name="tether:t" data="ends=a,free length=2 segments=20 diameter=0.02
      mass_per_length=2 EA=1e3 damping=1 integrator=)" +
                          pc.integrator + R"("/>
  </custom>
  <worldbody>
    <geom name="ground" type="plane" size="10 10 0.1" euler="0 )" +
                          Fmt(alpha) + R"( 0"/>
    <body name="slider" pos=")" +
                          Fmt(start.x()) + " 0 " + Fmt(start.z()) + R"(">
      <joint name="s" type="slide" axis=")" +
                          Fmt(down.x()) + " 0 " + Fmt(down.z()) + R"("/>
      <geom type="sphere" size="0.005" mass="0.2"/>
      <site name="a"/>
    </body>
  </worldbody>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  mj_forward(s.m, s.d);
  // Lying straight down the slope, sunk by the static penetration w cos(alpha) / k.
  const double k = GetTether(s.m, 0)->env().water.seabed_stiffness;
  const double sink = m * gp * std::cos(alpha) / k;
  Eigen::Matrix3Xd x(3, 21);
  for (int i = 0; i <= 20; ++i) x.col(i) = start + 0.1 * i * down - (0.001 + sink) * normal;
  double* xp = const_cast<double*>(NodePositions(s.m, s.d, 0));
  for (int i = 0; i < 63; ++i) xp[i] = x.data()[i], xp[63 + i] = 0;
  while (s.d->time < 1.0) ASSERT_TRUE(s.Step());
  const double moved = down.dot(Vec3(NodePositions(s.m, s.d, 0) + 30) - x.col(10));
  // Still on the plane: the middle node within 1 mm of it.
  EXPECT_NEAR(normal.dot(Vec3(NodePositions(s.m, s.d, 0) + 30)), -sink, 1e-3);
  if (pc.tan_alpha < mu) {
    const double creep = eps * std::atanh(pc.tan_alpha / mu);
    EXPECT_LT(std::abs(moved), 3 * creep * 1.0) << "tan(alpha) < mu: it should stay";
  } else {
    const double a = gp * (std::sin(alpha) - mu * std::cos(alpha));
    EXPECT_NEAR(moved, 0.5 * a, 0.1 * 0.5 * a) << "tan(alpha) > mu: it should slide";
  }
}

INSTANTIATE_TEST_SUITE_P(Cases, SeabedPlane,
                         ::testing::Values(PlaneCase{0.2, "implicit"}, PlaneCase{0.45, "implicit"},
                                           PlaneCase{0.2, "implicit2"},
                                           PlaneCase{0.45, "implicit2"}, PlaneCase{0.2, "explicit"},
                                           PlaneCase{0.45, "explicit"}, PlaneCase{0.2, "rk4"},
                                           PlaneCase{0.45, "rk4"}),
                         [](const ::testing::TestParamInfo<PlaneCase>& info) {
                           return "tan" + NumberName(info.param.tan_alpha) + "_" +
                                  info.param.integrator;
                         });

// Height field: models/seabed_hfield.xml (a sloping, rough hfield from a PNG, a 60 m tether
// lying on it) settles, and every node is on or above the surface within the static
// penetration. A node's seabed force balances its net weight w l_i and the pull of the
// segments on either side turning over the ground, F_i = |T_i t_i - T_{i-1} t_{i-1}|, and
// the bending shear F_b (below), so its penetration is at most (w l_i + F_i + F_b) / (k l_i)
// (plus 20 % for what is left of motion, and 1e-6 m): about 2e-5 m here. A wrong surface
// (rows and columns swapped, the other diagonal, the wrong height scale) puts nodes
// centimetres to metres off; and the surface the engine uses is checked against MuJoCo's own,
// by a ray cast down onto the geom at every node (mj_ray, within 1e-6 m: float data). At
// least 15 nodes must be on the ground (within 1 mm).
class SeabedHfield : public ::testing::TestWithParam<const char*> {};

TEST_P(SeabedHfield, NodesRestOnTheSurface) {
  // The model with the integrator under test appended to the tether's text (it declares the
  // default, implicit) and the PNG's path made absolute.
  std::string error;
  std::ifstream in(MJTETHER_MODELS_DIR "/seabed_hfield.xml");
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "Cdn=1.2 Cdt=0.01 Can=1";
  ASSERT_NE(xml.find(key), std::string::npos);
  xml.replace(xml.find(key), key.size(), key + " integrator=" + GetParam());
  const std::string png = "file=\"seabed_hfield.png\"";
  ASSERT_NE(xml.find(png), std::string::npos);
  xml.replace(xml.find(png), png.size(), "file=\"" MJTETHER_MODELS_DIR "/seabed_hfield.png\"");
  mjModel* m2 = LoadModelFromString(xml, "seabed_hfield.xml", &error);
  ASSERT_NE(m2, nullptr) << error;
  mjData* d = mj_makeData(m2);
  const Tether* tether = GetTether(m2, 0);
  const Water& w = tether->env().water;
  ASSERT_TRUE(w.surface.declared());
  const int N = tether->segments();
  // 30 s: the line's slowest swing (a 60 m catenary, period ~ 2 pi sqrt(L/g) ~ 15 s) damped
  // by drag and seabed friction.
  double vmax = 0;
  while (d->time < 30) {
    mj_step(m2, d);
    if (std::optional<std::string> message = CheckDivergence(m2, d)) FAIL() << *message;
  }
  const double* x = NodePositions(m2, d, 0);
  const double* v = NodeVelocities(m2, d, 0);
  std::vector<double> T(N);
  GetTensions(m2, d, 0, T.data());
  const double k = w.seabed_stiffness;
  const double wl = std::abs(tether->node_weight(N / 2).z()) / tether->rest_segment_length();
  int grounded = 0;
  double worst = 0, pen_max = 0,
         ray_gap = 0;  // largest penetration / its bound, largest penetration [m]
  for (int i = 1; i < N; ++i) {
    vmax = std::max(vmax, Vec3(v + 3 * i).norm());
    double zs;
    Vec3 n;
    w.surface.Under(x[3 * i], x[3 * i + 1], &zs, &n);
    // The engine's surface is MuJoCo's: a ray cast straight down onto the hfield geom (MuJoCo's
    // own triangles, mj_ray) lands at the same height (to round-off; the data are floats).
    const mjtNum from[3] = {x[3 * i], x[3 * i + 1], x[3 * i + 2] + 10}, down[3] = {0, 0, -1};
    int geom = -1;
    const double dist = mj_ray(m2, d, from, down, nullptr, 1, -1, &geom);
    ASSERT_GE(dist, 0) << "node " << i;
    EXPECT_NEAR(from[2] - dist, zs, 1e-6) << "node " << i;
    ray_gap = std::max(ray_gap, std::abs(from[2] - dist - zs));
    const double pen = (zs - x[3 * i + 2]) * n.z();
    const Vec3 ta = (Vec3(x + 3 * i) - Vec3(x + 3 * i - 3)).normalized();
    const Vec3 tb = (Vec3(x + 3 * i + 3) - Vec3(x + 3 * i)).normalized();
    const double li = tether->rest_segment_length();
    const double F = (T[i] * tb - T[i - 1] * ta).norm();
    // Bending: the moments EI sin(theta_j)/L0 at nodes i-1, i, i+1 (theta_j the turning angle
    // there) give node i shear forces of at most (|M_{i-1}| + 2 |M_i| + |M_{i+1}|) / L0.
    auto turning = [&](int j) {
      if (j <= 0 || j >= N) return 0.0;
      const Vec3 p = (Vec3(x + 3 * j) - Vec3(x + 3 * j - 3)).normalized();
      const Vec3 q = (Vec3(x + 3 * j + 3) - Vec3(x + 3 * j)).normalized();
      return p.cross(q).norm();
    };
    const double EI = tether->params().EI, L0 = tether->rest_segment_length();
    const double Fb = EI / (L0 * L0) * (turning(i - 1) + 2 * turning(i) + turning(i + 1));
    const double bound = 1.2 * (wl * li + F + Fb) / (k * li) + 1e-6;
    EXPECT_LE(pen, bound) << "node " << i;
    worst = std::max(worst, pen / bound);
    if (pen > -1e-3) ++grounded;
    pen_max = std::max(pen_max, pen);
  }
  EXPECT_GE(grounded, 15);
  // At rest within the regularisation: nodes on the ground creep at up to the friction's
  // slip speed eps and the hanging leg's drag-damped swing has decayed below 2 eps; the
  // inertia left (m_i v omega ~ 0.6 kg x 0.02 m/s x 0.6 rad/s ~ 0.01 N) is 1 % of a node's
  // weight, so the static bound above applies.
  EXPECT_LT(vmax, 2 * w.seabed_friction_speed) << "not at rest after 30 s";
  RecordProperty("grounded", grounded);
  RecordProperty("worst_penetration_over_bound", Fmt(worst));
  std::printf(
      "hfield %s: %d nodes grounded, worst penetration %.3g of its bound, largest %.3g m, "
      "vmax %.3g m/s, surface against mj_ray %.3g m\n",
      GetParam(), grounded, worst, pen_max, vmax, ray_gap);
  mj_deleteData(d);
  Detach(m2);
  mj_deleteModel(m2);
}

INSTANTIATE_TEST_SUITE_P(Integrators, SeabedHfield,
                         ::testing::Values("implicit", "implicit2", "explicit", "rk4"),
                         StringParamName());

// Declaration: seabed=NAME must name a plane or hfield fixed in the world; a bad name is
// reported with the key.
TEST(SeabedDeclaration, Refusals) {
  const std::string base = R"(
<mujoco>
  <option><flag contact="disable"/></option>
  <custom>
    <text name="water" data="seabed=SEABED"/>
    <text name="tether:t" data="ends=a,free length=2 segments=4 diameter=0.02
      mass_per_length=2 EA=1e3"/>
  </custom>
  <worldbody>
    <geom name="ground" type="plane" size="10 10 0.1"/>
    <geom name="ball" type="sphere" size="1" pos="0 0 -5"/>
    <body name="moving" mocap="true" pos="0 0 -3"><geom name="raft" type="plane" size="1 1 1"/></body>
    <site name="a" pos="0 0 1"/>
  </worldbody>
</mujoco>)";
  auto load = [&](const std::string& seabed, std::string* error) {
    std::string xml = base;
    xml.replace(xml.find("SEABED"), 6, seabed);
    mjModel* m = LoadModelFromString(xml, "scene.xml", error);
    if (m) {
      Detach(m);
      mj_deleteModel(m);
    }
    return m != nullptr;
  };
  std::string error;
  EXPECT_TRUE(load("ground", &error)) << error;
  EXPECT_FALSE(load("grond", &error));
  EXPECT_NE(error.find("key 'seabed' = 'grond': no geom of that name"), std::string::npos) << error;
  EXPECT_FALSE(load("ball", &error));
  EXPECT_NE(error.find("must be a plane or an hfield"), std::string::npos) << error;
  EXPECT_FALSE(load("raft", &error));
  EXPECT_NE(error.find("must be fixed in the world"), std::string::npos) << error;
  EXPECT_FALSE(load("nan", &error));
  EXPECT_NE(error.find("not a finite number"), std::string::npos) << error;
}

}  // namespace
}  // namespace mjtether::testing
