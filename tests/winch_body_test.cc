// The winch's reaction on its body (issue 13, item 2; docs/winch.md): a TMS on a free body
// feels the tension at the drum.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "mjtether.h"
#include "mujoco_fixture.h"

namespace mjtether {
namespace {

class WinchBodyTest : public testing::MuJoCoFixture {};

// A TMS (5000 kg free body, weightless: no gravity) with its drum at its centre of mass and a
// 10 m tether, straight and at its rest length, to a fixed anchor 10 m away; the winch holds
// 200 N (mode=tension). The winch hauls in until the tension reaches the set value, and the
// tension pulls the TMS towards the anchor.
// - Momentum: the TMS's linear momentum changes by the impulse of the drum force the API
//   reports (GetReactions force_a, summed over the steps: MuJoCo's Euler step is
//   m (v' - v) = h F for a free body whose force acts through its centre of mass), within
//   1e-9 of the impulse (round-off).
// - That force is the tension at the drum: |force_a| = tension_a, along the tether from the
//   drum towards the first deployed node (the tether is weightless and straight: cosine > 0.9999),
//   and within 10% of the set 200 N once the drum's lag (tau = 0.2 s) has passed (after 3 s).
// - The TMS moved towards the anchor by what the impulse says (x = integral of v, within 1 mm).
TEST_F(WinchBodyTest, ReactionMovesFreeTms) {
  const char* xml = R"(<mujoco><option timestep="0.002" gravity="0 0 0"/><custom>
  <text name="tether:line" data="ends=drum,anchor length=10 segments=10 diameter=0.02
        mass_per_length=1 EA=1e5 damping=2e3 integrator=implicit"/>
  <text name="winch:line" data="mode=tension actuator=w min_length=2 max_length=20
        max_speed=1 max_accel=2 tau=0.2"/>
  </custom><worldbody>
  <body name="tms"><freejoint/><inertial pos="0 0 0" mass="5000" diaginertia="1000 1000 1000"/>
    <site name="drum"/></body>
  <site name="anchor" pos="10 0 0"/></worldbody>
  <actuator><motor name="w" site="drum" gear="0 0 0 0 0 0"/></actuator></mujoco>)";
  mjModel* m = Load(xml);
  ASSERT_NE(m, nullptr);
  mjData* d = Make(m);
  const double mass = 5000, T_set = 200, h = m->opt.timestep;
  d->ctrl[0] = T_set;
  Vec3 impulse = Vec3::Zero(), travel = Vec3::Zero();
  double worst_T = 0, worst_norm = 0, worst_cos = 1;
  while (d->time < 8) {
    const Vec3 v0(d->qvel[0], d->qvel[1], d->qvel[2]);
    mj_step(m, d);
    const Vec3 v1(d->qvel[0], d->qvel[1], d->qvel[2]);
    const EndReactions r = GetReactions(m, d, 0);
    impulse += h * r.force_a;
    travel += h * v1;  // semi-implicit Euler: the position moves with the new velocity
    worst_norm = std::max(worst_norm, std::abs(r.force_a.norm() - r.tension_a));
    const WinchState ws = GetWinch(m, d, 0);
    const double* x = NodePositions(m, d, 0) + 3 * ws.first_node;
    const Vec3 chord = Vec3(x + 3) - Vec3(x);
    if (r.force_a.norm() > 1) {
      worst_cos = std::min(worst_cos, r.force_a.dot(chord) / (r.force_a.norm() * chord.norm()));
    }
    if (d->time > 3) worst_T = std::max(worst_T, std::abs(r.tension_a - T_set) / T_set);
    ASSERT_LE((mass * v1 - mass * v0 - h * r.force_a).norm(), 1e-9 * (1 + h * r.force_a.norm()))
        << "t = " << d->time;
  }
  const Vec3 p(d->qvel[0], d->qvel[1], d->qvel[2]);
  std::printf("TMS momentum %.6g N s, drum impulse %.6g N s; tension within %.3g%% of the set; "
              "moved %.3g m\n", mass * p.norm(), impulse.norm(), 100 * worst_T, d->qpos[0]);
  EXPECT_LE((mass * p - impulse).norm(), 1e-9 * impulse.norm());
  EXPECT_LE(worst_norm, 1e-9 * T_set);
  EXPECT_GT(worst_cos, 0.9999);
  EXPECT_LE(worst_T, 0.10);
  EXPECT_NEAR(d->qpos[0], travel[0], 1e-3);
  // It did move: about T_set/m t^2/2 = 0.04 m/s^2 x (8 s - the ~1 s build-up)^2/2 ~ 1 m (the
  // winch hauls in at the TMS's speed, 0.3 m/s at most, well within max_speed).
  EXPECT_GT(d->qpos[0], 0.5);
  EXPECT_GT(impulse[0], 0.5 * T_set * 5);  // towards the anchor, about T_set for 5 s or more
  ASSERT_FALSE(CheckDivergence(m, d).has_value());
}

}  // namespace
}  // namespace mjtether
