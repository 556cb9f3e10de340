// `mjtether run` and `mjtether info`.
//
//   mjtether run MODEL.xml --duration S [--log FILE.csv] [--nodes FILE.csv] [--every S]
//   mjtether info MODEL.xml
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli_command.h"
#include "cli_run_summary.h"
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

int Run(const RunOptions& opt) {
  std::string error;
  std::vector<mjtether::Override> overrides;
  for (const std::string& spec : opt.set) {
    std::optional<mjtether::Override> o = mjtether::ParseOverride(spec, &error);
    if (!o) {
      std::cerr << "mjtether: --set " << error << "\n";
      return 2;
    }
    overrides.push_back(*o);
  }
  mjModel* m = mjtether::LoadModel(opt.model, overrides, &error);
  if (!m) {
    std::cerr << "mjtether: " << error << "\n";
    return 2;
  }
  for (const std::string& w : mjtether::Warnings(m)) {
    std::cerr << "mjtether: warning: " << w << "\n";
  }
  mjData* d = mj_makeData(m);
  const double h = m->opt.timestep;
  const std::vector<int> bodies = FreeBodies(m);
  const int ntether = mjtether::TetherCount(m);

  std::ofstream log, nodes;
  if (!opt.log.empty()) {
    log.open(opt.log);
    if (!log) {
      std::cerr << "mjtether: cannot write --log " << opt.log << "\n";
      return 2;
    }
    log << "time";
    for (int b : bodies) {
      const std::string n = BodyName(m, b);
      log << "," << n << ".x," << n << ".y," << n << ".z";
    }
    for (int k = 0; k < ntether; ++k) {
      const std::string n = mjtether::TetherName(m, k);
      log << "," << n << ".tension_A," << n << ".tension_B," << n << ".tension_max," << n
          << ".slack_segments";
    }
    log << "\n";
  }
  if (!opt.nodes.empty()) {
    nodes.open(opt.nodes);
    if (!nodes) {
      std::cerr << "mjtether: cannot write --nodes " << opt.nodes << "\n";
      return 2;
    }
    nodes << "time,tether,node,x,y,z,tension\n";
  }
  log.precision(9);
  nodes.precision(9);

  std::vector<double> T;
  auto sample = [&]() {
    mj_forward(m, d);  // brings every tether to d->time (no extra work for the next step)
    if (log.is_open()) {
      log << d->time;
      for (int b : bodies) {
        log << "," << d->xpos[3 * b] << "," << d->xpos[3 * b + 1] << "," << d->xpos[3 * b + 2];
      }
      for (int k = 0; k < ntether; ++k) {
        const mjtether::EndReactions r = mjtether::GetReactions(m, d, k);
        T.resize(mjtether::GetTether(m, k)->segments());
        mjtether::GetTensions(m, d, k, T.data());
        double tmax = 0;
        int slack = 0;
        for (double t : T) {
          tmax = std::max(tmax, t);
          slack += t <= 0;
        }
        log << "," << r.tension_a << "," << r.tension_b << "," << tmax << "," << slack;
      }
      log << "\n";
    }
    if (nodes.is_open()) {
      for (int k = 0; k < ntether; ++k) {
        const mjtether::Tether* t = mjtether::GetTether(m, k);
        const double* x = mjtether::NodePositions(m, d, k);
        T.resize(t->segments());
        mjtether::GetTensions(m, d, k, T.data());
        for (int i = 0; i < t->nodes(); ++i) {
          nodes << d->time << "," << mjtether::TetherName(m, k) << "," << i << "," << x[3 * i]
                << "," << x[3 * i + 1] << "," << x[3 * i + 2] << ","
                << T[std::min(i, t->segments() - 1)] << "\n";
        }
      }
    }
  };

  // Samples at t_k = k * every, scheduled by step index so that no time is accumulated.
  const long long steps = std::llround(opt.duration / h);
  const double every = std::max(opt.every, h);
  long long next_sample = 0, sample_index = 0;
  std::optional<mjtether::cli::RunSummary> run_summary;
  if (!opt.summary.empty()) run_summary.emplace(m);
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  for (long long i = 0;; ++i) {
    mjtether::Prescribe(m, d);  // motion: and thrust: declarations at d->time
    if (i == next_sample) {
      sample();
      ++sample_index;
      next_sample = std::llround(sample_index * every / h);
    }
    if (i == steps) break;
    mj_step(m, d);
    if (run_summary) run_summary->Observe(m, d);
    if (std::optional<std::string> diverged = mjtether::CheckDivergence(m, d)) {
      std::cerr << "mjtether: " << *diverged << "\n";
      status = 1;
      break;
    }
    if (d->warning[mjWARN_BADQACC].number > 0) {
      std::cerr << "mjtether: " << opt.model << ": MuJoCo found a bad acceleration at t = "
                << d->time << " s and reset the simulation; reduce <option timestep> (now " << h
                << " s) or use a stiffer-safe integrator (implicit tether, RK4 for the bodies)\n";
      status = 1;
      break;
    }
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (status == 0) {
    std::cerr << "mjtether: simulated " << d->time << " s in " << wall << " s wall ("
              << (wall > 0 ? d->time / wall : 0) << "x real time)";
    if (!opt.log.empty()) std::cerr << "; log: " << opt.log;
    std::cerr << "\n";
  }
  if (run_summary && !run_summary->Write(opt.summary, m, d)) {
    std::cerr << "mjtether: cannot write --summary " << opt.summary << "\n";
    status = status ? status : 2;
  }
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
  return status;
}

int Info(const std::string& path) {
  std::string error;
  mjModel* m = mjtether::LoadModel(path, &error);
  if (!m) {
    std::cerr << "mjtether: " << error << "\n";
    return 2;
  }
  for (const std::string& w : mjtether::Warnings(m)) {
    std::cerr << "mjtether: warning: " << w << "\n";
  }
  std::cout << path << ": timestep " << m->opt.timestep << " s, "
            << mjtether::TetherCount(m) << " tether(s)\n";
  for (int k = 0; k < mjtether::TetherCount(m); ++k) {
    const mjtether::Tether* t = mjtether::GetTether(m, k);
    const mjtether::TetherParams& p = t->params();
    std::cout << "  tether '" << mjtether::TetherName(m, k) << "': " << p.segments
              << " segments of " << t->rest_segment_length() << " m, "
              << mjtether::IntegratorName(p.integrator)
              << ", effects " << mjtether::EffectsToString(p.effects) << "\n"
              << "    " << (p.integrator == mjtether::Integrator::kRK4 ? "rk4" : "explicit")
              << " stable step " << t->ExplicitStableStep() << " s; "
              << t->SubstepsFor(m->opt.timestep) << " tether step(s) per MuJoCo step\n";
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
  mjtether::Detach(m);
  mj_deleteModel(m);
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
      ->check(CLI::Range(0.0, 1e7));
  sub->add_option("--log", opt->log, "CSV: time, free bodies' positions, end tensions");
  sub->add_option("--nodes", opt->nodes, "CSV: time,tether,node,x,y,z,tension");
  sub->add_option("--every", opt->every, "sampling interval of both CSV files [s]")
      ->check(CLI::Range(1e-9, 1e7));
  sub->add_option("--set", opt->set,
                  "override one declaration key, TEXT.KEY=VALUE (e.g. water.current=0.5,0,0); "
                  "repeatable")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  sub->add_option("--summary", opt->summary,
                  "CSV row: peak tension over every step, the vehicle's final pose");
  return [opt]() { return Run(*opt); };
}

std::function<int()> SetupInfo(CLI::App* sub) {
  auto model = std::make_shared<std::string>();
  sub->add_option("model", *model, "MJCF file")->required()->check(CLI::ExistingFile);
  return [model]() { return Info(*model); };
}

const bool registered_run =
    mjtether::cli::Register({"run", "simulate a model and write its log", SetupRun});
const bool registered_info =
    mjtether::cli::Register({"info", "print the tethers of a model", SetupInfo});

}  // namespace
