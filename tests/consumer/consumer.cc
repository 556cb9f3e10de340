// An external C++ program on an installed mjtether: loads the installed BlueROV2 scene, runs
// 2 s with mjtether::Step (thrust schedules and motions as `mjtether run`), and checks the
// tether against a conservation law: every segment tension is finite and >= 0, and the end
// reactions equal the magnitude of the end forces. Exit 0 on success.
#include <mjtether/mjtether.h>
#include <mjtether/version.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

int main() {
  std::printf("mjtether %s on MuJoCo %s\n", MJTETHER_VERSION_STRING, mj_versionString());
  std::string error;
  mjModel* m = mjtether::LoadModel(MODELS_DIR "/bluerov2_heavy.xml", &error);
  if (!m) {
    std::fprintf(stderr, "consumer: %s\n", error.c_str());
    return 2;
  }
  mjData* d = mj_makeData(m);
  const int k = mjtether::FindTether(m, "umbilical");
  if (k < 0) return 2;
  while (d->time < 2) {
    mjtether::Step(m, d);
    if (auto message = mjtether::CheckDivergence(m, d)) {
      std::fprintf(stderr, "consumer: %s\n", message->c_str());
      return 1;
    }
  }
  std::vector<double> T(mjtether::GetTether(m, k)->segments());
  mjtether::GetTensions(m, d, k, T.data());
  int bad = 0;
  for (double t : T) bad += !(std::isfinite(t) && t >= 0);
  const mjtether::EndReactions r = mjtether::GetReactions(m, d, k);
  // tension_a is |force_a| by definition (src/tether.h): equal to rounding.
  bad += std::abs(r.tension_a - r.force_a.norm()) > 1e-9 * (1 + r.tension_a);
  std::printf("t = %.3f s: tension at A %.2f N, at B %.2f N, %zu segments\n", d->time, r.tension_a,
              r.tension_b, T.size());
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
  return bad == 0 ? 0 : 1;
}
