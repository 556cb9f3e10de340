// Validation cases that involve a body, through MuJoCo: a tip load, an end moment, a body
// sinking with a tether, a snap load. Each records its rows of the validation table (docs/validation.md).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "mjtether.h"
#include "mujoco_fixture.h"
#include "validation_record.h"

namespace mjtether {
namespace {

using testing::Format;
using testing::LastOrder;
using testing::Orders;
using testing::Percent;
using testing::Record;

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

// A loaded model and its data, released at the end of the scope.
struct Scene : testing::LoadedScene {
  explicit Scene(const std::string& xml) : LoadedScene(xml, "validation.xml") {}
  double MaxQvel() const {
    double s = 0;
    for (int i = 0; i < m->nv; ++i) s = std::max(s, std::abs(d->qvel[i]));
    return s;
  }
};

// ---------------------------------------------------------------------------------------------
// 4. Cantilever with a tip load, large deflection (the elastica). A weightless tether clamped
// at the world along +x carries a body of weight P at its free end (end B is a site on the
// body, which slides in x and z: a point load). Reference by shooting, computed here: with
// theta(s) the angle below the horizontal and the moment M(s) = P (x_tip - x(s)),
//   EI theta'' = -P (1 + P sin(theta)/EA) cos(theta),  theta(0) = 0,  theta'(L) = 0,
//   x' = (1 + P sin(theta)/EA) cos(theta),  z' = -(1 + P sin(theta)/EA) sin(theta)
// (the axial force P sin(theta) stretches the line; EA is finite in the model), integrated by
// RK4 with 4000 steps (error ~ 1e-13) and bisection on theta'(0). Values for EA -> inf agree
// with Bisshopp & Drucker, Q. Appl. Math. 3 (1945) (P L^2/EI = 1: tip drop 0.3017 L).
struct Elastica {
  double x, z, theta;  // tip position [m] and angle [rad]
};

Elastica ShootElastica(double P, double L, double EI, double EA, double kappa0) {
  const int n = 4000;
  const double ds = L / n;
  double th = 0, k = kappa0, x = 0, z = 0;
  auto rhs = [&](double th_, double k_, double* dth, double* dk, double* dx, double* dz) {
    const double stretch = 1 + P * std::sin(th_) / EA;
    *dth = k_;
    *dk = -P / EI * stretch * std::cos(th_);
    *dx = stretch * std::cos(th_);
    *dz = -stretch * std::sin(th_);
  };
  for (int i = 0; i < n; ++i) {
    double a[4], b[4], c[4], d[4];
    rhs(th, k, &a[0], &a[1], &a[2], &a[3]);
    rhs(th + ds / 2 * a[0], k + ds / 2 * a[1], &b[0], &b[1], &b[2], &b[3]);
    rhs(th + ds / 2 * b[0], k + ds / 2 * b[1], &c[0], &c[1], &c[2], &c[3]);
    rhs(th + ds * c[0], k + ds * c[1], &d[0], &d[1], &d[2], &d[3]);
    th += ds / 6 * (a[0] + 2 * b[0] + 2 * c[0] + d[0]);
    k += ds / 6 * (a[1] + 2 * b[1] + 2 * c[1] + d[1]);
    x += ds / 6 * (a[2] + 2 * b[2] + 2 * c[2] + d[2]);
    z += ds / 6 * (a[3] + 2 * b[3] + 2 * c[3] + d[3]);
  }
  return {x, z, k};  // theta'(L) returned in .theta for the shooting
}

Elastica SolveElastica(double P, double L, double EI, double EA) {
  double lo = 0, hi = 2 * P * L / EI;  // theta'(L) < 0 at lo, > 0 at hi
  // The shooting converges only if the bracket holds the root (then 100 halvings leave it
  // within 2^-100 of the bracket: converged to round-off).
  EXPECT_LT(ShootElastica(P, L, EI, EA, lo).theta, 0) << "elastica bracket, P " << P;
  EXPECT_GT(ShootElastica(P, L, EI, EA, hi).theta, 0) << "elastica bracket, P " << P;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (ShootElastica(P, L, EI, EA, mid).theta < 0 ? lo : hi) = mid;
  }
  return ShootElastica(P, L, EI, EA, 0.5 * (lo + hi));
}

std::string ElasticaXml(int N, double M, double L, double EI, double EA, const char* bending) {
  std::ostringstream s;
  s.precision(17);
  s << R"(<mujoco><option timestep="0.0004"/><custom>
      <text name="tether:beam" data="ends=root,tip length=)" << L << " segments=" << N
    << " diameter=0.01 mass_per_length=0.1 EA=" << EA << " EI=" << EI
    << " bending=" << bending << R"( clamp=A effects=axial,bending,clamp"/></custom>
    <worldbody><site name="root" pos="0 0 0"/>
      <body name="load" pos=")" << L << R"( 0 0">
        <joint type="slide" axis="1 0 0" damping="2"/><joint type="slide" axis="0 0 1" damping="2"/>
        <geom type="sphere" size="0.01" mass=")" << M << R"("/><site name="tip"/>
      </body></worldbody></mujoco>)";
  return s.str();
}

// Tolerance: the Galerkin curvature and the clamp's half-weight are second order in L0
// (observed orders below); at 40 segments the tip is within 0.3% of L of the elastica.
TEST(ValidationMuJoCo, ElasticaTipLoad) {
  const double L = 1, EI = 1, EA = 1e4;
  int row = 0;
  for (const char* bending : {"galerkin", "der"}) {
  for (double alpha : {0.5, 1.0, 2.0}) {
    const double P = alpha * EI / (L * L);
    const Elastica ref = SolveElastica(P, L, EI, EA);
    std::vector<std::pair<int, double>> e;
    double x40 = 0, z40 = 0;
    for (int N : {10, 20, 40}) {
      Scene s(ElasticaXml(N, P / kG, L, EI, EA, bending));
      ASSERT_NE(s.m, nullptr);
      bool settled = false;
      for (int k = 0; k < 50000 && !settled; ++k) {
        ASSERT_TRUE(s.Step());
        settled = k > 100 && s.MaxQvel() < 1e-7;
      }
      EXPECT_TRUE(settled) << "alpha " << alpha << " N " << N;
      const double x = s.d->xpos[3], z = s.d->xpos[5];
      const double err = std::hypot(x - ref.x, z - ref.z) / L;
      e.emplace_back(N, err);
      if (N == 40) x40 = x, z40 = z;
    }
    EXPECT_LT(e[2].second, 0.003) << "alpha " << alpha;
    EXPECT_NEAR(LastOrder(e), 2, 0.5) << "alpha " << alpha;
    Record(row++, {"4. Elastica, tip load PL²/EI = " + Format("%g", alpha) + ", bending=" +
                       bending + ": tip position (x, z)/L",
                   Format("shooting (%.5f, ", ref.x / L) + Format("%.5f)", ref.z / L),
                   Format("(%.5f, ", x40 / L) + Format("%.5f)", z40 / L),
                   Format("%.2g L", e[2].second), "0.3% of L, order 2 ± 0.5", Orders(e), 40});
  }
  }
}

// ---------------------------------------------------------------------------------------------
// 5. Constant end moment: a weightless tether clamped at both ends, end A to the world, end B
// to a body that slides in x and z and turns about y, loaded by a moment M about y (ramped
// over 1 s, then held). The elastica under a pure end moment is a circular arc of curvature
// kappa = M/EI (Euler): the body turns by M L/EI (here pi/2, a quarter circle). In the lumped
// model every node turns by theta with M = EI sin(theta)/L0 (galerkin) or 2 EI/L0
// tan(theta/2)/cos^2(theta/2) (der), so the end rotation is exact to theta^2/6 (galerkin, +) or
// theta^2/3 (der, -) relative: 0.1% and 0.2% at 20 segments; tolerance 0.5%. Under a pure
// moment the segments carry no tension, and a tension-only segment then has no defined
// length: the node positions (the arc's radius) are not compared. The body is heavy enough
// (0.5 kg, 1e-2 kg m^2) for the unloaded segments to settle instead of chattering between
// slack and taut against the explicitly coupled body (a 0.05 kg body did not settle at 20).
std::string ArcXml(int N, double L, double EI, const char* bending) {
  std::ostringstream s;
  s << R"(<mujoco><option timestep="0.0004" gravity="0 0 0"/><custom>
      <text name="tether:beam" data="ends=root,tip length=)" << L << " segments=" << N
    << " diameter=0.01 mass_per_length=0.1 EA=1e4 EI=" << EI
    << " bending=" << bending << R"( clamp=both"/></custom>
    <worldbody><site name="root" pos="0 0 0"/>
      <body name="end" pos=")" << L << R"( 0 0">
        <joint type="slide" axis="1 0 0" damping="1"/><joint type="slide" axis="0 0 1" damping="1"/>
        <joint name="turn" type="hinge" axis="0 1 0" damping="0.5"/>
        <inertial pos="0 0 0" mass="0.5" diaginertia="1e-2 1e-2 1e-2"/><site name="tip"/>
      </body></worldbody></mujoco>)";
  return s.str();
}

TEST(ValidationMuJoCo, EndMomentGivesCircularArc) {
  const double L = 1, EI = 1, M = kPi / 2 * EI / L;
  const double phi = M * L / EI;
  int row = 0;
  for (const char* bending : {"galerkin", "der"}) {
    std::vector<std::pair<int, double>> e;
    double angle20 = 0;
    for (int N : {5, 10, 20}) {
      Scene s(ArcXml(N, L, EI, bending));
      ASSERT_NE(s.m, nullptr);
      const int body = mj_name2id(s.m, mjOBJ_BODY, "end");
      const int turn = s.m->jnt_qposadr[mj_name2id(s.m, mjOBJ_JOINT, "turn")];
      bool settled = false;
      for (int k = 0; k < 50000 && !settled; ++k) {
        s.d->xfrc_applied[6 * body + 4] = M * std::min(1.0, s.d->time / 1.0);
        ASSERT_TRUE(s.Step());
        settled = s.d->time > 1.5 && s.MaxQvel() < 1e-7;
      }
      EXPECT_TRUE(settled) << bending << " N " << N << ": still moving at t = " << s.d->time;
      const double angle = s.d->qpos[turn];
      e.emplace_back(N, angle / phi - 1);
      if (N == 20) angle20 = angle;
    }
    EXPECT_NEAR(e[2].second, 0, 0.005) << bending;
    Record(row++, {std::string("5. End moment M L/EI = π/2 (clamped both ends), bending=") +
                       bending + ": end rotation",
                   "M L/EI " + Format("%.5f rad", phi), Format("%.5f rad", angle20),
                   Percent(e[2].second), "0.5%", Orders(e), 20});
  }
}

// ---------------------------------------------------------------------------------------------
// 10. Snap load: a 10 kg body on a vertical rail hangs from a slack tether (L = 10 m,
// EA = 1e6 N) and falls h = 1 m before it goes taut. Energy balance for a massless elastic
// line of stiffness k = EA/L: m g (h + x) = 1/2 k x^2, so the peak tension is
//   T = k x = m g + sqrt((m g)^2 + 2 k m g h).
// The tether's mass (0.02 kg, 0.2% of the body's) takes some of the energy: < 0.2% of T.
// MuJoCo's semi-implicit Euler on the body at h = 0.25 ms (omega h = 0.025) and the implicit
// tether add O(omega h) ~ 0.5%; the tolerance is 1%.
TEST(ValidationMuJoCo, SnapLoadPeakTension) {
  const double M = 10, L = 10, EA = 1e6, drop = 1;
  const double k = EA / L, W = M * kG;
  const double ref = W + std::sqrt(W * W + 2 * k * W * drop);
  double peak = 0;
  std::vector<std::pair<double, double>> by_step;
  for (double h : {1e-3, 5e-4, 2.5e-4}) {
    std::ostringstream xml;
    xml << R"(<mujoco><option timestep=")" << h << R"("/><custom>
      <text name="tether:line" data="ends=top,hook length=10 segments=20 diameter=0.01
            mass_per_length=0.002 EA=1e6"/></custom>
      <worldbody><site name="top" pos="0 0 0"/>
        <body name="load" pos="0.001 0 -9"><joint type="slide" axis="0 0 1"/>
          <geom type="sphere" size="0.1" mass="10"/><site name="hook"/></body>
      </worldbody></mujoco>)";
    Scene s(xml.str());
    ASSERT_NE(s.m, nullptr);
    double T = 0;
    while (s.d->time < 0.7) {
      ASSERT_TRUE(s.Step());
      T = std::max(T, GetReactions(s.m, s.d, 0).tension_b);
    }
    by_step.emplace_back(h, T / ref - 1);
    peak = T;
  }
  EXPECT_NEAR(by_step.back().second, 0, 0.01);
  std::string steps;
  for (auto& [h, e] : by_step) steps += (steps.empty() ? "" : ", ") + Percent(e);
  Record(0, {"10. Snap load: 10 kg falling 1 m on a slack tether (EA/L = 1e5 N/m): peak tension",
             "m g h + ½ k x² balance " + Format("%.1f N", ref), Format("%.1f N", peak),
             Percent(by_step.back().second), "1%",
             "time step 1/0.5/0.25 ms: " + steps, 20});
}

}  // namespace
}  // namespace mjtether
