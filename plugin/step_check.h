// One simulation step of a command that renders or plots: the motion: and thrust: schedules,
// mj_step, then the checks `mjtether run` makes after each step.
#ifndef MJTETHER_PLUGIN_CLI_STEP_H_
#define MJTETHER_PLUGIN_CLI_STEP_H_

#include <mujoco/mujoco.h>

#include <optional>
#include <sstream>
#include <string>
#include <tuple>

#include "mjtether.h"
#include "mjtether_vehicles.h"

namespace mjtether::cli {

// Returns why the run must stop (exit status 1), or nullopt. MuJoCo resets the data when it
// finds a bad acceleration (d->time goes back to 0), so the time reported is the step's own.
inline std::optional<std::string> StepAndCheck(const mjModel* m, mjData* d,
                                               const std::string& model) {
  const double t0 = d->time;
  const int bad_before = d->warning[mjWARN_BADQACC].number;
  const int bad_pos = d->warning[mjWARN_BADQPOS].number, bad_vel = d->warning[mjWARN_BADQVEL].number;
  mjtether::Step(m, d);  // Prescribe (schedules at d->time), then mj_step
  // A state that was not finite (or beyond 1e10) when the step began, set so by the caller (the
  // schedules and the tethers never write qpos or qvel): MuJoCo resets the data and steps on
  // from t = 0, which would read as a run that went on.
  for (const auto& [warning, before, what] :
       {std::tuple{mjWARN_BADQPOS, bad_pos, "position"}, {mjWARN_BADQVEL, bad_vel, "velocity"}}) {
    if (d->warning[warning].number > before) {
      std::ostringstream s;
      s << model << ": the state at t = " << t0 << " s had a " << what
        << " that is not a number or beyond MuJoCo's limit 1e10 (index "
        << d->warning[warning].lastinfo << " of " << (warning == mjWARN_BADQPOS ? "qpos" : "qvel")
        << "), and MuJoCo reset the simulation; set finite values";
      return s.str();
    }
  }
  if (std::optional<std::string> diverged = mjtether::CheckDivergence(m, d)) return diverged;
  if (d->warning[mjWARN_BADQACC].number > bad_before) {
    std::ostringstream s;
    s << model << ": MuJoCo found a bad acceleration in the step from t = " << t0 << " s (dof "
      << d->warning[mjWARN_BADQACC].lastinfo
      << ") and reset the simulation; reduce <option timestep> (now " << m->opt.timestep
      << " s) or use a stiffer-safe integrator (implicit tether, RK4 for the bodies)";
    return s.str();
  }
  return std::nullopt;
}

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_STEP_H_
