#include "vehicle.h"

#include <algorithm>
#include <sstream>

namespace mjtether {

std::optional<Vehicle> Vehicle::Create(const VehicleParams& params, const Environment& env,
                                       double body_mass, std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return std::nullopt;
  };
  if (!env.wet) {
    return fail("a vehicle needs water: add <text name=\"water\" data=\"density=1025\"/>");
  }
  if (!(body_mass > 0)) {
    return fail("the body has no mass; give its geoms a mass or density");
  }
  Vehicle v;
  v.p_ = params;
  v.env_ = env;
  const Vec3 A = params.added_mass.head<3>();
  v.a_iso_ = A.minCoeff();
  v.dA_ = A - Vec3::Constant(v.a_iso_);
  // The lag iteration a_{n+1} = (F - dA a_n)/(m + a_iso) converges while dA < m + a_iso.
  const double effective = body_mass + v.a_iso_;
  const double ratio = v.dA_.maxCoeff() / effective;
  if (ratio > kMaxExplicitRatio) {
    std::ostringstream s;
    s << "key 'added_mass': the translational added masses differ by " << v.dA_.maxCoeff()
      << " kg, more than " << kMaxExplicitRatio << " x (body mass " << body_mass
      << " kg + smallest translational added mass " << v.a_iso_
      << " kg); the difference is applied explicitly and would be unstable (see README, "
         "Vehicles)";
    return fail(s.str());
  }
  v.buoyancy_ = params.volume > 0 && env.gravity.squaredNorm() > 0;
  v.buoyancy_force_ = -env.water.density * params.volume * env.gravity;
  v.added_mass_ = params.added_mass.maxCoeff() > 0;
  v.linear_ = params.linear_damping.maxCoeff() > 0;
  v.quadratic_ = params.quadratic_damping.maxCoeff() > 0;
  return v;
}

Vec6 Vehicle::RelativeVelocity(const Eigen::Matrix3d& R, const Vec3& v, const Vec3& w,
                               double z) const {
  Vec6 nu_r;
  nu_r.head<3>() = R.transpose() * (v - env_.water.CurrentAt(z));
  nu_r.tail<3>() = w;
  return nu_r;
}

// Fossen (2011), diagonal linear plus quadratic damping: D(nu_r) nu_r = (D_l + D_q |nu_r|) nu_r.
Wrench Vehicle::Damping(const Vec6& nu_r) const {
  Vec6 tau = Vec6::Zero();
  if (linear_) tau -= p_.linear_damping.cwiseProduct(nu_r);
  if (quadratic_) tau -= p_.quadratic_damping.cwiseProduct(nu_r.cwiseAbs().cwiseProduct(nu_r));
  return {tau.head<3>(), tau.tail<3>()};
}

// Fossen (2011), C_A(nu_r) nu_r for M_A = diag(A), minus what the armature carries
// (a_iso dv/dt in the world frame = a_iso (dv_r/dt + w x v_r) in the body frame, and
// A_w dw/dt).
Wrench Vehicle::AddedMass(const Vec6& nu_r, const Vec3& dv_r) const {
  Wrench f;
  if (!added_mass_) return f;
  const Vec3 vr = nu_r.head<3>(), w = nu_r.tail<3>();
  const Vec3 Av = p_.added_mass.head<3>().cwiseProduct(vr);  // A_v v_r [kg m/s]
  const Vec3 Aw = p_.added_mass.tail<3>().cwiseProduct(w);   // A_w w [kg m^2/s]
  f.force = -dA_.cwiseProduct(dv_r);
  if (!p_.coriolis) return f;
  f.force -= w.cross(dA_.cwiseProduct(vr));
  f.torque = -vr.cross(Av) - w.cross(Aw);
  return f;
}

}  // namespace mjtether
