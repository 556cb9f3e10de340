// The fixed comparison line of bench_callback's BM_Line (tests/reference_scenes.h, fairlead on a
// mocap body, 2 ms through mj_step): K steps after a warm-up. Prints a hash of mjData::userdata
// (the tether state: equal hashes = the same bits) and the CPU time of the K steps. Built and
// run by tools/line_steps.sh (docs/benchmarks.md).
//   line_steps INTEGRATOR SEGMENTS K WARMUP
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <sstream>
#include <string>

#include <mujoco/mujoco.h>

#include "reference_scenes.h"  // tests/
#include "mjtether.h"

int main(int argc, char** argv) {
  namespace rs = mjtether::reference_scenes;
  const char* integrator = argc > 1 ? argv[1] : "bdf2";
  const int segments = argc > 2 ? atoi(argv[2]) : 100;
  const int K = argc > 3 ? atoi(argv[3]) : 5000;
  const int warm = argc > 4 ? atoi(argv[4]) : 5000;
  const rs::Scene s = rs::LineScene();
  const double h = 0.002;
  std::string error;
  mjModel* m = mjtether::LoadModelFromString(rs::LineModelXml(s, segments, integrator, h),
                                             "line.xml", &error);
  if (!m) { fprintf(stderr, "%s\n", error.c_str()); return 1; }
  mjData* d = mj_makeData(m);
  auto step = [&]() {
    const mjtether::Vec3 p = s.b(d->time + h).pos;
    for (int i = 0; i < 3; ++i) d->mocap_pos[i] = p[i];
    mj_step(m, d);
  };
  for (int k = 0; k < warm; ++k) step();
  timespec a, b;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  for (int k = 0; k < K; ++k) step();
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  uint64_t hsh = 1469598103934665603ull;
  const unsigned char* p = reinterpret_cast<const unsigned char*>(d->userdata);
  for (size_t i = 0; i < sizeof(mjtNum) * m->nuserdata; ++i) hsh = (hsh ^ p[i]) * 1099511628211ull;
  const double cpu = (b.tv_sec - a.tv_sec) + 1e-9 * (b.tv_nsec - a.tv_nsec);
  printf("%s %d hash %016llx cpu %.4f s  %.1f x_real_time\n", integrator, segments,
         (unsigned long long)hsh, cpu, K * h / cpu);
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
}
