// MuJoCo 2.2 glue for vehicles (Fossen hydrodynamics on free bodies), prescribed motion of
// mocap bodies and scripted actuator inputs.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <shared_mutex>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "mjtether.h"
#include "mjtether_vehicles.h"
#include "vehicle_declaration.h"
#include "vehicle_glue.h"

namespace mjtether {
namespace {

struct AttachedVehicle {
  std::string name;  // the body's name
  int body = -1;
  int dof = -1;  // first dof of the body's free joint
  Vehicle vehicle;
  int offset = 0;  // start of this vehicle's block in mjData::userdata
};

// Layout of one vehicle's block in mjData::userdata (mj_resetData zeroes it).
enum VehicleSlot : int {
  kSet = 0,         // 1 once the velocity below is recorded
  kTime,            // [s] time of the recorded velocity
  kVel,             // [m/s] world velocity of the body origin at kTime (3)
  kAcc = kVel + 3,  // [m/s^2] its finite difference over the last step (3)
  // Set when the vehicle's own damping became too stiff for MuJoCo's step (VehicleStopped):
  kStopped = kAcc + 3,  // 1 then; the vehicle applies no force until a reset
  kStopTime,            // [s] d->time of the call that found it
  kStopRate,            // [-] h lambda of the worst dof
  kStopDof,             // [-] that dof, 0-5 (surge, sway, heave, roll, pitch, yaw)
  kStopSpeed,           // [m/s or rad/s] its speed relative to the water
  kStopMass,            // [kg or kg m^2] its effective mass (body + added)
  kGrowth,      // [-] product of h lambda - 1 over the steps since h lambda last was <= limit
  kGrowthTime,  // [s] d->time of the step last multiplied into kGrowth
  kGrowthSteps, // [-] the steps in that product
  kCallTime,    // [s] d->time of the latest call (MuJoCo's RK4: which call is a state)
  kVehicleBlock,
};

struct AttachedMotion {
  int body = -1;
  int mocap = -1;
  Vec3 initial = Vec3::Zero();  // [m] the body's position in the model
  Motion motion;
};

struct AttachedSchedule {
  int actuator = -1;
  Schedule schedule;
};

struct ModelVehicles {
  std::vector<AttachedVehicle> vehicles;
  std::vector<AttachedMotion> motions;
  std::vector<AttachedSchedule> schedules;
  int nuserdata = 0;  // m->nuserdata after Attach, to catch a stale registration
};

std::shared_mutex g_mutex;
std::unordered_map<const mjModel*, std::unique_ptr<ModelVehicles>> g_models;

const ModelVehicles* Lookup(const mjModel* m) {
  std::shared_lock<std::shared_mutex> lock(g_mutex);
  auto it = g_models.find(m);
  // A model deleted without Detach and another allocated at the same address: ignore.
  if (it == g_models.end() || it->second->nuserdata != m->nuserdata) return nullptr;
  return it->second.get();
}

using RowMat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

std::string Directory(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? "" : path.substr(0, slash + 1);
}

// Relative tolerance [-] for "the mocap position is the prescribed one".
constexpr double kSamePosition = 1e-9;

}  // namespace

bool AttachVehicles(mjModel* m, const std::string& source, const Environment& env, int* offset,
                    bool* any, std::string* error) {
  *any = false;
  std::string element;
  auto fail = [&](const std::string& message) {
    if (error) *error = source + ": <text name=\"" + element + "\">: " + message;
    return false;
  };
  auto set = std::make_unique<ModelVehicles>();
  for (int i = 0; i < m->ntext; ++i) {
    element = m->names + m->name_textadr[i];
    const std::string data = m->text_data + m->text_adr[i];
    const size_t colon = element.find(':');
    if (colon == std::string::npos) continue;
    const std::string kind = element.substr(0, colon), name = element.substr(colon + 1);
    if (kind != "vehicle" && kind != "motion" && kind != "thrust") continue;
    if (name.empty()) return fail("a " + kind + " needs a name after '" + kind + ":'");
    DeclarationError e;
    if (kind == "vehicle") {
      const int b = mj_name2id(m, mjOBJ_BODY, name.c_str());
      if (b < 0) return fail("no body named '" + name + "' in the model");
      const int j = m->body_jntadr[b];
      if (m->body_jntnum[b] != 1 || m->jnt_type[j] != mjJNT_FREE) {
        return fail("body '" + name + "' must have exactly one joint, a free joint (<freejoint/>)");
      }
      // MuJoCo's inertia-box / ellipsoid fluid model acts on every body when density or
      // viscosity > 0: its drag would be counted on top of the declared damping.
      if (m->opt.density > 0 || m->opt.viscosity > 0) {
        std::ostringstream s;
        s << "MuJoCo's own fluid model (<option density=\"" << m->opt.density << "\" viscosity=\""
          << m->opt.viscosity << "\">) would also act on body '" << name
          << "', on top of the declared damping; set <option density=\"0\" viscosity=\"0\"> "
             "(the water's density and current come from <text name=\"water\">)";
        return fail(s.str());
      }
      std::optional<VehicleParams> p = ParseVehicle(data, &e);
      if (!p) return fail(e.message);
      std::string message;
      std::optional<Vehicle> v = Vehicle::Create(*p, env, m->body_subtreemass[b], &message);
      if (!v) return fail(message);
      set->vehicles.push_back({name, b, m->jnt_dofadr[j], *v, 0});
    } else if (kind == "motion") {
      const int b = mj_name2id(m, mjOBJ_BODY, name.c_str());
      if (b < 0) return fail("no body named '" + name + "' in the model");
      if (m->body_mocapid[b] < 0) {
        return fail("body '" + name + "' is not a mocap body: declare it with mocap=\"true\"");
      }
      std::optional<MotionParams> p = ParseMotion(data, &e);
      if (!p) return fail(e.message);
      const std::string path =
          !p->csv.empty() && p->csv[0] != '/' ? Directory(source) + p->csv : p->csv;
      std::string message;
      std::optional<Motion> mo = Motion::Create(*p, path, &message);
      if (!mo) return fail(message);
      set->motions.push_back({b, m->body_mocapid[b], Vec3(m->body_pos + 3 * b), *mo});
    } else {
      const int a = mj_name2id(m, mjOBJ_ACTUATOR, name.c_str());
      if (a < 0) return fail("no actuator named '" + name + "' in the model");
      std::optional<Schedule> s = ParseSchedule(data, &e);
      if (!s) return fail(e.message);
      set->schedules.push_back({a, *s});
    }
  }
  *any = !set->vehicles.empty() || !set->motions.empty() || !set->schedules.empty();
  if (!*any) return true;
  for (AttachedVehicle& av : set->vehicles) {
    av.offset = *offset;
    *offset += kVehicleBlock;
  }
  set->nuserdata = *offset;  // what Attach sets m->nuserdata to
  // Added mass into the free joints' armature: world-frame translation dofs take the isotropic
  // part, body-frame rotation dofs the rotational diagonal (see vehicle.h).
  for (const AttachedVehicle& av : set->vehicles) {
    for (int i = 0; i < 3; ++i) {
      m->dof_armature[av.dof + i] += av.vehicle.armature_translation();
      m->dof_armature[av.dof + 3 + i] += av.vehicle.armature_rotation()[i];
    }
  }
  // MuJoCo 2.2 bakes the armature of "simple" dofs (a free body with its centre of mass at the
  // origin and a diagonal inertia) into dof_M0 at compile time: recompute the constants.
  if (!set->vehicles.empty()) {
    mjData* scratch = mj_makeData(m);
    mj_setConst(m, scratch);
    mj_deleteData(scratch);
  }
  std::unique_lock<std::shared_mutex> lock(g_mutex);
  g_models[m] = std::move(set);
  return true;
}

void DetachVehicles(const mjModel* m) {
  std::unique_lock<std::shared_mutex> lock(g_mutex);
  g_models.erase(m);
}

namespace {

// MuJoCo integrates the vehicle's damping explicitly, like every force from mjcb_passive. On
// dof i the damping D_l,i nu_i + D_q,i |nu_i| nu_i (Fossen 2011, eq. 6.66, diagonal) changes by
// lambda_i M_i = D_l,i + 2 D_q,i |nu_i| per unit of velocity, M_i the dof's effective mass (the
// body's, plus its added mass in the armature). The explicit step multiplies a velocity
// perturbation about the motion by 1 - h lambda_i (Euler; RK4's real-axis limit is
// h lambda = 2.785): beyond 2 it reverses and grows every step, until MuJoCo reports a huge QACC
// and resets the data. The scene fuzzer found such runs (seeds 1885, 6154, 8370: thrusts of
// millions of newtons drove light vehicles at hundreds of m/s).
//
// A vehicle flung past the limit for a step or two (a snap) is not unstable: the quadratic law
// then slows it by more than it overshoots (its secant h D_q |v| / M is half the tangent), and
// the first fuzzer build that stopped at once stopped 5 runs that agreed with their 0.2 ms
// selves and 11 warned stretched starts that ran. So the growth is accumulated: the product of
// h lambda - 1 over the consecutive steps beyond the limit (once per MuJoCo step, the worst
// dof's) must reach kGrowthStop, a perturbation grown a hundredfold. True then; the figures go
// into u for VehicleStopped.
constexpr double kGrowthStop = 100;

bool DampingTooStiff(const mjModel* m, const mjData* d, const AttachedVehicle& av,
                     const Vec6& nu_r, double* u) {
  const VehicleParams& p = av.vehicle.params();
  const double h = m->opt.timestep;
  const double limit = ExplicitDampingLimit(m);
  double worst = 0;
  int dof = -1;
  double mass = 0;
  for (int i = 0; i < 6; ++i) {
    const double M = i < 3 ? m->body_subtreemass[av.body] + m->dof_armature[av.dof + i]
                           : m->body_inertia[3 * av.body + i - 3] + m->dof_armature[av.dof + i];
    const double rate =
        h * (p.linear_damping[i] + 2 * p.quadratic_damping[i] * std::abs(nu_r[i])) / M;
    if (rate > worst) worst = rate, dof = i, mass = M;
  }
  if (worst <= limit) {
    u[kGrowth] = 0;
    u[kGrowthSteps] = 0;
    return false;
  }
  // Once per MuJoCo step: the first call at a time at least a step after the last one counted
  // (RK4's stages at t + h/2 and repeated mj_forward calls at one time do not count again).
  if (u[kGrowthSteps] == 0 || d->time >= u[kGrowthTime] + 0.99 * h) {
    u[kGrowth] = (u[kGrowthSteps] == 0 ? 1 : u[kGrowth]) * (worst - 1);
    u[kGrowthSteps] += 1;
    u[kGrowthTime] = d->time;
  }
  if (u[kGrowth] < kGrowthStop) return false;
  u[kStopped] = 1;
  u[kStopRate] = worst;
  u[kStopDof] = dof;
  u[kStopSpeed] = std::abs(nu_r[dof]);
  u[kStopMass] = mass;
  return true;
}

}  // namespace

void ApplyVehicles(const mjModel* m, mjData* d) {
  const ModelVehicles* set = Lookup(m);
  if (!set) return;
  for (const AttachedVehicle& av : set->vehicles) {
    const Vehicle& veh = av.vehicle;
    const int b = av.body;
    double* u = d->userdata + av.offset;
    if (u[kStopped] != 0) continue;  // stopped (VehicleStopped): inert until a reset
    const Eigen::Map<const RowMat3> R(d->xmat + 9 * b);  // body to world
    const Vec3 origin(d->xpos + 3 * b);
    // Buoyancy at the centre of buoyancy.
    if (veh.has_buoyancy()) {
      const Vec3 cob = origin + R * veh.params().cob;
      const Vec3 f = veh.Buoyancy(), zero = Vec3::Zero();
      mj_applyFT(m, d, f.data(), zero.data(), cob.data(), b, d->qfrc_passive);
    }
    if (!veh.has_damping() && !veh.has_added_mass()) continue;
    // Free joint: qvel = world velocity of the body origin, then body-frame angular velocity.
    const Vec3 v(d->qvel + av.dof), w(d->qvel + av.dof + 3);
    const Vec6 nu_r = veh.RelativeVelocity(R, v, w, origin.z());
    if (veh.has_damping() && DampingTooStiff(m, d, av, nu_r, u)) {
      u[kStopTime] = d->time;
      continue;
    }
    Wrench tau = veh.Damping(nu_r);
    if (veh.has_added_mass()) {
      // The world acceleration over the last step, from the velocities of the last two states
      // (with Euler and implicit: the previous step's qacc). A second call at the same time
      // reuses it, so repeated mj_forward calls change nothing. With MuJoCo's RK4 the callback
      // also sees the stages' predicted states (t + h/2 twice, then t + h) before the state at
      // t + h: only a second call at a time a step after the last state's is a state. A
      // difference over the stages instead fed the remainder's own lagged force back through
      // RK4's extrapolation, and a vehicle with a remainder of half its mass sank at 70 m/s
      // (tests/vehicle_test.cc, RK4 case).
      const bool state =
          m->opt.integrator != mjINT_RK4 ||
          (d->time >= u[kTime] + 0.99 * m->opt.timestep && u[kCallTime] == d->time);
      if (u[kSet] == 0 || d->time < u[kTime]) {
        u[kSet] = 1;
        u[kTime] = d->time;
        for (int i = 0; i < 3; ++i) u[kVel + i] = v[i], u[kAcc + i] = 0;
      } else if (d->time > u[kTime] && state) {
        for (int i = 0; i < 3; ++i) {
          u[kAcc + i] = (v[i] - u[kVel + i]) / (d->time - u[kTime]);
          u[kVel + i] = v[i];
        }
        u[kTime] = d->time;
      }
      u[kCallTime] = d->time;
      const Vec3 a(u + kAcc);
      // Body-frame derivative of v_r (the lagged term).
      const Vec3 dv_r = R.transpose() * a - w.cross(nu_r.head<3>());
      const Wrench am = veh.AddedMass(nu_r, dv_r);
      tau.force += am.force;
      tau.torque += am.torque;
    }
    const Vec3 f = R * tau.force, t = R * tau.torque;
    mj_applyFT(m, d, f.data(), t.data(), origin.data(), b, d->qfrc_passive);
  }
}

bool PrescribedVelocity(const mjModel* m, const mjData* d, int body, Vec3* vel) {
  const ModelVehicles* set = Lookup(m);
  if (!set || body < 0) return false;
  const int root = m->body_rootid[body];
  for (const AttachedMotion& am : set->motions) {
    if (am.body != root) continue;
    const Vec3 expected = am.initial + am.motion.Offset(d->time);
    const Vec3 actual(d->mocap_pos + 3 * am.mocap);
    if ((actual - expected).norm() > kSamePosition * (1 + expected.norm())) return false;
    *vel = am.motion.Velocity(d->time);
    return true;
  }
  return false;
}

void Prescribe(const mjModel* m, mjData* d) {
  const ModelVehicles* set = Lookup(m);
  if (!set) return;
  for (const AttachedMotion& am : set->motions) {
    const Vec3 p = am.initial + am.motion.Offset(d->time);
    for (int i = 0; i < 3; ++i) d->mocap_pos[3 * am.mocap + i] = p[i];
  }
  for (const AttachedSchedule& as : set->schedules) {
    d->ctrl[as.actuator] = as.schedule.At(d->time);
  }
}

void Step(const mjModel* m, mjData* d) {
  Prescribe(m, d);
  mj_step(m, d);
}

int VehicleCount(const mjModel* m) {
  const ModelVehicles* set = Lookup(m);
  return set ? static_cast<int>(set->vehicles.size()) : 0;
}

int FindVehicle(const mjModel* m, const std::string& body_name) {
  const ModelVehicles* set = Lookup(m);
  if (!set) return -1;
  for (size_t k = 0; k < set->vehicles.size(); ++k) {
    if (set->vehicles[k].name == body_name) return static_cast<int>(k);
  }
  return -1;
}

int VehicleBody(const mjModel* m, int k) {
  const ModelVehicles* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->vehicles.size())) return -1;
  return set->vehicles[k].body;
}

const Vehicle* GetVehicle(const mjModel* m, int k) {
  const ModelVehicles* set = Lookup(m);
  if (!set || k < 0 || k >= static_cast<int>(set->vehicles.size())) return nullptr;
  return &set->vehicles[k].vehicle;
}

std::optional<std::string> VehicleStopped(const mjModel* m, const mjData* d, int* body) {
  const ModelVehicles* set = Lookup(m);
  if (!set) return std::nullopt;
  static const char* kDof[6] = {"surge", "sway", "heave", "roll", "pitch", "yaw"};
  for (const AttachedVehicle& av : set->vehicles) {
    const double* u = d->userdata + av.offset;
    if (u[kStopped] == 0) continue;
    if (body) *body = av.body;
    const int i = static_cast<int>(u[kStopDof]);
    const VehicleParams& p = av.vehicle.params();
    const bool lin = i < 3;
    const double h = m->opt.timestep;
    const double limit = ExplicitDampingLimit(m);
    std::ostringstream s;
    s << "vehicle '" << av.name << "' stopped at t = " << u[kStopTime]
      << " s: its own damping is too stiff for the step: moving in " << kDof[i] << " at "
      << u[kStopSpeed] << (lin ? " m/s" : " rad/s")
      << " through the water, its damping D_l + 2 D_q |v| = " << p.linear_damping[i] << " + 2 x "
      << p.quadratic_damping[i] << " x " << u[kStopSpeed] << " on an effective mass of "
      << u[kStopMass] << (lin ? " kg" : " kg m^2")
      << " (body + added) gives h lambda = " << u[kStopRate] << " > " << limit
      << " at <option timestep> " << h << " s, beyond it for " << u[kGrowthSteps]
      << " step(s) in a row: MuJoCo steps the damping explicitly, so a velocity perturbation "
         "reversed and grew "
      << u[kGrowth] << "-fold (it would go on until MuJoCo reports a huge QACC and resets). ";
    const double thrust = Vec3(d->qfrc_actuator + av.dof).norm();
    if (lin && thrust > 0) {
      s << "What drives it that fast: the actuators push it with " << thrust << " N. ";
    }
    s << "Reduce what drives it (thrust, motion), or <option timestep> below "
      << h * limit / u[kStopRate] << " s, or make the body heavier.";
    return s.str();
  }
  return std::nullopt;
}

int FreeRootDof(const mjModel* m, int body) {
  const int j = m->body_jntadr[m->body_rootid[body]];
  return j >= 0 && m->jnt_type[j] == mjJNT_FREE ? m->jnt_dofadr[j] : -1;
}

double ScheduledThrust(const mjModel* m, const mjData* d, int body) {
  const ModelVehicles* set = Lookup(m);
  const int dof = body > 0 ? FreeRootDof(m, body) : -1;
  if (!set || dof < 0) return 0;
  Vec3 force = Vec3::Zero();
  for (const AttachedSchedule& as : set->schedules) {
    const int a = as.actuator;
    // Motors and other fixed-gain, bias-free actuators: force = gain x ctrl along the moment.
    if (m->actuator_gaintype[a] != mjGAIN_FIXED || m->actuator_biastype[a] != mjBIAS_NONE) {
      continue;
    }
    double peak = 0;  // the schedule's value of largest magnitude (linear between its points)
    for (double c : as.schedule.value) {
      if (m->actuator_ctrllimited[a]) {
        c = std::clamp(c, m->actuator_ctrlrange[2 * a], m->actuator_ctrlrange[2 * a + 1]);
      }
      if (std::abs(c) > std::abs(peak)) peak = c;
    }
    force += m->actuator_gainprm[a * mjNGAIN] * peak * Vec3(d->actuator_moment + a * m->nv + dof);
  }
  return force.norm();
}

}  // namespace mjtether
