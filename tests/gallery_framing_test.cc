// The gallery's framing in every frame (issue 16, "each video shows the vehicle in every
// frame"): for each `render` command of renders/make_gallery.sh (read from the script, so a new
// gallery scene is checked without editing this file), the frames that command renders are
// posed as `mjtether render` poses them (same frame grid, same stills-only skipping, same
// automatic colour scale, same size and camera), and in every one
//   - the vehicle's projected box is inside the frame and at least 40 px, or the close-up is
//     shown and the box is inside it and at least 40 px there;
//   - with the follow and top cameras, every tether node projects inside the frame and outside
//     the HUD's and the colour scale's rectangles (track:BODY looks at the body only: the
//     tether may leave the frame and pass under the HUD; not checked).
// Posing needs no GL work (Renderer::NextPose, PipPose, ProjectPose), so every frame of every
// scene costs about as much as simulating it. The projection is checked against the GL camera
// MuJoCo renders with on one frame per scene (written here from the GL camera's fields), so
// that ProjectPose is not trusted blindly.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

#include "mjtether.h"
#include "mujoco_fixture.h"
#include "render.h"
#include "render_geometry.h"

namespace mjtether::render {
namespace {

// A `render` command of the gallery script.
struct GalleryRender {
  std::string model;  // path from the top of the repository
  double duration = 0, fps = 30, png_every = 0;
  int width = 1280, height = 720;
  std::string camera = "follow";
  bool video = false;
  std::string line;  // the command, for messages
};

void PrintTo(const GalleryRender& g, std::ostream* os) { *os << g.line; }

// The `$M render ...` commands of renders/make_gallery.sh (continuation lines joined).
std::vector<GalleryRender> ReadGallery() {
  std::ifstream in(std::string(MJTETHER_SOURCE_DIR) + "/renders/make_gallery.sh");
  std::vector<GalleryRender> out;
  std::string line, joined;
  while (std::getline(in, line)) {
    const bool more = !line.empty() && line.back() == '\\';
    joined += more ? line.substr(0, line.size() - 1) : line;
    if (more) continue;
    std::istringstream words(joined);
    std::vector<std::string> w;
    for (std::string s; words >> s;) w.push_back(s);
    if (w.size() >= 3 && w[0] == "$M" && w[1] == "render") {
      GalleryRender g;
      g.model = w[2];
      g.line = joined;
      for (size_t i = 3; i + 1 < w.size(); ++i) {
        if (w[i] == "--duration") g.duration = std::stod(w[i + 1]);
        if (w[i] == "--fps") g.fps = std::stod(w[i + 1]);
        if (w[i] == "--png-every") g.png_every = std::stod(w[i + 1]);
        if (w[i] == "--camera") g.camera = w[i + 1];
        if (w[i] == "--video") g.video = true;
        if (w[i] == "--size") std::sscanf(w[i + 1].c_str(), "%dx%d", &g.width, &g.height);
      }
      out.push_back(g);
    }
    joined.clear();
  }
  return out;
}

using test_util::ProjectGl;

// Box bounding the projections of body b's visible geoms through pose p in a W x H viewport.
std::array<double, 4> BodyBox(const mjModel* m, const mjData* d, int b, const CameraPose& p, int W,
                              int H) {
  return test_util::BodyBox(
      m, d, b, [&](const double* x) { return ProjectPose(p, m->vis.global.fovy, W, H, x); });
}

// The largest tension over the frames' instants, rounded up as `render --tension-max auto`
// does (the colour scale's labels set its width, so the layout).
double AutoTensionMax(const mjModel* m, const GalleryRender& g, long long nframes) {
  mjData* d = mj_makeData(m);
  mjData* o = mj_makeData(m);
  std::vector<double> T;
  double tmax = 0;
  long long step = 0;
  for (long long k = 0; k < nframes; ++k) {
    for (; step < FrameStep(k, g.fps, m->opt.timestep); ++step) Step(m, d);
    Prescribe(m, d);
    mj_copyData(o, m, d);
    mj_forward(m, o);
    for (int t = 0; t < TetherCount(m); ++t) {
      T.resize(GetTether(m, t)->segments());
      GetTensions(m, o, t, T.data());
      for (double x : T) tmax = std::max(tmax, x);
      const EndReactions r = GetReactions(m, o, t);
      tmax = std::max({tmax, r.tension_a, r.tension_b});
    }
  }
  mj_deleteData(o);
  mj_deleteData(d);
  return NiceCeil(tmax);
}

class Gallery : public ::testing::TestWithParam<GalleryRender> {};

TEST(GalleryScript, HasRenderCommands) {
  // The script is read, and holds the scenes the gallery shows (so an empty parse cannot pass).
  EXPECT_GE(ReadGallery().size(), 8u);
}

TEST_P(Gallery, VehicleSeenAndTetherOffTheOverlaysInEveryFrame) {
  const GalleryRender& g = GetParam();
  std::string error;
  testing::ModelPtr model(
      LoadModel(std::string(MJTETHER_SOURCE_DIR) + "/" + g.model, &error));
  ASSERT_NE(model, nullptr) << error;
  mjModel* m = model.get();
  const long long nframes = static_cast<long long>(std::floor(g.duration * g.fps + 1e-9)) + 1;
  RenderOptions opt;
  opt.width = g.width;
  opt.height = g.height;
  opt.samples = 0;  // one frame is rendered, to compare projections
  opt.camera = g.camera;
  opt.tension_max = AutoTensionMax(m, g, nframes);
  std::unique_ptr<Renderer> r = Renderer::Create(m, opt, &error);
  ASSERT_NE(r, nullptr) << error;
  const int vehicle = Vehicle(m);
  ASSERT_GE(vehicle, 0) << g.model;
  const bool framed = g.camera == "follow" || g.camera == "top";
  const int W = g.width, H = g.height;
  const double fovy = m->vis.global.fovy;

  mjData* d = mj_makeData(m);
  mjData* o = mj_makeData(m);
  std::vector<unsigned char> rgb(3 * W * H);
  long long step = 0, next_png = 0;
  int posed = 0, closeups = 0, failures = 0;
  double smallest = 1e300;
  bool compared = false;
  for (long long k = 0; k < nframes && failures < 10; ++k) {
    for (; step < FrameStep(k, g.fps, m->opt.timestep); ++step) Step(m, d);
    // As cli_render.cc: without a video, only the stills' frames are rendered (and posed).
    const bool still = g.png_every > 0 && k >= std::llround(next_png * g.png_every * g.fps);
    if (!g.video && !still) continue;
    while (still && std::llround(next_png * g.png_every * g.fps) <= k) ++next_png;
    Prescribe(m, d);
    mj_copyData(o, m, d);
    mj_forward(m, o);
    const CameraPose pose = r->NextPose(m, o);
    ++posed;
    const std::string at = g.model + " " + g.camera + " t = " + std::to_string(o->time) + " s";

    // Once per scene (halfway): ProjectPose against the GL camera MuJoCo rendered with, to
    // 0.5 px (both are the same pinhole model; float GL fields give ~1e-4 px).
    if (!compared && k >= nframes / 2) {
      compared = true;
      r->RenderAt(m, o, pose, rgb.data());
      const mjvGLCamera c = mjv_averageCamera(&r->scene().camera[0], &r->scene().camera[1]);
      const double* x = o->xpos + 3 * vehicle;
      const std::array<double, 2> a = ProjectPose(pose, fovy, W, H, x), b = ProjectGl(c, W, H, x);
      EXPECT_NEAR(a[0], b[0], 0.5) << at;
      EXPECT_NEAR(a[1], b[1], 0.5) << at;
    }

    const Layout l = r->layout();
    std::array<double, 4> box;
    int bw = W, bh = H;
    if (pose.pip) {
      ++closeups;
      bw = l.pip.w, bh = l.pip.h;
      box = BodyBox(m, o, vehicle, r->PipPose(m, o, pose), bw, bh);
    } else {
      box = BodyBox(m, o, vehicle, pose, W, H);
    }
    const double size = std::max(box[2] - box[0], box[3] - box[1]);
    smallest = std::min(smallest, size);
    std::ostringstream why;
    if (!(box[0] >= 0 && box[1] >= 0 && box[2] <= bw && box[3] <= bh)) {
      why << " vehicle box (" << box[0] << ", " << box[1] << ") - (" << box[2] << ", " << box[3]
          << ") not inside " << bw << "x" << bh << (pose.pip ? " (close-up);" : ";");
    }
    if (!(size >= 40)) why << " vehicle " << size << " px" << (pose.pip ? " (close-up);" : ";");
    if (framed) {
      for (int t = 0; t < TetherCount(m); ++t) {
        const double* x = NodePositions(m, o, t);
        for (int i = 0; i < GetTether(m, t)->nodes(); ++i) {
          const std::array<double, 2> p = ProjectPose(pose, fovy, W, H, x + 3 * i);
          if (!(p[0] >= 0 && p[0] <= W && p[1] >= 0 && p[1] <= H)) {
            why << " node " << i << " outside, at (" << p[0] << ", " << p[1] << ");";
          }
          if (l.hud.Contains(p[0], p[1])) why << " node " << i << " under the HUD;";
          if (l.scale.Contains(p[0], p[1])) why << " node " << i << " under the scale;";
        }
      }
    }
    if (!why.str().empty()) {
      ADD_FAILURE() << at << ":" << why.str();
      ++failures;  // (the first 10 failing frames are reported)
    }
  }
  EXPECT_TRUE(compared) << g.model;
  EXPECT_GE(posed, 1);
  std::printf("%s %s %dx%d: %d frame(s) posed, %d with the close-up; smallest vehicle %.0f px\n",
              g.model.c_str(), g.camera.c_str(), W, H, posed, closeups, smallest);
  r.reset();
  mj_deleteData(o);
  mj_deleteData(d);
}

INSTANTIATE_TEST_SUITE_P(Renders, Gallery, ::testing::ValuesIn(ReadGallery()),
                         [](const ::testing::TestParamInfo<GalleryRender>& info) {
                           std::string name = info.param.model;
                           name = name.substr(name.rfind('/') + 1);
                           name = name.substr(0, name.find('.'));
                           name += "_" + std::to_string(info.param.width) + "_" +
                                   std::to_string(info.index);
                           for (char& c : name) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return name;
                         });

}  // namespace
}  // namespace mjtether::render
