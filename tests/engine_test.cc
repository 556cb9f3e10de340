// Tests of the tether engine alone (no MuJoCo): closed forms, conservation laws.
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "band_cholesky.h"
#include "catenary_reference.h"
#include "declaration.h"
#include "engine_sim.h"
#include "make_tether.h"
#include "tether.h"

namespace mjtether {
namespace {

// ---------------------------------------------------------------------------------------------

TEST(BandCholesky, MatchesDenseSolve) {
  // A random SPD matrix with half-bandwidth 8, as the implicit step builds.
  const int n = 60, p = 8;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> U(-1, 1);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - p); j < i; ++j) A(i, j) = A(j, i) = U(rng);
    A(i, i) = 2 * p + 1;  // diagonally dominant
  }
  Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(n, [&]() { return U(rng); });
  std::vector<double> storage(BandMatrix::Size(n, p));
  BandMatrix B(storage.data(), n, p);
  B.SetZero();
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - p); j <= i; ++j) B.Add(i, j, A(i, j));
  }
  ASSERT_EQ(B.Factor(), -1);
  Eigen::VectorXd x = b;
  B.Solve(x.data());
  Eigen::VectorXd ref = A.llt().solve(b);
  EXPECT_LT((x - ref).norm(), 1e-12 * ref.norm());
}

TEST(BandCholesky, ReportsIndefiniteMatrix) {
  std::vector<double> storage(BandMatrix::Size(3, 1));
  BandMatrix B(storage.data(), 3, 1);
  B.SetZero();
  B.Add(0, 0, 1);
  B.Add(1, 0, 2);  // [[1,2],[2,1]] is indefinite
  B.Add(1, 1, 1);
  B.Add(2, 2, 1);
  EXPECT_EQ(B.Factor(), 1);
}

// The slack initial shape of a weighted line is the discrete chain's own static shape (the
// funicular polygon, Tether::HangChain): every interior node is at rest under its weight and
// its two segments' tensions EA strain. Oracle: the tether's own force evaluation at t = 0,
// whose largest nodal force must be round-off against the node's weight (1e-9; the bisections
// close the spans to ~1e-14 L; measured 2e-13 and 7e-11). The catenary sampled at arc spacing,
// the start before session 24, puts every chord short of L0 (here by 1.8% of L0 with 4
// segments, 1.8e-4 with 40): every segment starts slack and every node is out of balance by
// its whole weight (measured with that start: 1.00 of the node weight, all segments slack). The polygon's chords are L0 (1 + T/EA), so
// its length exceeds L by the mean strain, and it lies in the vertical plane of the ends.
TEST(InitialShape, SlackStartIsTheChainAtRest) {
  Environment env;
  for (int n : {4, 40}) {
    Sim s(Make(CatenaryParams(n), env));
    s.ends.a.pos = Vec3(0, 0, 0);
    s.ends.b.pos = Vec3(60, 30, 20);
    s.Init();
    std::vector<double> f(3 * s.tether.nodes()), T(n);
    s.tether.ComputeForces(s.x.data(), s.v.data(), s.ends, f.data(), T.data(), s.work.data());
    const double weight = 1.0 * 100.0 / n * 9.81;  // [N] one interior node (no water)
    double worst = 0, length = 0, strain = 0, lowest = 0, slack = 0;
    for (int i = 1; i < n; ++i) worst = std::max(worst, Vec3(&f[3 * i]).norm() / weight);
    for (int i = 0; i < n; ++i) {
      const double l = (s.node(i + 1) - s.node(i)).norm();
      length += l;
      strain += T[i] / 1e5 * (100.0 / n);  // [m] the stretch EA strain gives each segment
      if (T[i] <= 0) ++slack;
    }
    for (int i = 0; i <= n; ++i) lowest = std::min(lowest, s.node(i).z());
    std::printf("%d segments: largest nodal force %.2e of the node weight, %g slack, length %.6f "
                "m, sag to z = %.3f m\n", n, worst, slack, length, lowest);
    EXPECT_LT(worst, 1e-9);
    EXPECT_EQ(slack, 0);
    EXPECT_NEAR(length, 100 + strain, 1e-9 * 100);
    EXPECT_LT(lowest, -10);  // it sags
    EXPECT_EQ((s.node(0) - s.ends.a.pos).norm(), 0);
    EXPECT_EQ((s.node(n) - s.ends.b.pos).norm(), 0);
    const Vec3 normal = Vec3(60, 30, 0).cross(Vec3::UnitZ()).normalized();
    for (int i = 0; i <= n; ++i) EXPECT_NEAR(s.node(i).dot(normal), 0, 1e-9);
  }
}

// Without net weight (no gravity here; a neutral line likewise) every slack shape is at rest and
// the start stays the catenary of the declared length, its chords short of L0 (slack).
TEST(InitialShape, WeightlessSlackStartIsTheCatenary) {
  Environment env;
  env.gravity = Vec3::Zero();
  Sim s(Make(CatenaryParams(40), env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(60, 30, 20);
  s.Init();
  double length = 0;
  for (int i = 0; i < 40; ++i) length += (s.node(i + 1) - s.node(i)).norm();
  // Chords of a curve of length L are shorter than L by O(L0^2 kappa^2 / 24) each.
  EXPECT_NEAR(length, 100, 0.05);
  EXPECT_LT(length, 100);
}

// With compression a segment shorter than L0 pushes, so the slack initial shape must not
// start compressed. Weighted, the chain at rest has every chord at least L0. Weightless (the
// catenary), every chord is L0 (to 1e-9 relative; the walk converges to 1e-14), the end nodes
// are on the sites, and the shape is the same catenary as without compression to within the
// chord-versus-arc difference (the nodes move by less than 1% of L0 here).
TEST(InitialShape, WithCompressionEveryChordIsTheRestLength) {
  {
    Environment env;
    TetherParams p = CatenaryParams(40);
    p.EAc = 1e5;
    Sim s(Make(p, env));
    s.ends.a.pos = Vec3(0, 0, 0);
    s.ends.b.pos = Vec3(60, 30, 20);
    s.Init();
    double shortest = INFINITY;
    for (int i = 0; i < 40; ++i) shortest = std::min(shortest, (s.node(i + 1) - s.node(i)).norm());
    EXPECT_GE(shortest, 2.5 * (1 + 1e-6)) << "weighted: every segment taut";
  }
  Environment env;
  env.gravity = Vec3::Zero();
  TetherParams p = CatenaryParams(40);
  Sim plain(Make(p, env));
  p.EAc = 1e5;
  Sim s(Make(p, env));
  for (Sim* t : {&plain, &s}) {
    t->ends.a.pos = Vec3(0, 0, 0);
    t->ends.b.pos = Vec3(60, 30, 20);
    t->Init();
  }
  double worst = 0, moved = 0;
  for (int i = 0; i < 40; ++i) {
    worst = std::max(worst, std::abs((s.node(i + 1) - s.node(i)).norm() / 2.5 - 1));
  }
  for (int i = 0; i <= 40; ++i) moved = std::max(moved, (s.node(i) - plain.node(i)).norm());
  std::printf("compressed start: chord error %.2e, moved %.3g m\n", worst, moved);
  EXPECT_LT(worst, 1e-9);
  EXPECT_EQ((s.node(0) - s.ends.a.pos).norm(), 0);
  EXPECT_EQ((s.node(40) - s.ends.b.pos).norm(), 0);
  EXPECT_LT(moved, 0.01 * 2.5);
  const Vec3 normal = Vec3(60, 30, 0).cross(Vec3::UnitZ()).normalized();
  for (int i = 0; i <= 40; ++i) EXPECT_NEAR(s.node(i).dot(normal), 0, 1e-9);
}

// (With compression too: the hairpin at the bottom is where the equal-chord walk may give up
// and keep the arc spacing; either way the shape is finite and the same.)
TEST(InitialShape, VerticalEndsHangAU) {
  for (double EAc : {0.0, 1e5}) {
    Environment env;
    TetherParams p = CatenaryParams(20);
    p.EAc = EAc;
    Sim s(Make(p, env));
    s.ends.a.pos = Vec3(0, 0, 0);
    s.ends.b.pos = Vec3(0, 0, -10);
    s.Init();
    for (double xi : s.x) ASSERT_TRUE(std::isfinite(xi));
    double lowest = 0;
    for (int i = 0; i <= 20; ++i) lowest = std::min(lowest, s.node(i).z());
    // A U of length 100 between points 10 m apart vertically bottoms out 55 m below A.
    EXPECT_NEAR(lowest, -55, 2.5);  // the node spacing (5 m) limits how close a node gets
  }
}

// Static elastic catenary between two fixed points against Irvine's closed form. The lumped
// model carries the support force as the end segment's tension plus the end node's weight,
// which is n(0) of the continuum to O(L0^2): 0.5% at 40 segments (the target).
TEST(Catenary, EndTensionsMatchIrvineAt40Segments) {
  Environment env;  // dry: weight only
  Sim s(Make(CatenaryParams(40), env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(80, 0, 20);
  s.Init();
  // Backward Euler at a large step damps every mode: a static solve by time stepping.
  for (int k = 0; k < 3000; ++k) ASSERT_TRUE(s.Step(0.05).ok);
  const double w = 1.0 * 9.81;
  testing::Catenary ref = testing::SolveCatenary(80, 20, 100, w, 1e5);
  EndReactions r = s.Reactions();
  EXPECT_NEAR(r.tension_a / ref.tension_a(), 1, 0.005);
  EXPECT_NEAR(r.tension_b / ref.tension_b(), 1, 0.005);
  // Global equilibrium holds exactly: the supports carry the whole weight.
  EXPECT_NEAR(r.force_a.z() + r.force_b.z(), -w * 100, 1e-6 * w * 100);
  // Force on A is n(0): horizontal component H, pulling towards B.
  EXPECT_NEAR(r.force_a.x() / ref.H, 1, 0.005);
}

// A line hanging from one point with a free end stretches by w L^2 / (2 EA).
TEST(Catenary, FreeHangingLineStretchesByOwnWeight) {
  Environment env;
  TetherParams p = CatenaryParams(20);
  p.free_end = true;
  Sim s(Make(p, env));
  s.Init();
  for (int k = 0; k < 2000; ++k) ASSERT_TRUE(s.Step(0.05).ok);
  const double w = 9.81, L = 100, EA = 1e5;
  // Lumped: segment j carries the weight of the nodes below it exactly, so the discrete
  // stretch is sum_j w (L - (j + 1/2) L0) L0 / EA ... = w L^2 / (2 EA) exactly.
  EXPECT_NEAR(-s.node(20).z(), L + w * L * L / (2 * EA), 1e-6 * L);
}

// Internal forces (tension, damping, bending with pinned ends) are action-reaction pairs:
// they sum to zero and have no net moment (Newton's third law and the moment balance used to
// derive the bending shear).
TEST(Forces, InternalForcesHaveNoNetForceOrMoment) {
  Environment env;
  env.gravity.setZero();
  TetherParams p = CatenaryParams(12);
  p.EI = 50;
  Tether t = Make(p, env);
  ASSERT_TRUE(t.params().effects & kBending);
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0, 1);
  std::vector<double> x(3 * 13), v(3 * 13), f(3 * 13), work(t.WorkspaceSize());
  for (int i = 0; i <= 12; ++i) {
    for (int c = 0; c < 3; ++c) {
      x[3 * i + c] = (c == 0 ? 9.0 * i : 0.0) + N(rng);  // taut-ish, crooked
      v[3 * i + c] = N(rng);
    }
  }
  Ends ends;
  t.ComputeForces(x.data(), v.data(), ends, f.data(), nullptr, work.data());
  Vec3 F = Vec3::Zero(), Mo = Vec3::Zero();
  double scale = 0;
  for (int i = 0; i <= 12; ++i) {
    Vec3 fi(&f[3 * i]), xi(&x[3 * i]);
    F += fi;
    Mo += xi.cross(fi);
    scale += fi.norm() * (1 + xi.norm());
  }
  EXPECT_LT(F.norm(), 1e-12 * scale);
  EXPECT_LT(Mo.norm(), 1e-12 * scale);
}

// Drag only removes energy: the power of the drag forces on a moving tether in still water is
// never positive.
TEST(Forces, DragPowerIsNeverPositive) {
  Environment env;
  env.wet = true;
  env.gravity.setZero();
  TetherParams p = CatenaryParams(10);
  p.Cdn = 1.2;
  p.Cdt = 0.01;
  p.length = 1000;  // all segments slack below: only drag acts
  Tether t = Make(p, env, "axial,drag");
  std::mt19937 rng(3);
  std::normal_distribution<double> N(0, 1);
  std::vector<double> x(33), v(33), f(33), work(t.WorkspaceSize());
  for (int trial = 0; trial < 100; ++trial) {
    for (int i = 0; i < 33; ++i) {
      x[i] = 10 * N(rng);
      v[i] = N(rng);
    }
    t.ComputeForces(x.data(), v.data(), Ends{}, f.data(), nullptr, work.data());
    double power = 0;
    for (int i = 0; i < 33; ++i) power += f[i] * v[i];
    ASSERT_LE(power, 0);
  }
}

// Coincident nodes (zero-length segments) give finite forces and a finite step.
TEST(Forces, CoincidentNodesStayFinite) {
  Environment env;
  env.wet = true;
  env.water.current = Vec3(0.5, 0, 0);
  TetherParams p = CatenaryParams(8);
  p.EI = 1;
  p.Cdn = 1.2;
  p.Cdt = 0.01;
  p.Can = 1;
  for (Integrator integrator : {Integrator::kExplicit, Integrator::kImplicit}) {
    p.integrator = integrator;
    Sim s(Make(p, env));
    std::fill(s.x.begin(), s.x.end(), 0.0);
    std::fill(s.v.begin(), s.v.end(), 0.0);
    EXPECT_TRUE(s.Step(0.01).ok);
    for (double xi : s.x) ASSERT_TRUE(std::isfinite(xi));
  }
}

// With no damping and no drag, the explicit (symplectic) integrator keeps the total energy of
// a swinging tether bounded: symplectic Euler conserves a shadow energy within O(h), so the
// deviation is a fraction of the swing energy, does not grow, and returns at the end.
TEST(Energy, ExplicitUndampedSwingIsBounded) {
  Environment env;  // dry, gravity
  TetherParams p = CatenaryParams(20);
  p.damping = 0;
  p.integrator = Integrator::kExplicit;
  Sim s(Make(p, env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(80, 0, 0);
  s.Init();
  // Swing energy: start the catenary rotated 30 degrees about the chord, at rest.
  const double E_rest = s.Energy();
  const Eigen::AngleAxisd R(30 * M_PI / 180, Vec3::UnitX());
  for (int i = 0; i <= 20; ++i) {
    Vec3 r = R * s.node(i);
    for (int c = 0; c < 3; ++c) s.x[3 * i + c] = r[c];
  }
  const double E0 = s.Energy(), swing = E0 - E_rest;
  ASSERT_GT(swing, 0);
  // About 12 swing periods (T ~ 2 pi sqrt(sag/g) ~ 8 s for ~ 25 m of sag... measured below).
  double max_dev = 0, z_prev = 0;
  int crossings = 0;
  for (int k = 0; k < 10000; ++k) {
    ASSERT_TRUE(s.Step(0.01).ok);
    max_dev = std::max(max_dev, std::abs(s.Energy() - E0));
    const double y = s.node(10).y();
    if (k > 0 && (y > 0) != (z_prev > 0)) ++crossings;
    z_prev = y;
  }
  EXPECT_GE(crossings, 20);  // it really swung, at least 10 periods
  EXPECT_LT(max_dev, 0.02 * swing);
}

// The implicit integrator is dissipative: energy never rises above its start.
TEST(Energy, ImplicitUndampedSwingNeverGainsEnergy) {
  Environment env;
  TetherParams p = CatenaryParams(20);
  p.damping = 0;
  Sim s(Make(p, env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(80, 0, 0);
  s.Init();
  const Eigen::AngleAxisd R(30 * M_PI / 180, Vec3::UnitX());
  for (int i = 0; i <= 20; ++i) {
    Vec3 r = R * s.node(i);
    for (int c = 0; c < 3; ++c) s.x[3 * i + c] = r[c];
  }
  const double E0 = s.Energy();
  double E_prev = E0;
  for (int k = 0; k < 2000; ++k) {
    ASSERT_TRUE(s.Step(0.005).ok);
    const double E = s.Energy();
    ASSERT_LE(E, E0 + 1e-9 * std::abs(E0));
    E_prev = E;
  }
  EXPECT_LT(E_prev, E0);
}

// The catenary of p between (0,0,0) and (80,0,20), from its initial shape, stepped 400
// times by `call` [s] in tether steps of `step` [s]; false if Advance reported divergence.
// The final positions go to *x when given.
bool CatenaryRunsAt(TetherParams p, const Environment& env, double step, double call,
                    std::vector<double>* x) {
  p.max_step = step;
  Sim s(Make(p, env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(80, 0, 20);
  s.Init();
  bool ok = true;
  for (int k = 0; k < 400 && ok; ++k) ok = s.Step(call).ok;
  if (x) *x = s.x;
  return ok;
}

// The explicit stability limit is real: stepping at 0.72x the computed limit is stable and
// at 2.4x it blows up, which the divergence check reports. (The stable step, half the limit,
// is not what is tested here: at 3x it, 1.5x the limit, this heavily damped catenary does not
// blow up, the unstable mode being bounded by the slack clamp; docs/numerics.md.)
TEST(Stability, ExplicitLimitSeparatesStableFromUnstable) {
  Environment env;
  TetherParams p = CatenaryParams(20);
  p.integrator = Integrator::kExplicit;
  Tether t = Make(p, env);
  const double limit = t.ExplicitStabilityLimit();
  for (double factor : {0.72, 2.4}) {
    const bool ok = CatenaryRunsAt(p, env, factor * limit, 20 * factor * limit, nullptr);
    EXPECT_EQ(ok, factor < 1) << "factor " << factor << ", limit " << limit;
  }
}

// RK4's limit (about 2.8/w along both axes, times the safety factor 0.8) is real too. Undamped:
// 0.9x is stable and 1.5x (1.2x past the true limit: the frequency estimate 4 EA/(L0 m) is
// within 1% of the chain's highest mode at 20 segments) blows up. Damped (zeta 1.3 at the top
// mode, overdamped, so its fast root -w (zeta + sqrt(zeta^2 - 1)) sets the limit): 0.9x is
// stable and accurate, within 1 mm of a run at 0.1x after 70 s. (Past the limit a heavily
// damped chain need not blow up: the unstable mode drives segments slack, where the
// tension-only law clips the damping, and it jitters instead; at 2x the limit its kinetic
// energy is 25 times the 0.9x run's. The limit keeps it out of that regime.)
TEST(Stability, Rk4LimitSeparatesStableFromUnstable) {
  Environment env;
  for (double damping : {0.0, 2e3}) {
    TetherParams p = CatenaryParams(20);
    p.integrator = Integrator::kRK4;
    p.damping = damping;
    const double limit = Make(p, env).ExplicitStableStep();
    std::vector<double> positions[2];
    for (double factor : {0.9, 1.5, 0.1}) {
      if (damping > 0 ? factor == 1.5 : factor == 0.1) continue;
      const bool ok =
          CatenaryRunsAt(p, env, factor * limit, 18 * limit, &positions[factor < 0.5]);
      EXPECT_EQ(ok, factor < 1) << "factor " << factor << ", limit " << limit;
    }
    if (damping > 0) {
      double e = 0;
      for (size_t i = 0; i < positions[0].size(); ++i) {
        e = std::max(e, std::abs(positions[0][i] - positions[1][i]));
      }
      std::printf("damped, 0.9x against 0.1x: %.3g m\n", e);
      EXPECT_LT(e, 1e-3);
    }
  }
}

// RK4 is fourth order: a string pretensioned to 1% strain (ends 101 m apart, L = 100 m), released
// straight under gravity, sags and vibrates; its tension stays near EA/100 = 1 kN, so no
// segment goes slack and the motion is smooth (the tension-only switch would cost orders).
// After 2 s at steps H = 5 ms (h w = 0.3 for the top mode) and H/2 against H/16 the error
// ratio is 2^4 = 16; accepted: order 3.5-4.5 (measured 4.05). Symplectic Euler on the same
// run is first order (accepted below 1.5) and far less accurate, which shows that the test
// tells the schemes apart.
TEST(Rk4, FourthOrderInTime) {
  Environment env;
  auto run = [&](Integrator integrator, double h) {
    TetherParams p = CatenaryParams(10);
    p.damping = 0;
    p.integrator = integrator;
    p.max_step = h;
    Sim s(Make(p, env));
    s.ends.a.pos = Vec3(0, 0, 0);
    s.ends.b.pos = Vec3(101, 0, 0);
    s.Init();
    for (int k = 0; k < 100; ++k) EXPECT_TRUE(s.Step(0.02).ok);
    return s.x;
  };
  auto error = [](const std::vector<double>& a, const std::vector<double>& b) {
    double e = 0;
    for (size_t i = 0; i < a.size(); ++i) e = std::max(e, std::abs(a[i] - b[i]));
    return e;
  };
  const double H = 0.005;
  const std::vector<double> ref = run(Integrator::kRK4, H / 16);
  const double e1 = error(run(Integrator::kRK4, H), ref);
  const double e2 = error(run(Integrator::kRK4, H / 2), ref);
  const double order = std::log2(e1 / e2);
  std::printf("rk4: errors %.3g %.3g m, order %.2f\n", e1, e2, order);
  EXPECT_GT(order, 3.5);
  EXPECT_LT(order, 4.5);
  const double s1 = error(run(Integrator::kExplicit, H), ref);
  const double s2 = error(run(Integrator::kExplicit, H / 2), ref);
  std::printf("symplectic Euler: errors %.3g %.3g m, order %.2f\n", s1, s2, std::log2(s1 / s2));
  EXPECT_LT(std::log2(s1 / s2), 1.5);
  EXPECT_GT(s1, 100 * e1);
}

// ---------------------------------------------------------------------------------------------
// Compression (EAc): a shortened segment pushes back with EAc (l/L0 - 1), plus damping while
// it pushes; without EAc it carries nothing.

// Two segments of rest length L0 = 1 m between sites 2 m apart, in air without gravity; the
// middle node is moved along the line by `delta` [m].
TetherParams SpringParams() {
  TetherParams p;
  p.length = 2;
  p.segments = 2;
  p.diameter = 0.02;
  p.mass_per_length = 1;  // node mass 1 kg
  p.EA = 1e4;
  p.EAc = 3e3;  // different from EA, so that each law is seen
  p.integrator = Integrator::kExplicit;
  return p;
}

Environment NoGravity() {
  Environment env;
  env.gravity.setZero();
  return env;
}

// The force on the middle node of a straight line, displaced by 1 cm towards B (segment 0
// stretched, segment 1 shortened, both by 1%): EA eps pulls it back and EAc eps pushes it back,
// exactly (-100 N - 30 N); without EAc only the taut segment acts (-100 N). Reported tensions
// are the taut segment's 100 N and 0 for the compressed one (tension only). With damping, a
// compressed segment that is shortening pushes harder (EAc eps + c deps/dt), and one that
// lengthens fast enough to outrun its elastic push carries nothing (it never pulls).
TEST(Compression, ForceIsEAcTimesStrainAndOnlyPushes) {
  const Environment env = NoGravity();
  Ends ends;
  ends.b.pos = Vec3(2, 0, 0);
  std::vector<double> x = {0, 0, 0, 1.01, 0, 0, 2, 0, 0}, v(9, 0.0), f(9), T(2);
  for (bool declared : {true, false}) {
    TetherParams p = SpringParams();
    if (!declared) p.EAc = 0;
    Tether t = Make(p, env);
    EXPECT_EQ((t.params().effects & kCompression) != 0, declared);
    std::vector<double> work(t.WorkspaceSize());
    t.ComputeForces(x.data(), v.data(), ends, f.data(), T.data(), work.data());
    const double expected = -1e4 * 0.01 - (declared ? 3e3 * 0.01 : 0);
    EXPECT_NEAR(f[3], expected, 1e-9 * std::abs(expected)) << "declared " << declared;
    EXPECT_NEAR(f[4], 0, 1e-12);
    // Each end node receives its own segment's force: the pull of segment 0 on A, and the push
    // of segment 1 on B (outwards, +x).
    EXPECT_NEAR(f[0], 1e4 * 0.01, 1e-9);
    EXPECT_NEAR(f[6], declared ? 3e3 * 0.01 : 0, 1e-9);
    EXPECT_NEAR(T[0], 100, 1e-9);
    EXPECT_EQ(T[1], 0);
    t.Tensions(x.data(), v.data(), T.data());
    EXPECT_EQ(T[1], 0);
  }
  TetherParams p = SpringParams();
  p.damping = 50;  // [N s]
  Tether t = Make(p, env);
  std::vector<double> work(t.WorkspaceSize());
  // Middle node moving towards B at 0.2 m/s: segment 1 shortens, deps/dt = -0.2 1/s.
  v[3] = 0.2;
  t.ComputeForces(x.data(), v.data(), ends, f.data(), nullptr, work.data());
  EXPECT_NEAR(f[6], 3e3 * 0.01 + 50 * 0.2, 1e-9);
  // Moving away from B at 1 m/s: EAc eps + c deps/dt = -30 + 50 > 0, so no force.
  v[3] = -1;
  t.ComputeForces(x.data(), v.data(), ends, f.data(), nullptr, work.data());
  EXPECT_EQ(f[6], 0);
}

// The middle node oscillating along the line is a harmonic oscillator of stiffness
// (EA + EAc)/L0 whatever the sign of its displacement (one segment is always stretched and the
// other shortened by the same amount), so omega^2 = (EA + EAc)/(L0 m). Undamped, symplectic
// Euler at h omega = 1.1e-3: the period within 1e-3 (its frequency error is (h omega)^2/24
// and the zero crossings are timed to h / 20 periods) and the energy, elastic in both laws,
// within 1e-3 of its start (the method conserves a modified energy that differs from the true
// one by at most h omega / 2 = 5.7e-4 of it). Without compression the period would be
// sqrt(1.3) = 1.14 times longer.
TEST(Compression, UndampedSpringOscillationConservesEnergyAtTheAnalyticPeriod) {
  TetherParams p = SpringParams();
  const double omega = std::sqrt((p.EA + p.EAc) / (1.0 * 1.0));  // [rad/s]
  p.max_step = 1e-5;
  Sim s(Make(p, NoGravity()));
  s.ends.b.pos = Vec3(2, 0, 0);
  s.x = {0, 0, 0, 1.02, 0, 0, 2, 0, 0};
  std::fill(s.v.begin(), s.v.end(), 0.0);
  const double E0 = s.Energy();
  EXPECT_NEAR(E0, 0.5 * (p.EA + p.EAc) * 0.02 * 0.02, 1e-12);
  double dE = 0, first = -1, last = -1, prev = s.x[3] - 1;
  int crossings = 0;
  const double h = 1e-4;  // [s] per call: 10 substeps of max_step
  for (int k = 1; k <= 12000; ++k) {
    ASSERT_TRUE(s.Step(h).ok);
    dE = std::max(dE, std::abs(s.Energy() - E0));
    const double now = s.x[3] - 1;
    if ((now > 0) != (prev > 0)) {
      const double tc = (k - 1 + prev / (prev - now)) * h;
      if (first < 0) first = tc;
      last = tc;
      ++crossings;
    }
    prev = now;
  }
  ASSERT_GE(crossings, 40);
  const double period = 2 * (last - first) / (crossings - 1);
  std::printf("compressed spring: period / analytic %.6f, max |dE| / E0 %.2e\n",
              period * omega / (2 * M_PI), dE / E0);
  EXPECT_NEAR(period * omega / (2 * M_PI), 1, 1e-3);
  EXPECT_LT(dE, 1e-3 * E0);
}

// damping_ratio (MoorDyn's BA = -zeta) names the damping ratio of the segment axial mode,
// omega_n = (2/L0) sqrt(EA/mu). On a taut straight line with both ends held the axial modes are
// u_i = sin(k pi i / N) at omega_k = omega_n sin(k pi / 2N), and the internal damping, which is
// stiffness-proportional, gives mode k the ratio zeta_k = zeta sin(k pi / 2N): the highest
// (k = N - 1) decays as exp(-zeta_k omega_k t) (cos w_d t + zeta_k omega_k / w_d sin w_d t).
// 20 segments of 1 m, 1 kg/m, EA 1e4 N, stretched 1e-3 (10 N), mode amplitude 1e-4 m (strain
// 2e-4 at most: every segment stays taut, the law stays linear); rk4 at 1e-5 s (omega h 2e-3,
// its own damping ~(omega h)^5) to t = 0.05 s (3 decay times). The modal coordinate matches the
// closed form within 1e-6 of the amplitude; a damping off by 10% misses by 1e-2 of it.
TEST(InternalDamping, DampingRatioGivesTheSegmentModeItsDecay) {
  const char* text =
      "ends=a,b length=20 segments=20 diameter=0.02 mass_per_length=1 EA=1e4 damping_ratio=0.3 "
      "integrator=rk4 max_step=1e-5";
  DeclarationError e;
  std::optional<TetherDeclaration> d = ParseTether(text, NoGravity(), &e);
  ASSERT_TRUE(d) << e.message;
  const int N = 20, k = N - 1;
  const double L = 20, zeta = 0.3, A = 1e-4;
  Sim s(Make(d->params, NoGravity()));
  s.ends.b.pos = Vec3(L * 1.001, 0, 0);
  std::vector<double> phi(N + 1);
  double phi2 = 0;
  for (int i = 0; i <= N; ++i) {
    phi[i] = std::sin(k * M_PI * i / N);
    phi2 += phi[i] * phi[i];
    s.x[3 * i] = i * L * 1.001 / N + A * phi[i];
    s.x[3 * i + 1] = s.x[3 * i + 2] = 0;
  }
  std::fill(s.v.begin(), s.v.end(), 0.0);
  const double sk = std::sin(k * M_PI / (2 * N));
  const double wk = 2 * std::sqrt(1e4 / 1.0) * sk, zk = zeta * sk;  // [rad/s], [-]
  const double wd = wk * std::sqrt(1 - zk * zk);
  double worst = 0;
  const double h = 1e-3;  // [s] per call
  for (int step = 1; step <= 50; ++step) {
    ASSERT_TRUE(s.Step(h).ok);
    double q = 0;
    for (int i = 0; i <= N; ++i) q += (s.x[3 * i] - i * L * 1.001 / N) * phi[i];
    q /= phi2;
    const double t = step * h;
    const double exact = A * std::exp(-zk * wk * t) * (std::cos(wd * t) + zk * wk / wd * std::sin(wd * t));
    worst = std::max(worst, std::abs(q - exact));
  }
  std::printf("segment mode: damping %.6g N s, worst modal error %.3g of the amplitude\n",
              d->params.damping, worst / A);
  EXPECT_LT(worst, 1e-6 * A);
}

// The implicit step carries the compressed segment's stiffness in its Jacobian: with EAc ten
// times EA (so that a compression treated explicitly would blow up) and a step of 16 times
// 1/omega (far beyond the explicit limit 2/omega) the oscillation stays bounded and its energy
// never rises above the start (backward Euler only removes energy); the segments switch
// between the laws in most steps, which the Newton iteration absorbs.
TEST(Compression, ImplicitLargeStepNeverGainsEnergy) {
  TetherParams p = SpringParams();
  p.EAc = 1e5;
  p.integrator = Integrator::kImplicit;
  Sim s(Make(p, NoGravity()));
  s.ends.b.pos = Vec3(2, 0, 0);
  s.x = {0, 0, 0, 1.02, 0, 0, 2, 0, 0};
  std::fill(s.v.begin(), s.v.end(), 0.0);
  const double E0 = s.Energy();
  for (int k = 0; k < 200; ++k) {
    ASSERT_TRUE(s.Step(0.05).ok);
    ASSERT_LE(s.Energy(), E0 * (1 + 1e-12)) << "step " << k;
  }
  EXPECT_LT(s.Energy(), 1e-3 * E0);
}

// The explicit stability limit takes the stiffer of the two laws: with EAc = 10 EA the
// oscillator above (omega^2 = (EA + EAc)/(L0 m)) is stable at 0.9 times the advertised limit
// 2 / sqrt(4 EAc/(L0 m)) (the stable step is half of it), and diverges at the limit the
// tension law alone would give, 2 / sqrt(4 EA/(L0 m)), which is 1.66 times its own 2/omega.
TEST(Compression, ExplicitLimitUsesTheStifferLaw) {
  TetherParams p = SpringParams();
  p.EAc = 1e5;
  const Tether t = Make(p, NoGravity());
  const double limit = t.ExplicitStabilityLimit();
  const double tension_only = 2 / std::sqrt(4 * p.EA / (1.0 * 1.0));
  EXPECT_NEAR(limit, 2 / std::sqrt(4 * p.EAc), 1e-12);
  EXPECT_NEAR(t.ExplicitStableStep(), 0.5 * limit, 1e-15);
  for (double step : {0.9 * limit, tension_only}) {
    p.max_step = step;
    Sim s(Make(p, NoGravity()));
    s.ends.b.pos = Vec3(2, 0, 0);
    s.x = {0, 0, 0, 1.02, 0, 0, 2, 0, 0};
    std::fill(s.v.begin(), s.v.end(), 0.0);
    bool ok = true;
    for (int k = 0; k < 500 && ok; ++k) ok = s.Step(step).ok;
    EXPECT_EQ(ok, step < tension_only) << "step " << step << ", limit " << limit;
  }
}

// A slack tether in water whose end is pulled slowly (the scene fuzzer's seed 1279: 129
// segments of 8.3 cm, EA 2.9e4 N, a 2.2 t vehicle rising at up to 0.13 m/s): its segments
// switch between slack and taut all the time. Symplectic Euler conserves, on each law, a
// modified energy that differs from the true one by up to h w / 2 of it; a segment that goes
// slack or taut switches law at an arbitrary phase, so each switch may change the true energy
// by that fraction, and near the stability limit (h w = 1.6 at a safety factor of 0.8) the
// chain gained 2.8 J in 1 s beyond the 1.1 J its ends did on it, its kinetic energy 30 times
// the converged run's (0.7: 0.12 J). At the safety factor 0.5 (kExplicitSafety) it gains
// nothing (measured: E - E0 - W never above 0). Asserted: the tether's energy (interior nodes'
// kinetic, elastic, net weight) never rises above its start by more than the work its ends
// did on it, summed over the substeps (StepStatus::work_a, work_b), plus 5% of the gross work
// (the work is summed at the substeps' start forces, first order in the substep) and 1 mJ.
// Drag without a current only removes energy.
TEST(Energy, ExplicitSlackSwitchingGainsNoEnergyBeyondTheEndsWork) {
  Environment env;
  env.wet = true;
  TetherParams p;
  p.length = 10.74;           // [m]
  p.segments = 129;
  p.diameter = 0.0166;        // [m]
  p.mass_per_length = 0.599;  // [kg/m]
  p.EA = 2.877e4;             // [N]
  p.Cdn = 1.2;
  p.Cdt = 0.01;
  p.Can = 1;
  p.integrator = Integrator::kExplicit;
  const Tether t = Make(p, env);
  std::vector<double> x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize());
  Ends now;
  now.b.pos = Vec3(-4.98, 5.10, -3.40);
  t.InitialShape(now, x.data(), v.data());
  const double h = 0.002, a = 0.15;  // [s] MuJoCo-like call step, [m/s^2] end B's rise
  auto energy = [&]() {
    std::vector<double> vi = v;  // the end nodes move with the ends: their inertia is not
    std::fill(vi.begin(), vi.begin() + 3, 0.0);  // in the reactions (scene fuzzer's oracle)
    std::fill(vi.end() - 3, vi.end(), 0.0);
    return t.KineticEnergy(x.data(), vi.data()) + t.PotentialEnergy(x.data(), now);
  };
  const double E0 = energy();
  double W = 0, gross = 0, swing = 0, excess = 0;
  for (int k = 0; k < 500; ++k) {
    Ends next = now;
    const double t1 = (k + 1) * h;
    next.b.pos = Vec3(-4.98, 5.10, -3.40 + 0.5 * a * t1 * t1);
    next.b.vel = Vec3(0, 0, a * t1);
    const StepStatus s = t.Advance(x.data(), v.data(), now, next, h, work.data());
    ASSERT_TRUE(s.ok) << s.reason;
    now = next;
    W -= s.work_a + s.work_b;
    gross += std::abs(s.work_a) + std::abs(s.work_b);
    const double E = energy();
    swing = std::max(swing, std::abs(E - E0));
    excess = std::max(excess, E - E0 - W);
  }
  EXPECT_GT(W, 0.5);  // the rising end did work on the tether (0.67 J)
  EXPECT_LT(excess, 0.05 * (gross + swing) + 1e-3) << "W " << W << " J, gross " << gross;
}

// The impulse of the end forces over an advance (StepStatus::end_impulse_a, end_impulse_b,
// session 39: the coupling's work balance moves into the frame of the site with it) is the
// momentum the tether's interior took, with the sign reversed: dry, without gravity, every
// force on an interior node of an explicit tether is a segment's (axial, bending), equal and
// opposite on its two nodes, so the interior's momentum changes by minus what the segments
// put on the end nodes, and symplectic Euler takes each substep's force at its start, as the
// impulse is summed. Exact to rounding: 1e-9 of the largest impulse. End B yanked out and
// back (0.5 m/s for 0.1 s), so that the tension swings.
TEST(Momentum, TheEndImpulseIsTheMomentumTheInteriorTook) {
  Environment env;
  env.gravity = Vec3::Zero();
  TetherParams p;
  p.length = 5;               // [m]
  p.segments = 20;
  p.diameter = 0.02;          // [m]
  p.mass_per_length = 0.5;    // [kg/m]
  p.EA = 1e5;                 // [N]
  p.EI = 0.5;                 // [N m^2]
  p.integrator = Integrator::kExplicit;
  const Tether t = Make(p, env);
  std::vector<double> x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize());
  Ends now;
  now.b.pos = Vec3(4.9, 0.3, 0);
  t.InitialShape(now, x.data(), v.data());
  auto interior_momentum = [&]() {
    Vec3 P = Vec3::Zero();
    for (int i = 1; i + 1 < t.nodes(); ++i) P += t.node_mass(i) * Vec3(v.data() + 3 * i);
    return P;
  };
  const double h = 0.002;  // [s]
  Vec3 impulse = Vec3::Zero();
  double largest = 0;
  const Vec3 P0 = interior_momentum();
  for (int k = 0; k < 100; ++k) {
    Ends next = now;
    const double speed = k < 50 ? 0.5 : -0.5;  // [m/s]
    next.b.pos = now.b.pos + Vec3(h * speed, 0, 0);
    next.b.vel = Vec3(speed, 0, 0);
    const StepStatus s = t.Advance(x.data(), v.data(), now, next, h, work.data());
    ASSERT_TRUE(s.ok) << s.reason;
    ASSERT_GT(s.substeps, 1);
    now = next;
    impulse += s.end_impulse_a + s.end_impulse_b;
    largest = std::max(largest, std::max(s.end_impulse_a.norm(), s.end_impulse_b.norm()));
  }
  const Vec3 dP = interior_momentum() - P0;
  std::printf("interior momentum change %.6g N s, end impulses %.6g N s (largest %.3g)\n",
              dP.norm(), impulse.norm(), largest);
  EXPECT_GT(largest, 1e-3);  // the yank did pull
  EXPECT_LT((dP + impulse).norm(), 1e-9 * largest * 100);
}

// implicit2's end force as its momentum takes it (StepStatus::impulse_a, session 39): a line
// dragged by an end that accelerates uniformly. Dry, without gravity, end B free, 10 segments of
// EA 1e8 N (the axial mode's omega h at 2 ms about 90: each node follows the end's positions),
// end A pulled along the line at 1 m/s^2 from rest. The force on end A must be the rest of the
// line's mass times the acceleration, M a (Newton's second law; the line is rigid to 1e-8).
// SDIRK's second stage gives the node next to the end a larger inertia than its m a (a
// velocity change extrapolated over gamma h), so the force at the step's end reads over: here
// 14.80 N, 5.3 m a (1 kg nodes) too much; the stages' mean, weighted as the scheme weighs
// them, is the force the nodes' momentum took. Tolerance 1% over the last 0.1 s of 0.2 s (the
// start's jerk is damped by then; measured 0.001%).
TEST(Momentum, Implicit2sEndForceIsTheMeanOfItsStages) {
  Environment env;
  env.gravity = Vec3::Zero();
  TetherParams p;
  p.length = 10;             // [m]
  p.segments = 10;
  p.diameter = 0.02;         // [m]
  p.mass_per_length = 1;     // [kg/m]
  p.EA = 1e8;                // [N]
  p.free_end = true;
  p.integrator = Integrator::kImplicit2;
  const Tether t = Make(p, env);
  std::vector<double> x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize());
  Ends now;
  now.a.axis = Vec3::UnitX();  // the free line hangs along end A's axis, +x
  t.InitialShape(now, x.data(), v.data());
  double M = 0;  // [kg] the line's mass beyond end node A
  for (int i = 1; i < t.nodes(); ++i) M += t.node_mass(i);
  const double h = 0.002, a = 1;  // [s], [m/s^2] end A's acceleration along -x (pulling)
  double mean = 0, last = 0;
  int counted = 0;
  for (int k = 0; k < 100; ++k) {
    Ends next = now;
    const double t1 = (k + 1) * h;
    next.time = t1;
    next.a.pos = Vec3(-0.5 * a * t1 * t1, 0, 0);
    next.a.vel = Vec3(-a * t1, 0, 0);
    const StepStatus s = t.Advance(x.data(), v.data(), now, next, h, work.data());
    ASSERT_TRUE(s.ok) << s.reason;
    ASSERT_TRUE(s.has_impulse_a);
    now = next;
    if (k >= 50) {
      mean += s.impulse_a.x() / h;
      last += t.Reactions(x.data(), v.data(), now, work.data()).force_a.x();
      ++counted;
    }
  }
  mean /= counted;
  last /= counted;
  std::printf("implicit2, end A pulled at %g m/s^2: M a = %.4f N, stage mean %.4f N, force at "
              "the step's end %.4f N\n", a, M * a, mean, last);
  EXPECT_NEAR(mean, M * a, 0.01 * M * a);
}

// The line of the end-stiffness tests below: N segments of L0 [m], EA 1e4 N, 2 cm, 1 kg/m,
// implicit.
TetherParams EndTestLine(int N, double L0) {
  TetherParams p;
  p.length = N * L0;
  p.segments = N;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e4;  // [N]
  p.integrator = Integrator::kImplicit;
  return p;
}

// ---------------------------------------------------------------------------------------------
// Tether::EndBendingStiffness, the coupling advisor's stiffness across the line, against the
// forces: a straight line of 6 segments of L0 = 0.5 m along x (dry, no gravity, EA and EI) with
// end node B (then A) moved across it by d = 1e-6 L0. The force on the moved node across the
// line is -k d, k = EI/L0^3 at a pinned end and 3 EI/L0^3 at a clamped one (the end segment's
// shear from the next node's moment, and a clamp's own moment). On a single segment there is no
// interior node: k = 0 pinned, and 4 EI/L0^3 clamped at both ends (each end's moment). The axial
// force's share across is EA d^2/(2 L0^3) per metre, 1e-8 N/m here, far below the tolerance of
// 1e-5 EI/L0^3. Without the bending effect k is 0 (the axial EA/L0 is EndStiffness).
TEST(Forces, EndBendingStiffnessIsTheEndNodesForceAcrossAStraightLine) {
  const Environment env = NoGravity();
  const double L0 = 0.5, EI = 25, d = 1e-6 * L0;  // [m], [N m^2], [m]
  for (int N : {6, 1}) {
    for (bool clamped : {false, true}) {
      for (bool end_b : {true, false}) {
        TetherParams p = EndTestLine(N, L0);
        p.EI = EI;
        p.clamp_a = p.clamp_b = clamped;
        Tether t = Make(p, env);
        // One segment: no interior node; clamped at both ends, each end's moment (4 EI/L0^3).
        const double k = (N > 1 ? (clamped ? 3 : 1) : (clamped ? 4 : 0)) * EI / (L0 * L0 * L0);
        const double tolerance = 1e-5 * EI / (L0 * L0 * L0);  // [N/m]
        EXPECT_NEAR(t.EndBendingStiffness(end_b), k, 1e-12 * k) << N << clamped << end_b;
        Ends ends;
        ends.b.pos = Vec3(N * L0, 0, 0);
        std::vector<double> x(3 * (N + 1), 0.0), v(x.size(), 0.0), f(x.size());
        for (int i = 0; i <= N; ++i) x[3 * i] = i * L0;
        const int node = end_b ? N : 0;
        x[3 * node + 1] = d;
        (end_b ? ends.b : ends.a).pos.y() = d;
        std::vector<double> work(t.WorkspaceSize());
        t.ComputeForces(x.data(), v.data(), ends, f.data(), nullptr, work.data());
        EXPECT_NEAR(-f[3 * node + 1] / d, k, tolerance)
            << N << " segments, clamped " << clamped << ", end B " << end_b;
      }
    }
  }
  TetherParams p = SpringParams();
  EXPECT_EQ(Make(p, env).EndBendingStiffness(true), 0);
}

// The seabed's stiffness and damping at an end node (the coupling advisor's k_end where it is
// the largest, session 38): a straight line lying on a flat seabed, end node B (or A) pressed
// into it by d at a sinking speed v, is pushed back by k L0/2 d + c L0/2 v, the penalty and its
// damping over the node's share; the segment's own tension, EA d^2/(2 L0^2) at the angle d/L0,
// adds EA d^3/(2 L0^3) = 1.6e-7 N of the 32 N, below the tolerance.
TEST(Forces, EndSeabedStiffnessIsTheEndNodesPushFromTheSeabed) {
  Environment env = NoGravity();
  env.wet = true;
  env.water.has_seabed = true;
  env.water.seabed = 0;               // [m]
  env.water.seabed_stiffness = 2e5;   // [N/m^2]
  env.water.seabed_damping = 300;     // [N s/m^2]
  const double L0 = 2, d = 1e-4, v = 0.01;  // [m], [m], [m/s]
  const int N = 4;
  TetherParams p = EndTestLine(N, L0);
  p.Cdn = p.Cdt = p.Can = 0;
  Tether t = Make(p, env);
  ASSERT_TRUE(t.params().effects & kSeabed);
  const double k = 2e5 * L0 / 2, c = 300 * L0 / 2;  // [N/m], [N s/m]
  for (bool end_b : {true, false}) {
    EXPECT_NEAR(t.EndSeabedStiffness(end_b), k, 1e-12 * k);
    EXPECT_NEAR(t.EndSeabedDamping(end_b), c, 1e-12 * c);
    Ends ends;
    ends.b.pos = Vec3(N * L0, 0, 0);
    std::vector<double> x(3 * (N + 1), 0.0), vel(x.size(), 0.0), f(x.size());
    for (int i = 0; i <= N; ++i) x[3 * i] = i * L0;
    const int node = end_b ? N : 0;
    x[3 * node + 2] = -d;
    vel[3 * node + 2] = -v;
    EndState& e = end_b ? ends.b : ends.a;
    e.pos.z() = -d;
    e.vel.z() = -v;
    std::vector<double> work(t.WorkspaceSize());
    t.ComputeForces(x.data(), vel.data(), ends, f.data(), nullptr, work.data());
    EXPECT_NEAR(f[3 * node + 2], k * d + c * v, 1e-6 * (k * d + c * v)) << "end B " << end_b;
  }
  env.water.has_seabed = false;
  EXPECT_EQ(Make(p, env).EndSeabedStiffness(true), 0);
  EXPECT_EQ(Make(p, env).EndSeabedDamping(true), 0);
}

}  // namespace
}  // namespace mjtether
