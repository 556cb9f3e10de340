// Cost of the water's depth profile and of a geom seabed (docs/environment.md): one mj_step of
// a 20 m tether hanging from a fixed site to a fixed anchor near the bottom, part of it lying
// on the seabed, at 50 and 200 segments, implicit, with
//   uniform   current=0.3,0,0 and seabed=-10 (the flat seabed)
//   profile   current_profile with 11 rows (the same 0.3 m/s everywhere) and seabed=-10
//   plane     current=0.3,0,0 and seabed=GEOM, a horizontal plane geom at z = -10
//   hfield    current=0.3,0,0 and seabed=GEOM, a 65 x 65 flat hfield at z = -10
// profile/uniform is what the profile costs (a bisection per node and Newton iteration);
// hfield/uniform what the height field costs (a cell lookup per node).
//
//   ./build/tests/bench/bench_environment --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "mjtether.h"

namespace mjtether {
namespace {

std::string ProfileFile() {
  const std::string path = "/tmp/mjtether_bench_profile.csv";
  std::ofstream f(path);
  f << "z,ux,uy,uz\n";
  for (int i = 0; i <= 10; ++i) f << -20 + 2 * i << ",0.3,0,0\n";
  return path;
}

std::string Scene(int segments, const std::string& water) {
  return R"(<mujoco>
  <option timestep="0.002"><flag contact="disable"/></option>
  <asset><hfield name="flat" nrow="65" ncol="65" size="20 20 1 0.5"/></asset>
  <worldbody>
    <site name="a" pos="0 0 0"/>
    <site name="b" pos="8 0 -9.5"/>
    <geom name="plane" type="plane" size="30 30 1" pos="0 0 -10"/>
    <geom name="hf" type="hfield" hfield="flat" pos="0 0 -10"/>
  </worldbody>
  <custom>
    <text name="water" data=")" +
         water + R"("/>
    <text name="tether:t" data="ends=a,b length=20 segments=)" +
         std::to_string(segments) +
         R"( diameter=0.03 mass_per_length=1 EA=1e5 EAc=1e5 EI=1 damping=100 Cdn=1.2 Cdt=0.01
      integrator=implicit"/>
  </custom>
</mujoco>)";
}

void Step(benchmark::State& state, const std::string& water) {
  const int N = static_cast<int>(state.range(0));
  std::string error;
  mjModel* m = LoadModelFromString(Scene(N, water), "bench.xml", &error);
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  mjData* d = mj_makeData(m);
  // Settle onto the seabed, then time from this state.
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

void BM_Uniform(benchmark::State& s) { Step(s, "current=0.3,0,0 seabed=-10"); }
void BM_Profile(benchmark::State& s) {
  Step(s, "current_profile=" + ProfileFile() + " seabed=-10");
}
void BM_Plane(benchmark::State& s) { Step(s, "current=0.3,0,0 seabed=plane"); }
void BM_Hfield(benchmark::State& s) { Step(s, "current=0.3,0,0 seabed=hf"); }

BENCHMARK(BM_Uniform)->Arg(50)->Arg(200);
BENCHMARK(BM_Profile)->Arg(50)->Arg(200);
BENCHMARK(BM_Plane)->Arg(50)->Arg(200);
BENCHMARK(BM_Hfield)->Arg(50)->Arg(200);

}  // namespace
}  // namespace mjtether

BENCHMARK_MAIN();
