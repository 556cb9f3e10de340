// Internal glue between plugin.cc and the water's files and geoms (plugin/environment_glue.cc,
// docs/environment.md): the current profile's CSV and the seabed geom. Not public API.
#ifndef MJTETHER_PLUGIN_ENVIRONMENT_GLUE_H_
#define MJTETHER_PLUGIN_ENVIRONMENT_GLUE_H_

#include <mujoco/mujoco.h>

#include <string>

#include "params.h"

namespace mjtether {

// Completes a parsed water declaration for model m loaded from `source`: reads
// current_profile (relative to the model's directory) and fills the seabed surface from the
// geom named by seabed=GEOMNAME. False (and *error naming the key) if either cannot be used.
bool ResolveWater(const mjModel* m, const std::string& source, Water* water, std::string* error);

// The surface of height field h (MuJoCo's hfield_* arrays) in its geom's frame: centre at the
// origin, no yaw, heights data x size[2] [m]. Used by seabed=GEOMNAME (which then places it in
// the world) and by tether contact with hfield geoms (plugin/contact_glue.cc). False if the
// field has fewer than 2 x 2 heights.
bool HfieldSurface(const mjModel* m, int h, SeabedSurface* s);

// "'seabed' = -30 m" or "'seabed' = geom 'floor'", for messages.
std::string SeabedDescription(const Water& water);

}  // namespace mjtether

#endif  // MJTETHER_PLUGIN_ENVIRONMENT_GLUE_H_
