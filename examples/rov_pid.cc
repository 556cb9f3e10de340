// Controller prototyping on a tethered vehicle: the BlueROV2 Heavy of
// models/bluerov2_heavy.xml holds its depth and heading with a PID (examples/rov_controller.h)
// installed as MuJoCo's mjcb_control, while the pilot drives it away from the surface boat
// until its 30 m tether, slack at the start, comes taut.
//
//   rov_pid [MODEL.xml] [--surge N] [--duration S] [--bound M] [--station]
//           [--winch N] [--goal X] [--help]
//
// MODEL.xml defaults to bluerov2_heavy.xml in mjtether's models: the source tree's when built
// with mjtether, the installed ones (share/mjtether/models) when built on its own against an
// installed mjtether (examples/CMakeLists.txt).
//
// --station: hold the initial position (x, y) as well (station keeping; try
// models/manoeuvre_station_keeping.xml, a 0.3 m/s cross current); the pilot's surge is unused.
//
// --winch N: winch mode (try models/bluerov2_heavy_winch.xml, a reel on the boat): the
// tether's winch (docs/winch.md, mode=tension, its actuator named 'reel') holds N newtons at
// the drum while the PID flies the vehicle; with --goal X the station set-point moves X m along
// world x at 0.5 m/s from 2 s (implies --station). The winch takes up the slack, then pays out as the
// vehicle goes and hauls in if it comes back. Exit status 0 also needs the tension at the drum
// within 10% of N after 20 s (the winch's lag and the initial slack taken up) and the vehicle
// within 0.5 m of its set-point at the end.
//
// Prints, once a second: time, depth [m], heading [deg], surge speed [m/s], the tether's
// tension at the vehicle [N] and its vertical pull [N] (mjtether::GetReactions), and its slack
// segments (mjtether::GetTensions); in winch mode also the deployed length [m], the payout
// speed [m/s] (mjtether::GetWinch) and the tension at the drum [N]. Exit status 0 if the depth stayed within --bound [m] of the
// set-point after the first 5 s, 1 if not, 2 on a load error.
#include <mjtether/mjtether.h>
#include <mjtether/version.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "rov_controller.h"

#ifndef MJTETHER_MODELS_DIR
#define MJTETHER_MODELS_DIR MJTETHER_MODELS_INSTALL_DIR
#endif

namespace {

constexpr const char* kUsage =
    "usage: rov_pid [MODEL.xml] [--surge N] [--duration S] [--bound M] [--station]\n"
    "               [--winch N] [--goal X]\n"
    "  MODEL.xml   scene with a body 'rov', a tether 'umbilical' and thrusters fr, fl, rr, rl,\n"
    "              vfr, vfl, vrr, vrl (default: " MJTETHER_MODELS_DIR
    "/bluerov2_heavy.xml)\n"
    "  --surge N   pilot's surge force after 2 s [N] (default 20)\n"
    "  --duration S  simulated time [s] (default 60)\n"
    "  --bound M   allowed depth error after 5 s [m] (default 0.1)\n"
    "  --station   hold the initial x, y too (station keeping)\n"
    "  --winch N   the tether's winch (actuator 'reel', mode=tension) holds N newtons\n"
    "              (try " MJTETHER_MODELS_DIR "/bluerov2_heavy_winch.xml)\n"
    "  --goal X    move the station set-point X m along x at 0.5 m/s from 2 s (implies\n"
    "              --station)\n"
    "Exit status: 0 depth held within the bound (winch mode: and the tension within 10% of\n"
    "N after 20 s, the set-point reached within 0.5 m), 1 not, or diverged, 2 bad input.\n";

// Reads a number option's value; false (with the usage on stderr) if it is not a finite number.
bool ParseNumber(const char* option, const char* text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(*value)) {
    std::fprintf(stderr, "rov_pid: %s expects a number, got '%s'\n%s", option, text, kUsage);
    return false;
  }
  return true;
}

// mjcb_control is one global function pointer: the controller it calls lives here.
rov::DepthHeadingController* g_controller = nullptr;
rov::Setpoint g_setpoint;
double g_last_time = -1;

void Control(const mjModel* m, mjData* d) {
  // mj_forward may call this again at the same time: integrate only when time advanced.
  const double dt = g_last_time < 0 ? 0 : d->time - g_last_time;
  if (dt < 0 || g_last_time < 0 || dt > 0) g_last_time = d->time;
  g_controller->Compute(m, d, g_setpoint, std::max(dt, 0.0));
}

}  // namespace

int main(int argc, char** argv) {
  std::string model = MJTETHER_MODELS_DIR "/bluerov2_heavy.xml";
  double surge = 20, duration = 60, bound = 0.1, winch_tension = 0, goal = 0;
  bool station = false, winch_mode = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--help" || a == "-h") {
      std::printf("%s", kUsage);
      return 0;
    } else if (a == "--surge" && has_value) {
      if (!ParseNumber("--surge", argv[++i], &surge)) return 2;
    } else if (a == "--duration" && has_value) {
      if (!ParseNumber("--duration", argv[++i], &duration)) return 2;
    } else if (a == "--bound" && has_value) {
      if (!ParseNumber("--bound", argv[++i], &bound)) return 2;
    } else if (a == "--station") {
      station = true;
    } else if (a == "--winch" && has_value) {
      if (!ParseNumber("--winch", argv[++i], &winch_tension)) return 2;
      if (!(winch_tension > 0)) {
        std::fprintf(stderr, "rov_pid: --winch expects a tension > 0 N\n%s", kUsage);
        return 2;
      }
      winch_mode = true;
    } else if (a == "--goal" && has_value) {
      if (!ParseNumber("--goal", argv[++i], &goal)) return 2;
      station = true;
    } else if (!a.empty() && a[0] == '-') {
      std::fprintf(stderr, "rov_pid: unknown option or missing value: %s\n%s", a.c_str(), kUsage);
      return 2;
    } else {
      model = a;
    }
  }
  mjtether::InstallErrorHandlers();
  std::string error;
  mjModel* m = mjtether::LoadModel(model, &error);
  if (!m) {
    std::fprintf(stderr, "rov_pid: %s\n", error.c_str());
    return 2;
  }
  mjData* d = mj_makeData(m);
  rov::DepthHeadingController controller(m, "rov", "umbilical");
  if (!controller.ok()) {
    std::fprintf(stderr,
                 "rov_pid: %s needs a body 'rov', a tether 'umbilical' and thrusters "
                 "fr, fl, rr, rl, vfr, vfl, vrr, vrl\n",
                 model.c_str());
    return 2;
  }
  const int body = mj_name2id(m, mjOBJ_BODY, "rov");
  const int k = mjtether::FindTether(m, "umbilical");
  // Winch mode: the reel's actuator carries the set tension (ctrl [N]).
  const int reel = mj_name2id(m, mjOBJ_ACTUATOR, "reel");
  if (winch_mode && (reel < 0 || !mjtether::GetWinch(m, d, k).present)) {
    std::fprintf(stderr,
                 "rov_pid: --winch needs a winch on the tether 'umbilical' (<text "
                 "name=\"winch:umbilical\" data=\"mode=tension actuator=reel ...\">) and an "
                 "actuator 'reel'; %s has %s\n",
                 model.c_str(), reel < 0 ? "no actuator 'reel'" : "no winch");
    return 2;
  }
  g_controller = &controller;
  mj_forward(m, d);                          // positions at t = 0 (xpos is zero before)
  g_setpoint.depth = d->xpos[3 * body + 2];  // hold the initial depth...
  const double* R0 = d->xmat + 9 * body;
  g_setpoint.heading = std::atan2(R0[3], R0[0]);  // ...and heading
  g_setpoint.station = station;
  g_setpoint.x = d->xpos[3 * body];
  g_setpoint.y = d->xpos[3 * body + 1];
  mjcb_control = Control;

  std::vector<double> T(mjtether::GetTether(m, k)->segments());
  double worst = 0;
  long long step = 0;
  const long long per_second = std::llround(1 / m->opt.timestep);
  double worst_station = 0;
  const double x0 = g_setpoint.x;
  double worst_tension = 0;  // [N] largest |drum tension - set| after 20 s (winch mode)
  std::printf("time,depth,heading_deg,surge_speed,tension,tether_pull_z,slack_segments%s%s\n",
              station ? ",station_error" : "",
              winch_mode ? ",length,payout_speed,drum_tension" : "");
  while (d->time < duration) {
    g_setpoint.surge = d->time > 2 ? surge : 0;  // the pilot pushes forward after 2 s
    // The set-point moves to x0 + goal at 0.5 m/s from 2 s (a step of 20 m would saturate the
    // thrusters and lose the heading).
    g_setpoint.x = x0 + std::copysign(std::clamp(0.5 * (d->time - 2), 0.0, std::abs(goal)), goal);
    // The winch reads its ctrl in the passive forces, which MuJoCo computes before
    // mjcb_control: set it here, before the step.
    if (winch_mode) d->ctrl[reel] = winch_tension;
    mjtether::Step(m, d);                        // motion: of the boat, then mj_step
    if (auto message = mjtether::CheckDivergence(m, d)) {
      std::fprintf(stderr, "rov_pid: %s\n", message->c_str());
      return 1;
    }
    const double z = d->xpos[3 * body + 2];
    const double drift =
        std::hypot(d->xpos[3 * body] - g_setpoint.x, d->xpos[3 * body + 1] - g_setpoint.y);
    if (d->time > 5) worst = std::max(worst, std::abs(z - g_setpoint.depth));
    if (d->time > 20) worst_station = std::max(worst_station, drift);
    if (winch_mode && d->time > 20) {
      worst_tension = std::max(
          worst_tension, std::abs(mjtether::GetReactions(m, d, k).tension_a - winch_tension));
    }
    if (++step % per_second == 0) {
      mjtether::GetTensions(m, d, k, T.data());
      int slack = 0;  // among the deployed segments (with a winch, those on the drum read 0)
      const int first = winch_mode ? mjtether::GetWinch(m, d, k).first_node : 0;
      for (size_t j = first; j < T.size(); ++j) slack += T[j] <= 0;
      const double* R = d->xmat + 9 * body;
      std::printf("%.0f,%.4f,%.2f,%.3f,%.2f,%.2f,%d", d->time, z,
                  std::atan2(R[3], R[0]) * 180 / M_PI, d->qvel[0],
                  mjtether::GetReactions(m, d, k).tension_b, controller.tether_force_z(), slack);
      if (station) std::printf(",%.4f", drift);
      if (winch_mode) {
        const mjtether::WinchState w = mjtether::GetWinch(m, d, k);
        std::printf(",%.3f,%.3f,%.2f", w.length, w.payout_speed,
                    mjtether::GetReactions(m, d, k).tension_a);
      }
      std::printf("\n");
    }
  }
  std::printf("largest depth error after 5 s: %.4f m (bound %.3f m)\n", worst, bound);
  if (station) std::printf("largest horizontal drift after 20 s: %.4f m\n", worst_station);
  const double final_error =
      std::hypot(d->xpos[3 * body] - g_setpoint.x, d->xpos[3 * body + 1] - g_setpoint.y);
  bool ok = worst <= bound;
  if (winch_mode) {
    std::printf("winch: largest tension error after 20 s: %.2f N (%.1f%% of %.3g N); "
                "set-point missed by %.3f m at the end\n",
                worst_tension, 100 * worst_tension / winch_tension, winch_tension, final_error);
    ok = ok && worst_tension <= 0.1 * winch_tension && final_error <= 0.5;
  }
  mjcb_control = nullptr;
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
  return ok ? 0 : 1;
}
