// Internal glue between plugin.cc and the vehicle, motion and thrust declarations
// (plugin/vehicles.cc). Not part of the public API (see mjtether_vehicles.h).
#ifndef MJTETHER_PLUGIN_VEHICLE_GLUE_H_
#define MJTETHER_PLUGIN_VEHICLE_GLUE_H_

#include <mujoco/mujoco.h>

#include <optional>
#include <string>

#include "params.h"

namespace mjtether {

// Reads every "vehicle:", "motion:" and "thrust:" text of m, checks it, adds the vehicles'
// added mass to the free joints' armature and registers m. Each vehicle's state block is
// taken from mjData::userdata at *offset, which is advanced (the caller sets m->nuserdata).
// *any is set when m declares at least one of them. On error nothing is registered or changed;
// *error is "SOURCE: <text name=...>: message".
bool AttachVehicles(mjModel* m, const std::string& source, const Environment& env, int* offset,
                    bool* any, std::string* error);

// Forgets m's vehicles, motions and schedules.
void DetachVehicles(const mjModel* m);

// Adds the vehicles' buoyancy, damping and added-mass remainder to d->qfrc_passive (called from
// the passive callback). Allocates nothing.
void ApplyVehicles(const mjModel* m, mjData* d);

// The h lambda beyond which a velocity-dependent force from mjcb_passive, which MuJoCo
// integrates explicitly, makes a body's velocity reverse and grow every step: 2 for its Euler
// (and implicit, which does not see the callback's derivatives), 2.785 for RK4 (the real-axis
// stability limit of the classical RK4). Used for a tether end's damping (plugin.cc) and a
// vehicle's own (vehicles.cc).
inline double ExplicitDampingLimit(const mjModel* m) {
  return m->opt.integrator == mjINT_RK4 ? 2.785 : 2.0;
}

// The first dof of the free joint at the root of `body`'s tree, or -1 if it has none.
int FreeRootDof(const mjModel* m, int body);

// Whether a vehicle stopped because its own damping became too stiff for MuJoCo's explicit
// step (h lambda beyond 2, RK4 2.785, on its worst dof; it then applies no force until a
// reset): the message, "vehicle 'NAME' stopped at t = ...", without the file name, and the
// vehicle's body in *body (if not null).
std::optional<std::string> VehicleStopped(const mjModel* m, const mjData* d, int* body = nullptr);

// The translational force [N] the "thrust:" schedules put on the free root of `body` at their
// peaks: each fixed-gain, bias-free actuator's gain x the schedule's value of largest magnitude
// (clamped to ctrlrange) along its moment at d's pose, summed as vectors; 0 without schedules.
double ScheduledThrust(const mjModel* m, const mjData* d, int body);

// The exact velocity of a body moved by a "motion:" declaration at d->time, if its mocap
// position is the prescribed one at d->time (Prescribe was called); false otherwise.
bool PrescribedVelocity(const mjModel* m, const mjData* d, int body, Vec3* vel);

}  // namespace mjtether

#endif  // MJTETHER_PLUGIN_VEHICLE_GLUE_H_
