// The shipped height-field scene, models/hfield_rock.xml: a tether dragged by an ROV over a rock
// made from a PNG height map. The surface the test measures against is MuJoCo's own
// (mj_rayHfield straight down onto the rock geom), not the plugin's sampling of it.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "mjtether.h"
#include "mjtether_vehicles.h"
#include "mujoco_fixture.h"

namespace mjtether::testing {
namespace {

// The lowest height [m] the tether's axis may reach at (x, y): over the rock's footprint the
// geom contact holds the tether's skin on the surface (MuJoCo's: a ray straight down onto the
// hfield geom, through its triangles), so the axis r above it, less half the radius; elsewhere
// the seabed (z = 0) holds the axis itself, less half the radius.
double LowestAxis(const mjModel* m, const mjData* d, int rock, double r, double x, double y) {
  const double top = 100;  // [m] far above the rock (1.5 m high)
  const mjtNum pnt[3] = {x, y, top}, down[3] = {0, 0, -1};
  const mjtNum dist = mj_rayHfield(m, d, rock, pnt, down);
  return dist >= 0 ? top - dist + 0.5 * r : -0.5 * r;
}

// The model loads with its tether, its rock in contact= and its vehicle; run for 20 s (the ROV
// passes over the rock from about 4 s and the tether rests over the crest from about 10 s,
// the ROV beyond it). Checked at
// every step, for every node:
// - it stays above the surface: on the rock the skin (the axis r above it) at most r/2 into it,
//   on the seabed the axis at most r/2 below it, r = 6 mm the tether's radius. The penalties'
//   own depths under these loads is microns
//   (the net weight 1.3 N/m and the tension's pull over the crest, T/R ~ 6 N/m, over
//   contact_stiffness 1e6 N/m^2); the discretisation adds at most the rise of the surface
//   between two of the plugin's samples (half a cell, 3.3 cm) where a node sits on a crest;
//   so a node half its radius into the rock means the contact failed (a wrong triangle, a
//   missed broad phase, a tunnelling step), not a tolerance.
// At the end: the tether lies on the rock (at least 5 nodes within 2 cm of its surface over the
// footprint, where the field is above 5 cm) and the rock carries part of its weight (the
// summed contact impulse points up).
TEST(HfieldRock, ShippedModelKeepsTheTetherOnTheRock) {
  mju_user_warning = FailOnWarning;
  mju_user_error = AbortOnError;
  std::string error;
  mjModel* m = LoadModel(std::string(MJTETHER_MODELS_DIR) + "/hfield_rock.xml", &error);
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  ASSERT_EQ(TetherCount(m), 1);
  const int rock = mj_name2id(m, mjOBJ_GEOM, "rock");
  ASSERT_GE(rock, 0);
  ASSERT_EQ(m->geom_type[rock], mjGEOM_HFIELD);
  const Tether* t = GetTether(m, 0);
  const int n = t->nodes();
  const double r = 0.5 * t->params().diameter;
  double worst = -INFINITY;  // [m] largest (lowest allowed - axis height) over nodes and steps
  double worst_t = 0, worst_on_rock = -INFINITY;
  int worst_node = -1;
  while (d->time < 20) {
    mjtether::Step(m, d);
    const std::optional<std::string> diverged = CheckDivergence(m, d);
    ASSERT_FALSE(diverged) << *diverged;
    const double* x = NodePositions(m, d, 0);
    for (int i = 0; i < n; ++i) {
      const double lowest = LowestAxis(m, d, rock, r, x[3 * i], x[3 * i + 1]);
      const double below = lowest - x[3 * i + 2];
      if (lowest > 0) worst_on_rock = std::max(worst_on_rock, below);
      if (below > worst) {
        worst = below;
        worst_t = d->time;
        worst_node = i;
      }
    }
  }
  std::printf(
      "rock: closest node %d, %.3g m above its lowest allowed height at t = %.2f s (on the "
      "rock: %.3g m)\n",
      worst_node, -worst, worst_t, -worst_on_rock);
  EXPECT_LE(worst, 0) << "node " << worst_node << " at t = " << worst_t;

  const double* x = NodePositions(m, d, 0);
  int touching = 0;
  for (int i = 0; i < n; ++i) {
    const double h = LowestAxis(m, d, rock, r, x[3 * i], x[3 * i + 1]) - 0.5 * r;  // surface
    if (h > 0.05 && x[3 * i + 2] - h < r + 0.02) ++touching;
  }
  const Vec3 impulse = ContactImpulse(m, d, 0);
  std::printf(
      "rock: %d nodes on the rock at the end, contact impulse z %.4g N s in the last "
      "step\n",
      touching, impulse.z());
  EXPECT_GE(touching, 5) << "the tether does not lie on the rock";
  EXPECT_GT(impulse.z(), 0) << "the rock carries none of the tether's weight";
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
}

}  // namespace
}  // namespace mjtether::testing
