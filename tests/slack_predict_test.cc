// The implicit step's predicted pieces (issue 11, item 4; docs/numerics_slack.md, "Predicted
// pieces in the Newton iteration"): in the Newton iterations after the first, a slack segment
// that the last full Newton step left taut is linearised on the taut piece extended below L0,
// so that the next step does not overshoot L0 again. Counts, not times: the number of linear
// solves per step is deterministic (the cost figures are bench_slack's).
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "declaration.h"
#include "make_tether.h"
#include "slack_scene.h"
#include "tether.h"

namespace mjtether {
namespace {

// The bench's heavily damped slack tether in water: 152 segments of 5 cm, neutrally buoyant,
// drag and added mass, a 0.3 m/s current, damping 200 N s, end B circling; 10 s of 2 ms steps.
// Without the prediction the Newton iteration took 3.45 solves per step (measured with this
// scene on the base of this work, 93df67c); with it 2.90. Bound 3.2: between the two, so that
// losing the prediction fails, with 10% of headroom over the measured figure for changes
// elsewhere in the law. The steps must also not be bought with halvings or stalls: at most 1%
// of the steps retried in halves (measured 0.10%; 0.16% before), none stalled.
TEST(SlackPredict, HeavilyDampedSlackTetherInWaterTakesFewerSolves) {
  TetherParams p = DampedSlackParams(200);
  p.Cdn = 1.2;
  p.Cdt = 0.01;
  p.Can = 1;
  Environment env;
  env.wet = true;
  DeclarationError e;
  const std::optional<Water> water = ParseWater("density=1025 current=0,0.3,0", &e);
  ASSERT_TRUE(water) << e.message;
  env.water = *water;
  const int steps = 5000;
  const SlackCounts c = RunCircling(Make(p, env), 0.002, steps);
  ASSERT_TRUE(c.failure.empty()) << c.failure;
  const long retried = c.retried, stalled = c.stalled, newton = c.newton;
  const double solves = static_cast<double>(newton) / steps;
  std::printf("water, damping 200: %.3f solves per step, %.2f%% of the steps retried\n", solves,
              100.0 * retried / steps);
  EXPECT_LE(solves, 3.2);
  EXPECT_LE(retried, steps / 100);
  EXPECT_EQ(stalled, 0);
}

}  // namespace
}  // namespace mjtether
