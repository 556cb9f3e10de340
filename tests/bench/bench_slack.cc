// What slack costs the implicit step (issue 11, item 4): a tether settling onto a seabed
// against the same tether settling in free water, and a slack tether with internal damping
// against the same tether without it. Engine alone, integrator=implicit, 2 ms steps, one
// iteration = one whole run from the same start (so the median is over whole runs):
//
//   ./build/tests/bench/bench_slack --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
//
// Counters: us_per_step (CPU time per 2 ms step), realtime (simulated / CPU time),
// newton (Newton iterations per step), retried (share of steps redone in halves),
// stalled (steps whose Newton iteration ended above its tolerance), and for the seabed scene
// on_seabed (share of the length lying on the seabed at the end).
//
// Scenes (docs/numerics_slack.md):
//   Settle/seabed, Settle/free_water: 100 segments, 30 m, d 0.02 m, 0.35 kg/m, EA 2e5 N,
//     EI 0.5 N m^2, damping 50 N s, Cdn 1.2, Cdt 0.01, Can 1, water; end A at (0, 0, -4), end
//     B at (20, 0, -9.5); 20 s from rest on a path with 23 m of its 30 m on z = -10 (see
//     SettleStart). With the seabed at z = -10 (friction 0.3) that part settles on it; without
//     the seabed the same start falls free and hangs.
//   Slack/water_damping_D: 152 segments of 5 cm (7.6 m), neutrally buoyant (0.322 kg/m for
//     d 0.02 m), EA 2e5 N, EI 0.05 N m^2, drag and added mass, a 0.3 m/s current; end B
//     circles (radius 1 m, period 4 s) 5 m from end A, so the tether never comes taut; 10 s.
//   Slack/dry_zero_g_damping_D: the same tether and motion, dry and without gravity.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "declaration.h"
#include "tether.h"
#include "../slack_scene.h"

namespace mjtether {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStep = 0.002;  // [s] the MuJoCo step

struct Scene {
  Tether tether;
  Environment env;
};

std::optional<Scene> Build(const std::string& water, const std::string& tether, bool gravity,
                           std::string* error) {
  Environment env;
  if (!gravity) env.gravity = Vec3::Zero();
  DeclarationError e;
  if (!water.empty()) {
    env.wet = true;
    std::optional<Water> w = ParseWater(water, &e);
    if (!w) {
      *error = e.message;
      return std::nullopt;
    }
    env.water = *w;
  }
  std::optional<TetherDeclaration> d = ParseTether(tether, env, &e);
  if (!d) {
    *error = e.message;
    return std::nullopt;
  }
  std::optional<Tether> t = Tether::Create(d->params, env, error);
  if (!t) return std::nullopt;
  return Scene{*t, env};
}

// Runs `steps` steps of the ends given by `ends(t)` from (x0, v0) and records the counters.
template <class EndsAt>
void Run(benchmark::State& state, const Tether& t, const std::vector<double>& x0,
         const std::vector<double>& v0, int steps, EndsAt ends_at, double seabed = NAN) {
  std::vector<double> x, v, work(t.WorkspaceSize());
  double cpu = 0;
  long newton = 0, retried = 0, stalled = 0, total = 0;
  for (auto _ : state) {
    state.PauseTiming();
    x = x0;
    v = v0;
    state.ResumeTiming();
    Ends from = ends_at(0.0);
    for (int k = 0; k < steps; ++k) {
      const Ends to = ends_at((k + 1) * kStep);
      const StepStatus s = t.Advance(x.data(), v.data(), from, to, kStep, work.data());
      if (!s.ok) {
        state.SkipWithError(s.reason.c_str());
        return;
      }
      newton += s.newton_iterations;
      retried += s.halvings > 0;
      stalled += s.stalled_steps > 0;
      ++total;
      from = to;
    }
  }
  (void)cpu;
  const double runs = static_cast<double>(state.iterations());
  state.counters["us_per_step"] = benchmark::Counter(
      runs * steps * 1e-6, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["realtime"] =
      benchmark::Counter(runs * steps * kStep, benchmark::Counter::kIsRate);
  state.counters["newton"] = static_cast<double>(newton) / total;
  state.counters["retried"] = static_cast<double>(retried) / total;
  state.counters["stalled"] = static_cast<double>(stalled) / total;
  if (std::isfinite(seabed)) {
    // Share of the length whose both nodes are within 1 cm of the seabed.
    const int N = t.segments();
    int on = 0;
    for (int j = 0; j < N; ++j) {
      on += x[3 * j + 2] < seabed + 0.01 && x[3 * (j + 1) + 2] < seabed + 0.01;
    }
    state.counters["on_seabed"] = static_cast<double>(on) / N;
  }
}

const char* kSettleTether =
    "ends=a,b length=30 segments=100 diameter=0.02 mass_per_length=0.35 EA=2e5 EI=0.5 "
    "damping=50 Cdn=1.2 Cdt=0.01 Can=1 integrator=implicit";
constexpr double kSeabed = -10;  // [m]

// The start of the settling scenes: from end A at (0, 0, -4) straight down to (4, 0, -10),
// then along z = -10 as one period of a sine across x (x = 4..19, amplitude chosen so that the
// whole path is 30 m long), then up to end B at (20, 0, -9.5); nodes at equal arc length along
// that path, at rest. 23 m of the 30 lie on z = -10.
void SettleStart(const Tether& t, Ends* ends, std::vector<double>* x, std::vector<double>* v) {
  ends->a.pos = Vec3(0, 0, -4);
  ends->b.pos = Vec3(20, 0, -9.5);
  const double L = t.params().length;
  auto path = [&](double a, std::vector<Vec3>* pts) {
    pts->clear();
    pts->push_back(ends->a.pos);
    for (int k = 0; k <= 3000; ++k) {
      const double u = k / 3000.0;
      pts->push_back(Vec3(4 + 15 * u, a * std::sin(2 * kPi * u), kSeabed));
    }
    pts->push_back(ends->b.pos);
    double s = 0;
    for (size_t k = 1; k < pts->size(); ++k) s += ((*pts)[k] - (*pts)[k - 1]).norm();
    return s;
  };
  std::vector<Vec3> pts;
  double lo = 0, hi = 20;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (path(mid, &pts) < L ? lo : hi) = mid;
  }
  path(lo, &pts);
  x->assign(3 * t.nodes(), 0);
  v->assign(3 * t.nodes(), 0);
  double s = 0, target = 0;
  int node = 0;
  for (size_t k = 1; k < pts.size() && node < t.nodes(); ++k) {
    const double len = (pts[k] - pts[k - 1]).norm();
    while (node < t.nodes() && target <= s + len + 1e-12) {
      const Vec3 p = pts[k - 1] + (pts[k] - pts[k - 1]) * ((target - s) / len);
      for (int c = 0; c < 3; ++c) (*x)[3 * node + c] = p[c];
      ++node;
      target = L * node / t.segments();
    }
    s += len;
  }
  for (int c = 0; c < 3; ++c) (*x)[3 * t.segments() + c] = ends->b.pos[c];
}

void Settle(benchmark::State& state, bool seabed) {
  const std::string water =
      std::string("density=1025") + (seabed ? " seabed=-10 seabed_friction=0.3" : "");
  std::string error;
  std::optional<Scene> s = Build(water, kSettleTether, true, &error);
  if (!s) {
    state.SkipWithError(error.c_str());
    return;
  }
  const Tether& t = s->tether;
  Ends ends;
  std::vector<double> x0, v0;
  SettleStart(t, &ends, &x0, &v0);
  Run(
      state, t, x0, v0, static_cast<int>(std::lround(20 / kStep)), [&](double) { return ends; },
      seabed ? kSeabed : NAN);
}


void Slack(benchmark::State& state, bool wet, double damping) {
  const std::string tether =
      "ends=a,b length=7.6 segments=152 diameter=0.02 mass_per_length=0.32201 EA=2e5 EI=0.05 "
      "Cdn=1.2 Cdt=0.01 Can=1 integrator=implicit damping=" +
      std::to_string(damping);
  std::string error;
  std::optional<Scene> s = Build(wet ? "density=1025 current=0,0.3,0" : "", tether, wet, &error);
  if (!s) {
    state.SkipWithError(error.c_str());
    return;
  }
  const Tether& t = s->tether;
  std::vector<double> x0(3 * t.nodes()), v0(3 * t.nodes());
  t.InitialShape(Circling(0), x0.data(), v0.data());
  Run(state, t, x0, v0, static_cast<int>(std::lround(10 / kStep)), Circling);
}

}  // namespace
}  // namespace mjtether

int main(int argc, char** argv) {
  using namespace mjtether;
  for (bool seabed : {true, false}) {
    benchmark::RegisterBenchmark(seabed ? "Settle/seabed" : "Settle/free_water",
                                 [=](benchmark::State& s) { Settle(s, seabed); })
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  }
  for (bool wet : {true, false}) {
    for (double damping : {0.0, 20.0, 200.0}) {
      const std::string name = std::string("Slack/") + (wet ? "water" : "dry_zero_g") +
                               "_damping_" + std::to_string(static_cast<int>(damping));
      benchmark::RegisterBenchmark(name.c_str(),
                                   [=](benchmark::State& s) { Slack(s, wet, damping); })
          ->Iterations(1)
          ->Unit(benchmark::kMillisecond);
    }
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  return 0;
}
