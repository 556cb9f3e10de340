// mjtether vehicles: Fossen hydrodynamics for free bodies, prescribed motion for mocap bodies,
// scripted actuator inputs. Declared in MJCF <custom><text> (see README, "Vehicles, thrusters
// and prescribed motion") and attached by mjtether::Attach / LoadModel with the tethers.
//
//   <text name="vehicle:rov" data="volume=0.0114 cob=0,0,0.02 added_mass=... ..."/>
//   <text name="motion:ship" data="x=2,10,0 z=1,8,0"/>
//   <text name="thrust:surge" data="t=0,5,5.5 ctrl=0,0,40"/>
//
// The vehicle forces act through the same mjcb_passive callback as the tethers, so a plain
// mj_step moves a vehicle. Motions and schedules must be applied before the step's kinematics:
// call Prescribe(m, d) before every mj_step, or use Step(m, d).
#ifndef MJTETHER_PLUGIN_MJTETHER_VEHICLES_H_
#define MJTETHER_PLUGIN_MJTETHER_VEHICLES_H_

#include <mujoco/mujoco.h>

#include <string>

#include "vehicle.h"

namespace mjtether {

// Sets, for the time d->time, every "motion:" body's d->mocap_pos (initial position plus the
// ramped offset) and every "thrust:" actuator's d->ctrl (overwriting what a controller wrote to
// that actuator). Does nothing for a model without such declarations.
void Prescribe(const mjModel* m, mjData* d);

// Prescribe(m, d), then mj_step(m, d).
void Step(const mjModel* m, mjData* d);

// Vehicles declared in m, in declaration order.
int VehicleCount(const mjModel* m);
// Index of the vehicle on body `body_name`, -1 if none.
int FindVehicle(const mjModel* m, const std::string& body_name);
// The body of vehicle k (-1 if none) and its hydrodynamic model (parameters, added-mass split).
int VehicleBody(const mjModel* m, int k);
const Vehicle* GetVehicle(const mjModel* m, int k);

}  // namespace mjtether

#endif  // MJTETHER_PLUGIN_MJTETHER_VEHICLES_H_
