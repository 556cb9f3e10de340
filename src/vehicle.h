// Hydrodynamics of a rigid underwater vehicle in Fossen's body-frame model (T. I. Fossen,
// "Handbook of Marine Craft Hydrodynamics and Motion Control", Wiley 2011: the underwater
// vehicle's equations of motion relative to a current, with the added-mass Coriolis matrix
// C_A of a diagonal added-mass matrix and diagonal linear plus quadratic damping):
//
//   (M_RB + M_A) dnu/dt + C_RB(nu) nu + C_A(nu_r) nu_r + D(nu_r) nu_r + g(eta) = tau
//
// nu = [v; w] is the body-frame velocity of the body origin (v linear, w angular), nu_r the
// same relative to a uniform, irrotational current (v_r = v - R^T u, w_r = w). The rigid-body
// terms M_RB, C_RB and the weight are MuJoCo's own; this class gives the rest:
//
//   buoyancy      f = -rho V g (world), acting at the centre of buoyancy cob (body frame)
//   damping       D(nu_r) nu_r = (D_l + D_q |nu_r|) nu_r, diagonal, component by component
//   added mass    M_A = diag(A1..A6), with Coriolis/centripetal C_A(nu_r) nu_r =
//                 [ w x (A_v v_r) ;  v_r x (A_v v_r) + w x (A_w w) ]   (Munk moment, gyration)
//
// How the added mass is integrated (see README, "Vehicles"): MuJoCo's free joint has its
// translational dofs in the world frame and its rotational dofs in the body frame. So the
// isotropic part of the translational added mass, a_iso = min(A1, A2, A3), and the whole
// rotational added mass diag(A4, A5, A6) go into the joint's armature (MuJoCo then solves them
// implicitly, at any ratio to the body's mass, and armature has no weight). Only the
// translational remainder dA = diag(A1..A3) - a_iso is applied as a force, -dA dv_r/dt, with
// the body-frame acceleration of the previous step. That fixed-point lag is stable while
// dA_i < m + a_iso on every axis; Create refuses dA_i > kMaxExplicitRatio (m + a_iso).
//
// The class holds parameters only; it is free of MuJoCo, and computing allocates nothing.
#ifndef MJTETHER_SRC_VEHICLE_H_
#define MJTETHER_SRC_VEHICLE_H_

#include <Eigen/Core>
#include <optional>
#include <string>

#include "params.h"

namespace mjtether {

using Vec6 = Eigen::Matrix<double, 6, 1>;

// One vehicle's declared hydrodynamics (<text name="vehicle:BODY">). Order of the 6-vectors:
// surge, sway, heave, roll, pitch, yaw (body frame). Positive magnitudes of Fossen's
// coefficients (A1 = -X_udot, D_l1 = -X_u, D_q1 = -X_u|u|, ...).
struct VehicleParams {
  double volume = 0;                      // [m^3] displaced volume V
  Vec3 cob = Vec3::Zero();                // [m] centre of buoyancy, body frame
  Vec6 added_mass = Vec6::Zero();         // [kg, kg m^2] A1..A6
  Vec6 linear_damping = Vec6::Zero();     // [N s/m, N m s] D_l
  Vec6 quadratic_damping = Vec6::Zero();  // [N s^2/m^2, N m s^2] D_q
  // Include the added mass's Coriolis/centripetal terms C_A(nu_r) nu_r (the Munk moment
  // v_r x A_v v_r, w x A_v v_r, w x A_w w). Off: only the isotropic part's, which the armature
  // carries in the world frame, remains.
  bool coriolis = true;
};

// Body-frame force [N] and moment [N m] about the body origin.
struct Wrench {
  Vec3 force = Vec3::Zero();
  Vec3 torque = Vec3::Zero();
};

class Vehicle {
 public:
  // Largest translational added-mass remainder applied explicitly, as a fraction of the
  // effective mass m + a_iso on that axis (the lag iteration's ratio; 1 is the limit).
  static constexpr double kMaxExplicitRatio = 0.9;

  // Checks the parameters against the body's mass [kg] and the environment (needs water).
  // Returns nothing and sets *error (naming the key) if they cannot be simulated stably.
  static std::optional<Vehicle> Create(const VehicleParams& params, const Environment& env,
                                       double body_mass, std::string* error);

  const VehicleParams& params() const { return p_; }

  // Added mass that goes into the free joint's armature: translational (the same on the three
  // world-frame dofs) and rotational (body-frame dofs 3..5).
  double armature_translation() const { return a_iso_; }
  Vec3 armature_rotation() const { return p_.added_mass.tail<3>(); }
  // Translational remainder dA (body frame) applied explicitly.
  Vec3 explicit_added_mass() const { return dA_; }

  // What is simulated (only what is declared is computed).
  bool has_buoyancy() const { return buoyancy_; }
  bool has_added_mass() const { return added_mass_; }
  bool has_damping() const { return linear_ || quadratic_; }

  // Buoyancy force [N], world frame: -rho V g. Apply it at the cob.
  Vec3 Buoyancy() const { return buoyancy_force_; }

  // Body-frame velocity of the body origin relative to the water: v_r = R^T (v - u(z)), w.
  // R (body to world), v [m/s] world velocity of the body origin, w [rad/s] body frame, z [m]
  // the origin's height (the current at the vehicle's own depth with a current profile; the
  // profile's shear across the hull and the water's acceleration du/dz dz/dt are left out).
  Vec6 RelativeVelocity(const Eigen::Matrix3d& R, const Vec3& v, const Vec3& w,
                        double z) const;

  // Damping -(D_l + D_q |nu_r|) nu_r, body frame, about the body origin.
  Wrench Damping(const Vec6& nu_r) const;

  // The added-mass terms not carried by the armature: -dA dv_r/dt - w x (dA v_r) - Munk moment
  // v_r x (A_v v_r) - gyration w x (A_w w), body frame. dv_r/dt is the body-frame derivative of
  // v_r; with a uniform current it is R^T a - w x v_r, a [m/s^2] the world acceleration.
  Wrench AddedMass(const Vec6& nu_r, const Vec3& dv_r) const;

 private:
  Vehicle() = default;

  VehicleParams p_;
  Environment env_;
  double a_iso_ = 0;                    // [kg] isotropic translational added mass (armature)
  Vec3 dA_ = Vec3::Zero();              // [kg] explicit remainder, body frame
  Vec3 buoyancy_force_ = Vec3::Zero();  // [N] world frame
  bool buoyancy_ = false, added_mass_ = false, linear_ = false, quadratic_ = false;
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_VEHICLE_H_
