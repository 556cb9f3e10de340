// A GoogleTest fixture for tests through MuJoCo: models loaded from strings (with their
// tethers attached), data made from them, everything deleted at the end of the test. MuJoCo
// warnings fail the test that triggers them; errors abort it with the message (MuJoCo's
// default handler would wait on stdin).
#ifndef MJTETHER_TESTS_MUJOCO_FIXTURE_H_
#define MJTETHER_TESTS_MUJOCO_FIXTURE_H_

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include "mjtether.h"

namespace mjtether::testing {

// A number as it goes into an MJCF attribute or a declaration: 10 significant digits.
inline std::string Fmt(double x) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.10g", x);
  return buf;
}

// Overwrites the state of tether 0 with node positions x (3 x nodes) at rest (after the first
// callback set its initial shape).
inline void SetNodes(const mjModel* m, const mjData* d, const Eigen::Matrix3Xd& x) {
  double* xp = const_cast<double*>(NodePositions(m, d, 0));
  ASSERT_NE(xp, nullptr);
  const int n = GetTether(m, 0)->nodes();
  ASSERT_EQ(x.cols(), n);
  for (int i = 0; i < 3 * n; ++i) xp[i] = x.data()[i];
  for (int i = 0; i < 3 * n; ++i) xp[3 * n + i] = 0;
}

// Steps (mjtether::Step: motions and thrust schedules applied) until a tether reports a
// divergence or d->time reaches `seconds`: the divergence message, or nullopt.
inline std::optional<std::string> StepUntilDivergence(const mjModel* m, mjData* d,
                                                      double seconds) {
  while (d->time < seconds) {
    Step(m, d);
    if (std::optional<std::string> message = CheckDivergence(m, d)) return message;
  }
  return std::nullopt;
}

// Owns a model loaded with its tethers: detaches them and deletes the model when it goes out of
// scope, also where an ASSERT returns early.
struct ModelDeleter {
  void operator()(mjModel* m) const {
    Detach(m);
    mj_deleteModel(m);
  }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;

inline void FailOnWarning(const char* message) {
  ADD_FAILURE() << "MuJoCo warning: " << message;
}

inline void AbortOnError(const char* message) {
  std::fprintf(stderr, "MuJoCo error: %s\n", message);
  std::abort();
}

class MuJoCoFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    mju_user_warning = FailOnWarning;
    mju_user_error = AbortOnError;
  }
  void TearDown() override {
    for (mjData* d : datas_) mj_deleteData(d);
    for (mjModel* m : models_) {
      Detach(m);
      mj_deleteModel(m);
    }
  }
  // Loads MJCF text; `name` stands for the file in messages. Fails the test on error.
  mjModel* Load(const std::string& xml, const std::string& name = "test.xml") {
    std::string error;
    mjModel* m = LoadModelFromString(xml, name, &error);
    EXPECT_NE(m, nullptr) << error;
    if (m) models_.push_back(m);
    return m;
  }
  mjData* Make(mjModel* m) {
    mjData* d = mj_makeData(m);
    datas_.push_back(d);
    return d;
  }
  // mj_copyData carries the tether: a copy of a run's state after 250 steps, stepped on beside
  // it, reproduces it bit for bit (qpos, qvel and the tether's userdata block), which has not
  // diverged.
  void ExpectCopyIsBitIdentical(mjModel* m) {
    ASSERT_NE(m, nullptr);
    mjData* d = Make(m);
    for (int k = 0; k < 250; ++k) mj_step(m, d);
    mjData* copy = Make(m);
    mj_copyData(copy, m, d);
    for (int k = 0; k < 250; ++k) {
      mj_step(m, d);
      mj_step(m, copy);
    }
    EXPECT_EQ(std::memcmp(d->qpos, copy->qpos, sizeof(mjtNum) * m->nq), 0);
    EXPECT_EQ(std::memcmp(d->qvel, copy->qvel, sizeof(mjtNum) * m->nv), 0);
    EXPECT_EQ(std::memcmp(d->userdata, copy->userdata, sizeof(mjtNum) * m->nuserdata), 0);
    EXPECT_FALSE(CheckDivergence(m, d).has_value());
  }
  // mj_resetData re-initialises the tether from its declared shape: 200 steps after a reset
  // reproduce the first 200 bit for bit (qpos and the tether's userdata block).
  void ExpectResetIsBitIdentical(mjModel* m) {
    ASSERT_NE(m, nullptr);
    mjData* d = Make(m);
    for (int k = 0; k < 200; ++k) mj_step(m, d);
    std::vector<mjtNum> qpos(d->qpos, d->qpos + m->nq);
    std::vector<mjtNum> user(d->userdata, d->userdata + m->nuserdata);
    mj_resetData(m, d);
    for (int k = 0; k < 200; ++k) mj_step(m, d);
    EXPECT_EQ(std::memcmp(qpos.data(), d->qpos, sizeof(mjtNum) * m->nq), 0);
    EXPECT_EQ(std::memcmp(user.data(), d->userdata, sizeof(mjtNum) * m->nuserdata), 0);
  }
  std::vector<mjModel*> models_;
  std::vector<mjData*> datas_;
};

// A model loaded from a string and its data, released at the end of the scope; for tests
// that need several scenes at once or a scene outside a fixture.
struct LoadedScene {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  explicit LoadedScene(const std::string& xml, const std::string& name = "test.xml") {
    mju_user_warning = FailOnWarning;
    mju_user_error = AbortOnError;
    std::string error;
    m = LoadModelFromString(xml, name, &error);
    EXPECT_NE(m, nullptr) << error;
    if (m) d = mj_makeData(m);
  }
  LoadedScene(const LoadedScene&) = delete;
  LoadedScene& operator=(const LoadedScene&) = delete;
  ~LoadedScene() {
    if (d) mj_deleteData(d);
    if (m) {
      Detach(m);
      mj_deleteModel(m);
    }
  }
  // One mj_step; a divergence fails the test with the engine's message.
  bool Step() {
    mj_step(m, d);
    if (std::optional<std::string> message = CheckDivergence(m, d)) {
      ADD_FAILURE() << *message;
      return false;
    }
    return true;
  }
};

}  // namespace mjtether::testing

#endif  // MJTETHER_TESTS_MUJOCO_FIXTURE_H_
