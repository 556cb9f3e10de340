// One simulation step of a command that renders or plots: the motion: and thrust: schedules,
// mj_step, then the checks `mjtether run` makes after each step.
#ifndef MJTETHER_PLUGIN_CLI_STEP_H_
#define MJTETHER_PLUGIN_CLI_STEP_H_

#include <mujoco/mujoco.h>

#include <optional>
#include <sstream>
#include <string>

#include "mjtether.h"
#include "mjtether_vehicles.h"

namespace mjtether::cli {

// Returns why the run must stop (exit status 1), or nullopt.
inline std::optional<std::string> StepAndCheck(const mjModel* m, mjData* d,
                                               const std::string& model) {
  mjtether::Step(m, d);  // Prescribe (schedules at d->time), then mj_step
  if (std::optional<std::string> diverged = mjtether::CheckDivergence(m, d)) return diverged;
  if (d->warning[mjWARN_BADQACC].number > 0) {
    std::ostringstream s;
    s << model << ": MuJoCo found a bad acceleration at t = " << d->time
      << " s and reset the simulation; reduce <option timestep> (now " << m->opt.timestep
      << " s) or use a stiffer-safe integrator (implicit tether, RK4 for the bodies)";
    return s.str();
  }
  return std::nullopt;
}

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_STEP_H_
