// The slack scene of tests/slack_test.cc, tests/slack_linesearch_test.cc and
// tests/bench/bench_slack.cc (issue 11, item 4; docs/numerics_slack.md).
#pragma once

#include <cmath>

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

}  // namespace mjtether
