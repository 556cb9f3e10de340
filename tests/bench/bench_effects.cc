// Cost of one tether step per node (ns/node/step), engine alone, for 10-400 segments, both
// integrators, with each effect on and off, and MuJoCo's own step of one free body (the floor).
//
//   ./build/tests/bench/bench_effects --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
//
// Cases, on a 20 m ROV tether in a current over a seabed (ends 15 m apart):
//   all           every effect
//   no_<effect>   every effect but one: the difference to `all` is that effect's cost
//   axial         effects=axial, every coefficient still declared
//   bare          only the required keys, dry, no gravity (so axial only, by default, and
//                 nothing else declared): equal to `axial`
//                 within noise, which shows that an effect that is off costs nothing
// Each iteration is Advance over one tether step (the explicit scheme at 90% of its stable
// step, the implicit ones at 2 ms) plus the end reactions, as in the MuJoCo callback.
// Line/<integrator>/N: the fixed comparison line (tests/reference_scenes.h; axial with
// damping, weight, buoyancy, drag, added mass; no bending), its fairlead moving, one Advance
// of one tether step per iteration (explicit and rk4 at 90% of their stable step, the
// implicit ones at 2 ms) without the reactions: explicit's per_node_step is the cost of one
// force evaluation and update per node (issue 17's target: <= 20 ns).
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "../reference_scenes.h"
#include "declaration.h"
#include "tether.h"

namespace mjtether {
namespace {

const char* kAll = "axial,damping,bending,weight,buoyancy,drag,added_mass,current,seabed";
// The seabed is declared below the tether: its cost here is the per-node contact test. (With
// the slack tether lying on it, see bench_slack and docs/numerics_slack.md.)
const char* kWater = "density=1025 current=0.3,0,0 seabed=-20 seabed_friction=0.3";
const char* kCoefficients =
    "diameter=0.02 mass_per_length=0.35 EA=2e5 EI=0.5 damping=50 Cdn=1.2 Cdt=0.01 Can=1";

std::string Without(const std::string& effect) {
  std::string list = kAll, out;
  size_t start = 0;
  while (start <= list.size()) {
    size_t end = list.find(',', start);
    if (end == std::string::npos) end = list.size();
    const std::string item = list.substr(start, end - start);
    // current needs drag: dropping drag drops current too.
    if (item != effect && !(effect == "drag" && item == "current")) {
      out += (out.empty() ? "" : ",") + item;
    }
    start = end + 1;
  }
  return out;
}

void TetherStep(benchmark::State& state, std::string declaration, bool wet) {
  const int N = static_cast<int>(state.range(0));
  Environment env;
  if (!wet) env.gravity = Vec3::Zero();  // the bare case: no weight either, axial only
  if (wet) {
    DeclarationError e;
    env.wet = true;
    env.water = *ParseWater(kWater, &e);
  }
  DeclarationError e;
  std::optional<TetherDeclaration> d =
      ParseTether("ends=a,b length=20 segments=" + std::to_string(N) + " " + declaration, env, &e);
  if (!d) {
    state.SkipWithError(e.message.c_str());
    return;
  }
  std::string error;
  std::optional<Tether> t = Tether::Create(d->params, env, &error);
  const bool explicit_scheme = IsExplicit(d->params.integrator);
  const double h = explicit_scheme ? 0.9 * t->ExplicitStableStep() : 0.002;
  std::vector<double> x(3 * t->nodes()), v(3 * t->nodes()), work(t->WorkspaceSize());
  Ends ends;
  ends.a.pos = Vec3(0, 0, 0);
  ends.b.pos = Vec3(15, 0, -5);
  t->InitialShape(ends, x.data(), v.data());
  // Warm up for 0.5 s, then restart every 1000 steps from that state.
  const int warm = static_cast<int>(0.5 / h);
  for (int k = 0; k < warm; ++k) t->Advance(x.data(), v.data(), ends, ends, h, work.data());
  const std::vector<double> x0 = x, v0 = v;
  double sink = 0;
  int k = 0;
  for (auto _ : state) {
    if (++k % 1000 == 0) {
      state.PauseTiming();
      x = x0;
      v = v0;
      state.ResumeTiming();
    }
    t->Advance(x.data(), v.data(), ends, ends, h, work.data());
    sink += t->Reactions(x.data(), v.data(), ends, work.data()).tension_b;
  }
  benchmark::DoNotOptimize(sink);
  state.counters["per_node_step"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * (N + 1),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The fixed comparison line, engine alone (see the header). Warmed up over its first period
// (the snap from the inextensible catenary), restored every 10 s of simulated time.
void LineStep(benchmark::State& state, const std::string& integrator) {
  namespace rs = reference_scenes;
  const int N = static_cast<int>(state.range(0));
  const rs::Scene s = rs::LineScene();
  std::string error;
  std::optional<Tether> t = rs::MakeTether(s, N, integrator, 0, 0, &error);
  if (!t) {
    state.SkipWithError(error.c_str());
    return;
  }
  const double h = IsExplicit(t->params().integrator) ? 0.9 * t->ExplicitStableStep() : 0.002;
  std::vector<double> x(3 * t->nodes()), v(3 * t->nodes()), work(t->WorkspaceSize());
  std::vector<double> history(t->HistorySize() + 1);
  double time = 0;
  t->InitialShape(rs::EndsAt(s, 0), x.data(), v.data());
  auto step = [&]() {
    const StepStatus st = t->Advance(x.data(), v.data(), rs::EndsAt(s, time),
                                     rs::EndsAt(s, time + h), h, work.data(), history.data());
    time += h;
    return st.ok;
  };
  const int period = static_cast<int>(10 / h);
  for (int k = 0; k < period; ++k) step();
  const std::vector<double> x0 = x, v0 = v, history0 = history;
  const double time0 = time;
  bool ok = true;
  int k = 0;
  for (auto _ : state) {
    if (++k % period == 0) {
      state.PauseTiming();
      x = x0;
      v = v0;
      history = history0;
      time = time0;
      state.ResumeTiming();
    }
    ok = step() && ok;
  }
  if (!ok) state.SkipWithError("the line diverged");
  state.counters["per_node_step"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * (N + 1),
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// MuJoCo's own step of one free body: the floor under any callback.
void FreeBody(benchmark::State& state) {
  const std::string xml =
      "<mujoco><option timestep=\"0.002\"/><worldbody><body><freejoint/>"
      "<geom type=\"box\" size=\"0.35 0.25 0.2\" mass=\"50\"/></body></worldbody></mujoco>";
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  mj_makeEmptyFileVFS(&vfs, "free.xml", static_cast<int>(xml.size()));
  std::copy(xml.begin(), xml.end(),
            static_cast<char*>(vfs.filedata[mj_findFileVFS(&vfs, "free.xml")]));
  char err[1000] = "";
  mjModel* m = mj_loadXML("free.xml", &vfs, err, sizeof(err));
  mj_deleteVFS(&vfs);
  if (!m) {
    state.SkipWithError(err);
    return;
  }
  mjData* d = mj_makeData(m);
  for (auto _ : state) mj_step(m, d);
  mj_deleteData(d);
  mj_deleteModel(m);
}

}  // namespace
}  // namespace mjtether

int main(int argc, char** argv) {
  using namespace mjtether;
  const std::vector<std::string> effects = {"damping", "bending",    "weight",  "buoyancy",
                                            "drag",    "added_mass", "current", "seabed"};
  for (const char* integrator : {"explicit", "rk4", "implicit", "implicit2"}) {
    const std::string scheme = std::string(" integrator=") + integrator;
    std::vector<std::pair<std::string, std::pair<std::string, bool>>> cases;
    cases.push_back({"all", {std::string(kCoefficients) + " effects=" + kAll + scheme, true}});
    for (const std::string& e : effects) {
      cases.push_back(
          {"no_" + e, {std::string(kCoefficients) + " effects=" + Without(e) + scheme, true}});
    }
    cases.push_back({"axial", {std::string(kCoefficients) + " effects=axial" + scheme, true}});
    cases.push_back({"bare", {"diameter=0.02 mass_per_length=0.35 EA=2e5" + scheme, false}});
    for (const auto& [name, decl] : cases) {
      auto* b = benchmark::RegisterBenchmark(
          (std::string("Tether/") + integrator + "/" + name).c_str(),
          [decl = decl](benchmark::State& s) { TetherStep(s, decl.first, decl.second); });
      for (int N : {10, 50, 100, 400}) b->Arg(N);
    }
  }
  for (const char* integrator : {"explicit", "rk4", "implicit", "bdf2", "implicit2"}) {
    benchmark::RegisterBenchmark((std::string("Line/") + integrator).c_str(),
                                 [integrator](benchmark::State& s) { LineStep(s, integrator); })
        ->Arg(80)
        ->Arg(100);
  }
  benchmark::RegisterBenchmark("MuJoCoFreeBody", FreeBody);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
