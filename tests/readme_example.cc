// The C++ example of README.md, compiled and run by CTest. Keep the two in step.
#include <cmath>
#include <cstdio>
#include <string>

#include <mujoco/mujoco.h>

#include <mjtether/mjtether.h>

int main() {
  std::string error;
  mjModel* m = mjtether::LoadModel(MJTETHER_MODELS_DIR "/rov_tether.xml", &error);
  if (!m) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  mjData* d = mj_makeData(m);  // after LoadModel: sized for the tether state
  const int k = mjtether::FindTether(m, "umbilical");
  while (d->time < 60) {
    mjtether::Step(m, d);  // the thrust: schedules, then mj_step (the tether acts in mjcb_passive)
    if (auto message = mjtether::CheckDivergence(m, d)) {
      std::fprintf(stderr, "%s\n", message->c_str());
      return 1;
    }
  }
  const mjtether::EndReactions r = mjtether::GetReactions(m, d, k);
  std::printf("t = %.2f s: tension at the TMS %.1f N, at the ROV %.1f N\n", d->time,
              r.tension_a, r.tension_b);
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
  // The example's check, against an estimate from the declarations alone: the ROV drives
  // down-current on its surge thrusters until 12.5 s, is caught by the tether, and after the
  // thrust stops hangs on it, at rest in the 0.3 m/s current. The tether then holds the vehicle's drag at 0.3 m/s,
  // linear 10 * 0.3 + quadratic 100 * 0.3^2 = 12 N (surge), and its net buoyancy,
  // (1025 * 0.049268 - 50) * 9.81 = 4.91 N: the tension at the ROV is about
  // hypot(12, 4.91) = 12.97 N. Tolerance 10%: at 60 s the ROV still rises at up to
  // 0.04 m/s, whose heave damping 20 * 0.04 + 215 * 0.04^2 = 1.1 N is 8.5% of it; its 3 degree
  // pitch moves < 1% of the drag into heave, and the end node's own drag is 0.14 N.
  const double estimate = std::hypot(10 * 0.3 + 100 * 0.3 * 0.3, (1025 * 0.049268 - 50) * 9.81);
  if (!(std::abs(r.tension_b - estimate) <= 0.1 * estimate)) {
    std::fprintf(stderr, "tension at the ROV %.2f N, estimate %.2f N +- 10%%\n", r.tension_b,
                 estimate);
    return 1;
  }
  return 0;
}
