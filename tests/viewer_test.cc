// `mjtether view` under Xvfb (issue 16, item 7): the window's screenshot shows the tethers in
// their tension colours where their nodes project, the HUD in the top-left corner, the node
// overlay when asked; the pause, step, reset and speed keys (fed with --keys) set the
// simulated time as they should. Skipped when xvfb-run is not installed.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <png.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "cli_shell.h"
#include "mjtether.h"
#include "render.h"
#include "render_geometry.h"

namespace mjtether::render {
namespace {

namespace fs = std::filesystem;
using mjtether::test_util::kTwoTethers;
using mjtether::test_util::Shell;

constexpr int kW = 320, kH = 240;  // [pixel] window
constexpr double kH_step = 0.002;  // [s] MuJoCo's default timestep (the model sets none)

// RGB rows top-down, or empty.
std::vector<unsigned char> ReadPng(const std::string& path, int* w, int* h) {
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) return {};
  image.format = PNG_FORMAT_RGB;
  std::vector<unsigned char> rgb(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr)) return {};
  *w = static_cast<int>(image.width);
  *h = static_cast<int>(image.height);
  return rgb;
}

constexpr auto Project = test_util::ProjectScene;

class Viewer : public ::testing::Test {
 protected:
  void SetUp() override {
    int status = 0;
    Shell("command -v xvfb-run >/dev/null 2>&1", &status);
    if (status != 0) GTEST_SKIP() << "xvfb-run is not installed (Debian xvfb): no X server";
    dir_ = fs::temp_directory_path() /
           ("mjtether_viewer_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    model_ = (dir_ / "two.xml").string();
    std::ofstream(model_) << kTwoTethers;
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  // Runs the viewer under a virtual X server; returns its output (stdout and stderr).
  std::string View(const std::string& args, int* status) {
    return Shell("xvfb-run -a -s '-screen 0 640x480x24' " + std::string(MJTETHER_CLI) + " view " +
                     model_ + " " + args + " 2>&1",
                 status);
  }
  // The simulated time the viewer reports after its frames.
  static double TimeOf(const std::string& out) {
    const size_t at = out.find("t = ");
    return at == std::string::npos ? -1 : std::atof(out.c_str() + at + 4);
  }
  fs::path dir_;
  std::string model_;
};

TEST_F(Viewer, ScreenshotShowsTensionColoursAtTheNodesTheHudAndTheOverlay) {
  const std::string common =
      "--size 320x240 --samples 0 --camera side --tension-max 1000 "
      "--frames 3 --screenshot ";
  int status = 0;
  std::string out = View(common + (dir_ / "hud.png").string(), &status);
  ASSERT_EQ(status, 0) << out;
  out = View(common + (dir_ / "bare.png").string() + " --no-hud", &status);
  ASSERT_EQ(status, 0) << out;
  out = View(common + (dir_ / "overlay.png").string() + " --no-hud --overlay", &status);
  ASSERT_EQ(status, 0) << out;
  int w = 0, h = 0;
  const std::vector<unsigned char> hud = ReadPng((dir_ / "hud.png").string(), &w, &h);
  ASSERT_EQ(w, kW);
  ASSERT_EQ(h, kH);
  const std::vector<unsigned char> bare = ReadPng((dir_ / "bare.png").string(), &w, &h);
  const std::vector<unsigned char> overlay = ReadPng((dir_ / "overlay.png").string(), &w, &h);
  ASSERT_EQ(bare.size(), hud.size());
  ASSERT_EQ(overlay.size(), hud.size());
  // Pixel (column, row from the bottom) of a top-down image.
  auto px = [](const std::vector<unsigned char>& img, int col, int row) {
    return img.data() + 3 * ((kH - 1 - row) * kW + col);
  };

  // Where the nodes project: the same camera through an off-screen renderer of the same size.
  std::string error;
  mjModel* m = LoadModelFromString(kTwoTethers, "two.xml", &error);
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  RenderOptions opt;
  opt.width = kW;
  opt.height = kH;
  opt.samples = 0;
  opt.camera = "side";
  opt.tension_max = 1000;
  std::unique_ptr<Renderer> r = Renderer::Create(m, opt, &error);
  ASSERT_NE(r, nullptr) << error;
  std::vector<unsigned char> rgb(3 * kW * kH);
  r->Render(m, d, rgb.data());

  // At every interior node, a pixel within 1 px of the projection has the tether's colour:
  // red (R > 2G, R > 2B) for "hot" (1000 N), green (G > 2R, G > 2B) for "mid" (500 N); ratios
  // of 2 leave room for shading and exclude the blue water (render_test.cc). With the
  // overlay, a near-white pixel (every channel > 170, the node spheres are white and lit)
  // lies within 2 px, where the plain frame has none.
  int checked = 0;
  for (int k = 0; k < 2; ++k) {
    const bool hot = TetherName(m, k) == "hot";
    const double* x = NodePositions(m, d, k);
    for (int i = 1; i < 10; ++i) {
      const std::array<double, 2> p = Project(r->scene(), kW, kH, x + 3 * i);
      const int cx = static_cast<int>(std::lround(p[0])), cy = static_cast<int>(p[1]);
      ASSERT_TRUE(cx > 2 && cx < kW - 3 && cy > 2 && cy < kH - 3) << "node off screen";
      bool colour = false, white = false, white_before = false;
      for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
          const unsigned char* b = px(bare, cx + dx, cy + dy);
          const unsigned char* o = px(overlay, cx + dx, cy + dy);
          if (std::abs(dx) <= 1 && std::abs(dy) <= 1) {
            colour |=
                hot ? (b[0] > 2 * b[1] && b[0] > 2 * b[2]) : (b[1] > 2 * b[0] && b[1] > 2 * b[2]);
          }
          white |= o[0] > 170 && o[1] > 170 && o[2] > 170;
          white_before |= b[0] > 170 && b[1] > 170 && b[2] > 170;
        }
      }
      EXPECT_TRUE(colour) << TetherName(m, k) << " node " << i << " at (" << cx << ", " << cy
                          << ")";
      EXPECT_TRUE(white && !white_before) << TetherName(m, k) << " node " << i;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 18);

  // The HUD: the top-left 80x40 pixels change with it (its first lines of text), as in the
  // off-screen renders (render_test.cc).
  int changed = 0;
  for (int row = kH - 40; row < kH; ++row) {
    for (int col = 0; col < 80; ++col) {
      const unsigned char* a = px(hud, col, row);
      const unsigned char* b = px(bare, col, row);
      changed += a[0] != b[0] || a[1] != b[1] || a[2] != b[2];
    }
  }
  EXPECT_GT(changed, 200);

  r.reset();
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
}

TEST_F(Viewer, PauseStepResetAndSpeedKeysSetTheSimulatedTime) {
  const std::string common =
      "--size 64x48 --samples 0 --no-hud --screenshot " + (dir_ / "s.png").string() + " ";
  int status = 0;
  // 6 frames of 1/60 s: 0.1 s, to within half a step (the viewer steps while the next step
  // ends nearer the target).
  std::string out = View(common + "--frames 6", &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NEAR(TimeOf(out), 0.1, 0.5 * kH_step + 1e-12) << out;
  // "plus" doubles the speed: 0.2 s.
  out = View(common + "--frames 6 --keys plus", &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NEAR(TimeOf(out), 0.2, 0.5 * kH_step + 1e-12) << out;
  // Paused, then three single steps: exactly 3 steps whatever the frames.
  out = View(common + "--frames 6 --keys space,right,right,right", &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_NEAR(TimeOf(out), 3 * kH_step, 1e-12) << out;
  // Steps, then reset (still paused): back to 0.
  out = View(common + "--frames 2 --keys right,right,backspace", &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_EQ(TimeOf(out), 0) << out;
  // An unknown key name is bad input.
  out = View(common + "--frames 2 --keys nosuchkey", &status);
  EXPECT_EQ(status, 2) << out;
  EXPECT_NE(out.find("--keys"), std::string::npos) << out;
}

}  // namespace
}  // namespace mjtether::render
