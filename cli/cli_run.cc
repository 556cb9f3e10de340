// `mjtether run` and `mjtether info`.
//
//   mjtether run MODEL.xml --duration S [--log FILE.csv] [--nodes FILE.csv] [--every S]
//   mjtether info MODEL.xml [--set TEXT.KEY=VALUE]...
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_command.h"
#include "cli_common.h"
#include "cli_run_summary.h"
#include "cli_step_check.h"
#include "step_check.h"
#include "declaration.h"
#include "mjtether.h"
#include "overrides.h"

namespace {

struct RunOptions {
  std::string model;
  double duration = 0;
  std::string log;
  std::string nodes;
  double every = 0.1;
  std::vector<std::string> set;  // TEXT.KEY=VALUE overrides (overrides.h)
  std::string summary;           // one-row CSV about the whole run (cli_run_summary.h)
  int digits = 9;  // significant digits of the CSV numbers (17 round-trips a double)
  int check_step = 0;  // F: also run at h/F and compare (cli_step_check.h); 0: no check
  double check_from = 0;  // [s] the comparison starts here (a start-up transient before it)
};

// Bodies with a free joint: the vehicles whose position the log records.
std::vector<int> FreeBodies(const mjModel* m) {
  std::vector<int> bodies;
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] == mjJNT_FREE) bodies.push_back(m->jnt_bodyid[j]);
  }
  return bodies;
}

std::string BodyName(const mjModel* m, int b) {
  const char* name = mj_id2name(m, mjOBJ_BODY, b);
  return name && *name ? name : "body" + std::to_string(b);
}

// The step check's verdict (cli_step_check.h), printed; returns the run's exit status: `status`
// (0 or 1) where the check has nothing to add, kExitCheck where the run at h/F disagrees or
// stopped where this one ran on.
int ReportCheck(const RunOptions& opt, const mjModel* m, double end_time,
                const mjtether::cli::check::Trace& coarse,
                const mjtether::cli::check::Trace& fine, const std::vector<int>& bodies,
                int status, double fine_step, bool rang) {
  using namespace mjtether::cli;
  const std::string head = "mjtether: --check-step " + std::to_string(opt.check_step) + ": ";
  std::ostringstream at;
  at.precision(6);
  at << "--set option.timestep=" << fine_step;
  // The fine run's own warnings first: a reference that stalled or rang says so (the verdict
  // below compares with it all the same).
  if (!fine.interrupted) {
    for (const std::string& w : fine.warnings) {
      std::cerr << head << "the run at h/" << opt.check_step << ": warning: " << w << "\n";
    }
  }
  if (status == kExitDiverged) {
    // The run stopped: where did the same scene at h/F get to?
    if (fine.stop) {
      std::cerr << head << "at h/" << opt.check_step << " the scene stopped too, at t = "
                << fine.end_time << " s: the cause is not (only) the step\n";
    } else if (!fine.interrupted) {
      std::cerr << head << "at h/" << opt.check_step << " the scene ran to t = "
                << fine.end_time << " s: the step is the cause; run it with " << at.str()
                << "\n";
    }
    return status;
  }
  if (fine.stop) {
    std::cerr << head << "the same scene at h/" << opt.check_step << " stopped at t = "
              << fine.end_time << " s where this run went on to " << end_time
              << " s; this run is not confirmed:\n  " << *fine.stop << "\n";
    return kExitCheck;
  }
  std::vector<std::string> body_names, tether_names;
  for (int b : bodies) body_names.push_back(BodyName(m, b));
  for (int k = 0; k < mjtether::TetherCount(m); ++k) {
    tether_names.push_back(mjtether::TetherName(m, k));
  }
  const check::Verdict v = check::Compare(coarse, fine, body_names, tether_names);
  std::cerr << head << "against the same scene at h/" << opt.check_step << " (" << fine_step
            << " s), over " << coarse.window_end.size() << " window(s)"
            << (opt.check_from > 0 ? " from t = " : "");
  if (opt.check_from > 0) std::cerr << opt.check_from << " s";
  std::cerr << ":\n"
            << v.report;
  if (v.agrees) {
    std::cerr << head << "agrees within every tolerance\n";
    return status;
  }
  std::cerr << head << "DISAGREES: " << v.first_failure
            << ". This run's result depends on its step (its outputs are kept); ";
  if (rang) {
    // The ringing segment mode is resolved at neither step where its ratio is 0 (a finer step
    // converges in time but not in the segments: docs/reference.md, "Internal damping").
    std::cerr << "a snap rang its undamped segment mode (warning above): declare "
                 "damping_ratio=1 on the tether, with which the two steps agree where the "
                 "ringing was the cause, or use the smaller step ("
              << at.str() << ") (docs/step_check.md)\n";
  } else {
    std::cerr << "use the smaller step (" << at.str()
              << ") where it matters (docs/step_check.md)\n";
  }
  return kExitCheck;
}

// Whether a warning says that the run's outcome depends on its step and asks for the comparison
// that --check-step makes.
bool AsksForTheStepCheck(const std::string& warning) {
  return warning.find("compare with a smaller") != std::string::npos ||
         warning.find("10x smaller step") != std::string::npos;
}

void NoteTheStepCheck() {
  std::cerr << "mjtether: note: --check-step 10 makes that comparison: it runs the scene also at "
               "h/10 and says whether this run is off (docs/step_check.md)\n";
}

int Run(const RunOptions& opt) {
  using namespace mjtether::cli;
  using mjtether::CsvField;
  InstallStopHandlers();
  std::vector<mjtether::Override> overrides;
  if (!ParseSets(opt.set, &overrides)) return kExitBadInput;
  if (opt.check_step > 0 && !(opt.check_from < opt.duration)) {
    std::cerr << "mjtether: --check-from " << opt.check_from << " s leaves nothing to compare: "
              << "it must be below --duration " << opt.duration << " s\n";
    return kExitBadInput;
  }
  ModelPtr m = LoadChecked(opt.model, overrides);
  if (!m) return kExitBadInput;
  // A load warning that says the outcome depends on the step (a stretched start, a thrust near
  // what the tether holds, a held end force) asks for a comparison that --check-step makes; so
  // does a run warning (a snap that rang, at the run's end), noted there unless noted here.
  bool check_noted = false;
  if (opt.check_step == 0) {
    for (const std::string& w : mjtether::Warnings(m.get())) {
      if (AsksForTheStepCheck(w)) {
        NoteTheStepCheck();
        check_noted = true;
        break;
      }
    }
  }
  // --check-step F: the same scene at h/F (the same overrides, then the step), loaded now so
  // that a refusal comes before any output is opened. Its load warnings are the run's.
  ModelPtr fine_model;
  if (opt.check_step > 0) {
    std::vector<mjtether::Override> fine_overrides = overrides;
    std::ostringstream step;
    step.precision(17);
    step << m->opt.timestep / opt.check_step;
    fine_overrides.push_back({"option", "timestep", step.str()});
    std::string error;
    fine_model.reset(mjtether::LoadModel(opt.model, fine_overrides, &error));
    if (!fine_model) {
      std::cerr << "mjtether: --check-step " << opt.check_step << ": at the step "
                << step.str() << " s the scene cannot be loaded: " << error << "\n";
      return kExitBadInput;
    }
  }
  // Every output is claimed and opened (as a temporary file) before the run: a bad second path
  // leaves the first untouched, and no output may be an input or the other output.
  OutputGuard guard;
  guard.AddModel(opt.model, m.get());
  OutputFile log, nodes;
  std::string error;
  if ((!opt.log.empty() && !log.Open(opt.log, "--log", &guard, &error)) ||
      (!opt.nodes.empty() && !nodes.Open(opt.nodes, "--nodes", &guard, &error))) {
    std::cerr << "mjtether: " << error << "\n";
    return kExitBadInput;
  }
  // --summary is written at the end, but claimed now: it may not be an input or another output.
  if (!opt.summary.empty() && !guard.Claim(opt.summary, "--summary", &error)) {
    std::cerr << "mjtether: " << error << "\n";
    return kExitBadInput;
  }
  DataPtr data = MakeData(m.get());
  mjData* d = data.get();
  const mjModel* mm = m.get();
  const double h = mm->opt.timestep;
  const std::vector<int> bodies = FreeBodies(mm);
  const int ntether = mjtether::TetherCount(mm);
  if (opt.every < h && (log.is_open() || nodes.is_open())) {
    std::cerr << "mjtether: warning: --every " << opt.every << " s is below the time step " << h
              << " s: sampling every step\n";
  }

  if (log.is_open()) {
    std::string head = "time";
    for (int b : bodies) {
      const std::string n = BodyName(mm, b);
      for (const char* axis : {".x", ".y", ".z"}) head += "," + CsvField(n + axis);
    }
    for (int k = 0; k < ntether; ++k) {
      const std::string n = mjtether::TetherName(mm, k);
      for (const char* column : {".tension_A", ".tension_B", ".tension_max", ".slack_segments"}) {
        head += "," + CsvField(n + column);
      }
      // A winch (docs/winch.md): deployed unstretched length [m] and payout speed [m/s].
      if (mjtether::GetWinch(mm, d, k).present) {
        for (const char* column : {".length", ".payout_speed"}) head += "," + CsvField(n + column);
      }
    }
    log.Write(head + "\n");
  }
  if (nodes.is_open()) nodes.Write("time,tether,node,x,y,z,tension\n");

  // A sample reads the state at d->time from a copy brought there by mj_forward: the run itself
  // is the same whatever is logged and how often (Observer).
  Observer observer(mm);
  std::vector<double> T;
  long long rows = 0;
  double last_row_time = 0;
  auto sample = [&]() {
    const mjData* o = observer.Observe(d);
    std::ostringstream row;
    row.precision(opt.digits);
    if (log.is_open()) {
      row << o->time;
      for (int b : bodies) {
        row << "," << o->xpos[3 * b] << "," << o->xpos[3 * b + 1] << "," << o->xpos[3 * b + 2];
      }
      for (int k = 0; k < ntether; ++k) {
        const mjtether::EndReactions r = mjtether::GetReactions(mm, o, k);
        T.resize(mjtether::GetTether(mm, k)->segments());
        mjtether::GetTensions(mm, o, k, T.data());
        double tmax = 0;
        int slack = 0;
        const mjtether::WinchState w = mjtether::GetWinch(mm, o, k);
        for (size_t j = w.present ? w.first_node : 0; j < T.size(); ++j) {  // deployed only
          tmax = std::max(tmax, T[j]);
          slack += T[j] <= 0;
        }
        row << "," << r.tension_a << "," << r.tension_b << "," << tmax << "," << slack;
        if (w.present) row << "," << w.length << "," << w.payout_speed;
      }
      row << "\n";
      log.Write(row.str());
    }
    if (nodes.is_open()) {
      for (int k = 0; k < ntether; ++k) {
        const mjtether::Tether* t = mjtether::GetTether(mm, k);
        const double* x = mjtether::NodePositions(mm, o, k);
        const std::string name = CsvField(mjtether::TetherName(mm, k));
        T.resize(t->segments());
        mjtether::GetTensions(mm, o, k, T.data());
        std::ostringstream rows_k;
        rows_k.precision(opt.digits);
        const mjtether::WinchState w = mjtether::GetWinch(mm, o, k);
        for (int i = w.present ? w.first_node : 0; i < t->nodes(); ++i) {  // deployed only
          rows_k << o->time << "," << name << "," << i << "," << x[3 * i] << "," << x[3 * i + 1]
                 << "," << x[3 * i + 2] << "," << T[std::min(i, t->segments() - 1)] << "\n";
        }
        nodes.Write(rows_k.str());
      }
    }
    ++rows;
    last_row_time = o->time;
  };

  // Samples at t_k = k * every, scheduled by step index so that no time is accumulated.
  const long long steps = std::llround(opt.duration / h);
  const double every = std::max(opt.every, h);
  long long next_sample = 0, sample_index = 0;
  std::optional<mjtether::cli::RunSummary> run_summary;
  if (!opt.summary.empty()) run_summary.emplace(mm);
  const auto start = std::chrono::steady_clock::now();
  int status = kExitOk;
  bool stall_noticed = false;
  // The step check's fine run, on a second thread (cli_step_check.h).
  std::optional<check::Recorder> recorder;
  check::Trace fine_trace;
  std::atomic<bool> cancel_fine{false}, fine_done{false};
  std::atomic<double> fine_progress{0};  // [s] the fine run's time
  std::thread fine_thread;
  const long long per_window = check::StepsPerWindow(h, opt.duration - opt.check_from);
  if (fine_model) {
    std::cerr << "mjtether: --check-step " << opt.check_step << ": the scene runs also at h/"
              << opt.check_step << " = " << fine_model->opt.timestep
              << " s on a second thread, about " << opt.check_step << "x the cost\n";
    const long long skip = std::min(steps, std::llround(opt.check_from / h));
    recorder.emplace(mm, bodies, per_window, skip);
    mjtether::Prescribe(mm, d);
    recorder->Start(mm, observer.Observe(d));
    fine_thread = std::thread(check::RunFine, fine_model.get(), steps * opt.check_step,
                              std::cref(bodies), per_window * opt.check_step,
                              skip * opt.check_step, std::cref(opt.model),
                              std::cref(cancel_fine), &fine_progress, &fine_done, &fine_trace);
  }
  for (long long i = 0;; ++i) {
    mjtether::Prescribe(mm, d);  // motion: and thrust: declarations at d->time
    if (i == next_sample) {
      sample();
      ++sample_index;
      next_sample = std::llround(sample_index * every / h);
      if (log.failed() || nodes.failed()) break;  // a write failed: reported below (exit 5)
    }
    if (i == steps) break;
    if (const int signal = StopSignal()) {
      std::cerr << "mjtether: " << opt.model << ": " << Interrupted(signal, d->time, i, steps);
      if (rows > 0)
        std::cerr << "; the outputs keep " << rows << " sample(s) up to t = " << last_row_time
                  << " s";
      std::cerr << "\n";
      status = 128 + signal;
      break;
    }
    if (std::optional<std::string> stop = StepAndCheck(mm, d, opt.model)) {
      std::cerr << "mjtether: " << *stop << "\n";
      status = kExitDiverged;
      break;
    }
    if (run_summary) run_summary->Observe(mm, d);
    if (recorder) recorder->AfterStep(mm, d);
    // Stalled implicit steps make a run slow: said once, as soon as seen (the check costs a
    // look at each tether's counter; the full warning with the count comes at the end).
    if (!stall_noticed) {
      for (const std::string& w : mjtether::StallWarnings(mm, d, /*early=*/true)) {
        std::cerr << "mjtether: note: " << w << "\n";
        stall_noticed = true;
      }
    }
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (recorder) {
    recorder->Finish(mm, d);
    // A signal or a failed write: the fine run stops too (a divergence lets it run on, to say
    // whether the step was the cause).
    if (status != kExitOk && status != kExitDiverged) cancel_fine = true;
  }
  // Implicit steps that did not converge, snaps that rang: once per run, at its end (README,
  // Numerics; docs/reference.md "Internal damping").
  for (const std::string& w : mjtether::RunWarnings(mm, d)) {
    std::cerr << "mjtether: warning: " << w << "\n";
    if (opt.check_step == 0 && !check_noted && AsksForTheStepCheck(w)) {
      NoteTheStepCheck();
      check_noted = true;
    }
  }
  const bool rang = !mjtether::RingWarnings(mm, d).empty();  // for the step check's advice
  for (OutputFile* f : {&log, &nodes}) {
    if (!f->Commit(&error)) {
      std::cerr << "mjtether: " << error << "\n";
      if (status == kExitOk) status = kExitOutput;
    }
  }
  if (status == kExitOk) {
    std::cerr << "mjtether: simulated " << d->time << " s in " << wall << " s wall ("
              << (wall > 0 ? d->time / wall : 0) << "x real time)";
    if (!opt.log.empty()) std::cerr << "; log: " << opt.log;
    std::cerr << "\n";
  }
  // The summary observes the final state as the last log row does (brought to d->time on a copy).
  if (run_summary && !run_summary->Write(opt.summary, mm, observer.Observe(d))) {
    std::cerr << "mjtether: output error: cannot write --summary " << opt.summary << "\n";
    status = status ? status : kExitOutput;
  }
  if (recorder) {
    // The run's outputs are complete; the run at h/F may take F times longer: say so at once
    // (the user sees why the program has not exited), then its progress every 10 s; a signal
    // stops it.
    const auto waiting = std::chrono::steady_clock::now();
    int said = 0, signal = 0;
    if (!fine_done.load())
      std::cerr << "mjtether: --check-step " << opt.check_step << ": this run's outputs are "
                << "complete; waiting for the run at h/" << opt.check_step << " (Ctrl-C stops "
                << "it): the run at h/" << opt.check_step << " is at t = "
                << fine_progress.load() << " of " << steps * h << " s\n";
    while (!fine_done.load()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      if (!signal && StopSignal()) signal = StopSignal(), cancel_fine = true;
      const double waited =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - waiting).count();
      if (!signal && waited >= 10 * (said + 1)) {
        ++said;
        std::cerr << "mjtether: --check-step " << opt.check_step << ": the run at h/"
                  << opt.check_step << " is at t = " << fine_progress.load() << " of "
                  << steps * h << " s\n";
      }
    }
    fine_thread.join();
    if (signal && status <= kExitDiverged) {
      std::cerr << "mjtether: --check-step " << opt.check_step << ": interrupted by "
                << (signal == SIGINT ? "SIGINT" : "SIGTERM") << " while the run at h/"
                << opt.check_step << " was at t = " << fine_progress.load()
                << " s; nothing was compared (this run's outputs are complete)\n";
      return 128 + signal;
    }
    if (status <= kExitDiverged) {
      status = ReportCheck(opt, mm, d->time, recorder->trace(), fine_trace, bodies, status,
                           fine_model->opt.timestep, rang);
    }
  }
  return status;
}

int Info(const std::string& path, const std::vector<std::string>& set) {
  std::vector<mjtether::Override> overrides;
  if (!mjtether::cli::ParseSets(set, &overrides)) return mjtether::cli::kExitBadInput;
  mjtether::cli::ModelPtr owner = mjtether::cli::LoadChecked(path, overrides);
  if (!owner) return mjtether::cli::kExitBadInput;
  const mjModel* m = owner.get();
  std::cout << path << ": timestep " << m->opt.timestep << " s, "
            << mjtether::TetherCount(m) << " tether(s)\n";
  for (int k = 0; k < mjtether::TetherCount(m); ++k) {
    const mjtether::Tether* t = mjtether::GetTether(m, k);
    const mjtether::TetherParams& p = t->params();
    std::cout << "  tether '" << mjtether::TetherName(m, k) << "': " << p.segments
              << " segments of " << t->rest_segment_length() << " m, "
              << mjtether::IntegratorName(p.integrator)
              << ", effects " << mjtether::EffectsToString(p.effects) << ", start "
              << mjtether::StartName(p.start)
              << (p.start == mjtether::Start::kStatic ? " (relaxed to static equilibrium)"
                                                      : " (engine catenary, at rest)")
              << "\n"
              << "    " << (p.integrator == mjtether::Integrator::kRK4 ? "rk4" : "explicit")
              << " stable step " << t->ExplicitStableStep() << " s; "
              << t->SubstepsFor(m->opt.timestep) << " tether step(s) per MuJoCo step\n";
    if (p.start == mjtether::Start::kStatic) {
      const mjtether::StaticResult r = mjtether::GetStaticStart(m, k);
      std::cout << "    static start: " << (r.converged ? "converged" : "NOT converged") << " in "
                << r.iterations << " pseudo step(s), last displacement " << r.displacement
                << " m, largest residual force " << r.residual << " N at node " << r.node
                << " (load " << r.load << " N), last pseudo step " << r.final_step << " s\n";
    }
    // The time-step advisor's limits, each on its own line (docs/coupling.md).
    const mjtether::Tether::StabilityTerms& st = t->stability_terms();
    std::cout << "    stable step from: axial omega " << st.w_axial << " rad/s";
    if (st.w_bending > 0) std::cout << ", bending omega " << st.w_bending << " rad/s";
    if (st.w_seabed > 0) std::cout << ", seabed omega " << st.w_seabed << " rad/s";
    std::cout << ", damping rate " << st.rate << " 1/s\n";
    // The segment axial mode (docs/reference.md "Internal damping"): the ringing after a snap
    // that an implicit step damps and a smaller one resolves, and whose energy an explicit
    // scheme keeps as the step left it (RingWarnings at a run's end).
    const double h_tether = m->opt.timestep / std::max(1, t->SubstepsFor(m->opt.timestep));
    std::cout << "    segment axial mode: omega_n " << t->SegmentModeFrequency()
              << " rad/s, omega_n h " << t->SegmentModeFrequency() * h_tether
              << ", damping ratio " << t->SegmentModeRatio();
    if (t->StepsAsBackwardEuler()) {
      std::cout << " (above " << t->SecondOrderMaxDampingRatio()
                << ": this tether steps as backward Euler)";
    }
    std::cout << (!mjtether::WatchesRinging(*t, m->opt.timestep) ? ""
                  : mjtether::IsExplicit(t->params().integrator)
                      ? " (undamped: the substeps keep a snap's ringing, with an energy that "
                        "depends on the step, which makes the tensions depend on it; "
                        "damping_ratio=1 damps it)"
                      : " (undamped but for the step's numerical damping: a snap's ringing makes "
                        "the tensions depend on the step; damping_ratio=1 damps it)")
              << "\n";
    // The whole line's lowest axial mode, ends held: the chain's omega_k = omega_n sin(k pi /
    // 2N), k = 1, and, Kelvin-Voigt damping being proportional to the stiffness, its damping
    // ratio zeta_k = zeta_n sin(k pi / 2N) (= c omega_k / (2 EA)). damping_ratio damps the
    // segment mode; this one keeps ringing after a start or a snap, and where it slackens the
    // line the snap train it makes is chaotic (docs/reference.md "Internal damping").
    const double lowest = std::sin(M_PI / (2.0 * t->segments()));  // [-] omega_1 / omega_n
    const double w1 = t->SegmentModeFrequency() * lowest;          // [rad/s]
    std::cout << "    lowest axial mode (ends held): omega_1 " << w1 << " rad/s (period "
              << 2 * M_PI / w1 << " s), damping ratio " << t->SegmentModeRatio() * lowest
              << "\n";
    const double cost = mjtether::EstimatedCostPerSecond(*t, m->opt.timestep);
    std::cout << "    estimated cost " << cost << " s of CPU per simulated second ("
              << (cost > 0 ? 1 / cost : 0) << "x real time)\n";
    for (int end = 0; end < 2; ++end) {
      const mjtether::CouplingLimit c = mjtether::GetCouplingLimit(m, k, end);
      if (c.body < 0) continue;
      std::cout << "    coupling at end " << (end == 0 ? "A" : "B") << " (body '"
                << BodyName(m, c.body) << "'): k_end = " << mjtether::EndStiffnessName(c)
                << " = " << c.k_end
                << " N/m, m_eff = " << c.m_eff << " kg, omega = " << c.omega
                << " rad/s, omega h = " << c.omega_h;
      if (c.damping_h > 0) std::cout << ", h damping/(L0 m_eff) = " << c.damping_h;
      if (c.seabed_omega_h > 0) {
        std::cout << ", the seabed under the end node: omega h = " << c.seabed_omega_h
                  << ", h c/m_eff = " << c.seabed_damping_h;
      }
      if (c.consistent) {
        std::cout << "; consistent coupling (end node B solved with the body in the tether's "
                     "step)";
        if (c.heavy_node) {
          std::cout << ", end node B (" << c.m_node
                    << " kg with its added mass) outweighing m_eff";
        }
        // SlowModeCorrection (plugin/plugin.cc): not on a winch.
        if (!p.winch) std::cout << ", its damping of slow modes on a taut line corrected";
      } else if (c.omega_h > 0) {
        std::cout << "; held end force";
      }
      if (c.applies) {
        std::cout << "; limit " << c.limit;
      } else if (c.consistent) {
        std::cout << "; no limit";
      } else {
        std::cout << "; no limit for " << mjtether::IntegratorName(p.integrator) << " (explicit "
                  << mjtether::kCouplingLimitExplicit << ", rk4 " << mjtether::kCouplingLimitRk4
                  << ", implicit2 " << mjtether::kCouplingLimitImplicit2 << ")";
      }
      std::cout << "\n";
      // The body bouncing on the whole taut line (BounceMode, RingWarnings' bounce watch).
      const mjtether::BounceMode b = mjtether::GetBounceMode(m, k, end);
      std::cout << "      body bounce on the whole line: omega = sqrt(EA/(L (m_eff + mu L/3))) = "
                << b.omega
                << " rad/s, omega h = " << b.omega_h << ", damping ratio " << b.ratio
                << (b.watched         ? " (snaps and swings watched)"
                    : b.swing_watched ? " (swings watched)"
                                      : "")
                << "\n";
    }
  }
  // Vehicles: net buoyancy and how the added mass is split (README, Vehicles).
  for (int v = 0; v < mjtether::VehicleCount(m); ++v) {
    const mjtether::Vehicle* veh = mjtether::GetVehicle(m, v);
    const int b = mjtether::VehicleBody(m, v);
    const double mass = m->body_subtreemass[b];
    const double net = veh->Buoyancy().norm() - mass * mju_norm3(m->opt.gravity);
    std::cout << "  vehicle '" << mj_id2name(m, mjOBJ_BODY, b) << "': " << mass << " kg, net "
              << (net >= 0 ? "buoyancy " : "weight ") << std::abs(net)
              << " N; added mass in the armature " << veh->armature_translation()
              << " kg (translation), explicit remainder up to "
              << veh->explicit_added_mass().maxCoeff() << " kg (ratio "
              << veh->explicit_added_mass().maxCoeff() / (mass + veh->armature_translation())
              << " of m + a_iso; limit " << mjtether::Vehicle::kMaxExplicitRatio << ")\n";
  }
  return 0;
}

}  // namespace

namespace {

std::function<int()> SetupRun(CLI::App* sub) {
  auto opt = std::make_shared<RunOptions>();
  sub->add_option("model", opt->model, "MJCF file declaring the tethers")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--duration", opt->duration, "simulated time [s]")
      ->required()
      ->check(mjtether::cli::Number(0, 1e7, false, "s"));
  sub->add_option("--log", opt->log, "CSV: time, free bodies' positions, end tensions");
  sub->add_option("--nodes", opt->nodes, "CSV: time,tether,node,x,y,z,tension");
  sub->add_option("--every", opt->every, "sampling interval of both CSV files [s]")
      ->check(mjtether::cli::Number(0, 1e7, true, "s"));
  sub->add_option("--digits", opt->digits,
                  "significant digits of the CSV numbers (default 9; 17 is exact)")
      ->check(mjtether::cli::Count(1, 17));
  mjtether::cli::AddSetOption(sub, &opt->set);
  sub->add_option("--summary", opt->summary,
                  "CSV row: peak tension over every step, the vehicle's final pose");
  CLI::Option* check_step = sub->add_option("--check-step", opt->check_step,
                  "also run the scene at a step F times smaller (on a second thread) and "
                  "compare: bodies within max(5 cm, 2% of the span), window means and peak "
                  "tensions within max(0.5 N, 5%); exit 6 where they disagree (10 is usual)")
      ->check(mjtether::cli::Count(2, mjtether::cli::check::kMaxFactor));
  sub->add_option("--check-from", opt->check_from,
                  "with --check-step: compare from this time on, leaving out a start-up "
                  "transient [s] (default 0)")
      ->check(mjtether::cli::Number(0, 1e7, false, "s"))
      ->needs(check_step);
  return [opt]() { return Run(*opt); };
}

std::function<int()> SetupInfo(CLI::App* sub) {
  auto model = std::make_shared<std::string>();
  auto set = std::make_shared<std::vector<std::string>>();
  sub->add_option("model", *model, "MJCF file")->required()->check(CLI::ExistingFile);
  // The same overrides as run: what the advisor says at another step or with another EA.
  mjtether::cli::AddSetOption(sub, set.get());
  return [model, set]() { return Info(*model, *set); };
}

const bool registered_run =
    mjtether::cli::Register({"run", "simulate a model and write its log", SetupRun});
const bool registered_info =
    mjtether::cli::Register({"info", "print the tethers of a model", SetupInfo});

}  // namespace
