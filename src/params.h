// Parameters of one tether and of the water it is in. SI units throughout.
//
// These are plain structs: the declaration parser (declaration.h) fills and validates them,
// the Tether class (tether.h) precomputes everything that never changes from them.
#ifndef MJTETHER_SRC_PARAMS_H_
#define MJTETHER_SRC_PARAMS_H_

#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "current_profile.h"
#include "seabed.h"

namespace mjtether {

using Vec3 = Eigen::Vector3d;

// One bit per physical effect. An effect whose bit is clear is not evaluated at all.
enum Effect : unsigned {
  kAxial = 1u << 0,      // elastic tension EA*strain, tension only (see kCompression)
  kDamping = 1u << 1,    // internal axial damping, damping*strain rate
  kBending = 1u << 2,    // bending stiffness EI (Galerkin curvature at the nodes)
  kWeight = 1u << 3,     // dry weight, mass_per_length * g
  kBuoyancy = 1u << 4,   // displaced water, density * pi d^2/4 * g
  kDrag = 1u << 5,       // Morison quadratic drag, normal (Cdn) and tangential (Cdt)
  kAddedMass = 1u << 6,  // normal added mass Can * density * pi d^2/4
  kCurrent = 1u << 7,    // drag on the velocity relative to the current
  kSeabed = 1u << 8,     // flat seabed: penalty, damping, Coulomb friction
  kClamp = 1u << 9,      // clamped end(s): tangent held, bending moment to the body
  kCompression = 1u << 10,  // shortened segments push back, EAc*strain (declared by EAc)
  kContact = 1u << 11,   // segments against MuJoCo geoms: penalty, damping, Coulomb friction
};

// Name of each effect as written in `effects=` (same order as the bits).
inline constexpr const char* kEffectNames[] = {"axial",    "damping",    "bending", "weight",
                                               "buoyancy", "drag",       "added_mass",
                                               "current",  "seabed",     "clamp",
                                               "compression", "contact"};
inline constexpr int kNumEffects = 12;

// How nodal curvature is measured from the turning angle theta between two segments (both
// give the same small-angle stiffness EI/w; they differ at large angles per node).
enum class Bending {
  kGalerkin,  // M = EI sin(theta)/w, potential EI/w (1 - cos theta) (Buckham & Nahon 1999)
  kDER,       // discrete elastic rod (Bergou et al. 2008): kappa = 2 tan(theta/2)/w, potential
              // 2 EI/w tan^2(theta/2), M = its derivative 2 EI/w tan(theta/2)/cos^2(theta/2)
};

enum class Integrator {
  kExplicit,  // symplectic Euler, substeps from the stability limit
  kImplicit,  // linearised backward Euler, banded solve
  kImplicit2,  // two-stage L-stable SDIRK (second order), each stage a backward-Euler solve
  kRK4,       // classical fourth-order Runge-Kutta, substeps from its own stability limit
  kBdf2,  // generalized-alpha (second order, one backward-Euler-sized solve per step)
};

// Explicit schemes take substeps at their stability limit; implicit ones take the MuJoCo step.
inline bool IsExplicit(Integrator i) { return i == Integrator::kExplicit || i == Integrator::kRK4; }
// The name a declaration uses for it (key `integrator`).
inline const char* IntegratorName(Integrator i) {
  switch (i) {
    case Integrator::kExplicit: return "explicit";
    case Integrator::kImplicit: return "implicit";
    case Integrator::kImplicit2: return "implicit2";
    case Integrator::kRK4: return "rk4";
    case Integrator::kBdf2: return "bdf2";
  }
  return "?";
}

// How a tether starts (key `start`; docs/static_start.md).
enum class Start {
  kCatenary,  // the engine's initial shape (Tether::InitialShape), at rest: the default
  kStatic,    // that shape relaxed to static equilibrium (Tether::RelaxToStatic), at rest
};
inline const char* StartName(Start s) { return s == Start::kStatic ? "static" : "catenary"; }

// The water a tether is in (declared by <text name="water">). Absent: a dry scene.
struct Water {
  double density = 1025;         // [kg/m^3]
  Vec3 current = Vec3::Zero();   // [m/s] uniform current velocity, world frame
  // A depth profile (`current_profile=FILE.csv`) instead of the uniform current: the file as
  // declared, and its rows once read (by the MuJoCo glue, relative to the model's directory).
  std::string current_profile;
  CurrentProfile profile;
  bool has_seabed = false;       // a flat seabed was declared
  double seabed = 0;             // [m] height (world z) of the seabed plane
  // seabed=GEOMNAME: a plane or hfield geom is the seabed; its surface, filled by the MuJoCo
  // glue at load (seabed.h). `seabed` above is then unused.
  std::string seabed_geom;
  SeabedSurface surface;
  double seabed_stiffness = 1e5;  // [N/m^2] normal force per length of tether per penetration
  double seabed_damping = -1;    // [N s/m^2] per length; < 0: critical for the tether's mass
  double seabed_friction = 0;    // [-] Coulomb coefficient across the tether
  double seabed_friction_axial = -1;  // [-] along the tether; < 0: same as seabed_friction
  double seabed_friction_speed = 0.01;  // [m/s] slip speed over which friction saturates (tanh)

  // A current is declared: uniform and non-zero, or a profile.
  bool has_current() const { return !profile.empty() || current.squaredNorm() > 0; }
  // The current [m/s] at height z [m] (world frame).
  Vec3 CurrentAt(double z) const { return profile.empty() ? current : profile.At(z); }
  // Height of the seabed [m] under (x, y): the flat seabed's, or the geom's surface.
  double SeabedHeight(double x, double y) const {
    return surface.declared() ? surface.HeightUnder(x, y) : seabed;
  }
  // Largest current speed anywhere [m/s].
  double MaxCurrentSpeed() const { return profile.empty() ? current.norm() : profile.MaxSpeed(); }
};

struct TetherParams {
  double length = 0;           // [m] unstretched length
  int segments = 0;            // [-] number of segments N (N+1 nodes)
  double diameter = 0;         // [m] hydrodynamic and buoyancy diameter d
  double mass_per_length = 0;  // [kg/m] dry mass per unstretched length
  double EA = 0;               // [N] axial stiffness
  double EAc = 0;              // [N] axial stiffness in compression (l < L0); 0: tension only
  double EI = 0;               // [N m^2] bending stiffness
  double damping = 0;          // [N s] internal axial damping: T = EA*eps + damping*deps/dt
  // [-] `damping_ratio=` as declared (MoorDyn's BA = -zeta): the damping ratio of the
  // segment axial mode, from which the parser sets damping (SegmentModeDamping); < 0: not given
  double damping_ratio = -1;
  double Cdn = 0;              // [-] normal drag coefficient, reference area d per length
  double Cdt = 0;              // [-] tangential drag coefficient, reference area pi*d per length
  double Can = 0;              // [-] normal added-mass coefficient, reference pi*d^2/4 per length
  Integrator integrator = Integrator::kBdf2;  // the declaration's default (docs/numerics.md)
  Bending bending = Bending::kGalerkin;  // curvature formulation (bending=galerkin|der)
  bool free_end = false;       // end B is not attached (dangling)
  bool clamp_a = false;        // end A tangent held along its site's x-axis
  bool clamp_b = false;        // end B tangent held along its site's x-axis
  int substeps = 0;            // [-] tether steps per call; 0: automatic
  double max_step = 0;         // [s] largest tether step; 0: automatic
  double max_strain = 1.0;     // [-] strain above which the run is declared diverged
  unsigned effects = 0;        // bit set of Effect, resolved by the parser
  // Contact with MuJoCo geoms (declared by `contact=`; docs/contact.md). Per unit length of
  // tether: a segment's contact point carries the stiffness of its rest length L0.
  double contact_stiffness = 1e6;  // [N/m^2] normal force per length of tether per penetration
  double contact_damping = -1;     // [N s/m^2] per length; < 0: critical for the tether's mass
  double contact_friction = 0;     // [-] Coulomb coefficient (isotropic)
  double contact_friction_speed = 0.01;  // [m/s] slip speed over which friction saturates (tanh)
  // A winch at end A (declared by winch:NAME; docs/winch.md): segments is then the allocation
  // for the longest deployment and length = segments x L0; the explicit stability limit is
  // taken at the shortest viable winch segment, L0/2.
  bool winch = false;
  Start start = Start::kCatenary;  // key `start` (catenary | static)
};

// Everything a Tether needs from its surroundings.
struct Environment {
  Vec3 gravity = Vec3(0, 0, -9.81);  // [m/s^2]
  bool wet = false;                  // a water declaration exists
  Water water;
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_PARAMS_H_
