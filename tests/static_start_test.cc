// The static start (key start=static; src/tether.cc, Tether::RelaxToStatic;
// docs/static_start.md): the relaxed shape against Irvine's elastic catenary and against the
// state a long damped dynamic run settles to, the warning when it does not converge, and in
// MuJoCo a run started static keeps its end tensions where the catenary start rings.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "catenary_reference.h"
#include "declaration.h"
#include "engine_sim.h"
#include "make_tether.h"
#include "mujoco_fixture.h"
#include "tether.h"

namespace mjtether {
namespace {

// The end tensions of a run started static may change over its first second by at most this
// fraction (EndTensionsHoldOverTheFirstSecond): the relaxation stops when no node moves by more
// than 1e-8 L = 1e-6 m per pseudo step, which at the end segment's EA/L0 = 5e4 N/m is 0.05 N,
// 3e-4 of the 161 N end-B tension of that scene. Measured: 4e-9 with every integrator; the
// default start's tensions change by 3% as the line swings out into the current (by a factor
// 50 before session 24, from the inextensible catenary's slack chords).
constexpr double kHoldTolerance = 3e-4;

void Print(const char* what, const StaticResult& r) {
  std::printf("%s: converged %d ok %d iterations %d displacement %.3g m residual %.3g N "
              "(node %d) final step %.3g s %s\n",
              what, r.converged, r.ok, r.iterations, r.displacement, r.residual, r.node,
              r.final_step, r.reason.c_str());
}

TEST(StaticStart, DryCatenaryEqualsIrvine) {
  Environment env;
  Sim s(Make(CatenaryParams(40), env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(80, 0, 20);
  s.Init();
  const StaticResult r = s.Relax();
  Print("dry catenary", r);
  EXPECT_TRUE(r.converged);
  const double w = 1.0 * 9.81;
  testing::Catenary ref = testing::SolveCatenary(80, 20, 100, w, 1e5);
  EndReactions e = s.Reactions();
  EXPECT_NEAR(e.tension_a / ref.tension_a(), 1, 0.005);
  EXPECT_NEAR(e.tension_b / ref.tension_b(), 1, 0.005);
}

TEST(StaticStart, UniformCurrentEqualsSettledRun) {
  Environment env;
  env.wet = true;
  env.water.current = Vec3(0, 1.0, 0);
  TetherParams p = CatenaryParams(50);
  p.diameter = 0.03;
  p.Cdn = 1.2;
  p.Cdt = 0.01;
  p.Can = 1.0;
  Sim s(Make(p, env)), ref(Make(p, env));
  for (Sim* t : {&s, &ref}) {
    t->ends.a.pos = Vec3(0, 0, 0);
    t->ends.b.pos = Vec3(70, 0, -30);
    t->Init();
  }
  const StaticResult r = s.Relax();
  Print("current", r);
  EXPECT_TRUE(r.converged);
  double moved = 0;
  for (int k = 0; k < 20000; ++k) {
    std::vector<double> before = ref.x;
    ASSERT_TRUE(ref.Step(0.05).ok);
    double d = 0;
    for (size_t i = 0; i < before.size(); ++i) d = std::max(d, std::abs(ref.x[i] - before[i]));
    moved = d;
  }
  double diff = 0;
  for (int i = 0; i <= 50; ++i) diff = std::max(diff, (s.node(i) - ref.node(i)).norm());
  std::printf("settled run last step moved %.3g m; static vs settled %.3g m; mid y %.3f\n",
              moved, diff, s.node(25).y());
  EXPECT_LT(diff, 1e-3);
}

// A probe over harder cases: printed, each asserted to converge to a usable shape.
TEST(StaticStart, ConvergesOnSeabedBendingAndFreeEnd) {
  struct Case {
    const char* name;
    bool seabed, bending, free_end;
    double current;
  };
  for (const Case& c : {Case{"seabed, friction 0.5", true, false, false, 0.3},
                        Case{"bending EI 50 EAc", false, true, false, 0.5},
                        Case{"seabed and bending", true, true, false, 0.5},
                        Case{"free end in current", false, false, true, 1.0}}) {
    Environment env;
    env.wet = true;
    env.water.current = Vec3(0.6 * c.current, 0.8 * c.current, 0);
    if (c.seabed) {
      env.water.has_seabed = true;
      env.water.seabed = -40;
      env.water.seabed_friction = 0.5;
    }
    TetherParams p = CatenaryParams(60);
    p.length = 120;
    p.diameter = 0.03;
    p.Cdn = 1.2;
    p.Cdt = 0.01;
    p.Can = 1.0;
    p.free_end = c.free_end;
    if (c.bending) {
      p.EI = 50;
      p.EAc = p.EA;
    }
    Sim s(Make(p, env));
    s.ends.a.pos = Vec3(0, 0, 0);
    s.ends.b.pos = Vec3(30, 0, -38);
    s.Init();
    const StaticResult r = s.Relax();
    Print(c.name, r);
    EXPECT_TRUE(r.ok) << c.name;
    EXPECT_TRUE(r.converged) << c.name;
  }
}

// Iteration cap 1: not converged, reported with the residual and its node; the shape is the
// first pseudo step's (finite, usable).
TEST(StaticStart, IterationCapReportsNonConvergence) {
  Environment env;
  env.wet = true;
  env.water.current = Vec3(0, 1.0, 0);
  TetherParams p = CatenaryParams(50);
  p.diameter = 0.03;
  p.Cdn = 1.2;
  Sim s(Make(p, env));
  s.ends.a.pos = Vec3(0, 0, 0);
  s.ends.b.pos = Vec3(70, 0, -30);
  s.Init();
  StaticOptions o;
  o.max_iterations = 1;
  const StaticResult r = s.Relax(o);
  Print("cap 1", r);
  EXPECT_FALSE(r.converged);
  EXPECT_TRUE(r.ok);
  EXPECT_EQ(r.iterations, 1);
  EXPECT_GT(r.residual, 1e-3 * r.load);  // far from equilibrium: the current's drag unbalanced
  EXPECT_GT(r.node, 0);
  EXPECT_LT(r.node, 50);
  for (double xi : s.x) EXPECT_TRUE(std::isfinite(xi));
}

TEST(StaticStart, DeclarationKey) {
  Environment env;
  DeclarationError e;
  const std::string base =
      "ends=a,b length=10 segments=5 diameter=0.02 mass_per_length=1 EA=1e5 ";
  std::optional<TetherDeclaration> d = ParseTether(base, env, &e);
  ASSERT_TRUE(d.has_value()) << e.message;
  EXPECT_EQ(d->params.start, Start::kCatenary);  // the default: today's start
  d = ParseTether(base + "start=static", env, &e);
  ASSERT_TRUE(d.has_value()) << e.message;
  EXPECT_EQ(d->params.start, Start::kStatic);
  EXPECT_FALSE(ParseTether(base + "start=equilibrium", env, &e).has_value());
  EXPECT_NE(e.message.find("allowed: catenary (default), static"), std::string::npos) << e.message;
  EXPECT_FALSE(ParseTether(base + "strat=static", env, &e).has_value());
  EXPECT_NE(e.message.find("did you mean 'start'"), std::string::npos) << e.message;
}

// ---------------------------------------------------------------------------------------------
// In MuJoCo: a tether between two world sites in a 0.5 m/s current across its plane.

std::string CurrentScene(const std::string& integrator, const std::string& start,
                         const std::string& extra = "") {
  return R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025 current=0,0.5,0"/>
    <text name="tether:t" data="ends=a,b length=100 segments=50 diameter=0.03
      mass_per_length=1.0 EA=1e5 damping=200 Cdn=1.2 Cdt=0.01 Can=1 integrator=)" +
         integrator + " start=" + start + " " + extra + R"("/>
  </custom><worldbody><site name="a" pos="0 0 0"/><site name="b" pos="70 0 -30"/>
  <geom name="rock" type="sphere" size="1" pos="0 0 -80"/></worldbody></mujoco>)";
}

// Largest relative change of the end tensions over the first second (500 steps of 2 ms) from
// their values after the first step.
double TensionDrift(const std::string& xml) {
  testing::LoadedScene s(xml);
  EXPECT_NE(s.m, nullptr);
  if (!s.m) return NAN;
  EXPECT_TRUE(s.Step());
  const EndReactions r0 = GetReactions(s.m, s.d, 0);
  double drift = 0;
  for (int k = 0; k < 500; ++k) {
    EXPECT_TRUE(s.Step());
    const EndReactions r = GetReactions(s.m, s.d, 0);
    drift = std::max({drift, std::abs(r.tension_a / r0.tension_a - 1),
                      std::abs(r.tension_b / r0.tension_b - 1)});
  }
  return drift;
}

// Started static, the end tensions stay where they start, with every integrator; started from
// the default shape, they change as the line swings out into the current. (Before session 24
// the default was the inextensible catenary, slack at every chord, and its tensions changed
// 50-fold; now it is the chain at rest in still water, and the current's drag changes them by
// 3%, still a hundred times kHoldTolerance.)
TEST(StaticStartMuJoCo, EndTensionsHoldOverTheFirstSecond) {
  for (const char* integrator : {"bdf2", "implicit", "implicit2", "explicit", "rk4"}) {
    const double still = TensionDrift(CurrentScene(integrator, "static"));
    const double rings = TensionDrift(CurrentScene(integrator, "catenary"));
    std::printf("%s: end tensions drift %.3g (static start), %.3g (catenary start)\n",
                integrator, still, rings);
    EXPECT_LT(still, kHoldTolerance) << integrator;
    EXPECT_GT(rings, 30 * kHoldTolerance) << integrator;
  }
}

// A reset starts again from the load-time static shape, bit for bit.
TEST(StaticStartMuJoCo, ResetStartsFromTheSameShape) {
  testing::LoadedScene s(CurrentScene("bdf2", "static"));
  ASSERT_NE(s.m, nullptr);
  mj_forward(s.m, s.d);
  const int n = 3 * GetTether(s.m, 0)->nodes();
  const std::vector<double> first(NodePositions(s.m, s.d, 0), NodePositions(s.m, s.d, 0) + n);
  for (int k = 0; k < 50; ++k) ASSERT_TRUE(s.Step());
  mj_resetData(s.m, s.d);
  mj_forward(s.m, s.d);
  const double* again = NodePositions(s.m, s.d, 0);
  for (int i = 0; i < n; ++i) ASSERT_EQ(again[i], first[i]) << i;
}

// Not converged (the test hook caps the relaxation at one pseudo step): a warning at load
// naming the tether, the residual force and its node; the run goes on from that shape.
TEST(StaticStartMuJoCo, NonConvergenceWarnsAtLoad) {
  setenv("MJTETHER_STATIC_MAX_ITERATIONS", "1", 1);
  testing::LoadedScene s(CurrentScene("bdf2", "static"));
  unsetenv("MJTETHER_STATIC_MAX_ITERATIONS");
  ASSERT_NE(s.m, nullptr);
  std::string all;
  for (const std::string& w : Warnings(s.m)) all += w + "\n";
  EXPECT_NE(all.find("<text name=\"tether:t\">: key 'start' = static: not converged"),
            std::string::npos) << all;
  EXPECT_NE(all.find("largest residual force"), std::string::npos) << all;
  EXPECT_NE(all.find(" at node "), std::string::npos) << all;
  EXPECT_TRUE(s.Step());
  // Converged (no cap): no such warning.
  testing::LoadedScene ok(CurrentScene("bdf2", "static"));
  ASSERT_NE(ok.m, nullptr);
  for (const std::string& w : Warnings(ok.m)) EXPECT_EQ(w.find("not converged"), std::string::npos);
}

// With contact (candidates from MuJoCo's geoms at each step) the static start is refused.
TEST(StaticStartMuJoCo, RefusedWithContact) {
  std::string error;
  mjModel* m = LoadModelFromString(CurrentScene("bdf2", "static", "contact=rock"), "c.xml",
                                   &error);
  EXPECT_EQ(m, nullptr);
  if (m) {
    Detach(m);
    mj_deleteModel(m);
  }
  EXPECT_NE(error.find("key 'start' = static is not supported with key 'contact'"),
            std::string::npos) << error;
}

}  // namespace
}  // namespace mjtether
