// Cost of tether-geom contact (docs/contact.md): one mj_step of a scene with a 50-segment
// implicit tether (20 m, dry, slung between two fixed sites over a pipe it rests on), with
//   none   no `contact=` (nothing computed)
//   g2     contact=all, 2 geoms: the pipe (touching 2-3 segments) and a box far away
//   g200   contact=all, the same plus 198 boxes on a 1 m grid 2 m under the tether
//          (inside the tether's span, outside its reach: the broad phase's work)
//   far    contact=far: one geom out of reach (the shape is none's: the tether hangs through
//          the pipe), so far - none is the cost of contact per step that touches nothing
//   none200 no `contact=`, with the 198 boxes (MuJoCo's own cost of the extra geoms)
// and the same at 200 segments. Per-node cost: (g2 - none)/nodes; per-geom cost of contact:
// ((g200 - none200) - (g2 - none))/198. The issue's target: contact's cost with 200 geoms at
// most 2x its cost with 2.
//
//   ./build/tests/bench/bench_contact --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <cstdio>
#include <string>

#include "mjtether.h"

namespace mjtether {
namespace {

std::string Scene(int segments, const char* contact, int boxes) {
  std::string grid;
  for (int k = 0; k < boxes; ++k) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "<geom type=\"box\" size=\"0.2 0.2 0.2\" pos=\"%g %g -3\"/>\n",
                  -9.5 + (k % 20), -4.5 + (k / 20));
    grid += buf;
  }
  return R"(<mujoco>
  <option timestep="0.002"/>
  <worldbody>
    <site name="a" pos="-10 0 0"/>
    <site name="b" pos="10 0 0"/>
    <geom name="pipe" type="cylinder" size="0.3 2" pos="0 0 -1.4" zaxis="0 1 0"/>
    <geom name="far" type="box" size="0.5 0.5 0.5" pos="40 0 0"/>
    )" + grid +
         R"(
  </worldbody>
  <custom>
    <text name="tether:t" data="ends=a,b length=20.2 segments=)" +
         std::to_string(segments) + R"( diameter=0.03 mass_per_length=1 EA=1e5
      EAc=1e5 EI=1 damping=100 integrator=implicit )" +
         contact + R"("/>
  </custom>
</mujoco>)";
}

void Step(benchmark::State& state, const char* contact, int boxes) {
  const int N = static_cast<int>(state.range(0));
  std::string error;
  mjModel* m = LoadModelFromString(Scene(N, contact, boxes), "bench.xml", &error);
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  mjData* d = mj_makeData(m);
  // Settle onto the pipe, then time from this state.
  for (int i = 0; i < 1000; ++i) mj_step(m, d);
  mjData* saved = mj_copyData(nullptr, m, d);
  int k = 0;
  for (auto _ : state) {
    if (++k % 500 == 0) mj_copyData(d, m, saved);
    mj_step(m, d);
  }
  if (auto message = CheckDivergence(m, d)) state.SkipWithError(message->c_str());
  state.counters["nodes"] = N + 1;
  mj_deleteData(saved);
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
}

void BM_None(benchmark::State& s) { Step(s, "", 0); }
void BM_None200(benchmark::State& s) { Step(s, "", 198); }
void BM_Far(benchmark::State& s) { Step(s, "contact=far", 0); }
void BM_G2(benchmark::State& s) { Step(s, "contact=all", 0); }
void BM_G200(benchmark::State& s) { Step(s, "contact=all", 198); }
BENCHMARK(BM_None)->Arg(50)->Arg(200);
BENCHMARK(BM_None200)->Arg(50)->Arg(200);
BENCHMARK(BM_Far)->Arg(50)->Arg(200);
BENCHMARK(BM_G2)->Arg(50)->Arg(200);
BENCHMARK(BM_G200)->Arg(50)->Arg(200);

}  // namespace
}  // namespace mjtether

BENCHMARK_MAIN();
