// Rollouts on a thread pool (rollout.h).
#include "rollout.h"

#include <sched.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <limits>

#include "mjtether.h"

namespace mjtether {
namespace {

int UsableCores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

// The state's parts: where each is in mjData and how many doubles it has.
struct Part {
  mjtNum* mjData::*field;
  int size;
};

std::vector<Part> Parts(const mjModel* m) {
  return {{&mjData::qpos, m->nq},
          {&mjData::qvel, m->nv},
          {&mjData::act, m->na},
          {&mjData::qacc_warmstart, m->nv},
          {&mjData::ctrl, m->nu},
          {&mjData::qfrc_applied, m->nv},
          {&mjData::xfrc_applied, 6 * m->nbody},
          {&mjData::mocap_pos, 3 * m->nmocap},
          {&mjData::mocap_quat, 4 * m->nmocap},
          {&mjData::userdata, m->nuserdata}};
}

}  // namespace

int StateSize(const mjModel* m) {
  int n = 1;  // time
  for (const Part& p : Parts(m)) n += p.size;
  return n;
}

void GetState(const mjModel* m, const mjData* d, double* state) {
  *state++ = d->time;
  for (const Part& p : Parts(m)) {
    std::memcpy(state, d->*p.field, sizeof(double) * p.size);
    state += p.size;
  }
}

void SetState(const mjModel* m, mjData* d, const double* state) {
  d->time = *state++;
  for (const Part& p : Parts(m)) {
    std::memcpy(d->*p.field, state, sizeof(double) * p.size);
    state += p.size;
  }
}

RolloutPool::RolloutPool(const mjModel* m, int threads) : m_(m) {
  const int t = threads > 0 ? threads : UsableCores();
  for (int w = 0; w < t; ++w) datas_.push_back(mj_makeData(m));
  for (int w = 0; w < t; ++w) threads_.emplace_back(&RolloutPool::Work, this, w);
}

RolloutPool::~RolloutPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : threads_) t.join();
  for (mjData* d : datas_) mj_deleteData(d);
}

// One rollout on a worker's data: reset, the initial state, then per step the controls, the
// policy, the schedules and mj_step, with the checks `mjtether run` makes.
void RolloutPool::One(mjData* d, int i) {
  const mjModel* m = m_;
  Rollouts& r = *out_;
  mj_resetData(m, d);
  SetState(m, d, initial_ + (shared_initial_ ? 0 : size_t(i) * r.nstate));
  int s = 0;
  for (; s < r.steps; ++s) {
    if (controls_)
      std::memcpy(d->ctrl, controls_ + (size_t(i) * r.steps + s) * m->nu, sizeof(double) * m->nu);
    if (*policy_) (*policy_)(m, d, i, s);
    if (options_.prescribe) Prescribe(m, d);
    mj_step(m, d);
    if (std::optional<std::string> diverged = CheckDivergence(m, d)) {
      r.message[i] = *diverged;
      break;
    }
    if (d->warning[mjWARN_BADQACC].number > 0) {
      r.message[i] = "MuJoCo found a bad acceleration at t = " + std::to_string(d->time) +
                     " s and reset the simulation";
      break;
    }
    const size_t row = size_t(i) * r.steps + s;
    r.time[row] = d->time;
    // Pointer arithmetic on data(), not &v[k]: a model without sensors has an empty
    // sensordata vector, and v[0] of an empty vector is undefined (UBSan reports it).
    std::memcpy(r.qpos.data() + row * r.nq, d->qpos, sizeof(double) * r.nq);
    std::memcpy(r.qvel.data() + row * r.nv, d->qvel, sizeof(double) * r.nv);
    if (r.nsensordata > 0)
      std::memcpy(r.sensordata.data() + row * r.nsensordata, d->sensordata,
                  sizeof(double) * r.nsensordata);
    for (int k = 0; k < r.ntether; ++k) {
      const EndReactions e = GetReactions(m, d, k);
      r.tension[(row * r.ntether + k) * 2] = e.tension_a;
      r.tension[(row * r.ntether + k) * 2 + 1] = e.tension_b;
    }
  }
  r.steps_done[i] = s;
  GetState(m, d, &r.final_state[size_t(i) * r.nstate]);
}

void RolloutPool::Work(int worker) {
  long seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    for (;;) {
      int i;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (next_ >= n_) break;
        i = next_++;
      }
      One(datas_[worker], i);
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (--busy_ == 0) done_.notify_all();
  }
}

Rollouts RolloutPool::Run(const double* initial, int n, const double* controls,
                          const Policy& policy, int steps, bool shared_initial,
                          const RolloutOptions& options) {
  const mjModel* m = m_;
  Rollouts r;
  r.n = n;
  r.steps = steps;
  r.nq = m->nq;
  r.nv = m->nv;
  r.nsensordata = m->nsensordata;
  r.ntether = TetherCount(m);
  r.nstate = StateSize(m);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const size_t rows = size_t(n) * steps;
  r.time.assign(rows, nan);
  r.qpos.assign(rows * r.nq, nan);
  r.qvel.assign(rows * r.nv, nan);
  r.sensordata.assign(rows * r.nsensordata, nan);
  r.tension.assign(rows * r.ntether * 2, nan);
  r.final_state.assign(size_t(n) * r.nstate, nan);
  r.steps_done.assign(n, 0);
  r.message.assign(n, "");
  {
    std::lock_guard<std::mutex> lock(mutex_);
    initial_ = initial;
    shared_initial_ = shared_initial;
    controls_ = controls;
    policy_ = &policy;
    options_ = options;
    n_ = n;
    next_ = 0;
    out_ = &r;
    busy_ = threads();
    ++generation_;
  }
  wake_.notify_all();
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [&] { return busy_ == 0; });
  out_ = nullptr;
  policy_ = nullptr;
  return r;
}

Rollouts Rollout(const mjModel* m, const double* initial, int n, const double* controls,
                 const Policy& policy, int steps, int threads, bool shared_initial) {
  RolloutPool pool(m, std::min(threads > 0 ? threads : UsableCores(), std::max(n, 1)));
  return pool.Run(initial, n, controls, policy, steps, shared_initial);
}

}  // namespace mjtether
