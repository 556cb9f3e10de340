// Rollouts: many simulations of one model from given initial states under given controls (or
// a policy), on a pool of threads with one mjData per worker. Each rollout's result is
// bit-identical to running it alone, one after another, with mj_step: a rollout depends only on
// its initial state and its inputs, never on the worker or the order (tests/rollout_test.cc).
//
//   mjtether::RolloutPool pool(m);                       // every usable core
//   std::vector<double> x0(mjtether::StateSize(m));
//   mjtether::GetState(m, d, x0.data());                 // from a prepared mjData
//   mjtether::Rollouts r = pool.Run(x0.data(), n, controls, nullptr, steps, true);
//   const double* q = r.Qpos(i, s);                      // rollout i after step s+1
//
// The state (GetState/SetState) is everything mj_step reads that a user or a step changes, as
// MuJoCo 3's mjSTATE_INTEGRATION: time, qpos, qvel, act, qacc_warmstart, ctrl, qfrc_applied,
// xfrc_applied, mocap_pos, mocap_quat and userdata, which holds the tethers and vehicles.
#ifndef MJTETHER_PLUGIN_ROLLOUT_H_
#define MJTETHER_PLUGIN_ROLLOUT_H_

#include <mujoco/mujoco.h>

#include <condition_variable>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace mjtether {

// Number of doubles in a state of model m.
int StateSize(const mjModel* m);
// Copies the state of d into state[StateSize(m)], and back.
void GetState(const mjModel* m, const mjData* d, double* state);
void SetState(const mjModel* m, mjData* d, const double* state);

// Called before each step of a rollout, after the step's controls (if any) are in d->ctrl:
// may read d and write d->ctrl, d->qfrc_applied, d->xfrc_applied. It is called from several
// threads at once, with distinct d: it must not write shared data without a lock.
using Policy = std::function<void(const mjModel* m, mjData* d, int rollout, int step)>;

struct RolloutOptions {
  bool prescribe = true;  // apply the model's motion: and thrust: schedules (as Step does),
                          // after the controls and the policy
};

// Results of n rollouts of `steps` steps. Trajectories are recorded after every step; a
// rollout that stops early (a tether diverged, MuJoCo's bad-acceleration reset) has NaN in its
// remaining rows, `steps_done` < steps and a `message`.
struct Rollouts {
  int n = 0, steps = 0;
  int nq = 0, nv = 0, nsensordata = 0, ntether = 0, nstate = 0;
  std::vector<double> time;          // n x steps [s]
  std::vector<double> qpos;          // n x steps x nq
  std::vector<double> qvel;          // n x steps x nv
  std::vector<double> sensordata;    // n x steps x nsensordata
  std::vector<double> tension;       // n x steps x ntether x 2: at ends A and B [N]
  std::vector<double> final_state;   // n x nstate: where each rollout ended (for chaining)
  std::vector<int> steps_done;       // n
  std::vector<std::string> message;  // n; empty when the rollout ran all its steps

  // Rollout i after step s + 1.
  // (data() + offset, not &v[k]: a vector is empty when the model has no sensors.)
  const double* Qpos(int i, int s) const { return qpos.data() + (size_t(i) * steps + s) * nq; }
  const double* Qvel(int i, int s) const { return qvel.data() + (size_t(i) * steps + s) * nv; }
  const double* Sensordata(int i, int s) const {
    return sensordata.data() + (size_t(i) * steps + s) * nsensordata;
  }
  // Tension [N] of tether k at end 0 (A) or 1 (B).
  double Tension(int i, int s, int k, int end) const {
    return tension[((size_t(i) * steps + s) * ntether + k) * 2 + end];
  }
};

// A pool of worker threads, each with its own mjData of model m (which must outlive the pool).
class RolloutPool {
 public:
  // threads <= 0: every core this process may use.
  explicit RolloutPool(const mjModel* m, int threads = 0);
  ~RolloutPool();
  RolloutPool(const RolloutPool&) = delete;
  RolloutPool& operator=(const RolloutPool&) = delete;

  int threads() const { return static_cast<int>(datas_.size()); }

  // n rollouts of `steps` steps. initial: n x StateSize(m) (or one state for all when
  // `shared_initial`); controls: n x steps x nu, or nullptr; policy: optional. Blocks until
  // all are done. Not reentrant: one Run at a time per pool.
  Rollouts Run(const double* initial, int n, const double* controls, const Policy& policy,
               int steps, bool shared_initial = false,
               const RolloutOptions& options = RolloutOptions());

 private:
  void Work(int worker);
  void One(mjData* d, int i);

  const mjModel* m_;
  std::vector<mjData*> datas_;
  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  long generation_ = 0;  // bumped by Run to start the workers
  int busy_ = 0;
  bool stop_ = false;
  // The current Run's job.
  const double* initial_ = nullptr;
  bool shared_initial_ = false;
  const double* controls_ = nullptr;
  const Policy* policy_ = nullptr;
  RolloutOptions options_;
  int n_ = 0, next_ = 0;
  Rollouts* out_ = nullptr;
};

// One-off: a pool for this call only.
Rollouts Rollout(const mjModel* m, const double* initial, int n, const double* controls,
                 const Policy& policy, int steps, int threads = 0, bool shared_initial = false);

}  // namespace mjtether

#endif  // MJTETHER_PLUGIN_ROLLOUT_H_
