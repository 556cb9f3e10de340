// Parsers of the vehicle, motion and thrust declarations (same `key=value` syntax and error
// style as declaration.h; the caller prefixes the file and the element).
//
//   <text name="vehicle:rov" data="volume=0.0114 cob=0,0,0.02 added_mass=5.5,12.7,14.57,...
//         linear_damping=... quadratic_damping=..."/>
//   <text name="motion:ship" data="x=2,10,0 z=1,8,0"/>   or  data="csv=FILE ramp=5"
//   <text name="thrust:ACTUATOR" data="t=0,5,5.5 ctrl=0,0,40"/>
#ifndef MJTETHER_SRC_VEHICLE_DECLARATION_H_
#define MJTETHER_SRC_VEHICLE_DECLARATION_H_

#include <optional>
#include <string>

#include "declaration.h"
#include "motion.h"
#include "vehicle.h"

namespace mjtether {

// Keys: volume [m^3] in [0, 1e4]; cob [m] 3 numbers in [-1000, 1000]; added_mass,
// linear_damping, quadratic_damping: 6 numbers each in [0, 1e9]. All optional (default 0).
// coriolis: 1 (default) or 0, the added mass's Coriolis/centripetal and Munk terms.
std::optional<VehicleParams> ParseVehicle(const std::string& text, DeclarationError* error);

// Keys: x, y, z = amplitude [m] in [0, 1e4], period [s] in (0, 1e6], phase [rad] in
// [-1000, 1000]; csv=FILE (excludes x, y, z); ramp [s] in [0, 1e6].
std::optional<MotionParams> ParseMotion(const std::string& text, DeclarationError* error);

// Keys: t (times [s], non-decreasing, in [0, 1e7]) and ctrl (as many values, each in
// [-1e9, 1e9]); both required.
std::optional<Schedule> ParseSchedule(const std::string& text, DeclarationError* error);

}  // namespace mjtether

#endif  // MJTETHER_SRC_VEHICLE_DECLARATION_H_
