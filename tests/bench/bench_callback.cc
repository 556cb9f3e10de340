// Cost of the passive callback per MuJoCo step, for 10-200 segments, each integrator:
// a tether between a fixed site and a free body in a current (the default scene's
// physics), stepped with mj_step. Reports time per step and per node-step.
// BM_Line*: the fixed comparison line (tests/reference_scenes.h: 100 m, EA 1e6, damping 1000,
// no bending, fairlead on a mocap body moving x = 80 + 2 sin(2 pi t/10)), 2 ms steps, as the
// accuracy/cost sweep runs it through MuJoCo; `x_real_time` is simulated seconds per CPU
// second (issue 17's target: >= 250 at 100 segments, bdf2 and implicit).
// BM_RingWatchOn/Off: the cost of the ringing watch (see Watch).
//
//   ./build/tests/bench/bench_callback --benchmark_repetitions=5
//     --benchmark_report_aggregates_only=true
#include <sstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include "../reference_scenes.h"
#include "mjtether.h"

namespace {

// `damping`: the internal damping key as declared ("damping=50" [N s], or "damping_ratio=Z").
std::string Scene(int segments, const char* integrator, const std::string& damping = "damping=50") {
  std::ostringstream s;
  s << R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025 current=0.3,0,0"/>
    <text name="tether:u" data="ends=tms,rov length=20 segments=)"
    << segments << R"( diameter=0.02 mass_per_length=0.322 EA=2e5 EI=0.5 )"
    << damping << R"(
          Cdn=1.2 Cdt=0.01 Can=1.0 integrator=)"
    << integrator << R"("/></custom>
    <worldbody><site name="tms" pos="0 0 0"/>
      <body name="rov" pos="15 0 -5"><freejoint/><geom type="box" size="0.35 0.25 0.2"
          mass="50"/><site name="rov"/></body></worldbody></mujoco>)";
  return s.str();
}

// Times `step` (one mj_step and whatever goes with it) from the state in d, restoring that
// state every `period` steps (outside the timing) so that every batch measures the same motion,
// and reports seconds per node-step (printed with an SI prefix: "650n" is 650 ns) for a tether
// of `segments`. Frees d.
template <class StepFn>
void TimeRestoring(benchmark::State& state, const mjModel* m, mjData* d, int period, int segments,
                   StepFn step) {
  mjData* saved = mj_copyData(nullptr, m, d);
  int k = 0;
  for (auto _ : state) {
    if (++k % period == 0) {
      state.PauseTiming();
      mj_copyData(d, m, saved);
      state.ResumeTiming();
    }
    step();
  }
  state.counters["per_node_step"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * (segments + 1),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  mj_deleteData(saved);
}

// Warms m up past its initial transient (500 steps), then times mj_step from that state,
// restored every 1000 steps (TimeRestoring).
void TimeWarmedSteps(benchmark::State& state, const mjModel* m, int segments) {
  mjData* d = mj_makeData(m);
  for (int k = 0; k < 500; ++k) mj_step(m, d);
  TimeRestoring(state, m, d, 1000, segments, [&]() { mj_step(m, d); });
  mj_deleteData(d);
}

void Step(benchmark::State& state, const char* integrator, bool tether) {
  const int segments = static_cast<int>(state.range(0));
  std::string error;
  mjModel* m = tether ? mjtether::LoadModelFromString(Scene(segments, integrator), "b.xml", &error)
                      : nullptr;
  if (!tether) {
    char buf[1000];
    mjVFS* vfs = new mjVFS;
    mj_defaultVFS(vfs);
    const std::string xml = Scene(segments, integrator);
    mj_makeEmptyFileVFS(vfs, "b.xml", static_cast<int>(xml.size()));
    std::copy(xml.begin(), xml.end(), static_cast<char*>(vfs->filedata[0]));
    m = mj_loadXML("b.xml", vfs, buf, sizeof(buf));
    mj_deleteVFS(vfs);
    delete vfs;
  }
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  TimeWarmedSteps(state, m, segments);
  mjtether::Detach(m);
  mj_deleteModel(m);
}

// The ringing watch's cost (RingWarnings, plugin/mjtether.h): the same bdf2 scene with the
// segment mode's damping ratio just below kRingDampingRatio (watched: one pass over the
// segments before each advance) and at it (not watched); both declare the damping effect, so
// the difference is the watch alone. Skips if the predicate does not split them so.
void Watch(benchmark::State& state, bool watched) {
  const int segments = static_cast<int>(state.range(0));
  std::ostringstream ratio;
  ratio << "damping_ratio=" << (watched ? 0.99 : 1.0) * mjtether::kRingDampingRatio;
  std::string error;
  mjModel* m =
      mjtether::LoadModelFromString(Scene(segments, "bdf2", ratio.str()), "b.xml", &error);
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  if (mjtether::WatchesRinging(*mjtether::GetTether(m, 0), m->opt.timestep) != watched) {
    state.SkipWithError("the ringing watch is not what this benchmark assumes");
  } else {
    TimeWarmedSteps(state, m, segments);
  }
  mjtether::Detach(m);
  mj_deleteModel(m);
}

// The fixed comparison line through mj_step at 2 ms (see the header): warmed up over its first
// period (the snap from the inextensible catenary), then 10 s (one period of the fairlead)
// before each restore of that state.
void Line(benchmark::State& state, const char* integrator) {
  namespace rs = mjtether::reference_scenes;
  const int segments = static_cast<int>(state.range(0));
  const rs::Scene s = rs::LineScene();
  const double h = 0.002;  // [s]
  std::string error;
  mjModel* m = mjtether::LoadModelFromString(rs::LineModelXml(s, segments, integrator, h),
                                             "line.xml", &error);
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  mjData* d = mj_makeData(m);
  auto step = [&]() {
    const mjtether::Vec3 p = s.b(d->time + h).pos;  // the fairlead at the end of this step
    for (int i = 0; i < 3; ++i) d->mocap_pos[i] = p[i];
    mj_step(m, d);
  };
  const int period = static_cast<int>(std::lround(10 / h));
  for (int k = 0; k < period; ++k) step();
  TimeRestoring(state, m, d, period, segments, step);
  if (mjtether::CheckDivergence(m, d)) state.SkipWithError("the line diverged");
  state.counters["x_real_time"] = benchmark::Counter(static_cast<double>(state.iterations()) * h,
                                                     benchmark::Counter::kIsRate);
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
}

// The consistent coupling with its slow-mode correction (docs/coupling.md, session 34): a 100 kg
// body hanging in a current on a taut 10 m line of EA 1e7 N (omega h 4 at 400 segments, above
// implicit's threshold of 1 at every count here), every segment in tension at every step, so
// that the correction's line stiffness (Tether::LineStiffness) and its check that the step ended
// taut (Tether::AllTaut, session 37) run each step.
void ConsistentTaut(benchmark::State& state) {
  const int segments = static_cast<int>(state.range(0));
  std::ostringstream s;
  s << R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025 current=0.5,0,0"/>
    <text name="tether:t" data="ends=a,b length=10 segments=)"
    << segments << R"( diameter=0.02 mass_per_length=0.3 EA=1e7
          Cdn=1.2 Cdt=0.01 Can=1 integrator=implicit"/></custom>
    <worldbody><body name="anchor" mocap="true"><site name="a"/></body>
      <body name="rov" pos="0 0 -10.001"><freejoint/><inertial pos="0 0 0" mass="100"
          diaginertia="1 1 1"/><site name="b"/></body></worldbody></mujoco>)";
  std::string error;
  mjModel* m = mjtether::LoadModelFromString(s.str(), "b.xml", &error);
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  if (!mjtether::GetCouplingLimit(m, 0, 1).consistent) {
    state.SkipWithError("not the consistent coupling, which this benchmark assumes");
  } else {
    TimeWarmedSteps(state, m, segments);
  }
  mjtether::Detach(m);
  mj_deleteModel(m);
}

void BM_LineBdf2(benchmark::State& s) { Line(s, "bdf2"); }
void BM_LineImplicit(benchmark::State& s) { Line(s, "implicit"); }
void BM_LineImplicit2(benchmark::State& s) { Line(s, "implicit2"); }
BENCHMARK(BM_LineBdf2)->Arg(80)->Arg(100);
BENCHMARK(BM_LineImplicit)->Arg(80)->Arg(100);
BENCHMARK(BM_LineImplicit2)->Arg(100);
void BM_ConsistentTaut(benchmark::State& s) { ConsistentTaut(s); }
BENCHMARK(BM_ConsistentTaut)->Arg(100)->Arg(400);

void BM_RingWatchOn(benchmark::State& s) { Watch(s, true); }
void BM_RingWatchOff(benchmark::State& s) { Watch(s, false); }
BENCHMARK(BM_RingWatchOn)->Arg(10)->Arg(100)->Arg(400);
BENCHMARK(BM_RingWatchOff)->Arg(10)->Arg(100)->Arg(400);

void BM_StepImplicit(benchmark::State& s) { Step(s, "implicit", true); }
void BM_StepBdf2(benchmark::State& s) { Step(s, "bdf2", true); }
void BM_StepExplicit(benchmark::State& s) { Step(s, "explicit", true); }
void BM_StepRk4(benchmark::State& s) { Step(s, "rk4", true); }
void BM_StepNoTether(benchmark::State& s) { Step(s, "implicit", false); }

BENCHMARK(BM_StepImplicit)->Arg(10)->Arg(20)->Arg(50)->Arg(100)->Arg(200);
BENCHMARK(BM_StepBdf2)->Arg(10)->Arg(20)->Arg(50)->Arg(100)->Arg(200);
BENCHMARK(BM_StepExplicit)->Arg(10)->Arg(20)->Arg(50)->Arg(100)->Arg(200);
BENCHMARK(BM_StepRk4)->Arg(10)->Arg(20)->Arg(50)->Arg(100)->Arg(200);
BENCHMARK(BM_StepNoTether)->Arg(10);

}  // namespace

BENCHMARK_MAIN();
