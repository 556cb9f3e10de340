// Prescribed motion of a body (a ship, a tether-management system, a fairlead) and scripted
// actuator inputs, both functions of time only.
//
//   <text name="motion:ship" data="x=2,10,0 z=1,8,0 ramp=10"/>  harmonic, per axis
//   <text name="motion:tms" data="csv=tms_track.csv"/>          time table
//   <text name="thrust:surge" data="t=0,5,5.5,20 ctrl=0,0,40,40"/>  piecewise linear ctrl
//
// A motion is an offset added to the body's initial position. Harmonic axis i moves by
// s_i(t) = a_i sin(2 pi t / T_i + phi_i). A CSV table gives rows `time,x,y,z` (offsets [m]),
// interpolated linearly and held before the first and after the last row. Either is multiplied
// by the start ramp r(t) = (1 - cos(pi t / T_r))/2 for t < T_r, 1 after, so that the body
// starts at its initial position with zero velocity (C1 start). Velocities are the exact time
// derivatives of these positions.
#ifndef MJTETHER_SRC_MOTION_H_
#define MJTETHER_SRC_MOTION_H_

#include <optional>
#include <string>
#include <vector>

#include "params.h"

namespace mjtether {

struct MotionParams {
  bool harmonic[3] = {false, false, false};
  double amplitude[3] = {0, 0, 0};  // [m] a_i
  double period[3] = {1, 1, 1};     // [s] T_i
  double phase[3] = {0, 0, 0};      // [rad] phi_i
  std::string csv;                  // table file (relative to the model's directory)
  double ramp = -1;  // [s] T_r; < 0: the longest declared period (harmonic), 0 (table)
};

class Motion {
 public:
  // A harmonic motion, or the table read from `csv_path` (rows time,x,y,z; an optional header
  // line; times strictly increasing). Returns nothing and sets *error on a bad file.
  static std::optional<Motion> Create(const MotionParams& params, const std::string& csv_path,
                                      std::string* error);

  Vec3 Offset(double t) const;    // [m] added to the initial position
  Vec3 Velocity(double t) const;  // [m/s] d Offset / dt
  double ramp() const { return ramp_; }

 private:
  Motion() = default;
  Vec3 Raw(double t, Vec3* rate) const;  // unramped offset and its rate

  MotionParams p_;
  double ramp_ = 0;           // [s]
  std::vector<double> time_;  // table times [s] (n)
  std::vector<Vec3> table_;   // table offsets [m] (n)
};

// A piecewise-linear time table of one actuator's ctrl: held before the first and after the
// last point; equal consecutive times give a step.
struct Schedule {
  std::vector<double> t;      // [s] non-decreasing
  std::vector<double> value;  // ctrl (the actuator's unit: N for a motor with gear 1)
  double At(double time) const;
};

}  // namespace mjtether

#endif  // MJTETHER_SRC_MOTION_H_
