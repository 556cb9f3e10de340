// The slack scene of tests/slack_test.cc, tests/slack_linesearch_test.cc and
// tests/bench/bench_slack.cc (issue 11, item 4; docs/numerics_slack.md).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "params.h"
#include "tether.h"

namespace mjtether {

// End B circles in the y-z plane 5 m from end A (radius 1 m, period 4 s), with the circle's
// velocity, so that a 7.6 m tether between them is always slack.
inline Ends Circling(double t) {
  const double w = 2 * 3.14159265358979323846 / 4, r = 1;  // [rad/s], [m]
  Ends e;
  e.a.pos = Vec3(0, 0, 0);
  e.b.pos = Vec3(5, r * std::sin(w * t), r * (std::cos(w * t) - 1));
  e.b.vel = Vec3(0, r * w * std::cos(w * t), -r * w * std::sin(w * t));
  return e;
}

// The tether of the heavily damped slack tests (tests/slack_linesearch_test.cc,
// tests/slack_predict_test.cc): 152 segments of 5 cm, 7.6 m, neutrally buoyant in water
// (0.322 kg/m for a 2 cm diameter), EA 2e5 N, EI 0.05 N m^2, internal damping [N s],
// backward Euler; drag and added mass are the caller's.
inline TetherParams DampedSlackParams(double damping) {
  TetherParams p;
  p.length = 7.6;  // [m]
  p.segments = 152;
  p.diameter = 0.02;            // [m]
  p.mass_per_length = 0.32201;  // [kg/m]
  p.EA = 2e5;                   // [N]
  p.EI = 0.05;                  // [N m^2]
  p.damping = damping;          // [N s]
  p.integrator = Integrator::kImplicit;
  return p;
}

// What a run of `steps` steps of h, end B circling from the initial shape, cost the implicit
// step: steps retried in halves, stalled steps, Newton solves; a failed step's reason and index.
struct SlackCounts {
  long retried = 0, stalled = 0, newton = 0;
  std::string failure;
};

inline SlackCounts RunCircling(const Tether& t, double h, int steps) {
  std::vector<double> x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize());
  t.InitialShape(Circling(0), x.data(), v.data());
  SlackCounts c;
  for (int k = 0; k < steps; ++k) {
    const StepStatus s =
        t.Advance(x.data(), v.data(), Circling(k * h), Circling((k + 1) * h), h, work.data());
    if (!s.ok) {
      c.failure = s.reason + " at step " + std::to_string(k);
      return c;
    }
    c.retried += s.halvings > 0;
    c.stalled += s.stalled_steps;
    c.newton += s.newton_iterations;
  }
  return c;
}

}  // namespace mjtether
