// Framing and layout of the renders (issue 16): in the shipped scenes the vehicle is seen (in
// the frame and at least 40 px, or in its close-up), the HUD and the colour scale cover no
// tether node, the follow camera moves smoothly, the overlays fit the frame at 320x240 and
// 1920x1080 and draw only inside their rectangles; the CLI renders the last instant, takes
// "auto" for its automatic values and `plot` refuses the options it would ignore.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "cli_shell.h"
#include "mjtether.h"
#include "mujoco_fixture.h"
#include "render.h"
#include "render_geometry.h"

namespace mjtether::render {
namespace {

namespace fs = std::filesystem;
using mjtether::test_util::Shell;

using test_util::ProjectGl;

mjvGLCamera MainCamera(const Renderer& r) { return test_util::MonoCamera(r.scene()); }

// Box bounding the projections of body b's visible geoms through camera c in a W x H viewport.
std::array<double, 4> BodyBox(const mjModel* m, const mjData* d, int b, const mjvGLCamera& c, int W,
                              int H) {
  return test_util::BodyBox(m, d, b, [&](const double* x) { return ProjectGl(c, W, H, x); });
}

struct Scene {
  const char* file;
  double duration;  // [s] of the manoeuvre
};

void PrintTo(const Scene& s, std::ostream* os) { *os << s.file; }

class ShippedScene : public ::testing::TestWithParam<std::tuple<Scene, const char*>> {};

// Through each shipped manoeuvre, rendered at 320x240 with the follow or top camera at 10 frames
// per second: at 6 instants the vehicle's projected box is in the frame and at least 40 px
// (or, when the close-up is shown, in the close-up and at least 40 px there); no tether node
// projects into the HUD's or the colour scale's rectangle, and every node is in the frame.
// Between consecutive frames (0.1 s) the camera moves smoothly: its look-at point moves by less
// than 5 % of its distance and the distance changes by less than 5 %. (The vehicles move at
// most about 1.5 m/s, 0.15 m per frame, against distances of 5-40 m, and the filter's time
// constant is 1 s; seen: at most 0.5 % and 2.2 %. A cut, the jump this guards against, moves
// the view by a large part of its size.)
TEST_P(ShippedScene, VehicleSeenOverlaysOffTheTetherAndSmoothCamera) {
  const Scene scene = std::get<0>(GetParam());
  std::string error;
  testing::ModelPtr model(
      LoadModel(std::string(MJTETHER_MODELS_DIR) + "/" + scene.file, &error));
  ASSERT_NE(model, nullptr) << error;
  mjModel* m = model.get();
  mjData* d = mj_makeData(m);
  const int W = 320, H = 240;
  RenderOptions opt;
  opt.width = W;
  opt.height = H;
  opt.samples = 0;
  opt.camera = std::get<1>(GetParam());
  opt.tension_max = 100;
  std::unique_ptr<Renderer> r = Renderer::Create(m, opt, &error);
  ASSERT_NE(r, nullptr) << error;
  const int vehicle = Vehicle(m);
  ASSERT_GE(vehicle, 0);
  std::vector<unsigned char> rgb(3 * W * H);
  const int frames = static_cast<int>(std::lround(scene.duration * 10));
  CameraPose last;
  double worst_pan = 0, worst_zoom = 0, worst_time = 0;
  int checked = 0, closeups = 0;
  for (int k = 0; k <= frames; ++k) {
    while (d->time < 0.1 * k - 1e-9) Step(m, d);
    mj_forward(m, d);
    const CameraPose pose = r->NextPose(m, d);
    if (k > 0) {
      double pan = 0;
      for (int i = 0; i < 3; ++i) pan += std::pow(pose.lookat[i] - last.lookat[i], 2);
      worst_pan = std::max(worst_pan, std::sqrt(pan) / last.distance);
      const double zoom = std::abs(std::log(pose.distance / last.distance));
      if (zoom > worst_zoom) worst_zoom = zoom, worst_time = d->time;
    }
    last = pose;
    if (k % (frames / 5) != 0) continue;
    r->RenderAt(m, d, pose, rgb.data());
    ++checked;
    const std::string at = std::string(scene.file) + " t = " + std::to_string(d->time);
    const Layout l = r->layout();
    const mjvGLCamera main = MainCamera(*r);
    for (int t = 0; t < TetherCount(m); ++t) {
      const double* x = NodePositions(m, d, t);
      for (int i = 0; i < GetTether(m, t)->nodes(); ++i) {
        const std::array<double, 2> p = ProjectGl(main, W, H, x + 3 * i);
        EXPECT_TRUE(p[0] >= 0 && p[0] <= W && p[1] >= 0 && p[1] <= H)
            << at << " node " << i << " at (" << p[0] << ", " << p[1] << ")";
        EXPECT_FALSE(l.hud.Contains(p[0], p[1])) << at << " node " << i << " under the HUD";
        EXPECT_FALSE(l.scale.Contains(p[0], p[1])) << at << " node " << i << " under the scale";
      }
    }
    std::array<double, 4> box;
    int bw = W, bh = H;
    if (const mjvGLCamera* pip = r->pip_camera()) {
      ++closeups;
      bw = l.pip.w, bh = l.pip.h;
      box = BodyBox(m, d, vehicle, *pip, bw, bh);
    } else {
      box = BodyBox(m, d, vehicle, main, W, H);
    }
    EXPECT_TRUE(box[0] >= 0 && box[1] >= 0 && box[2] <= bw && box[3] <= bh)
        << at << ": vehicle box (" << box[0] << ", " << box[1] << ") - (" << box[2] << ", "
        << box[3] << ") not inside " << bw << "x" << bh;
    EXPECT_GE(std::max(box[2] - box[0], box[3] - box[1]), 40) << at;
  }
  EXPECT_EQ(checked, 6);
  EXPECT_LT(worst_pan, 0.05) << scene.file;
  EXPECT_LT(worst_zoom, std::log(1.05)) << scene.file;
  std::printf("%s %s: %d close-up(s) of 6; worst pan %.3f D, zoom %.3f per 0.1 s (t = %.1f s)\n",
              scene.file, opt.camera.c_str(), closeups, worst_pan, worst_zoom, worst_time);
  r.reset();
  mj_deleteData(d);
}

INSTANTIATE_TEST_SUITE_P(
    Manoeuvres, ShippedScene,
    ::testing::Combine(::testing::Values(Scene{"manoeuvre_surge_snap.xml", 24},
                                         Scene{"manoeuvre_turn_wrap.xml", 30},
                                         Scene{"manoeuvre_station_keeping.xml", 40},
                                         Scene{"manoeuvre_dive_return.xml", 30},
                                         Scene{"bluerov2_heavy.xml", 20},
                                         Scene{"rov_tether.xml", 20}),
                       ::testing::Values("follow", "top")),
    [](const auto& info) {
      std::string name = std::get<0>(info.param).file;
      name = name.substr(0, name.find('.')) + "_" + std::get<1>(info.param);
      return name;
    });

// The overlays fit the frame at 320x240 and 1920x1080: the HUD and the colour scale are inside
// it and apart, no two overlays (HUD, scale, current arrow, close-up) overlap at 320x240,
// 640x480 or 1920x1080, the "segment tension [N]" label (its width from MuJoCo's font metrics, as the
// code draws it) lies inside the scale's panel, and a frame with the HUD differs from one
// without only inside the HUD's and the scale's rectangles (nothing drawn elsewhere, so
// nothing cut or overlapping outside them).
TEST(Layout, OverlaysFitAndDrawOnlyInsideTheirRectangles) {
  std::string error;
  testing::ModelPtr model(
      LoadModel(std::string(MJTETHER_MODELS_DIR) + "/manoeuvre_station_keeping.xml", &error));
  ASSERT_NE(model, nullptr) << error;
  mjModel* m = model.get();
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  for (const std::array<int, 2> size : {std::array<int, 2>{320, 240}, {640, 480}, {1920, 1080}}) {
    const int W = size[0], H = size[1];
    RenderOptions opt;
    opt.width = W;
    opt.height = H;
    opt.samples = 0;
    opt.tension_max = 1000;
    std::unique_ptr<Renderer> r = Renderer::Create(m, opt, &error);
    ASSERT_NE(r, nullptr) << error;
    const CameraPose pose = r->NextPose(m, d);
    const Layout l = r->layout();
    const std::string at = std::to_string(W) + "x" + std::to_string(H);
    auto inside = [](const Rect& a, const Rect& b) {  // a inside b
      return a.x >= b.x && a.y >= b.y && a.x + a.w <= b.x + b.w && a.y + a.h <= b.y + b.h;
    };
    const Rect frame = {0, 0, W, H};
    EXPECT_TRUE(inside(l.hud, frame)) << at;
    EXPECT_TRUE(inside(l.scale, frame)) << at;
    EXPECT_TRUE(inside(l.label, l.scale)) << at;
    EXPECT_EQ(l.label.w, r->TextWidth("segment tension [N]")) << at;
    EXPECT_GT(l.label.w, 0) << at;
    EXPECT_FALSE(l.hud.x < l.scale.x + l.scale.w && l.scale.x < l.hud.x + l.hud.w &&
                 l.hud.y < l.scale.y + l.scale.h && l.scale.y < l.hud.y + l.hud.h)
        << at << ": HUD and colour scale overlap";
    // No two overlays overlap (HUD, colour scale, current arrow, the vehicle close-up when it
    // is shown: the vehicle of this scene is below the close-up threshold at 320x240).
    const std::array<std::pair<const char*, Rect>, 4> boxes = {
        {{"HUD", l.hud}, {"colour scale", l.scale}, {"current arrow", l.arrow}, {"close-up", l.pip}}};
    for (size_t i = 0; i < boxes.size(); ++i) {
      const Rect& a = boxes[i].second;
      if (a.empty()) continue;
      EXPECT_TRUE(inside(a, frame)) << at << ": " << boxes[i].first << " outside the frame";
      for (size_t j = i + 1; j < boxes.size(); ++j) {
        const Rect& b = boxes[j].second;
        if (b.empty()) continue;
        EXPECT_FALSE(a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h)
            << at << ": " << boxes[i].first << " and " << boxes[j].first << " overlap";
      }
    }
    // The HUD and the scale stay small: the scene keeps most of the frame. MuJoCo 2.2.2's
    // smallest font has 18 px lines (its 50 % scale draws as 100 %), so at 320x240 the HUD's
    // five lines and the scale's three rows take 36 % of the frame (19 % and 16 %; the
    // framing keeps the scene out of both); at 1920x1080 the font is 250 % and they take
    // under a tenth.
    EXPECT_LT(l.hud.w * l.hud.h + l.scale.w * l.scale.h, (W < 480 ? 0.4 : 0.1) * W * H) << at;

    std::vector<unsigned char> with(3 * W * H), without(3 * W * H);
    r->RenderAt(m, d, pose, with.data());
    RenderOptions bare = opt;
    bare.hud = false;
    std::unique_ptr<Renderer> r0 = Renderer::Create(m, bare, &error);
    ASSERT_NE(r0, nullptr) << error;
    r0->NextPose(m, d);  // (decides whether its close-up is shown, as r's did)
    r0->RenderAt(m, d, pose, without.data());
    const Layout l0 = r0->layout();
    int outside = 0, in_label = 0;
    for (int row = 0; row < H; ++row) {
      for (int col = 0; col < W; ++col) {
        const int i = 3 * (row * W + col);
        const bool changed =
            with[i] != without[i] || with[i + 1] != without[i + 1] || with[i + 2] != without[i + 2];
        const double x = col + 0.5, y = row + 0.5;
        // (The close-up is sized to fit beside the HUD and the scale, so without them it may be
        // larger: its rectangles in both frames are left out.)
        // Its border is drawn max(1, H/240) px outside the rectangle.
        const int b = std::max(1, H / 240);
        auto in_pip = [&](const Rect& p) {
          return !p.empty() && x >= p.x - b && x <= p.x + p.w + b && y >= p.y - b &&
                 y <= p.y + p.h + b;
        };
        if (changed && !l.hud.Contains(x, y) && !l.scale.Contains(x, y) && !in_pip(l.pip) &&
            !in_pip(l0.pip))
          ++outside;
        // Text pixels of the label: near white.
        in_label +=
            l.label.Contains(x, y) && with[i] > 200 && with[i + 1] > 200 && with[i + 2] > 200;
      }
    }
    EXPECT_EQ(outside, 0) << at;
    EXPECT_GT(in_label, 10) << at << ": the label is drawn";
  }
  mj_deleteData(d);
}

// ---- the command line ----

class FramingCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("mjtether_framing_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  const std::string cli_ = MJTETHER_CLI;
  const std::string model_ = std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml";
};

// `--duration 1 --png-every 1` gives stills at t = 0 and t = 1 (the end is on the frame grid);
// "auto" is accepted for --distance and --tension-max; a word that is not a number or auto is
// refused naming the option.
TEST_F(FramingCli, LastInstantIsRenderedAndAutoIsAccepted) {
  int status = 0;
  const std::string out = Shell(cli_ + " render " + model_ +
                                    " --duration 1 --size 64x48 --samples 0 --distance auto "
                                    "--tension-max auto --png-every 1 " +
                                    (dir_ / "s").string() + " 2>&1",
                                &status);
  ASSERT_EQ(status, 0) << out;
  EXPECT_TRUE(fs::exists(dir_ / "s" / "t_00000.000.png")) << out;
  EXPECT_TRUE(fs::exists(dir_ / "s" / "t_00001.000.png")) << out;
  const std::string bad =
      Shell(cli_ + " render " + model_ + " --duration 1 --distance far --png-every 1 " +
                (dir_ / "b").string() + " 2>&1",
            &status);
  EXPECT_EQ(status, 2) << bad;
  EXPECT_NE(bad.find("--distance"), std::string::npos) << bad;
  // The help says what auto means.
  const std::string help = Shell(cli_ + " render --help 2>&1", &status);
  EXPECT_NE(help.find("auto (default"), std::string::npos) << help;
}

// From a run log, --duration and --every are not used: refused, exit 2, naming the option.
TEST_F(FramingCli, PlotRefusesOptionsItWouldIgnore) {
  const std::string log = (dir_ / "log.csv").string();
  int status = 0;
  Shell(cli_ + " run " + model_ + " --duration 0.1 --log " + log + " 2>&1", &status);
  ASSERT_EQ(status, 0);
  for (const char* option : {"--duration 5", "--every 0.1"}) {
    const std::string out = Shell(
        cli_ + " plot " + log + " " + option + " --out " + (dir_ / "p.png").string() + " 2>&1",
        &status);
    EXPECT_EQ(status, 2) << out;
    const std::string name = std::string(option).substr(0, std::string(option).find(' '));
    EXPECT_NE(out.find(name), std::string::npos) << out;
    EXPECT_FALSE(fs::exists(dir_ / "p.png"));
  }
}

}  // namespace
}  // namespace mjtether::render

namespace mjtether::render {
namespace {

// The vehicles' drawn geometry changes neither their inertia nor their contacts: the compiled
// mass, inertia and centre of mass are those of the <inertial> each model declares (Wu 2018 for
// the BlueROV2 Heavy; the work-class ROV's box of 4000 kg), and none of the vehicle's geoms
// collides (as the single declared box did not: contype = conaffinity = 0).
struct Declared {
  const char* file;
  double mass;        // [kg]
  double inertia[3];  // [kg m^2] principal
};

TEST(VehicleLooks, MassInertiaAndContactsStayAsDeclared) {
  const Declared models[] = {{"bluerov2_heavy.xml", 11.5, {0.16, 0.16, 0.16}},
                             {"manoeuvre_surge_snap.xml", 11.5, {0.16, 0.16, 0.16}},
                             {"manoeuvre_turn_wrap.xml", 11.5, {0.16, 0.16, 0.16}},
                             {"manoeuvre_dive_return.xml", 11.5, {0.16, 0.16, 0.16}},
                             {"manoeuvre_station_keeping.xml", 11.5, {0.16, 0.16, 0.16}},
                             {"workclass_rov_tms.xml", 4000, {2667, 4333, 4333}}};
  for (const Declared& x : models) {
    std::string error;
    testing::ModelPtr model(
        LoadModel(std::string(MJTETHER_MODELS_DIR) + "/" + x.file, &error));
    ASSERT_NE(model, nullptr) << error;
    const mjModel* m = model.get();
    const int b = mj_name2id(m, mjOBJ_BODY, "rov");
    ASSERT_GE(b, 0) << x.file;
    // Exact: MuJoCo copies a declared <inertial> (a diagonal one needs no rotation).
    EXPECT_EQ(m->body_mass[b], x.mass) << x.file;
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(m->body_inertia[3 * b + i], x.inertia[i]) << x.file;
      EXPECT_EQ(m->body_ipos[3 * b + i], 0) << x.file;
    }
    int drawn = 0;
    for (int g = 0; g < m->ngeom; ++g) {
      if (m->geom_bodyid[g] != b) continue;
      EXPECT_EQ(m->geom_contype[g], 0) << x.file << " geom " << g;
      EXPECT_EQ(m->geom_conaffinity[g], 0) << x.file << " geom " << g;
      drawn += m->geom_group[g] <= 2;
    }
    EXPECT_GE(drawn, 10) << x.file << ": frame, buoyancy, thrusters";
  }
}

}  // namespace
}  // namespace mjtether::render
