// The C++ example of README.md, compiled and run by CTest. Keep the two in step.
#include <cstdio>
#include <string>

#include <mujoco/mujoco.h>

#include "mjtether.h"

int main() {
  std::string error;
  mjModel* m = mjtether::LoadModel(MJTETHER_MODELS_DIR "/rov_tether.xml", &error);
  if (!m) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  mjData* d = mj_makeData(m);  // after LoadModel: sized for the tether state
  const int k = mjtether::FindTether(m, "umbilical");
  while (d->time < 5) {
    mj_step(m, d);  // plain MuJoCo: the tether acts through mjcb_passive
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
  // The example's check: by 5 s the tether has caught the sinking ROV.
  return r.tension_b > 0 ? 0 : 1;
}
