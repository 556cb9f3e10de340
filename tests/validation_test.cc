// Validation of the tether engine against closed forms and published solutions (no MuJoCo).
// Each test records its rows of the validation table (docs/validation.md) (validation_record.h); the
// cases that need a body are in validation_mujoco_test.cc.
//
// Statics are solved by time stepping with the implicit (backward Euler) integrator at a large
// step until every node is at rest; dynamics use the explicit (symplectic Euler) integrator,
// which has no numerical damping.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "catenary_reference.h"
#include "declaration.h"
#include "engine_sim.h"
#include "make_tether.h"
#include "tether.h"
#include "validation_record.h"

namespace mjtether {
namespace {

using testing::Format;
using testing::LastOrder;
using testing::Orders;
using testing::Percent;
using testing::Record;
using testing::Row;

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

// engine_sim.h's tether with its state and workspace, whose steps must not fail, and what the
// validation cases need besides.
struct Sim : mjtether::Sim {
  using mjtether::Sim::Sim;
  StepStatus Step(double dt) {
    StepStatus s = mjtether::Sim::Step(dt);
    if (!s.ok) ADD_FAILURE() << "node " << s.node << ": " << s.reason;
    return s;
  }
  // Moves the ends to `to` over dt.
  StepStatus Move(const Ends& to, double dt) {
    StepStatus s = tether.Advance(x.data(), v.data(), ends, to, dt, work.data());
    if (!s.ok) ADD_FAILURE() << "node " << s.node << ": " << s.reason;
    ends = to;
    return s;
  }
  Vec3 vel(int i) const { return Vec3(v[3 * i], v[3 * i + 1], v[3 * i + 2]); }
  void set(int i, const Vec3& p) {
    for (int c = 0; c < 3; ++c) x[3 * i + c] = p[c];
  }
  void set_vel(int i, const Vec3& u) {
    for (int c = 0; c < 3; ++c) v[3 * i + c] = u[c];
  }
  double MaxSpeed() const {
    double s = 0;
    for (int i = 0; i < tether.nodes(); ++i) s = std::max(s, vel(i).norm());
    return s;
  }
  // Implicit steps of h until every node moves slower than `speed` [m/s]; false if it did
  // not settle within max_steps.
  bool Settle(double h, int max_steps, double speed) {
    for (int k = 0; k < max_steps; ++k) {
      if (!Step(h).ok) return false;
      if (MaxSpeed() < speed) return true;
    }
    ADD_FAILURE() << "still moving at " << MaxSpeed() << " m/s";
    return false;
  }
  double Energy() const {
    return tether.KineticEnergy(x.data(), v.data()) + tether.PotentialEnergy(x.data(), ends);
  }
  EndReactions Reactions() { return tether.Reactions(x.data(), v.data(), ends, work.data()); }
};


Environment Water(double density = 1025) {
  Environment env;
  env.wet = true;
  env.water.density = density;
  return env;
}

// Bisection for the root of a function that changes sign on [lo, hi] (checked: without a sign
// change there is no root to converge to, and the test fails).
double Bisect(const std::function<double(double)>& f, double lo, double hi) {
  const double flo = f(lo);
  EXPECT_LE(flo * f(hi), 0) << "Bisect: no sign change on [" << lo << ", " << hi << "]";
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    ((f(mid) > 0) == (flo > 0) ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// ---------------------------------------------------------------------------------------------
// 1. Elastic catenary between two points, fully suspended: Irvine, "Cable Structures" (1981),
// ch. 2, solved in catenary_reference.h. The lumped model's end force (end segment tension
// plus the end node's weight) is the continuum n(0) to O(L0^2): 0.5% bounds it at 40 segments
// with a factor ~ 40 of margin (the accuracy target), and the order must be ~ 2.
TEST(Validation, CatenarySuspendedMatchesIrvine) {
  const double L = 100, mu = 1, EA = 1e5, w = mu * kG;  // strain ~ 1%: elasticity matters
  const testing::Catenary ref = testing::SolveCatenary(80, 20, L, w, EA);
  std::vector<std::pair<int, double>> ea, eb;
  double Ta = 0, Tb = 0;
  for (int N : {10, 20, 40, 80}) {
    TetherParams p;
    p.length = L;
    p.segments = N;
    p.diameter = 0.02;
    p.mass_per_length = mu;
    p.EA = EA;
    p.damping = 2e3;
    Sim s(Make(p, Environment()));
    s.ends.a.pos = Vec3(0, 0, 0);
    s.ends.b.pos = Vec3(80, 0, 20);
    s.Init();
    ASSERT_TRUE(s.Settle(0.05, 20000, 1e-9)) << N;
    const EndReactions r = s.Reactions();
    ea.emplace_back(N, r.tension_a / ref.tension_a() - 1);
    eb.emplace_back(N, r.tension_b / ref.tension_b() - 1);
    if (N == 40) Ta = r.tension_a, Tb = r.tension_b;
  }
  EXPECT_NEAR(ea[2].second, 0, 0.005);
  EXPECT_NEAR(eb[2].second, 0, 0.005);
  EXPECT_NEAR(LastOrder(ea), 2, 0.3);
  EXPECT_NEAR(LastOrder(eb), 2, 0.3);
  Record(0, {"1. Elastic catenary, suspended (span 80 m, rise 20 m, L 100 m, EA 1e5 N): "
             "tension at A",
             "Irvine (1981) " + Format("%.2f N", ref.tension_a()), Format("%.2f N", Ta),
             Percent(ea[2].second), "0.5%, order 2 ± 0.3", Orders(ea), 40});
  Record(1, {"1. Elastic catenary, suspended: tension at B",
             "Irvine (1981) " + Format("%.2f N", ref.tension_b()), Format("%.2f N", Tb),
             Percent(eb[2].second), "0.5%, order 2 ± 0.3", Orders(eb), 40});
}

// ---------------------------------------------------------------------------------------------
// 2. Elastic catenary resting partly on the seabed. Closed form of the quasi-static mooring
// line with a portion LB on the bottom (Jonkman, "Dynamics modeling and loads analysis of an
// offshore floating wind turbine", NREL/TP-500-41958, 2007, eqs. 2-1 and 2-2; the form used by
// FAST and MAP++), with HF, VF the horizontal and vertical force at the fairlead, w the wet
// weight per length and CB the seabed friction coefficient:
//   LB = L - VF/w
//   XF = LB + HF/w asinh(VF/HF) + HF L/EA
//        + CB w/(2 EA) [-LB^2 + (LB - HF/(CB w)) max(LB - HF/(CB w), 0)]
//   ZF = HF/w (sqrt(1 + (VF/HF)^2) - 1) + VF^2/(2 EA w)
struct Mooring {
  double H, V;  // [N]
};

void MooringEnd(double H, double V, double L, double w, double EA, double CB, double* XF,
                double* ZF) {
  const double LB = L - V / w;
  double x = LB + H / w * std::asinh(V / H) + H * L / EA;
  if (CB > 0) {
    const double r = LB - H / (CB * w);
    x += CB * w / (2 * EA) * (-LB * LB + r * std::max(r, 0.0));
  }
  *XF = x;
  *ZF = H / w * (std::sqrt(1 + (V / H) * (V / H)) - 1) + V * V / (2 * EA * w);
}

Mooring SolveMooring(double XF, double ZF, double L, double w, double EA) {
  double H = w * L / 4, V = w * L / 2;
  bool converged = false;
  for (int it = 0; it < 100 && !converged; ++it) {
    double x, z;
    MooringEnd(H, V, L, w, EA, 0, &x, &z);
    const double rx = x - XF, rz = z - ZF;
    converged = std::hypot(rx, rz) < 1e-13 * L;
    if (converged) break;
    const double dH = 1e-7 * H, dV = 1e-7 * V;
    double xh, zh, xv, zv;
    MooringEnd(H + dH, V, L, w, EA, 0, &xh, &zh);
    MooringEnd(H, V + dV, L, w, EA, 0, &xv, &zv);
    const double a = (xh - x) / dH, b = (xv - x) / dV, c = (zh - z) / dH, d = (zv - z) / dV;
    const double det = a * d - b * c;
    double sH = (d * rx - b * rz) / det, sV = (-c * rx + a * rz) / det;
    while (H - sH <= 0 || V - sV <= 0) sH /= 2, sV /= 2;
    H -= sH;
    V -= sV;
  }
  // The reference must have converged (end B within 1e-13 L of the fairlead), or it is none.
  EXPECT_TRUE(converged) << "SolveMooring(" << XF << ", " << ZF << ", " << L << ", " << w
                         << ", " << EA << "): Newton did not converge";
  return {H, V};
}

// Position (x, z) of material point s of the reference line, relative to the anchor (or the
// free end), with LB on the bottom carrying tension H - CB w (LB - s) (zero friction: H), and
// the catenary with horizontal force H beyond the touchdown point.
Vec3 MooringShape(double s, double LB, double H, double w, double EA, double CB) {
  if (s <= LB) {
    const double T0 = CB > 0 ? std::max(0.0, H - CB * w * LB) : H;  // tension at s = 0
    const double s0 = CB > 0 ? std::max(0.0, LB - H / (CB * w)) : 0;  // where tension starts
    const double r = std::max(0.0, s - s0);
    const double stretch = CB > 0 ? (T0 * r + 0.5 * CB * w * r * r) / EA : H * s / EA;
    return Vec3(s + stretch, 0, 0);
  }
  const double x0 = MooringShape(LB, LB, H, w, EA, CB).x();
  const double r = s - LB;
  return Vec3(x0 + H * r / EA + H / w * std::asinh(w * r / H), 0,
              w * r * r / (2 * EA) + (std::hypot(H, w * r) - H) / w);
}

TetherParams MooringParams(int N) {
  TetherParams p;
  p.length = 100;
  p.segments = N;
  p.diameter = 0.02;
  p.mass_per_length = 1;  // wet weight (1 - 1025 pi 0.01^2) 9.81 = 6.65 N/m
  p.EA = 1e5;             // strain ~ 0.3%
  p.damping = 2e3;
  return p;
}

// Without friction: the anchor (end A) lies on the seabed, the fairlead (end B) is 85 m away
// and 30 m up. The bottom portion carries HF; the lumped model's fairlead force is n(L) to
// O(L0^2) as in case 1, except near the touchdown point, which falls between nodes: the error
// there is O(L0^2) as well because the line meets the bottom tangentially. The penalty
// seabed sinks the bottom portion by w/k = 7e-5 m (k = 1e5 N/m^2), a relative 2e-6 of ZF.
// 0.5% at 40 segments as in case 1.
TEST(Validation, CatenaryOnSeabedWithoutFriction) {
  Environment env = Water();
  env.water.has_seabed = true;
  env.water.seabed = -30;
  const double L = 100, EA = 1e5, XF = 85, ZF = 30;
  const double w = (1 - 1025 * kPi * 0.01 * 0.01) * kG;
  const double sink = w / env.water.seabed_stiffness;
  const Mooring ref = SolveMooring(XF, ZF + sink, L, w, EA);
  const double LB = L - ref.V / w;
  ASSERT_GT(LB, 10);  // a real portion on the bottom
  const double TF = std::hypot(ref.H, ref.V);
  std::vector<std::pair<int, double>> eT, eH;
  double T40 = 0, H40 = 0;
  for (int N : {10, 20, 40, 80}) {
    Sim s(Make(MooringParams(N), env));
    s.ends.a.pos = Vec3(0, 0, -30 - sink);
    s.ends.b.pos = Vec3(XF, 0, 0);
    // Start near the reference shape (the statics do not depend on it; it saves settling).
    for (int i = 0; i <= N; ++i) {
      s.set(i, s.ends.a.pos + MooringShape(L * i / N, LB, ref.H, w, EA, 0));
    }
    s.set(N, s.ends.b.pos);
    ASSERT_TRUE(s.Settle(0.05, 20000, 1e-9)) << N;
    const EndReactions r = s.Reactions();
    eT.emplace_back(N, r.tension_b / TF - 1);
    eH.emplace_back(N, -r.force_b.x() / ref.H - 1);
    if (N == 40) T40 = r.tension_b, H40 = -r.force_b.x();
  }
  EXPECT_NEAR(eT[2].second, 0, 0.005);
  EXPECT_NEAR(eH[2].second, 0, 0.005);
  Record(0, {"2. Catenary partly on the seabed, no friction (XF 85 m, ZF 30 m, L 100 m): "
             "fairlead tension",
             "Jonkman (2007) eqs. 2-1, 2-2 " + Format("%.2f N", TF), Format("%.2f N", T40),
             Percent(eT[2].second), "0.5%", Orders(eT), 40});
  Record(1, {"2. Catenary on the seabed, no friction: horizontal force HF",
             "Jonkman (2007) " + Format("%.2f N", ref.H) + Format(", LB = %.1f m", LB),
             Format("%.2f N", H40), Percent(eH[2].second), "0.5%", Orders(eH), 40});
}

// With friction: the fairlead (end A) tows the line at a steady speed U along the seabed; end
// B is free and lies on the bottom. In steady state every node moves at U, so the friction on
// the bottom portion is fully mobilised (tanh(U/v_eps) = 1 - 4e-44 here) and the tension
// falls from HF at the touchdown point to zero at the free end: H = CB w LB, V = w (L - LB),
// the case of Jonkman's formula where the zero-tension point is the end of the line. The
// current equals U so that drag, which damps the transient, vanishes in the steady state.
// Unknown LB from ZF; then XF and the fairlead tension follow. Tolerance 0.5% as above.
TEST(Validation, CatenaryOnSeabedWithFriction) {
  const double L = 100, EA = 1e5, ZF = 30, U = 0.5, CB = 0.5;
  Environment env = Water();
  env.water.has_seabed = true;
  env.water.seabed = -30;
  env.water.seabed_friction = CB;
  env.water.seabed_friction_axial = CB;
  env.water.current = Vec3(U, 0, 0);
  const double w = (1 - 1025 * kPi * 0.01 * 0.01) * kG;
  const double sink = w / env.water.seabed_stiffness;
  auto zf = [&](double LB) {
    double x, z;
    MooringEnd(CB * w * LB, w * (L - LB), L, w, EA, CB, &x, &z);
    return z - (ZF + sink);
  };
  const double LB = Bisect(zf, 1e-6, L - 1e-6);
  const double H = CB * w * LB, V = w * (L - LB);
  double XF, z;
  MooringEnd(H, V, L, w, EA, CB, &XF, &z);
  const double TF = std::hypot(H, V);
  ASSERT_GT(LB, 10);
  std::vector<std::pair<int, double>> eT, eX;
  double T40 = 0, X40 = 0;
  for (int N : {10, 20, 40, 80}) {
    TetherParams p = MooringParams(N);
    p.Cdn = 1.2;
    p.free_end = true;
    Sim s(Make(p, env));
    // Initial shape: the reference, moving at U (end A at the fairlead, B the free end).
    for (int i = 0; i <= N; ++i) {
      const Vec3 r = MooringShape(L * (N - i) / N, LB, H, w, EA, CB);
      s.set(i, Vec3(r.x(), 0, -30 - sink + r.z()));
    }
    s.ends.a.pos = s.node(0);
    s.ends.a.vel = Vec3(U, 0, 0);
    for (int i = 0; i <= N; ++i) s.set_vel(i, Vec3(U, 0, 0));
    // Tow for 120 s (60 m); average the last 20 s.
    const double h = 0.05;
    double Ta = 0, xf = 0, slip = 0;
    for (int k = 0; k < 2400; ++k) {
      Ends to = s.ends;
      to.a.pos += h * to.a.vel;
      ASSERT_TRUE(s.Move(to, h).ok) << N;
      if (k >= 2000) {
        Ta += s.Reactions().tension_a / 400;
        xf += (s.node(0).x() - s.node(N).x()) / 400;
        for (int i = 0; i <= N; ++i) slip = std::max(slip, (s.vel(i) - Vec3(U, 0, 0)).norm());
      }
    }
    // Steady: what is left is a ripple of the slack tail near the free end (tension ~ 0).
    EXPECT_LT(slip, 0.01 * U) << N;
    eT.emplace_back(N, Ta / TF - 1);
    eX.emplace_back(N, xf / XF - 1);
    if (N == 40) T40 = Ta, X40 = xf;
  }
  EXPECT_NEAR(eT[2].second, 0, 0.005);
  EXPECT_NEAR(eX[2].second, 0, 0.005);
  Record(0, {"2. Catenary partly on the seabed, towed, friction CB 0.5 (ZF 30 m, L 100 m): "
             "fairlead tension",
             "Jonkman (2007) with CB " + Format("%.2f N", TF), Format("%.2f N", T40),
             Percent(eT[2].second), "0.5%", Orders(eT), 40});
  Record(1, {"2. Catenary on the seabed, friction: span from free end to fairlead XF",
             "Jonkman (2007) " + Format("%.3f m", XF) + Format(", LB = %.1f m", LB),
             Format("%.3f m", X40), Percent(eX[2].second), "0.5%", Orders(eX), 40});
}

// ---------------------------------------------------------------------------------------------
// 3. Cantilever under self-weight, small deflection: tip deflection q L^4/(8 EI)
// (Euler-Bernoulli; Timoshenko & Gere, Mechanics of Materials, table of beam deflections).
// qL^3/EI = 0.01, so the geometrically non-linear correction is ~ 1e-5 relative; EA = 1e7
// makes the stretch irrelevant. The root moment q L^2/2 checks the moment passed to the body.
TEST(Validation, CantileverSelfWeight) {
  const double L = 1, mu = 0.1, EI = 100, q = mu * kG;
  const double ref = q * std::pow(L, 4) / (8 * EI), ref_moment = q * L * L / 2;
  int row = 0;
  for (Bending bending : {Bending::kGalerkin, Bending::kDER}) {
    std::vector<std::pair<int, double>> e;
    double tip40 = 0;
    for (int N : {10, 20, 40, 80}) {
      TetherParams p;
      p.length = L;
      p.segments = N;
      p.diameter = 0.01;
      p.mass_per_length = mu;
      p.EA = 1e7;
      p.EI = EI;
      p.clamp_a = true;
      p.free_end = true;
      p.bending = bending;
      Sim s(Make(p, Environment()));
      ASSERT_TRUE(s.tether.params().effects & kClamp);
      s.ends.a.axis = Vec3::UnitX();
      for (int i = 0; i <= N; ++i) s.set(i, Vec3(L * i / N, 0, 0));
      ASSERT_TRUE(s.Settle(0.01, 20000, 1e-12)) << N;
      const double tip = -s.node(N).z();
      e.emplace_back(N, tip / ref - 1);
      const EndReactions r = s.Reactions();
      // The wall carries the weight and its moment: torque_a = sum x_i x W_i = +y q L^2/2.
      EXPECT_NEAR(r.torque_a.y() / ref_moment, 1, 1e-3) << N;
      EXPECT_NEAR(r.force_a.z() / (q * L), -1, 1e-6) << N;
      if (N == 40) tip40 = tip;
    }
    // Discretisation: the clamp's one-sided curvature (weight L0/2) and the lumped load.
    EXPECT_NEAR(e[2].second, 0, 0.005);
    EXPECT_NEAR(LastOrder(e), 2, 0.5);
    Record(row++, {std::string("3. Cantilever, self-weight (qL³/EI = 0.01), bending=") +
                       (bending == Bending::kDER ? "der" : "galerkin") + ": tip deflection",
                   "qL⁴/(8EI) " + Format("%.6g m", ref), Format("%.6g m", tip40),
                   Percent(e[2].second), "0.5%, order 2 ± 0.5", Orders(e), 40});
  }
}

// ---------------------------------------------------------------------------------------------
// 5 (engine part). Clamps, moments and forces are consistent: the forces of the conservative
// terms (axial, bending, clamp, weight) are minus the gradient of PotentialEnergy, and the
// internal forces with the clamp moments passed to the bodies have no net moment. A wrong
// sign of a clamp moment or of the bending shear fails one of the two.
TEST(Validation, ConservativeForcesAreTheGradientOfTheEnergy) {
  TetherParams p;
  p.length = 10;
  p.segments = 8;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e4;
  p.EI = 20;
  p.clamp_a = p.clamp_b = true;
  Environment env;
  for (Bending bending : {Bending::kGalerkin, Bending::kDER}) {
  p.bending = bending;
  Tether t = Make(p, env);
  std::mt19937 rng(5);
  std::normal_distribution<double> N(0, 1);
  const int n = 9;
  std::vector<double> x(3 * n), v(3 * n, 0.0), f(3 * n), work(t.WorkspaceSize());
  for (int trial = 0; trial < 20; ++trial) {
    for (int i = 0; i < n; ++i) {
      for (int c = 0; c < 3; ++c) x[3 * i + c] = (c == 0 ? 1.3 * i : 0.0) + 0.3 * N(rng);
    }
    Ends ends;
    ends.a.pos = Vec3(x[0], x[1], x[2]);
    ends.b.pos = Vec3(x[3 * 8], x[3 * 8 + 1], x[3 * 8 + 2]);
    ends.a.axis = Vec3(1 + 0.3 * N(rng), 0.3 * N(rng), 0.3 * N(rng)).normalized();
    ends.b.axis = Vec3(1 + 0.3 * N(rng), 0.3 * N(rng), 0.3 * N(rng)).normalized();
    t.ComputeForces(x.data(), v.data(), ends, f.data(), nullptr, work.data());
    // Central differences of the energy; the step makes the O(d^2) error ~ 1e-8 relative.
    const double d = 1e-5;
    double worst = 0, scale = 0;
    for (int k = 0; k < 3 * n; ++k) {
      std::vector<double> xp = x, xm = x;
      xp[k] += d;
      xm[k] -= d;
      const double grad = (t.PotentialEnergy(xp.data(), ends) - t.PotentialEnergy(xm.data(), ends)) / (2 * d);
      worst = std::max(worst, std::abs(f[k] + grad));
      scale = std::max(scale, std::abs(f[k]));
    }
    ASSERT_LT(worst, 1e-6 * scale) << "trial " << trial;
    // Moment balance about the origin: sum x_i x f_i (internal forces: weight taken out) plus
    // the torques on the bodies.
    const EndReactions r = t.Reactions(x.data(), v.data(), ends, work.data());
    Vec3 Mo = r.torque_a + r.torque_b;
    double mscale = r.torque_a.norm() + r.torque_b.norm();
    for (int i = 0; i < n; ++i) {
      const Vec3 xi(&x[3 * i]), fi = Vec3(&f[3 * i]) - t.node_weight(i);
      Mo += xi.cross(fi);
      mscale += xi.norm() * fi.norm();
    }
    ASSERT_LT(Mo.norm(), 1e-12 * mscale) << "trial " << trial;
  }
  }
}

// bending=galerkin|der is parsed, and anything else is an error naming the key.
TEST(Validation, BendingKeyIsParsed) {
  Environment env;
  const std::string base = "ends=a,b length=1 segments=4 diameter=0.01 mass_per_length=0.1 "
                           "EA=1e3 EI=1 bending=";
  DeclarationError e;
  auto der = ParseTether(base + "der", env, &e);
  ASSERT_TRUE(der.has_value()) << e.message;
  EXPECT_EQ(der->params.bending, Bending::kDER);
  auto galerkin = ParseTether(base + "galerkin", env, &e);
  ASSERT_TRUE(galerkin.has_value()) << e.message;
  EXPECT_EQ(galerkin->params.bending, Bending::kGalerkin);
  EXPECT_FALSE(ParseTether(base + "euler", env, &e).has_value());
  EXPECT_EQ(e.key, "bending");
  EXPECT_NE(e.message.find("allowed: galerkin, der"), std::string::npos) << e.message;
}

// ---------------------------------------------------------------------------------------------
// 6 and 7. Natural frequencies of a string or pinned beam between two fixed points, from the
// zero crossings of a node's transverse displacement after releasing one mode shape.
struct Vibration {
  double L = 10;       // [m] rest length
  double stretch = 0;  // [-] strain of the pre-tension
  int N = 40;
  TetherParams p;
  Environment env;
};

// Frequency [Hz] of mode n measured over `periods` periods (explicit integrator).
double MeasureFrequency(const Vibration& c, int n, double periods, double f_guess) {
  Sim s(Make(c.p, c.env));
  const double Ls = c.L * (1 + c.stretch);
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(Ls, 0, 0);
  // Amplitude small enough that the tension it adds changes nothing measurable.
  const double a = 1e-6 * c.L;
  for (int i = 0; i <= c.N; ++i) {
    s.set(i, Vec3(Ls * i / c.N, a * std::sin(n * kPi * i / c.N), 0));
    s.set_vel(i, Vec3::Zero());
  }
  const int probe = std::max(1, int(std::lround(c.N / (2.0 * n))));
  const double h = s.tether.ExplicitStableStep();
  const double duration = periods / f_guess;
  std::vector<double> crossings;
  double y_prev = s.node(probe).y(), t = 0;
  while (t < duration) {
    EXPECT_TRUE(s.Step(h).ok);
    t += h;
    const double y = s.node(probe).y();
    if ((y > 0) != (y_prev > 0)) crossings.push_back(t - h * y / (y - y_prev));
    y_prev = y;
  }
  if (crossings.size() < 3) return 0;
  return (crossings.size() - 1) / (2 * (crossings.back() - crossings.front()));
}

// Taut string: f_n = n/(2L) sqrt(T/mu) (e.g. Irvine 1981, ch. 3), in water with mu the dry
// mass plus the normal added mass Can rho pi d^2/4, both per stretched length. The lumped
// string's frequencies are 2 sqrt(T/(m l)) sin(n pi/2N) / 2 pi: the relative error is
// -(n pi/N)^2/24 (2.3e-4 for n = 3 at 40 segments), the tolerance twice that.
TEST(Validation, TautStringFrequencies) {
  const double EA = 1e4, stretch = 0.01, T = EA * stretch;
  for (bool wet : {false, true}) {
    std::vector<std::vector<std::pair<int, double>>> errors(3);
    std::vector<double> f40(3), ref(3);
    for (int N : {20, 40, 80}) {
      Vibration c;
      c.N = N;
      c.stretch = stretch;
      c.p.length = c.L;
      c.p.segments = N;
      c.p.diameter = 0.05;
      c.p.mass_per_length = 1;
      c.p.EA = EA;
      c.env.gravity.setZero();
      c.p.integrator = Integrator::kExplicit;
      double mu = 1;
      if (wet) {
        c.env = Water();
        c.env.gravity.setZero();
        c.p.Can = 1;
        mu += 1025 * kPi * 0.05 * 0.05 / 4;
      }
      const double Ls = c.L * (1 + stretch), mu_s = mu * c.L / Ls;
      for (int n = 1; n <= 3; ++n) {
        ref[n - 1] = n / (2 * Ls) * std::sqrt(T / mu_s);
        const double f = MeasureFrequency(c, n, 8, ref[n - 1]);
        errors[n - 1].emplace_back(N, f / ref[n - 1] - 1);
        if (N == 40) {
          f40[n - 1] = f;
          const double dispersion = std::pow(n * kPi / N, 2) / 24;
          EXPECT_NEAR(f / ref[n - 1] - 1, 0, 2 * dispersion) << "n " << n << " wet " << wet;
        }
      }
    }
    for (int n = 1; n <= 3; ++n) {
      EXPECT_NEAR(LastOrder(errors[n - 1]), 2, 0.5);
      Record((wet ? 3 : 0) + n - 1,
             {std::string("6. Taut string") + (wet ? " in water (μ with added mass)" : ", dry") +
                  ": f" + std::to_string(n),
              "n/(2L)·√(T/μ) " + Format("%.5f Hz", ref[n - 1]), Format("%.5f Hz", f40[n - 1]),
              Percent(errors[n - 1][1].second),
              Format("2·(nπ/N)²/24 = %.2g%%", 100 * 2 * std::pow(n * kPi / 40, 2) / 24),
              Orders(errors[n - 1]), 40});
    }
  }
}

// Pinned beam with and without tension: omega_n^2 = (EI k^4 + T k^2)/mu, k = n pi/L
// (Euler-Bernoulli beam under axial tension; e.g. Irvine 1981, ch. 3). The mode shapes are
// exact eigenvectors of the lumped Galerkin operator, whose eigenvalues replace k^2 by
// lambda = (2/L0 sin(k L0/2))^2: relative frequency error ~ -(k L0)^2/12 when bending
// dominates (0.46% for n = 3 at 40 segments); the tolerance is 1.5 times the discrete
// formula's deviation plus 1e-4 for the pre-stretch (1e-4) that the reference ignores in EI.
// "Without tension" is T = 0.01 N (kept in the reference, 0.05% of omega_1^2): at exactly
// zero tension the segments switch between slack and taut every step and the explicit scheme
// grows a slow instability at steps above ~0.56 of its estimated limit (see the report).
TEST(Validation, PinnedBeamFrequencies) {
  const double L = 2, mu = 1, EI = 4, EA = 1e5;
  int row = 0;
  for (double T : {0.01, 10.0}) {
    std::vector<std::vector<std::pair<int, double>>> errors(3);
    std::vector<double> f40(3), ref(3);
    for (int N : {20, 40, 80}) {
      Vibration c;
      c.L = L;
      c.N = N;
      c.stretch = T / EA;
      c.p.length = L;
      c.p.segments = N;
      c.p.diameter = 0.05;
      c.p.mass_per_length = mu;
      c.p.EA = EA;
      c.p.EI = EI;
      c.p.integrator = Integrator::kExplicit;
      c.env.gravity.setZero();
      const double Ls = L * (1 + c.stretch), mu_s = mu * L / Ls;
      for (int n = 1; n <= 3; ++n) {
        const double k = n * kPi / Ls;
        ref[n - 1] = std::sqrt((EI * std::pow(k, 4) + T * k * k) / mu_s) / (2 * kPi);
        const double f = MeasureFrequency(c, n, 4, ref[n - 1]);
        errors[n - 1].emplace_back(N, f / ref[n - 1] - 1);
        if (N == 40) {
          f40[n - 1] = f;
          const double L0 = Ls / N;
          const double lambda = std::pow(2 / L0 * std::sin(k * L0 / 2), 2);
          const double discrete =
              std::sqrt((EI * lambda * lambda + T * lambda) / mu_s) / (2 * kPi) / ref[n - 1] - 1;
          EXPECT_NEAR(f / ref[n - 1] - 1, 0, 1.5 * std::abs(discrete) + 1e-4)
              << "n " << n << " T " << T;
        }
      }
    }
    for (int n = 1; n <= 3; ++n) {
      EXPECT_NEAR(LastOrder(errors[n - 1]), 2, 0.5);
      const double k = n * kPi / L, L0 = L / 40;
      const double lambda = std::pow(2 / L0 * std::sin(k * L0 / 2), 2);
      const double discrete = std::sqrt((EI * lambda * lambda + T * lambda) /
                                        (EI * std::pow(k, 4) + T * k * k)) - 1;
      Record(row++, {std::string("7. Pinned beam, ") + (T > 1 ? "T = 10 N" : "T ≈ 0 (0.01 N)") +
                         " (EI 4 N m², L 2 m): f" + std::to_string(n),
                     "√((EIk⁴+Tk²)/μ)/2π " + Format("%.5f Hz", ref[n - 1]),
                     Format("%.5f Hz", f40[n - 1]), Percent(errors[n - 1][1].second),
                     Format("1.5·|discrete| + 0.01%% = %.2g%%", 100 * (1.5 * std::abs(discrete) + 1e-4)),
                     Orders(errors[n - 1]), 40});
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 8. Free-hanging tether in a uniform current with no tangential drag: every element sees the
// same normal load, so the line is straight at the critical angle phi from the vertical where
// the normal drag balances the normal component of the wet weight (Pode, "Tables for
// computing the equilibrium configuration of a flexible cable in a uniform stream", DTMB
// report 687, 1951):  1/2 rho Cdn d U^2 cos^2 phi = w sin phi.
// The drag acts on the stretched length and the weight on the unstretched one, which tilts
// the line by ~ 0.3 strain (strain < 5e-5 here): 1e-4 rad bounds it.
TEST(Validation, CriticalAngleInCurrent) {
  const double U = 1, d = 0.02, Cdn = 1.2, rho = 1025, L = 50;
  Environment env = Water(rho);
  env.water.current = Vec3(U, 0, 0);
  const double w = (1 - rho * kPi * d * d / 4) * kG, k = 0.5 * rho * Cdn * d;
  const double s = (-w + std::sqrt(w * w + 4 * k * k * std::pow(U, 4))) / (2 * k * U * U);
  const double phi = std::asin(s);
  double worst40 = 0, mean40 = 0;
  for (int N : {10, 20, 40}) {
    TetherParams p;
    p.length = L;
    p.segments = N;
    p.diameter = d;
    p.mass_per_length = 1;
    p.EA = 1e7;
    p.Cdn = Cdn;
    p.free_end = true;
    Sim sim(Make(p, env));
    sim.Init();
    ASSERT_TRUE(sim.Settle(0.1, 20000, 1e-10)) << N;
    double worst = 0, mean = 0;
    for (int j = 0; j < N; ++j) {
      const Vec3 t = (sim.node(j + 1) - sim.node(j)).normalized();
      const double angle = std::atan2(t.x(), -t.z());
      worst = std::max(worst, std::abs(angle - phi));
      mean += angle / N;
      EXPECT_NEAR(t.y(), 0, 1e-9);
    }
    EXPECT_LT(worst, 1e-4) << N;
    if (N == 40) worst40 = worst, mean40 = mean;
  }
  Record(0, {"8. Free-hanging line in a current U 1 m/s, Cdt = 0: angle from vertical "
             "(worst segment)",
             "Pode (1951) critical angle " + Format("%.4f°", phi * 180 / kPi),
             Format("%.4f°", mean40 * 180 / kPi),
             Format("%.2g rad", worst40), "1e-4 rad, every segment, N = 10/20/40", "exact (straight)", 40});
}

// ---------------------------------------------------------------------------------------------
// 9. Terminal sinking speed of a horizontal heavy tether: normal drag balances the wet weight,
// 1/2 rho Cdn d V^2 = w, V = sqrt(2 w/(rho Cdn d)) (Morison drag). The line starts
// horizontal, every node sinking at the reference V, end A lowered at V, end B free. It keeps
// sinking at V, horizontal, only if V is the terminal speed (otherwise the free nodes speed up
// or slow down relative to A); the force needed to lower end A is the whole line's drag minus
// its weight, L (k V^2 - w), zero exactly at V (a 1% error in V would show as 2% of w L).
// The lumped drag and weight are in the same proportion at every node, so the discrete
// terminal speed is exact: tolerances at round-off level over 5 s (1e-9 V on every node's
// speed, 1e-9 w L on the force at A). Started from rest with A prescribed, the line would not
// stay horizontal: in the frame sinking at V the net load vanishes and nothing restores a tilt
// (the transient tilts it and it ends hanging from A).
TEST(Validation, TerminalSinkingSpeed) {
  const double rho = 1025, d = 0.02, Cdn = 1.2, mu = 1, L = 10;
  const double w = (mu - rho * kPi * d * d / 4) * kG, V = std::sqrt(2 * w / (rho * Cdn * d));
  Environment env = Water(rho);
  TetherParams p;
  p.length = L;
  p.segments = 20;
  p.diameter = d;
  p.mass_per_length = mu;
  p.EA = 1e4;
  p.Cdn = Cdn;
  p.Cdt = 0.01;
  p.free_end = true;
  Sim s(Make(p, env));
  for (int i = 0; i <= 20; ++i) s.set(i, Vec3(L * i / 20, 0, 0)), s.set_vel(i, Vec3(0, 0, -V));
  s.ends.a.vel = Vec3(0, 0, -V);
  const double h = 0.01;
  for (int k = 0; k < 500; ++k) {
    Ends to = s.ends;
    to.a.pos.z() = -V * (k + 1) * h;
    ASSERT_TRUE(s.Move(to, h).ok);
  }
  double worst = 0, tilt = 0;
  for (int i = 0; i <= 20; ++i) {
    worst = std::max(worst, std::abs(-s.vel(i).z() / V - 1));
    tilt = std::max(tilt, std::abs(s.node(i).z() - s.node(0).z()));
  }
  const double force = s.Reactions().force_a.norm();
  EXPECT_LT(worst, 1e-9);
  EXPECT_LT(force, 1e-9 * w * L);
  EXPECT_LT(tilt, 1e-9 * L);
  Record(0, {"9. Terminal sinking speed of a horizontal tether (d 0.02 m, Cdn 1.2, wet weight "
             "6.65 N/m): every node's speed, end A lowered at V",
             "√(2w/(ρ Cdn d)) " + Format("%.5f m/s", V),
             Format("%.5f m/s", -s.vel(20).z()), Format("%.2g (worst node)", worst),
             "1e-9 on speeds; force at A 1e-9 w L", "exact (no discretisation error)", 20});
}

// ---------------------------------------------------------------------------------------------
// 10 (second part). Axial wave speed c = sqrt(EA/mu): end A is jerked away from B with a
// velocity ramp 0 -> V over tau; the tension at the fixed end B (where the wave reflects and
// doubles, to 2 sqrt(EA mu) V) crosses half its plateau at L/c + tau/2. The lumped chain
// disperses waves shorter than a few segments; the ramp spans c tau = 10 segments at N = 100,
// so the arrival time is exact to O((L0/c tau)^2) ~ 1% of tau, 0.05% of L/c: tolerance 0.5%.
TEST(Validation, AxialWaveSpeed) {
  const double L = 100, EA = 1e6, mu = 1, V = 1, tau = 0.01;
  const double c = std::sqrt(EA / mu), expected = L / c + tau / 2;
  std::vector<std::pair<int, double>> e;
  double t100 = 0;
  for (int N : {50, 100, 200}) {
    TetherParams p;
    p.length = L;
    p.segments = N;
    p.diameter = 0.02;
    p.mass_per_length = mu;
    p.EA = EA;
    p.integrator = Integrator::kExplicit;
    Environment env;
    env.gravity.setZero();
    Sim s(Make(p, env));
    s.ends.a.pos = Vec3(0, 0, 0);
    s.ends.b.pos = Vec3(L, 0, 0);
    s.Init();
    const double h = s.tether.ExplicitStableStep();
    const double plateau = 2 * std::sqrt(EA * mu) * V;
    double t = 0, Tb_prev = 0, arrival = -1;
    while (t < 1.5 * L / c && arrival < 0) {
      Ends to = s.ends;
      const double t1 = t + h;
      // x_A(t) = -V (t^2/(2 tau)) during the ramp, then -V (t - tau/2).
      to.a.pos.x() = t1 < tau ? -V * t1 * t1 / (2 * tau) : -V * (t1 - tau / 2);
      to.a.vel.x() = t1 < tau ? -V * t1 / tau : -V;
      ASSERT_TRUE(s.Move(to, h).ok);
      const double Tb = s.Reactions().tension_b;
      if (Tb >= plateau / 2 && Tb_prev < plateau / 2) {
        arrival = t + h * (plateau / 2 - Tb_prev) / (Tb - Tb_prev);
      }
      Tb_prev = Tb;
      t = t1;
    }
    ASSERT_GT(arrival, 0) << N;
    e.emplace_back(N, arrival / expected - 1);
    if (N == 100) t100 = arrival;
  }
  EXPECT_NEAR(e[1].second, 0, 0.005);
  const double c100 = L / (t100 - tau / 2);
  Record(0, {"10. Axial wave (EA 1e6 N, μ 1 kg/m, L 100 m): speed from the arrival time at B",
             "√(EA/μ) " + Format("%.2f m/s", c), Format("%.2f m/s", c100),
             Percent(c100 / c - 1), "arrival time 0.5%", Orders(e), 100});
}

// ---------------------------------------------------------------------------------------------
// 11. Energy. With drag and damping off, symplectic Euler (the explicit integrator) conserves
// a modified energy E + (h/2) f.v to O(h^2) (harmonic oscillator: x^2 + v^2 - h x v is
// invariant), so |E - E0| stays below h max|f.v| (f.v the power of the forces on the free
// nodes) and does not drift. Swinging catenary with bending, 100 swing periods.
TEST(Validation, ExplicitEnergyBoundedOver100Periods) {
  TetherParams p;
  p.length = 100;
  p.segments = 20;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e5;
  p.EI = 1e3;
  p.integrator = Integrator::kExplicit;
  Environment env;
  Sim s(Make(p, env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(80, 0, 0);
  // Start from the elastic equilibrium (the inextensible initial shape has every segment at
  // its rest length, i.e. slack: the line would drop and switch segments between slack and
  // taut, a non-smooth force law under which symplectic Euler does drift).
  TetherParams q = p;
  q.integrator = Integrator::kImplicit;
  Sim rest(Make(q, env));
  rest.ends = s.ends;
  rest.Init();
  ASSERT_TRUE(rest.Settle(0.05, 20000, 1e-9));
  s.x = rest.x;
  const double E_rest = s.Energy();
  const Eigen::AngleAxisd R(30 * kPi / 180, Vec3::UnitX());
  for (int i = 0; i <= 20; ++i) s.set(i, R * s.node(i));
  const double E0 = s.Energy(), swing = E0 - E_rest;
  const double h = s.tether.ExplicitStableStep();
  std::vector<double> f(3 * 21);
  double max_dev = 0, max_power = 0, y_prev = 0, t = 0;
  double first_mean = 0, last_mean = 0;
  int crossings = 0;
  std::vector<double> crossing_times;
  while (crossings < 201) {
    ASSERT_TRUE(s.Step(h).ok);
    t += h;
    const double E = s.Energy();
    max_dev = std::max(max_dev, std::abs(E - E0));
    s.tether.ComputeForces(s.x.data(), s.v.data(), s.ends, f.data(), nullptr, s.work.data());
    double power = 0;
    for (int i = 1; i < 20; ++i) power += Vec3(&f[3 * i]).dot(s.vel(i));
    max_power = std::max(max_power, std::abs(power));
    const double y = s.node(10).y();
    if (t > h && (y > 0) != (y_prev > 0)) {
      ++crossings;
      crossing_times.push_back(t);
    }
    if (crossings >= 1 && crossings <= 20) first_mean += (E - E0) * h;
    if (crossings >= 181 && crossings <= 200) last_mean += (E - E0) * h;
    y_prev = y;
  }
  const double period = 2 * (crossing_times.back() - crossing_times.front()) / 200;
  first_mean /= 10 * period;
  last_mean /= 10 * period;
  const double bound = h * max_power;
  EXPECT_LT(max_dev, bound);
  // No drift: the mean deviation over the last 10 periods is that of the first 10.
  EXPECT_LT(std::abs(last_mean - first_mean), 0.05 * bound);
  Record(0, {"11. Energy, explicit, no drag or damping: 100 swing periods of a catenary "
             "with bending (max |E − E₀|)",
             Format("bound h·max|f·v| = %.3g J", bound) + Format(" (swing %.3g J)", swing),
             Format("%.3g J", max_dev), Format("%.2g of the bound", max_dev / bound),
             "below the bound; drift < 5% of it", "–", 20});
  Record(1, {"11. Energy drift over 100 periods (mean of periods 91-100 minus 1-10)", "0",
             Format("%.3g J", last_mean - first_mean),
             Format("%.2g of the swing energy", (last_mean - first_mean) / swing),
             "< 5% of the bound", "–", 20});
}

// Drag power is never positive: along a dynamic run in a current, the drag forces (computed as
// the difference between the tether with and without the drag effect) do no positive work
// relative to the water, f_drag . (v - u) <= 0 at every node (Morison drag opposes the
// relative velocity, normal and tangential parts separately).
TEST(Validation, DragPowerNeverPositiveInARun) {
  Environment env = Water();
  env.water.current = Vec3(0.7, 0.2, 0);
  TetherParams p;
  p.length = 40;
  p.segments = 20;
  p.diameter = 0.03;
  p.mass_per_length = 1.5;
  p.EA = 1e5;
  p.EI = 5;
  p.Cdn = 1.2;
  p.Cdt = 0.02;
  p.Can = 1;
  p.integrator = Integrator::kExplicit;
  Sim s(Make(p, env));
  Tether no_drag = Make(p, env, "axial,bending,weight,buoyancy,added_mass");
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(25, 0, -10);
  s.ends.b.vel = Vec3(0, 2, 0);
  s.Init();
  std::vector<double> f1(3 * 21), f2(3 * 21);
  double worst = -INFINITY, dissipated = 0;
  for (int k = 0; k < 3000; ++k) {
    // End B circles: the line whips through the water.
    Ends to = s.ends;
    const double t = (k + 1) * 0.01;
    to.b.pos = Vec3(23 + 2 * std::cos(t), 2 * std::sin(t), -10);
    to.b.vel = Vec3(-2 * std::sin(t), 2 * std::cos(t), 0);
    ASSERT_TRUE(s.Move(to, 0.01).ok);
    s.tether.ComputeForces(s.x.data(), s.v.data(), s.ends, f1.data(), nullptr, s.work.data());
    no_drag.ComputeForces(s.x.data(), s.v.data(), s.ends, f2.data(), nullptr, s.work.data());
    for (int i = 0; i <= 20; ++i) {
      const double power = (Vec3(&f1[3 * i]) - Vec3(&f2[3 * i])).dot(s.vel(i) - env.water.current);
      worst = std::max(worst, power);
      dissipated -= power * 0.01;
      ASSERT_LE(power, 1e-12) << "node " << i << " step " << k;
    }
  }
  EXPECT_GT(dissipated, 0);
  Record(0, {"11. Drag power relative to the water, 30 s of a whipping line in a current",
             "≤ 0 at every node and step", Format("max %.2g W", worst),
             Format("dissipated %.3g J", dissipated), "≤ 1e-12 W", "–", 20});
}

}  // namespace
}  // namespace mjtether
