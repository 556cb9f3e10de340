// Rollouts on a thread pool (plugin/rollout.h): each rollout bit-identical to the same run done
// alone with mj_step, whatever the number of threads; a policy; chaining through the final
// state; a rollout that diverges stops alone. Also built under ThreadSanitizer by tools/tsan.sh.
#include "rollout.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mjtether.h"
#include "mujoco_fixture.h"

namespace mjtether {
namespace {

using RolloutTest = testing::MuJoCoFixture;

std::string DefaultScene() {
  std::ifstream f(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml");
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

const int kSteps = 400;  // 0.8 s of the default scene: the thrusters ramp up, the tether moves

// Initial states that differ: the ROV's initial velocity.
std::vector<double> InitialStates(const mjModel* m, mjData* d, int n) {
  const int ns = StateSize(m);
  std::vector<double> x(size_t(n) * ns);
  for (int i = 0; i < n; ++i) {
    mj_resetData(m, d);
    d->qvel[0] = 0.2 * i;
    d->qvel[2] = -0.1 * i;
    GetState(m, d, &x[size_t(i) * ns]);
  }
  return x;
}

// Controls: the heave thruster differs per rollout and per step (the surge ones are scheduled).
std::vector<double> Controls(const mjModel* m, int n) {
  std::vector<double> u(size_t(n) * kSteps * m->nu);
  for (int i = 0; i < n; ++i) {
    for (int s = 0; s < kSteps; ++s) {
      u[(size_t(i) * kSteps + s) * m->nu + 2] = 20 * std::sin(0.01 * s * (i + 1));
    }
  }
  return u;
}

// The same rollout alone, as a user writes it: fresh data, the state, then per step the
// controls, the policy, the schedules and mj_step. Returns qpos after every step.
std::vector<double> Alone(const mjModel* m, const double* x0, const double* u, const Policy& p,
                          int i, std::vector<double>* final_state) {
  mjData* d = mj_makeData(m);
  SetState(m, d, x0);
  std::vector<double> q;
  for (int s = 0; s < kSteps; ++s) {
    if (u) std::memcpy(d->ctrl, u + size_t(s) * m->nu, sizeof(double) * m->nu);
    if (p) p(m, d, i, s);
    Step(m, d);
    q.insert(q.end(), d->qpos, d->qpos + m->nq);
  }
  final_state->resize(StateSize(m));
  GetState(m, d, final_state->data());
  mj_deleteData(d);
  return q;
}

// 5 rollouts on 1, 2 and 3 threads (more threads than this machine's 2 cores, so the workers
// interleave) are bit for bit the rollouts run alone, and differ from each other.
TEST_F(RolloutTest, BitIdenticalToRunningEachAlone) {
  mjModel* m = Load(DefaultScene(), "rov_tether.xml");
  ASSERT_TRUE(m);
  mjData* d = Make(m);
  const int n = 5, ns = StateSize(m);
  const std::vector<double> x0 = InitialStates(m, d, n);
  const std::vector<double> u = Controls(m, n);
  std::vector<std::vector<double>> alone(n), final_alone(n);
  for (int i = 0; i < n; ++i) {
    alone[i] =
        Alone(m, &x0[size_t(i) * ns], &u[size_t(i) * kSteps * m->nu], nullptr, i, &final_alone[i]);
  }
  for (int threads : {1, 2, 3}) {
    const Rollouts r = Rollout(m, x0.data(), n, u.data(), nullptr, kSteps, threads);
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(r.steps_done[i], kSteps);
      EXPECT_EQ(r.message[i], "");
      EXPECT_EQ(std::memcmp(r.Qpos(i, 0), alone[i].data(), sizeof(double) * kSteps * m->nq), 0)
          << "rollout " << i << ", " << threads << " threads";
      EXPECT_EQ(
          std::memcmp(&r.final_state[size_t(i) * ns], final_alone[i].data(), sizeof(double) * ns),
          0)
          << "rollout " << i << ", " << threads << " threads";
      EXPECT_GT(r.Tension(i, kSteps - 1, 0, 1), 0);
    }
  }
  // The rollouts differ (so the comparisons above could fail).
  for (int i = 1; i < n; ++i) EXPECT_NE(alone[i], alone[0]);
}

// A feedback policy (depth hold on the heave thruster), called once per rollout and step from
// two threads: the same trajectories as alone.
TEST_F(RolloutTest, PolicyGivesTheSameAsAlone) {
  mjModel* m = Load(DefaultScene(), "rov_tether.xml");
  ASSERT_TRUE(m);
  mjData* d = Make(m);
  const int n = 4, ns = StateSize(m);
  const std::vector<double> x0 = InitialStates(m, d, n);
  std::atomic<int> calls{0};
  const Policy hold = [&calls](const mjModel*, mjData* dd, int i, int) {
    ++calls;
    dd->ctrl[2] = -200 * (dd->qpos[2] + 12 + 0.5 * i) - 50 * dd->qvel[2];
  };
  const Rollouts r = Rollout(m, x0.data(), n, nullptr, hold, kSteps, 2);
  EXPECT_EQ(calls.load(), n * kSteps);
  for (int i = 0; i < n; ++i) {
    std::vector<double> final_state;
    const std::vector<double> q = Alone(m, &x0[size_t(i) * ns], nullptr, hold, i, &final_state);
    EXPECT_EQ(std::memcmp(r.Qpos(i, 0), q.data(), sizeof(double) * q.size()), 0) << i;
  }
}

// Chaining: 2 x 200 steps through final_state, on a reused pool, equal 400 steps at once.
TEST_F(RolloutTest, ChainingThroughTheFinalStateIsExact) {
  mjModel* m = Load(DefaultScene(), "rov_tether.xml");
  ASSERT_TRUE(m);
  mjData* d = Make(m);
  const int n = 3;
  const std::vector<double> x0 = InitialStates(m, d, n);
  RolloutPool pool(m, 2);
  const Rollouts whole = pool.Run(x0.data(), n, nullptr, nullptr, 400);
  const Rollouts first = pool.Run(x0.data(), n, nullptr, nullptr, 200);
  const Rollouts second = pool.Run(first.final_state.data(), n, nullptr, nullptr, 200);
  for (int i = 0; i < n; ++i) {
    EXPECT_EQ(std::memcmp(second.Qpos(i, 199), whole.Qpos(i, 399), sizeof(double) * m->nq), 0);
    EXPECT_EQ(
        std::memcmp(&second.final_state[size_t(i) * whole.nstate],
                    &whole.final_state[size_t(i) * whole.nstate], sizeof(double) * whole.nstate),
        0);
  }
}

// One rollout starts with a NaN node velocity: it stops with the divergence message and NaN
// rows; the others, on the same workers, run to the end.
TEST_F(RolloutTest, DivergedRolloutStopsAlone) {
  mjModel* m = Load(DefaultScene(), "rov_tether.xml");
  ASSERT_TRUE(m);
  mjData* d = Make(m);
  const int n = 3, ns = StateSize(m);
  // States after one step, so that the tether is initialised in userdata.
  std::vector<double> x0(size_t(n) * ns);
  mj_resetData(m, d);
  Step(m, d);
  for (int i = 0; i < n; ++i) GetState(m, d, &x0[size_t(i) * ns]);
  // Rollout 1: every node velocity NaN (the tether's state in userdata, after the header).
  const Tether* t = GetTether(m, 0);
  const double* x = NodePositions(m, d, 0);
  const size_t header = x - d->userdata;
  const size_t v = ns - m->nuserdata + header + 3 * t->nodes();
  x0[size_t(1) * ns + v + 3 * 10] = std::nan("");
  const Rollouts r = Rollout(m, x0.data(), n, nullptr, nullptr, 50, 2);
  EXPECT_EQ(r.steps_done[0], 50);
  EXPECT_EQ(r.steps_done[2], 50);
  EXPECT_LT(r.steps_done[1], 50);
  EXPECT_TRUE(r.message[1].find("tether 'umbilical' diverged") != std::string::npos)
      << r.message[1];
  EXPECT_TRUE(std::isnan(r.Qpos(1, 49)[0]));
  EXPECT_EQ(r.message[0], "");
}

}  // namespace
}  // namespace mjtether
