// Cost of the winch (docs/winch.md), engine alone: a 50 m tether (100 segments of 0.5 m)
// hanging from a drum with a free end, implicit, 2 ms steps, axial + damping + weight.
//
//   ./build/tests/bench/bench_winch --benchmark_repetitions=3
//     --benchmark_report_aggregates_only=true
//
//   plain         the same tether without a winch (the reference)
//   still         with a winch (allocation for 100 m, 200 segments), not moving: the cost of
//                 the Deployed view per step
//   payout/V      paying out at V mm/s (counter inserted = nodes inserted per step)
//   regrid        one insertion and one removal at the drum (Tether::Regrid): the cost of
//                 re-discretisation itself, per pair of nodes
//   impedance     the drum's impedance of the settled line (tension mode, once per step)
// Payout cost per inserted node = (payout - still) / inserted, or regrid / 2 for the
// operation alone.
#include <benchmark/benchmark.h>

#include <vector>

#include "tether.h"

namespace mjtether {
namespace {

constexpr double kL0 = 0.5;  // [m]

TetherParams Params(bool winch) {
  TetherParams p;
  p.segments = winch ? 200 : 100;
  p.length = p.segments * kL0;
  p.diameter = 0.02;
  p.mass_per_length = 0.5;
  p.EA = 1e5;
  p.damping = 50;
  p.free_end = true;
  p.integrator = Integrator::kImplicit;
  p.effects = kAxial | kDamping | kWeight;
  p.winch = winch;
  return p;
}

struct Hang {
  Tether t;
  std::vector<double> x, v, work;
  Ends ends;
  Payout payout;
  explicit Hang(bool winch) : t(*Tether::Create(Params(winch), Environment(), nullptr)) {
    x.resize(3 * t.nodes());
    v.resize(3 * t.nodes());
    work.resize(t.WorkspaceSize());
    ends.a.axis = Vec3(0, 0, -1);
    Reset();
  }
  void Reset() {
    std::fill(x.begin(), x.end(), 0.0);
    std::fill(v.begin(), v.end(), 0.0);
    if (!t.params().winch) {
      t.InitialShape(ends, x.data(), v.data());
      return;
    }
    payout.first = t.segments() - 100;
    payout.rest = kL0;
    const Tether view = t.Deployed(payout.first, kL0, 0);
    view.InitialShape(ends, x.data() + 3 * payout.first, v.data() + 3 * payout.first);
  }
  void Step(double speed) {
    if (!t.params().winch) {
      t.Advance(x.data(), v.data(), ends, ends, 0.002, work.data());
      return;
    }
    payout.speed = speed;
    t.Advance(x.data(), v.data(), ends, ends, 0.002, work.data(), &payout);
  }
};

void Plain(benchmark::State& state) {
  Hang h(false);
  for (auto _ : state) h.Step(0);
}
BENCHMARK(Plain)->Name("plain");

void Still(benchmark::State& state) {
  Hang h(true);
  for (auto _ : state) h.Step(0);
}
BENCHMARK(Still)->Name("still");

void PayoutBench(benchmark::State& state) {
  Hang h(true);
  const double speed = state.range(0) * 1e-3;  // [m/s]
  long long inserted = 0, steps = 0;
  for (auto _ : state) {
    const int first = h.payout.first;
    h.Step(speed);
    inserted += first - h.payout.first;
    ++steps;
    if (h.payout.first == 0) {  // full: start again (rare, untimed)
      state.PauseTiming();
      h.Reset();
      state.ResumeTiming();
    }
  }
  state.counters["inserted"] = steps ? double(inserted) / steps : 0;
}
BENCHMARK(PayoutBench)->Name("payout")->Arg(500)->Arg(2000);

void Regrid(benchmark::State& state) {
  Hang h(true);
  for (int k = 0; k < 100; ++k) h.Step(0);  // settled
  Payout base = h.payout;
  const std::vector<double> x0 = h.x, v0 = h.v;
  for (auto _ : state) {
    Payout p = base;
    p.rest = 1.5 * kL0 + 1e-6;
    h.t.Regrid(h.x.data(), h.v.data(), h.ends, &p);  // insert
    p.rest = 0.5 * kL0 - 1e-6;
    h.t.Regrid(h.x.data(), h.v.data(), h.ends, &p);  // remove
    benchmark::DoNotOptimize(h.x.data());
  }
}
BENCHMARK(Regrid)->Name("regrid");

// The drum's impedance (Tether::DrumImpedance), which a winch in tension mode computes once per
// MuJoCo step, on the settled hanging line (100 taut segments): compare with `still`.
void Impedance(benchmark::State& state) {
  Hang h(true);
  for (int k = 0; k < 100; ++k) h.Step(0);  // settled
  for (auto _ : state) {
    benchmark::DoNotOptimize(h.t.DrumImpedance(h.x.data(), h.payout, 0.002));
  }
}
BENCHMARK(Impedance)->Name("impedance");

}  // namespace
}  // namespace mjtether

BENCHMARK_MAIN();
