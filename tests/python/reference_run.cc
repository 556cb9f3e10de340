// The C++ run that the Python bindings must reproduce bit for bit (tests/python/test_mjtether.py):
// the public API used as Simulation does (docs/python.md): load, schedules and mj_forward at
// t = 0, then CHUNKS times: STEPS x mjtether::Step, schedules, mj_forward. Prints the time,
// qpos, qvel and every tether's node positions as C hex floats (%a), one value a line.
//   reference_run MODEL.xml CHUNKS STEPS
#include <mjtether/mjtether.h>
#include <mujoco/mujoco.h>

#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: reference_run MODEL.xml CHUNKS STEPS\n");
    return 2;
  }
  std::string error;
  mjModel* m = mjtether::LoadModel(argv[1], &error);
  if (!m) {
    std::fprintf(stderr, "%s\n", error.c_str());
    return 2;
  }
  mjData* d = mj_makeData(m);
  mjtether::Prescribe(m, d);
  mj_forward(m, d);
  const int chunks = std::atoi(argv[2]), steps = std::atoi(argv[3]);
  for (int c = 0; c < chunks; ++c) {
    for (int i = 0; i < steps; ++i) mjtether::Step(m, d);
    mjtether::Prescribe(m, d);
    mj_forward(m, d);
  }
  std::printf("%a\n", d->time);
  for (int i = 0; i < m->nq; ++i) std::printf("%a\n", d->qpos[i]);
  for (int i = 0; i < m->nv; ++i) std::printf("%a\n", d->qvel[i]);
  for (int k = 0; k < mjtether::TetherCount(m); ++k) {
    const double* x = mjtether::NodePositions(m, d, k);
    for (int i = 0; i < 3 * mjtether::GetTether(m, k)->nodes(); ++i) std::printf("%a\n", x[i]);
  }
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
  return 0;
}
