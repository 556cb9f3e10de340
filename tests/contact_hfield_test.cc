// Tether contact with height-field geoms (docs/contact.md, "Height fields"): an hfield named in
// `contact=` (not the seabed) pushes the tether out of its top surface with the same penalty,
// damping and friction as the other geoms. Against a tilted plane (a linear ramp is exact on
// the field's triangles), Coulomb on a ramp, statics on a Gaussian ridge, and every integrator
// finite and energy-bounded.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <cstdint>
#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include <unistd.h>

#include "mujoco_fixture.h"
#include "param_name.h"
#include "slope_scene.h"

namespace mjtether::testing {
namespace {



// An <hfield> asset of nrow x ncol heights e(x, y) in [0, 1] (MuJoCo's layout: row-major, rows
// along y from -ry, columns along x from -rx), size "rx ry top base": heights e x top above the
// geom's origin. MJCF 2.2 has no `elevation` attribute: the heights go to a file in MuJoCo's
// own binary format (int32 nrow, int32 ncol, float32 data[nrow ncol]) in the test's temporary
// directory. e's minimum must be 0 and its maximum 1, so that MuJoCo's normalisation of the
// data changes nothing.
std::string Hfield(const std::string& name, int nrow, int ncol, double rx, double ry, double top,
                   double base, const std::function<double(double, double)>& e) {
  std::vector<float> data;
  for (int r = 0; r < nrow; ++r) {
    for (int c = 0; c < ncol; ++c) {
      const double x = -rx + 2 * rx * c / (ncol - 1), y = -ry + 2 * ry * r / (nrow - 1);
      data.push_back(static_cast<float>(e(x, y)));
    }
  }
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string file = ::testing::TempDir() + "hfield_" + std::to_string(::getpid()) + "_" +
                     info->test_suite_name() + "_" + info->name() + "_" + name + ".bin";
  std::replace(file.begin(), file.end(), '/', '_');
  file = ::testing::TempDir() + file.substr(::testing::TempDir().size());
  FILE* f = std::fopen(file.c_str(), "wb");
  EXPECT_NE(f, nullptr) << file;
  if (f) {
    const int32_t dims[2] = {nrow, ncol};
    std::fwrite(dims, sizeof(int32_t), 2, f);
    std::fwrite(data.data(), sizeof(float), data.size(), f);
    std::fclose(f);
  }
  return R"(<hfield name=")" + name + R"(" file=")" + file + R"(" size=")" + Fmt(rx) + " " +
         Fmt(ry) + " " + Fmt(top) + " " + Fmt(base) + R"("/>)";
}

// ---------------------------------------------------------------------------------------------
// (a) A linear ramp is exact on the field's triangles (each is a piece of the same plane), so a
// tether resting across a ramp hfield must settle where it settles on the tilted `plane` geom
// through the same surface. The ramp rises along the oblique direction (cos 30, sin 30) with
// slope 0.25, so both triangles of a cell and both grid directions carry the slope. The heights
// are stored as floats: each is off by at most 2^-24 x 1.6 m ~ 1e-7 m, and the normal by
// ~1e-7 / cell = 1e-6 rad; over the 3 m tether that is below 1e-5 m, the bound asserted on every
// node. What is compared: the plane scene runs 6 s (frictionless, in water: drag slows it, but
// the last sway decays slowly, 4 cm/s left at 8 s), then its state is given to the hfield scene
// and both run 2 s more from it, the tether lying on the surface: the two continuations stay
// within the bound (the same forces on the same states: the plane's equilibrium is the field's).
// (From the start, the two scenes agree to 2e-6 m until the tether lands, then the landing
// amplifies the 1e-7 m height rounding, a penalty force k L0 1e-7 = 0.5 % of a segment's weight,
// to millimetres.) A wrong triangle (the other diagonal), a swapped row/column or a flipped
// normal is off by centimetres or more.
TEST(HfieldContact, RampActsAsTheTiltedPlane) {
  const double rx = 2, ry = 2, slope = 0.25, beta = 30 * M_PI / 180;
  const double gx = slope * std::cos(beta), gy = slope * std::sin(beta);  // dh/dx, dh/dy
  // h(x, y) = h0 + gx x + gy y over [-rx, rx] x [-ry, ry]: from hmin to hmax.
  const double hmin = -gx * rx - gy * ry, hmax = gx * rx + gy * ry, top = hmax - hmin;
  const std::string field = Hfield("ramp", 41, 41, rx, ry, top, 0.1, [&](double x, double y) {
    return (gx * x + gy * y - hmin) / top;
  });
  // Geom at z = hmin: the surface is z = gx x + gy y. The plane through the origin, normal
  // (-gx, -gy, 1).
  const Vec3 n = Vec3(-gx, -gy, 1).normalized();
  auto scene = [&](bool hfield) {
    const std::string geom =
        hfield ? R"(<geom name="ground" type="hfield" hfield="ramp" pos="0 0 )" + Fmt(hmin) +
                     R"("/>)"
               : R"(<geom name="ground" type="plane" size="3 3 0.1" zaxis=")" + Fmt(n.x()) +
                     " " + Fmt(n.y()) + " " + Fmt(n.z()) + R"("/>)";
    return R"(
<mujoco>
  <option timestep="0.002"/>
  <asset>)" + field + R"(</asset>
  <worldbody>
    )" + geom + R"(
    <site name="a" pos="-1.2 -0.6 )" +
           Fmt(-1.2 * gx - 0.6 * gy + 0.5) + R"("/>
    <site name="b" pos="1.2 0.6 )" +
           Fmt(1.2 * gx + 0.6 * gy + 0.5) + R"("/>
  </worldbody>
  <custom>
    <text name="water" data="density=1025"/>
    <text name="tether:t" data="ends=a,b length=3.4 segments=34 diameter=0.02
      mass_per_length=2 EA=1e5 damping=20 Cdn=1.2 Cdt=0.01 integrator=implicit
      contact=ground"/>
  </custom>
</mujoco>)";
  };
  LoadedScene p(scene(false)), h(scene(true));
  ASSERT_NE(p.d, nullptr);
  ASSERT_NE(h.d, nullptr);
  while (p.d->time < 6) {
    ASSERT_TRUE(p.Step());
    ASSERT_TRUE(h.Step());
  }
  // The plane scene's state (near rest) given to the hfield scene: both continue 2 s from it.
  double* sh = const_cast<double*>(NodePositions(h.m, h.d, 0));
  const double* sp = NodePositions(p.m, p.d, 0);
  for (int i = 0; i < 6 * 35; ++i) sh[i] = sp[i];
  while (p.d->time < 8) {
    ASSERT_TRUE(p.Step());
    ASSERT_TRUE(h.Step());
  }
  const double* xp = NodePositions(p.m, p.d, 0);
  const double* xh = NodePositions(h.m, h.d, 0);
  const double* vp = NodeVelocities(p.m, p.d, 0);
  double diff = 0, vmax = 0, lowest = INFINITY;
  for (int i = 0; i <= 34; ++i) {
    diff = std::max(diff, (Vec3(xp + 3 * i) - Vec3(xh + 3 * i)).norm());
    vmax = std::max(vmax, Vec3(vp + 3 * i).norm());
    lowest = std::min(lowest, n.dot(Vec3(xp + 3 * i)));
  }
  std::printf("ramp hfield vs plane: largest node difference %.3g m (v max %.3g m/s)\n", diff,
              vmax);
  RecordProperty("difference", Fmt(diff));
  // It rests on the ramp (some node within 1 mm of the surface: the contact is exercised).
  EXPECT_LT(lowest, 0.01 + 1e-3);
  EXPECT_LT(diff, 1e-5);
}

// ---------------------------------------------------------------------------------------------
// (b) Coulomb on a ramp hfield, as contact_test's Resting on a plane (the scene and the bounds:
// slope_scene.h): the field's heights fall linearly along x, friction mu = 0.3.
struct RampCase {
  double tan_alpha;
  const char* integrator;
};
void PrintTo(const RampCase& c, std::ostream* os) {
  *os << "tan alpha " << c.tan_alpha << ", " << c.integrator;
}

class HfieldRamp : public ::testing::TestWithParam<RampCase> {};

TEST_P(HfieldRamp, SlidesWhenTanAlphaExceedsMu) {
  const RampCase rc = GetParam();
  const Slope sl{std::atan(rc.tan_alpha)};
  // Heights fall from top at x = -rx to 0 at x = rx; the geom placed so that the surface passes
  // through the origin: z = -tan(alpha) x.
  const double rx = 2, ry = 0.5, top = 2 * rx * rc.tan_alpha;
  const std::string field = Hfield("ramp", 5, 81, rx, ry, top, 0.1,
                                   [&](double x, double) { return (rx - x) / (2 * rx); });
  const std::string surface =
      R"(<geom name="ground" type="hfield" hfield="ramp" pos="0 0 )" + Fmt(-0.5 * top) + R"("/>)";
  const double moved = SlideDownSlope(sl, field, surface, rc.integrator);
  std::printf("hfield ramp tan %.2f %s: moved %.4g m\n", rc.tan_alpha, rc.integrator, moved);
  ExpectCoulomb(sl, moved);
}

INSTANTIATE_TEST_SUITE_P(Contact, HfieldRamp,
                         ::testing::Values(RampCase{0.2, "explicit"}, RampCase{0.45, "explicit"},
                                           RampCase{0.2, "rk4"}, RampCase{0.45, "rk4"},
                                           RampCase{0.2, "implicit"}, RampCase{0.45, "implicit"},
                                           RampCase{0.2, "bdf2"}, RampCase{0.45, "bdf2"}),
                         [](const ::testing::TestParamInfo<RampCase>& info) {
                           return "tan" + NumberName(info.param.tan_alpha) + "_" +
                                  info.param.integrator;
                         });

// ---------------------------------------------------------------------------------------------
// (c), (d) A Gaussian ridge (an hfield on the world body, not the seabed) under a tether hung
// between two sites: z = H g(x), g = (exp(-x^2/(2 sigma^2)) - e0)/(1 - e0) (0 at the field's
// edges x = +-3 m, 1 on the crest; e0 = exp(-4.5)), H = 0.5 m, sigma = 1 m, cells 5 cm along x.
// The tether (6 m, 60 segments, ends 5 m apart 0.6 m above the flat ground) starts as a tent
// above the ridge, at rest and unstretched, and falls onto it in water.
//  (d) every integrator: every node finite, and at every step kinetic + gravitational energy at
//      most the start's (the elastic, bending and contact energies are >= 0 and 0 at the start,
//      drag and damping only remove energy; 2 % of the energy released allowed for the
//      integrators' own error over the impact).
//  (c) implicit (friction 0.3, which stops the sway), after 20 s: at rest; no node below the
//      exact surface by more than its static penetration 1.2 (w l + F_i)/(k l) (the net weight
//      per length w and the pull F_i = |T_i t_i - T_{i-1} t_{i-1}| of the two segments turning
//      over the ground, plus 20 %) plus the sampling error of the segment's plane (below), nor
//      any segment midpoint; and statics: the contact force on the
//      tether (its impulse over the last advance / h) carries what the ends do not,
//      F_c,z = |W| + F_a,z + F_b,z (W the net weight, F_a, F_b the forces on the end sites),
//      within 1 % of |W|.
class HfieldRidge : public ::testing::TestWithParam<const char*> {};

TEST_P(HfieldRidge, RestsOnTheRidge) {
  const std::string integrator = GetParam();
  const double H = 0.5, sigma = 1, rx = 3, ry = 1, e0 = std::exp(-rx * rx / (2 * sigma * sigma));
  auto g = [&](double x) {
    return (std::exp(-x * x / (2 * sigma * sigma)) - e0) / (1 - e0);
  };
  const std::string field =
      Hfield("ridge", 11, 121, rx, ry, H, 0.1, [&](double x, double) { return g(x); });
  const int N = 60;
  const double L = 6, span = 5, zend = 0.6;
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"/>
  <asset>)" + field + R"(</asset>
  <worldbody>
    <geom name="rock" type="hfield" hfield="ridge"/>
    <site name="a" pos=")" + Fmt(-span / 2) +
                          " 0 " + Fmt(zend) + R"("/>
    <site name="b" pos=")" + Fmt(span / 2) +
                          " 0 " + Fmt(zend) + R"("/>
  </worldbody>
  <custom>
    <text name="water" data="density=1025"/>
    <text name="tether:t" data="ends=a,b length=6 segments=60 diameter=0.02
      mass_per_length=2 EA=1e5 damping=20 Cdn=1.2 Cdt=0.01 integrator=)" +
                          integrator + R"( contact=all contact_friction=)" +
                          (integrator == "implicit2" ? "0" : "0.3") + R"("/>
  </custom>
</mujoco>)";
  LoadedScene s(xml);
  ASSERT_NE(s.d, nullptr);
  mj_forward(s.m, s.d);
  const Tether* tether = GetTether(s.m, 0);
  // The tent: straight from each end up to the apex, 3 m each side.
  const double apex = zend + std::sqrt(0.25 * L * L - 0.25 * span * span);
  const Vec3 A(-span / 2, 0, zend), B(span / 2, 0, zend), P(0, 0, apex);
  Eigen::Matrix3Xd x0(3, N + 1);
  for (int i = 0; i <= N; ++i) {
    const double f = static_cast<double>(i) / N;
    x0.col(i) = f <= 0.5 ? Vec3(A + 2 * f * (P - A)) : Vec3(P + (2 * f - 1) * (B - P));
  }
  SetNodes(s.m, s.d, x0);
  // Energy: kinetic + the net weight's potential, of the inner nodes (the ends are fixed).
  auto energy = [&](const double* x, const double* v) {
    double E = 0;
    for (int i = 1; i < N; ++i) {
      E += 0.5 * tether->node_mass(i) * Vec3(v + 3 * i).squaredNorm();
      E -= tether->node_weight(i).dot(Vec3(x + 3 * i));
    }
    return E;
  };
  std::vector<double> zero(3 * (N + 1), 0.0);
  const double Estart = energy(x0.data(), zero.data());
  double Erest = Estart, excess = -INFINITY;
  const double t_end = integrator == "implicit" ? 20 : 3;
  while (s.d->time < t_end) {
    ASSERT_TRUE(s.Step());
    const double* x = NodePositions(s.m, s.d, 0);
    const double* v = NodeVelocities(s.m, s.d, 0);
    for (int i = 0; i < 6 * (N + 1); ++i) ASSERT_TRUE(std::isfinite(x[i])) << "t = " << s.d->time;
    const double E = energy(x, v);
    excess = std::max(excess, E - Estart);
    Erest = std::min(Erest, E);
  }
  std::printf("ridge %s: energy above the start's %.3g J (released %.3g J)\n", integrator.c_str(),
              excess, Estart - Erest);
  EXPECT_LE(excess, 0.02 * (Estart - Erest)) << "energy grew";
  if (integrator != "implicit") return;

  const double* x = NodePositions(s.m, s.d, 0);
  const double* v = NodeVelocities(s.m, s.d, 0);
  std::vector<double> T(N);
  GetTensions(s.m, s.d, 0, T.data());
  const double k = tether->params().contact_stiffness, L0 = tether->rest_segment_length();
  const double w = std::abs(tether->node_weight(N / 2).z()) / L0;  // [N/m] net weight
  const double r = 0.01;
  // The surface's largest curvature |z''| (the crest's, H/sigma^2/(1 - e0)). A segment's plane
  // is lifted over the surface at its samples (every half cell, 2.5 cm): between two samples
  // the surface may rise above it by |z''| (cell/2)^2/8 (the discretisation asserted).
  double curv = 0;
  for (double xs = -rx; xs <= rx; xs += 1e-3) {
    const double q = xs * xs / (2 * sigma * sigma);
    curv = std::max(curv, std::abs(H / (1 - e0) * (2 * q - 1) / (sigma * sigma) * std::exp(-q)));
  }
  const double spacing = 0.5 * 2 * rx / 120;  // [m] half a cell
  const double geometric = curv * spacing * spacing / 8;
  // Exact surface height and the depth of a point below the tether's surface (its axis r above
  // the ridge), measured vertically (the slope under the tether is at most 0.3: the normal
  // depth is at least 0.95 of it).
  auto depth = [&](const Vec3& p) { return H * g(p.x()) + r - p.z(); };
  double vmax = 0, worst = 0, deepest = -INFINITY;
  int touching = 0;
  for (int i = 1; i < N; ++i) {
    vmax = std::max(vmax, Vec3(v + 3 * i).norm());
    const Vec3 xi(x + 3 * i);
    const Vec3 ta = (xi - Vec3(x + 3 * i - 3)).normalized(), tb = (Vec3(x + 3 * i + 3) - xi).normalized();
    const double F = (T[i] * tb - T[i - 1] * ta).norm();
    const double bound = 1.2 * (w * L0 + F) / (k * L0) + geometric + 1e-6;
    const double di = depth(xi);
    EXPECT_LE(di, bound) << "node " << i;
    worst = std::max(worst, di / bound);
    deepest = std::max(deepest, di);
    if (di > -1e-3) ++touching;
    const double dm = depth(0.5 * (xi + Vec3(x + 3 * i + 3)));
    EXPECT_LE(dm, bound) << "midpoint " << i;
    deepest = std::max(deepest, dm);
  }
  EXPECT_LT(vmax, 0.01) << "not at rest";
  EXPECT_GE(touching, 5) << "the tether does not rest on the ridge";
  // Statics.
  const EndReactions re = GetReactions(s.m, s.d, 0);
  double W = 0;
  for (int i = 0; i <= N; ++i) W += tether->node_weight(i).z();
  const double h = s.m->opt.timestep;
  const double Fc = ContactImpulse(s.m, s.d, 0).z() / h;
  const double carried = -W + re.force_a.z() + re.force_b.z();
  std::printf(
      "ridge: %d nodes touching, deepest node or midpoint %.3g m (node: %.2f of its bound), "
      "contact %.4f N, "
      "statics %.4f N of weight %.4f N\n",
      touching, deepest, worst, Fc, carried, -W);
  EXPECT_GT(Fc, 0.1 * -W) << "the ridge carries a fair part of the weight";
  EXPECT_NEAR(Fc, carried, 0.01 * -W);
}

INSTANTIATE_TEST_SUITE_P(Contact, HfieldRidge,
                         ::testing::Values("implicit", "explicit", "rk4", "implicit2", "bdf2"),
                         StringParamName());

// ---------------------------------------------------------------------------------------------
// Declaration: an hfield may be named in contact= (and is in contact=all), but not the seabed
// geom, which the seabed force already acts on (refused, naming it); under contact=all the
// seabed geom is left out (a tether on an hfield seabed feels it once: the seabed's stiffness,
// not twice).
TEST(HfieldContact, SeabedGeomIsNotAContactGeom) {
  auto load = [](const std::string& contact) {
    const std::string xml = R"(
<mujoco>
  <asset>)" + Hfield("h", 3, 3, 2, 2, 0.5, 0.1, [](double x, double) { return 0.5 + x / 4; }) +
                            R"(</asset>
  <worldbody>
    <geom name="floor" type="hfield" hfield="h" pos="0 0 -5"/>
    <geom name="rock" type="hfield" hfield="h" pos="0 0 -1"/>
    <site name="a" pos="0 0 2"/>
  </worldbody>
  <custom>
    <text name="water" data="density=1025 seabed=floor"/>
    <text name="tether:t" data="ends=a,free length=2 segments=4 diameter=0.02
      mass_per_length=1 EA=1e5 )" + contact + R"("/>
  </custom>
</mujoco>)";
    std::string error;
    mjModel* m = LoadModelFromString(xml, "scene.xml", &error);
    std::vector<std::string> warnings;
    if (m) {
      warnings = Warnings(m);
      Detach(m);
      mj_deleteModel(m);
    }
    return std::make_pair(error, warnings);
  };
  EXPECT_EQ(load("contact=rock").first, "");
  const auto all = load("contact=all");
  EXPECT_EQ(all.first, "");
  for (const std::string& w : all.second) {
    EXPECT_EQ(w.find("hfield"), std::string::npos) << "hfields are supported now: " << w;
  }
  const std::string e = load("contact=rock,floor").first;
  EXPECT_NE(e.find("scene.xml: <text name=\"tether:t\">: key 'contact': geom 'floor' is the "
                   "seabed"),
            std::string::npos)
      << e;
}

}  // namespace
}  // namespace mjtether::testing
