// Contact candidates between tether segments and the surfaces of other bodies, as the engine
// sees them: no geometry, only a local tangent plane per candidate that moves with its body
// (docs/contact.md). The MuJoCo glue (plugin/contact_glue.cc) finds them once per MuJoCo step
// from the geoms; the engine evaluates the penalty, damping and friction on them at every
// substep and stage, and adds up the impulse each one gave the tether so that the glue can
// return exactly the opposite to the body.
#ifndef MJTETHER_SRC_CONTACT_H_
#define MJTETHER_SRC_CONTACT_H_

#include "params.h"

namespace mjtether {

// One candidate: the point of segment `segment` at fraction `s` against the plane through
// `point` with unit normal `normal` (out of the other body). The plane moves with `velocity`:
// at time t its point is point + velocity (t - time_ref). Along the segment the gap is
//   g(s) = normal . (x_s - p(t)) - d/2,   x_s = (1 - s) x_j + s x_{j+1},
// and the segment is in contact where g < 0 (the force integrates over it, Tether::
// ContactForce; `s`, the closest point when the candidate was found, is for information).
struct ContactPoint {
  int segment = 0;                // j, 0 <= j < N
  double s = 0;                   // [-] 0 at node j, 1 at node j+1
  Vec3 point = Vec3::Zero();      // [m] surface point at time_ref, world frame
  Vec3 normal = Vec3::UnitZ();    // [-] unit, pointing out of the other body
  Vec3 velocity = Vec3::Zero();   // [m/s] velocity of the body's material point at `point`
  Vec3 impulse = Vec3::Zero();    // [N s] out: impulse on the tether, summed by Advance
  Vec3 impulse_b = Vec3::Zero();  // [N s] out: the part of `impulse` on node j+1
  Vec3 stage = Vec3::Zero();      // [N s] scratch (first stage of implicit2)
  Vec3 stage_b = Vec3::Zero();    // [N s] scratch: its part on node j+1
  int tag = -1;                   // the caller's (the MuJoCo glue: the geom's body)
};

// The candidates of one Advance (owned by the caller; Advance only writes `impulse`/`stage`).
struct ContactSet {
  ContactPoint* points = nullptr;
  int count = 0;
  double time_ref = 0;  // [s] time at which the planes are where `point` says
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_CONTACT_H_
