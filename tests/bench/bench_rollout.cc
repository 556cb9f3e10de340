// Throughput of mjtether::Rollout (plugin/rollout.h) on 1 and 2 threads: 8 rollouts of 500
// steps (1 s) of the default scene (40 segments, implicit, a free ROV under thrust). Reports
// MuJoCo steps per second of wall time (items_per_second), the process's CPU time (all
// threads) and the 1-minute load average at the end of each benchmark (a shared machine
// slows the 2-thread case first).
//
//   ./build/tests/bench/bench_rollout --benchmark_repetitions=5
//     --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mjtether.h"
#include "rollout.h"

namespace {

double LoadAverage() {
  std::ifstream f("/proc/loadavg");
  double load = -1;
  f >> load;
  return load;
}

void Rollouts(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int n = 8, steps = 500;
  std::string error;
  mjModel* m = mjtether::LoadModel(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml", &error);
  if (!m) {
    state.SkipWithError(error.c_str());
    return;
  }
  mjData* d = mj_makeData(m);
  std::vector<double> x0(size_t(n) * mjtether::StateSize(m));
  for (int i = 0; i < n; ++i) {
    mj_resetData(m, d);
    d->qvel[0] = 0.1 * i;
    mjtether::GetState(m, d, &x0[size_t(i) * mjtether::StateSize(m)]);
  }
  {
    mjtether::RolloutPool pool(m, threads);
    for (auto _ : state) {
      mjtether::Rollouts r = pool.Run(x0.data(), n, nullptr, nullptr, steps);
      benchmark::DoNotOptimize(r.qpos.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * n * steps);
  state.counters["load1"] = LoadAverage();
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
}

BENCHMARK(Rollouts)
    ->ArgName("threads")
    ->Arg(1)
    ->Arg(2)
    ->UseRealTime()
    ->MeasureProcessCPUTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
