// Controller prototyping on a tethered vehicle: the BlueROV2 Heavy of
// models/bluerov2_heavy.xml holds its depth and heading with a PID (examples/rov_controller.h)
// installed as MuJoCo's mjcb_control, while the pilot drives it away from the surface boat
// until its 30 m tether, slack at the start, comes taut.
//
//   rov_pid [MODEL.xml] [--surge N] [--duration S] [--bound M] [--station] [--help]
//
// MODEL.xml defaults to bluerov2_heavy.xml in mjtether's models: the source tree's when built
// with mjtether, the installed ones (share/mjtether/models) when built on its own against an
// installed mjtether (examples/CMakeLists.txt).
//
// --station: hold the initial position (x, y) as well (station keeping; try
// models/manoeuvre_station_keeping.xml, a 0.3 m/s cross current); the pilot's surge is unused.
//
// Prints, once a second: time, depth [m], heading [deg], surge speed [m/s], the tether's
// tension at the vehicle [N] and its vertical pull [N] (mjtether::GetReactions), and its slack
// segments (mjtether::GetTensions). Exit status 0 if the depth stayed within --bound [m] of the
// set-point after the first 5 s, 1 if not, 2 on a load error.
#include <mjtether/mjtether.h>
#include <mjtether/version.h>
#include <mujoco/mujoco.h>

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
    "  MODEL.xml   scene with a body 'rov', a tether 'umbilical' and thrusters fr, fl, rr, rl,\n"
    "              vfr, vfl, vrr, vrl (default: " MJTETHER_MODELS_DIR
    "/bluerov2_heavy.xml)\n"
    "  --surge N   pilot's surge force after 2 s [N] (default 20)\n"
    "  --duration S  simulated time [s] (default 60)\n"
    "  --bound M   allowed depth error after 5 s [m] (default 0.1)\n"
    "  --station   hold the initial x, y too (station keeping)\n"
    "Exit status: 0 depth held within the bound, 1 not held or diverged, 2 bad input.\n";

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
  double surge = 20, duration = 60, bound = 0.1;
  bool station = false;
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
  std::printf("time,depth,heading_deg,surge_speed,tension,tether_pull_z,slack_segments%s\n",
              station ? ",station_error" : "");
  while (d->time < duration) {
    g_setpoint.surge = d->time > 2 ? surge : 0;  // the pilot pushes forward after 2 s
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
    if (++step % per_second == 0) {
      mjtether::GetTensions(m, d, k, T.data());
      int slack = 0;
      for (double t : T) slack += t <= 0;
      const double* R = d->xmat + 9 * body;
      std::printf("%.0f,%.4f,%.2f,%.3f,%.2f,%.2f,%d", d->time, z,
                  std::atan2(R[3], R[0]) * 180 / M_PI, d->qvel[0],
                  mjtether::GetReactions(m, d, k).tension_b, controller.tether_force_z(), slack);
      if (station) std::printf(",%.4f", drift);
      std::printf("\n");
    }
  }
  std::printf("largest depth error after 5 s: %.4f m (bound %.3f m)\n", worst, bound);
  if (station) std::printf("largest horizontal drift after 20 s: %.4f m\n", worst_station);
  mjcb_control = nullptr;
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
  return worst <= bound ? 0 : 1;
}
