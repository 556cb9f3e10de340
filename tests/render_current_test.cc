// The current arrow with a current profile (issue 16, item 6): the arrow shows the current at
// the depth of the view's centre. A profile that is still water above z = -9 m and 1 m/s below
// z = -10 m; a tether between two fixed bodies at z = -3 m and z = -20 m; the track camera on
// each body in turn (same distance, same frame size). Looking at the deep body, the arrow's
// rectangle holds near-white pixels (the arrow, drawn white); looking at the shallow one, none
// (no current there, no arrow). With a uniform current the arrow showed the declared
// `current` alone, which a profile leaves at zero, so no arrow was drawn in either view.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "mjtether.h"
#include "render.h"

namespace mjtether::render {
namespace {

// Pixels of rgb (W x H, rows bottom-up) inside r that are near-white (each channel > 200 of
// 255): the arrow's colour (0.95, 0.95, 1); the water behind it is blue-green and darker.
int WhitePixels(const std::vector<unsigned char>& rgb, int W, const Rect& r) {
  int n = 0;
  for (int y = r.y; y < r.y + r.h; ++y) {
    for (int x = r.x; x < r.x + r.w; ++x) {
      const unsigned char* p = &rgb[3 * (static_cast<size_t>(y) * W + x)];
      if (p[0] > 200 && p[1] > 200 && p[2] > 200) ++n;
    }
  }
  return n;
}

TEST(CurrentArrow, FollowsTheProfileAtTheDepthOfTheViewCentre) {
  const std::string csv = ::testing::TempDir() + "render_current_profile.csv";
  std::ofstream(csv) << "z,ux,uy,uz\n-10,1,0,0\n-9,0,0,0\n";
  const std::string xml = R"(
<mujoco>
  <option timestep="0.002"/>
  <custom>
    <text name="water" data="density=1025 current_profile=)" + csv + R"("/>
    <text name="tether:t" data="ends=a,b length=17.5 segments=10 diameter=0.02 mass_per_length=0.3
      EA=1e5 Cdn=1.2 Cdt=0.01"/>
  </custom>
  <worldbody>
    <body name="shallow" pos="0 0 -3"><geom type="box" size="0.3 0.3 0.3"/><site name="a"/></body>
    <body name="deep" pos="0 0 -20"><geom type="box" size="0.3 0.3 0.3"/><site name="b"/></body>
  </worldbody>
</mujoco>)";
  int white[2] = {-1, -1};
  const char* bodies[2] = {"shallow", "deep"};
  for (int i = 0; i < 2; ++i) {
    std::string error;
    mjModel* m = LoadModelFromString(xml, "current_profile_scene", &error);
    ASSERT_NE(m, nullptr) << error;
    mjData* d = mj_makeData(m);
    mj_forward(m, d);
    RenderOptions opt;
    opt.width = 320;
    opt.height = 240;
    opt.samples = 0;
    opt.camera = std::string("track:") + bodies[i];
    opt.distance = 5;  // [m] the other body (14-17 m away) is far out of the frame
    opt.tension_max = 100;
    {
      std::unique_ptr<Renderer> r = Renderer::Create(m, opt, &error);
      ASSERT_NE(r, nullptr) << error;
      const Rect arrow = r->layout().arrow;
      ASSERT_FALSE(arrow.empty()) << "a profile is a current: the arrow has its place";
      std::vector<unsigned char> rgb(3 * opt.width * opt.height);
      r->Render(m, d, rgb.data());
      white[i] = WhitePixels(rgb, opt.width, arrow);
    }
    mj_deleteData(d);
    Detach(m);
    mj_deleteModel(m);
  }
  EXPECT_EQ(white[0], 0) << "no current at z = -3 m, yet something white in the arrow's place";
  // The arrow at 1 m/s: 0.5 D = 2.5 m long (145 px at 5 m), capped at 70 % of the rectangle's
  // width: about 32 px, a shaft 1-2 px thick whose lit side is near-white. A third of that
  // length, one pixel thick, is the least an arrow can show (the shading darkens the rest).
  EXPECT_GT(white[1], 10) << "1 m/s at z = -20 m, yet no arrow";
}

}  // namespace
}  // namespace mjtether::render
