// A depth, heading and attitude controller for the BlueROV2 Heavy of models/bluerov2_heavy.xml,
// written against the plain MuJoCo API plus mjtether's read-outs, to show how a controller is
// prototyped on a tethered vehicle. Header-only so that tests/vehicle_test.cc runs the same
// code as examples/rov_pid.cc.
//
// Control law (all in the body frame, for small roll and pitch):
//   heave force  F_z = PID(depth error) + buoyancy feed-forward - (tether force)_z
//   yaw moment   N   = PID(heading error)
//   roll, pitch  K, M = PD(angle) (the vertical thrusters also hold the vehicle level, like
//                       ArduSub's "stabilize" mode: without it the Munk moment overturns the
//                       vehicle in pitch above 0.5 m/s, see README)
//   surge        the pilot's command [N], open loop; or, in station keeping, a PID on the
//                world horizontal position error, turned into body-frame surge and sway
// Allocation: the four vertical thrusters at (+-x_v, +-y_v) share F_z, K, M by the
// pseudo-inverse of their geometry; the four vectored horizontal ones share surge and yaw.
// The tether's pull on the vehicle (mjtether::GetReactions, force on end B) is fed forward in
// heave: this is the "read the tether from a controller" part of the example.
#ifndef MJTETHER_EXAMPLES_ROV_CONTROLLER_H_
#define MJTETHER_EXAMPLES_ROV_CONTROLLER_H_

#include <mjtether/mjtether.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace rov {

// A PID on an error and its rate (rate from the measured velocity, not a difference), with a
// clamped integral (anti-windup).
struct Pid {
  double kp = 0, ki = 0, kd = 0;  // gains
  double integral_limit = 0;      // |integral term| limit, in the output's unit
  double integral = 0;            // state: integral of ki * error
  double Update(double error, double rate, double dt) {
    integral = std::clamp(integral + ki * error * dt, -integral_limit, integral_limit);
    return kp * error + integral + kd * rate;
  }
};

struct Setpoint {
  double depth = -10;    // [m] world z of the body origin
  double heading = 0;    // [rad] yaw about world z
  double surge = 0;      // [N] pilot's open-loop surge force
  bool station = false;  // hold the horizontal position (x, y) instead of the pilot's surge
  double x = 0, y = 0;   // [m] world position held when station is set
};

class DepthHeadingController {
 public:
  // Finds the vehicle body, its tether (end B on the vehicle) and the eight thrusters by the
  // names used in models/bluerov2_heavy.xml. ok() is false if any is missing.
  DepthHeadingController(const mjModel* m, const std::string& body, const std::string& tether) {
    body_ = mj_name2id(m, mjOBJ_BODY, body.c_str());
    tether_ = mjtether::FindTether(m, tether);
    const char* names[8] = {"fr", "fl", "rr", "rl", "vfr", "vfl", "vrr", "vrl"};
    ok_ = body_ >= 0 && tether_ >= 0;
    for (int i = 0; i < 8; ++i) {
      act_[i] = mj_name2id(m, mjOBJ_ACTUATOR, names[i]);
      ok_ = ok_ && act_[i] >= 0;
    }
    if (!ok_) return;
    // Vertical thruster positions (body frame) from their sites.
    for (int i = 0; i < 4; ++i) {
      const int site = m->actuator_trnid[2 * act_[4 + i]];
      xv_[i] = m->site_pos[3 * site];
      yv_[i] = m->site_pos[3 * site + 1];
    }
    // Net buoyancy [N] of the vehicle (weight minus buoyancy), fed forward.
    const mjtether::Vehicle* v = mjtether::GetVehicle(m, mjtether::FindVehicle(m, body));
    const double g = -m->opt.gravity[2];
    buoyancy_ = v ? v->Buoyancy().z() - m->body_subtreemass[body_] * g : 0;
    // Gains: heave (m + A3 = 26 kg) at 1.5 rad/s, critically damped; yaw (I + A = 0.28 kg m^2)
    // at 3 rad/s; roll and pitch at 10 rad/s, stiffer than the Munk moment's destabilising
    // (A3 - A1) U^2 = 9 N m/rad per (m/s)^2 up to 1.5 m/s.
    depth.kp = 60, depth.ki = 20, depth.kd = 80, depth.integral_limit = 40;
    yaw.kp = 2.5, yaw.ki = 1, yaw.kd = 1.7, yaw.integral_limit = 3;
    level.kp = 30, level.kd = 6;
    // Station keeping: m + A1,2 ~ 20 kg at 0.8 rad/s, critically damped.
    px.kp = py.kp = 13, px.ki = py.ki = 3, px.kd = py.kd = 32;
    px.integral_limit = py.integral_limit = 40;
  }

  bool ok() const { return ok_; }

  // Writes the eight thrusters' ctrl [N] for the state in d. dt [s] is the control period.
  void Compute(const mjModel* m, mjData* d, const Setpoint& sp, double dt) {
    const double* R = d->xmat + 9 * body_;  // body to world, row-major
    const double* qv = d->qvel + m->jnt_dofadr[m->body_jntadr[body_]];
    const double z = d->xpos[3 * body_ + 2];
    const double vz = qv[2];
    const double yaw_angle = std::atan2(R[3], R[0]);
    const double roll = std::atan2(R[7], R[8]), pitch = -std::asin(std::clamp(R[6], -1.0, 1.0));
    const double p = qv[3], q = qv[4], r = qv[5];  // body-frame angular velocity [rad/s]

    // The tether's pull on the vehicle, fed forward in heave.
    tether_force_z_ = mjtether::GetReactions(m, d, tether_).force_b.z();
    const double Fz = depth.Update(sp.depth - z, -vz, dt) - buoyancy_ -
                      (feed_forward_tether ? tether_force_z_ : 0);
    double heading_error = std::remainder(sp.heading - yaw_angle, 2 * M_PI);
    const double N = yaw.Update(heading_error, -r, dt);
    const double K = -level.kp * roll - level.kd * p;
    const double M = -level.kp * pitch - level.kd * q;

    // Vertical thrusters: f_i = Fz/4 + K y_i / sum(y^2) - M x_i / sum(x^2) (world-vertical
    // force taken along the body z-axis: small roll and pitch).
    double sx = 0, sy = 0;
    for (int i = 0; i < 4; ++i) sx += xv_[i] * xv_[i], sy += yv_[i] * yv_[i];
    for (int i = 0; i < 4; ++i) {
      d->ctrl[act_[4 + i]] = Fz / 4 + K * yv_[i] / sy - M * xv_[i] / sx;
    }
    // Horizontal force: the pilot's surge, or the station-keeping PID's world force turned
    // into the body frame (yaw only).
    double surge = sp.surge, sway = 0;
    if (sp.station) {
      const double fx = px.Update(sp.x - d->xpos[3 * body_], -qv[0], dt);
      const double fy = py.Update(sp.y - d->xpos[3 * body_ + 1], -qv[1], dt);
      const double c = std::cos(yaw_angle), sn = std::sin(yaw_angle);
      surge = c * fx + sn * fy;
      sway = -sn * fx + c * fy;
    }
    // Horizontal thrusters (gears at 45 deg): per N of ctrl each, surge 0.7071 N with signs
    // +, +, +, + for fr, fl, rr, rl; sway 0.7071 N with +, -, -, +; yaw 0.1888 N m with
    // +, -, +, -.
    const double s = surge / (4 * 0.7071), w = sway / (4 * 0.7071), n = N / (4 * 0.1888);
    d->ctrl[act_[0]] = s + w + n;
    d->ctrl[act_[1]] = s - w - n;
    d->ctrl[act_[2]] = s - w + n;
    d->ctrl[act_[3]] = s + w - n;
  }

  double tether_force_z() const { return tether_force_z_; }  // [N] at the last Compute

  Pid depth, yaw, level, px, py;
  bool feed_forward_tether = true;  // cancel the tether's vertical pull in the heave force

 private:
  bool ok_ = false;
  int body_ = -1, tether_ = -1;
  int act_[8] = {-1, -1, -1, -1, -1, -1, -1, -1};
  double xv_[4] = {0, 0, 0, 0}, yv_[4] = {0, 0, 0, 0};  // [m] vertical thruster positions
  double buoyancy_ = 0;                                 // [N] net upward force at rest
  double tether_force_z_ = 0;                           // [N]
};

}  // namespace rov

#endif  // MJTETHER_EXAMPLES_ROV_CONTROLLER_H_
