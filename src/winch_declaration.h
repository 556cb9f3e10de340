// The winch declaration (docs/winch.md):
//
//   <text name="winch:umbilical" data="end=A mode=speed actuator=winch
//         min_length=5 max_length=300 max_speed=1.5 max_accel=0.5"/>
//
// and the drum's law: the payout speed over the next step from the actuator's ctrl, the
// tension at the drum and the limits. MuJoCo-free (the glue reads ctrl and applies it).
#ifndef MJTETHER_SRC_WINCH_DECLARATION_H_
#define MJTETHER_SRC_WINCH_DECLARATION_H_

#include <optional>
#include <string>

#include "declaration.h"

namespace mjtether {

enum class WinchMode {
  kSpeed,    // ctrl is the payout speed [m/s], > 0 pays out
  kTension,  // ctrl is the tension to hold at the drum [N]
};

struct WinchParams {
  int end = 0;                        // [-] 0: end A, 1: end B (where the drum is)
  WinchMode mode = WinchMode::kSpeed;
  std::string actuator;               // MuJoCo actuator whose ctrl commands the winch
  double min_length = 0;              // [m] shortest deployed unstretched length
  double max_length = 0;              // [m] longest deployed unstretched length
  double max_speed = 0;               // [m/s] largest payout or haul-in speed
  double max_accel = 0;               // [m/s^2] largest rate of change of the payout speed
  double tau = 0.2;                   // [s] drum time constant (tension mode)
  double band = 0.05;                 // [-] tension mode: the tension error, as a fraction
                                      //     of the set tension, that commands max_speed
};

// Parses a winch declaration: every key range-checked; actuator, min_length, max_length,
// max_speed and max_accel are required; min_length <= max_length.
std::optional<WinchParams> ParseWinch(const std::string& text, DeclarationError* error);

// The drum's state between steps: deployed unstretched length and payout speed.
struct DrumState {
  double length = 0;  // [m]
  double speed = 0;   // [m/s]
};

// The payout speed over the next step of dt [s] (held constant over it, so that the length
// grows by exactly speed dt), from the state, the actuator's ctrl and, in tension mode, the
// tension at the drum T [N]:
//   speed mode:   target = ctrl;
//   tension mode: target = max_speed (T - ctrl)/(band ctrl) (pays out above the set tension),
//                 followed with the first-order lag tau: s += (target - s) dt/(tau + dt)
//                 (backward Euler of tau s' = target - s), with the tension taken at the
//                 step's end, T - Z (s - s_prev), Z the drum's impedance [N s/m]
//                 (Tether::DrumImpedance; 0: the tension at the step's start);
// then |s| <= max_speed, |s - s_prev| <= max_accel dt, slowing down ahead of a limit at
// max_accel so as to stop on it, and the brake: a speed that would still carry the length past
// min_length or max_length within the step is cut so that it stops there (length exactly at
// the limit), and stays 0 while the command pushes outward.
double WinchSpeed(const WinchParams& w, const DrumState& s, double ctrl, double tension,
                  double dt, double impedance = 0);

}  // namespace mjtether

#endif  // MJTETHER_SRC_WINCH_DECLARATION_H_
