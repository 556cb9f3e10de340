// `mjtether run --check-step [F]`: the run compared with the same scene at a step F times smaller.
//
// A tether's answer depends on the MuJoCo step wherever the step does not resolve what happens:
// a snap, a start transient, the vehicle bouncing on a stiff end segment (README, Limitations;
// the scene fuzzer finds about 1 in 100 random scenes off their fine-step selves,
// docs/scene_fuzzer.md). The check makes the comparison that the advisor's messages ask for
// ("compare with a smaller step") part of the run: the scene is loaded a second time with
// option.timestep = h/F (the same overrides otherwise), run on a second thread over the same
// duration, and both runs are compared with the scene fuzzer's criterion (issue 11), applied to
// every window of the run instead of only its last:
//   - each free body's position at the end of every window, within
//     max(kPositionAbs, kPositionRel x the largest initial distance between a tether's ends);
//   - each tether end's tension averaged over every window, within
//     max(kTensionAbs, kTensionRel x the larger of the two);
//   - each tether's peak tension over every step (segments and ends), within the same.
// Windows are kWindow long (longer for very long runs: at most kMaxWindows of them) and a whole
// number of steps of both runs, so both runs' windows cover the same instants. --check-from S
// leaves out the steps before S (a start-up transient that the user discards): windows and the
// peak start there.
//
// The fine run is the reference, not proof: where it is itself unresolved (a snap shorter than
// h/F) both can be wrong together. It costs about F times the run.
#ifndef MJTETHER_CLI_STEP_CHECK_H_
#define MJTETHER_CLI_STEP_CHECK_H_

#include <mujoco/mujoco.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_common.h"  // StopSignal
#include "mjtether.h"
#include "step_check.h"

namespace mjtether::cli::check {

constexpr double kWindow = 0.2;        // [s] the tension means' window (the scene fuzzer's)
constexpr long long kMaxWindows = 100000;  // windows grow beyond kWindow in longer runs
constexpr double kPositionAbs = 0.05;  // [m]
constexpr double kPositionRel = 0.02;  // of the largest initial span between a tether's ends
constexpr double kTensionAbs = 0.5;    // [N]
constexpr double kTensionRel = 0.05;   // of the larger of the two tensions
constexpr int kMaxFactor = 1000;       // --check-step F in [2, kMaxFactor]

// The steps of the coarse run in one window: a whole number, at least one.
inline long long StepsPerWindow(double h, double duration) {
  const double window = std::max(kWindow, duration / kMaxWindows);
  return std::max(1LL, std::llround(window / h));
}

// What one run records: at the end of every window each free body's position and each tether
// end's mean tension over the window; over the whole run each tether's peak tension.
struct Trace {
  std::vector<double> window_start, window_end;  // [s] per window
  std::vector<double> position;    // [m] per window, bodies x 3
  std::vector<double> mean;        // [N] per window, tethers x 2 (ends A, B)
  std::vector<double> peak;        // [N] per tether, over every step
  std::vector<double> peak_time;   // [s] per tether (the tether's time at that step)
  std::vector<double> span;        // [m] per tether, the ends' distance at the start
  double end_time = 0;             // [s] where the run ended
  std::optional<std::string> stop;  // why it stopped early (StepAndCheck's message)
  bool interrupted = false;         // by a signal or because the other run was
  // The run's own end-of-run warnings (StallWarnings, RingWarnings), as `mjtether run` prints
  // them for itself: a fine run that stalled or rang is a weaker reference, and says so.
  std::vector<std::string> warnings;
};

class Recorder {
 public:
  // `steps_per_window` steps of this run make one window; the first `skip` steps are not
  // compared (--check-from: a start-up transient).
  Recorder(const mjModel* m, const std::vector<int>& bodies, long long steps_per_window,
           long long skip)
      : bodies_(bodies),
        ntether_(TetherCount(m)),
        steps_per_window_(steps_per_window),
        skip_(skip) {
    int n = 0;
    for (int k = 0; k < ntether_; ++k) n = std::max(n, GetTether(m, k)->segments());
    tensions_.resize(n);
    sum_.assign(2 * ntether_, 0.0);
    trace_.peak.assign(ntether_, 0.0);
    trace_.peak_time.assign(ntether_, 0.0);
  }

  // Before the first step, on a state brought to d->time (mj_forward): the ends' distance.
  void Start(const mjModel* m, const mjData* d) {
    trace_.span.clear();
    for (int k = 0; k < ntether_; ++k) {
      const double* x = NodePositions(m, d, k);
      const WinchState w = GetWinch(m, d, k);
      const int first = w.present ? w.first_node : 0, last = GetTether(m, k)->nodes() - 1;
      double s = 0;
      for (int a = 0; a < 3; ++a) s += (x[3 * last + a] - x[3 * first + a]) * (x[3 * last + a] - x[3 * first + a]);
      trace_.span.push_back(std::sqrt(s));
    }
  }

  // After each mj_step. The end tensions are the reactions of the step's callback (at its
  // start), as the run's --summary reads them; both runs read them the same way.
  void AfterStep(const mjModel* m, const mjData* d) {
    trace_.end_time = d->time;
    if (skip_ > 0) {
      --skip_;
      return;
    }
    for (int k = 0; k < ntether_; ++k) {
      const EndReactions r = GetReactions(m, d, k);
      sum_[2 * k] += r.tension_a;
      sum_[2 * k + 1] += r.tension_b;
      GetTensions(m, d, k, tensions_.data());
      double peak = std::max(r.tension_a, r.tension_b);
      for (int j = 0; j < GetTether(m, k)->segments(); ++j) peak = std::max(peak, tensions_[j]);
      if (peak > trace_.peak[k]) trace_.peak[k] = peak, trace_.peak_time[k] = TetherTime(m, d, k);
    }
    if (count_++ == 0) trace_.window_start.push_back(d->time - m->opt.timestep);
    if (count_ == steps_per_window_) Close(m, d);
  }

  // At the end of the run: the last, partial window.
  void Finish(const mjModel* m, const mjData* d) {
    if (count_ > 0) Close(m, d);
  }

  Trace& trace() { return trace_; }

 private:
  void Close(const mjModel* m, const mjData* d) {
    trace_.window_end.push_back(d->time);
    for (int b : bodies_) {
      // A free joint's qpos is its body's position in the world, at d->time.
      const double* q = d->qpos + m->jnt_qposadr[m->body_jntadr[b]];
      trace_.position.insert(trace_.position.end(), q, q + 3);
    }
    for (double& s : sum_) trace_.mean.push_back(s / count_), s = 0;
    count_ = 0;
  }

  std::vector<int> bodies_;
  int ntether_;
  long long steps_per_window_, skip_, count_ = 0;
  std::vector<double> tensions_, sum_;
  Trace trace_;
};

// Runs `steps` steps of m (the fine run, on its own thread) and records them; `progress` is its
// time, `done` set at the end. Stops early on a divergence (StepAndCheck), a signal (SIGINT or
// SIGTERM, StopSignal), or `cancel`.
inline void RunFine(const mjModel* m, long long steps, const std::vector<int>& bodies,
                    long long steps_per_window, long long skip, const std::string& model,
                    const std::atomic<bool>& cancel, std::atomic<double>* progress,
                    std::atomic<bool>* done, Trace* out) {
  mjData* d = mj_makeData(m);
  Recorder rec(m, bodies, steps_per_window, skip);
  Prescribe(m, d);
  {  // the start, on a copy brought to t = 0 (d itself is stepped as the run's is)
    mjData* start = mj_copyData(nullptr, m, d);
    mj_forward(m, start);
    rec.Start(m, start);
    mj_deleteData(start);
  }
  for (long long i = 0; i < steps; ++i) {
    if (cancel.load(std::memory_order_relaxed) || StopSignal()) {
      rec.trace().interrupted = true;
      break;
    }
    if (std::optional<std::string> stop = StepAndCheck(m, d, model)) {
      rec.trace().stop = *stop;
      break;
    }
    rec.AfterStep(m, d);
    progress->store(d->time, std::memory_order_relaxed);
  }
  rec.Finish(m, d);
  *out = std::move(rec.trace());
  out->warnings = RunWarnings(m, d);
  mj_deleteData(d);
  done->store(true);
}

struct Verdict {
  bool agrees = true;
  std::string report;  // one line per compared quantity, each ending in '\n'
  std::string first_failure;  // the first quantity beyond its tolerance, for the summary line
};

inline double TensionTolerance(double a, double b) {
  return std::max(kTensionAbs, kTensionRel * std::max(std::abs(a), std::abs(b)));
}

// Compares the windows that both runs completed. `body_names` and `tether_names` name them.
inline Verdict Compare(const Trace& coarse, const Trace& fine,
                       const std::vector<std::string>& body_names,
                       const std::vector<std::string>& tether_names) {
  Verdict v;
  const size_t nb = body_names.size(), nt = tether_names.size();
  const size_t windows = std::min(coarse.window_end.size(), fine.window_end.size());
  double span = 0;
  for (double s : coarse.span) span = std::max(span, s);
  const double tol_x = std::max(kPositionAbs, kPositionRel * span);
  std::ostringstream r;
  r.precision(4);
  auto fail = [&](const std::string& what) {
    if (v.agrees) v.first_failure = what;
    v.agrees = false;
  };
  for (size_t b = 0; b < nb; ++b) {
    double worst = 0, when = 0;
    for (size_t w = 0; w < windows; ++w) {
      double s = 0;
      for (int a = 0; a < 3; ++a) {
        const double e = coarse.position[(w * nb + b) * 3 + a] - fine.position[(w * nb + b) * 3 + a];
        s += e * e;
      }
      if (std::sqrt(s) > worst) worst = std::sqrt(s), when = coarse.window_end[w];
    }
    std::ostringstream line;
    line.precision(4);
    line << "body '" << body_names[b] << "': position off by " << worst << " m at most";
    if (worst > 0) line << " (t = " << when << " s)";
    line << "; tolerance " << tol_x << " m";
    r << "  " << line.str() << (worst > tol_x ? "  EXCEEDED" : "") << "\n";
    if (worst > tol_x) fail(line.str());
  }
  for (size_t k = 0; k < nt; ++k) {
    for (int end = 0; end < 2; ++end) {
      double worst = -1, c = 0, f = 0, from = 0, to = 0;  // the window most beyond tolerance
      for (size_t w = 0; w < windows; ++w) {
        const double a = coarse.mean[w * nt * 2 + 2 * k + end], b = fine.mean[w * nt * 2 + 2 * k + end];
        const double excess = std::abs(a - b) / TensionTolerance(a, b);
        if (excess > worst) {
          worst = excess, c = a, f = b;
          from = coarse.window_start[w], to = coarse.window_end[w];
        }
      }
      if (worst < 0) continue;
      std::ostringstream line;
      line.precision(4);
      line << "tether '" << tether_names[k] << "' end " << (end == 0 ? 'A' : 'B')
           << ": mean tension " << c << " N against " << f << " N over " << from << "-" << to
           << " s (the window farthest off); tolerance " << TensionTolerance(c, f) << " N";
      r << "  " << line.str() << (worst > 1 ? "  EXCEEDED" : "") << "\n";
      if (worst > 1) fail(line.str());
    }
    const double c = coarse.peak[k], f = fine.peak[k];
    std::ostringstream line;
    line.precision(4);
    line << "tether '" << tether_names[k] << "': peak tension " << c << " N (t = "
         << coarse.peak_time[k] << " s) against " << f << " N (t = " << fine.peak_time[k]
         << " s); tolerance " << TensionTolerance(c, f) << " N";
    const bool over = std::abs(c - f) > TensionTolerance(c, f);
    r << "  " << line.str() << (over ? "  EXCEEDED" : "") << "\n";
    if (over) fail(line.str());
  }
  v.report = r.str();
  return v;
}

}  // namespace mjtether::cli::check

#endif  // MJTETHER_CLI_STEP_CHECK_H_
