// Internal glue between plugin.cc and tether-geom contact (plugin/contact_glue.cc,
// docs/contact.md). Not part of the public API.
#ifndef MJTETHER_PLUGIN_CONTACT_GLUE_H_
#define MJTETHER_PLUGIN_CONTACT_GLUE_H_

#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "contact.h"
#include "seabed.h"
#include "tether.h"

namespace mjtether {

// One geom a tether may touch, with the arc lengths from end A and end B [m] within which its
// segments skip it (the geom is on that end's body: the tether starts inside or against it).
// A mesh geom's convex hull in the geom's frame: its triangles (3 corners each) and each
// triangle's plane (outward unit normal n, offset o: n.p - o is the signed distance to it).
struct ConvexHull {
  std::vector<Vec3> corner;  // (3 per triangle)
  std::vector<Vec3> normal;  // (1 per triangle)
  std::vector<double> offset;
  double scale = 1;  // [m] size of the hull (difference step of the normal)
};

struct ContactGeom {
  int geom = -1;
  double skip[2] = {0, 0};
  ConvexHull hull;  // mesh geoms only
  // Height-field geoms only: the surface in the geom's frame (environment_glue.h,
  // HfieldSurface), its base depth below the origin and its top above it [m] (MuJoCo's
  // hfield size[3] and size[2]), and a bounding radius about the origin [m] (MuJoCo's
  // geom_rbound is 0 for hfields).
  SeabedSurface hfield;
  double hfield_base = 0, hfield_top = 0, hfield_rbound = 0;
  // [m] the most a segment's predicted displacement may move it relative to the geom when its
  // plane is found ahead (FindContacts): a quarter of the geom's thinnest half-size, so that
  // a fast segment's prediction does not cross the geom's middle and flip the plane.
  double max_ahead = 0;
};

struct TetherContacts {
  std::vector<ContactGeom> geoms;
  int capacity = 0;  // candidates per step (4 per segment + 16); more are dropped and counted
};

// Resolves `contact=` ("all" or geom/body names) for a tether whose end sites are site[0],
// site[1] (-1: free). Supported geom types: plane, sphere, capsule, cylinder, box, ellipsoid,
// mesh (its convex hull), hfield (its top surface). The seabed geom (seabed=GEOMNAME) is left
// out of `all` and an error when named (the seabed force already acts on it).
bool ResolveContactGeoms(const mjModel* m, const std::string& spec, const int site[2],
                         const Tether& tether, TetherContacts* out,
                         std::vector<std::string>* warnings, std::string* error);

// The candidates of one step [t, t + dt]: every segment point of the state x (3 x n) within a
// margin of a geom as it is in d (broad phase on bounding spheres against 8-segment boxes,
// then the segment-geom closest points). Writes at most `capacity` into out; returns the
// count, and sets *dropped to the number left out. `boxes` is scratch of ChunkBoxesSize
// doubles. Allocates nothing.
int FindContacts(const mjModel* m, const mjData* d, const TetherContacts& tc, const Tether& tether,
                 const double* x, const double* v, double dt, double* boxes, ContactPoint* out,
                 int capacity, int* dropped);
inline int ChunkBoxesSize(int segments) { return 6 * (segments / 8 + 1); }

}  // namespace mjtether

#endif  // MJTETHER_PLUGIN_CONTACT_GLUE_H_
