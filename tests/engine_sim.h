// A tether with its state and workspace for engine tests (no MuJoCo), and the catenary line
// several of them start from.
#ifndef MJTETHER_TESTS_ENGINE_SIM_H_
#define MJTETHER_TESTS_ENGINE_SIM_H_

#include <vector>

#include "tether.h"

namespace mjtether {

struct Sim {
  Tether tether;
  std::vector<double> x, v, work;
  Ends ends;
  explicit Sim(const Tether& t)
      : tether(t), x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize()) {}
  void Init() { tether.InitialShape(ends, x.data(), v.data()); }
  StepStatus Step(double dt) {
    return tether.Advance(x.data(), v.data(), ends, ends, dt, work.data());
  }
  // start=static: relaxes the present shape to static equilibrium with the ends held.
  StaticResult Relax(const StaticOptions& o = {}) {
    return tether.RelaxToStatic(ends, x.data(), v.data(), work.data(), o);
  }
  Vec3 node(int i) const { return Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]); }
  double Energy() const {
    return tether.KineticEnergy(x.data(), v.data()) + tether.PotentialEnergy(x.data(), ends);
  }
  EndReactions Reactions() { return tether.Reactions(x.data(), v.data(), ends, work.data()); }
};

// 100 m of 1 kg/m line, 2 cm, EA 1e5 N (strain about 1% at ~1 kN tensions: elasticity
// matters), damping 2e3 N s, backward Euler.
inline TetherParams CatenaryParams(int segments) {
  TetherParams p;
  p.length = 100;
  p.segments = segments;
  p.diameter = 0.02;
  p.mass_per_length = 1.0;
  p.EA = 1e5;  // [N]
  p.damping = 2e3;  // [N s]
  p.integrator = Integrator::kImplicit;
  return p;
}

}  // namespace mjtether

#endif  // MJTETHER_TESTS_ENGINE_SIM_H_
