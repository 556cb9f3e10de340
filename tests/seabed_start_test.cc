// The start shape on the seabed with compression stiffness EAc (src/tether.cc, RestOnSeabed):
// every segment starts at its rest length L0, also where the path bends sharply (an anchor
// just above the seabed, a vertical drop, the U of extra length, a slope, a rough hfield),
// and the first step's elastic forces stay within what the tether's weight explains (no
// kN spike from a compressed start).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "mujoco_fixture.h"

namespace mjtether {
namespace {

using testing::Fmt;
using testing::MuJoCoFixture;

// A tether with EA = EAc (the values of models/hfield_rock.xml, where the compressed corner
// was found) from site a to site b (or a free end), over the seabed given by `water` (a height
// or a geom in `world`).
std::string Scene(const std::string& seabed, const std::string& world, const Vec3& a,
                  const std::string& b, double length, int segments) {
  return R"(<mujoco><option timestep="0.002"/><compiler angle="radian"/><custom>
    <text name="water" data="density=1025 seabed=)" +
         seabed + R"("/>
    <text name="tether:u" data="ends=a,)" +
         (b.empty() ? std::string("free") : std::string("b")) + " length=" + Fmt(length) +
         " segments=" + std::to_string(segments) +
         R"( diameter=0.03 mass_per_length=1.0 EA=5e4 EAc=5e4 damping=5 Cdn=1.2 Cdt=0.01
      integrator=implicit"/>
  </custom><worldbody>)" +
         world + R"(<site name="a" pos=")" + Fmt(a.x()) + " " + Fmt(a.y()) + " " + Fmt(a.z()) +
         R"("/>)" + (b.empty() ? std::string() : R"(<site name="b" pos=")" + b + R"("/>)") +
         R"(</worldbody></mujoco>)";
}

class SeabedStart : public MuJoCoFixture {
 protected:
  // The start shape's chords, then the elastic forces of the first steps.
  //
  // Chords: at most L0 (1e-9: round-off of the positions), and at least (1 - 1e-6) L0. The
  // nodes are placed by a root solve to ~1e-14 L0 and the path's length is solved until the
  // last chord is within 1e-9 L0 (tether.cc); 1e-6 leaves room for that and is far below the cut
  // corners of arc spacing (0.71-0.85 L0 for an anchor 5 cm above the seabed). A strain of
  // 1e-6 at EAc 5e4 pushes with 0.05 N, under the 0.54 N wet weight of a 0.2 m segment.
  //
  // Forces: in the first ten 2 ms steps from rest (the first callback sets the shape, the
  // later ones advance it), the elastic force EA strain (EAc strain when compressed) of every
  // segment is at most w L, the tether's whole wet weight (w per length):
  // a line at rest starting near its static shape holds at most the weight hanging below the
  // highest point plus the horizontal tension a w, both below w L in these scenes (slack lines
  // mostly on the seabed). Spaced by arc length (main 93df67c), these starts pushed with
  // 7.5 kN to 133 kN (54 to 2300 w L).
  void Check(mjModel* m, int min_grounded, double seabed_z = NAN) {
    ASSERT_NE(m, nullptr);
    mjData* d = Make(m);
    mj_forward(m, d);
    const Tether* t = GetTether(m, 0);
    const TetherParams& p = t->params();
    const double L0 = t->rest_segment_length();
    const double w = (p.mass_per_length - 1025 * M_PI * p.diameter * p.diameter / 4) * 9.81;
    const double* x = NodePositions(m, d, 0);
    auto chord = [&](const double* x, int j) {
      return std::hypot(std::hypot(x[3 * j + 3] - x[3 * j], x[3 * j + 4] - x[3 * j + 1]),
                        x[3 * j + 5] - x[3 * j + 2]);
    };
    int grounded = 0;
    double shortest = INFINITY;
    for (int j = 0; j < t->segments(); ++j) {
      const double l = chord(x, j);
      shortest = std::min(shortest, l / L0);
      EXPECT_LE(l, L0 * (1 + 1e-9)) << "segment " << j << " starts stretched";
      EXPECT_GE(l, L0 * (1 - 1e-6)) << "segment " << j << " starts compressed";
    }
    for (int i = 0; i < t->nodes(); ++i) {
      if (std::isfinite(seabed_z) && x[3 * i + 2] < seabed_z + 1e-9) ++grounded;
    }
    if (std::isfinite(seabed_z)) {
      EXPECT_GE(grounded, min_grounded) << "the shape does not lie on the seabed";
    }
    double largest = 0;
    for (int step = 0; step < 10; ++step) {
      mj_step(m, d);
      ASSERT_FALSE(CheckDivergence(m, d));
      x = NodePositions(m, d, 0);
      for (int j = 0; j < t->segments(); ++j) {
        const double strain = chord(x, j) / L0 - 1;
        largest = std::max(largest, std::abs((strain > 0 ? p.EA : p.EAc) * strain));
      }
    }
    std::printf(
        "shortest chord %.9f L0; largest elastic force in the first 10 steps %.3g N "
        "(w L %.3g N)\n",
        shortest, largest, w * p.length);
    EXPECT_LE(largest, w * p.length);
  }
  int Segments(mjModel* m) { return GetTether(m, 0)->segments(); }
};

// The corner of models/hfield_rock.xml: an anchor 5 cm above the seabed (a quarter of a
// 0.2 m segment), 7 m of tether. With the far end 3 m up the line hangs as catenaries of a
// small a onto the seabed; with it 0.3 m up and 2 m away, its extra length lies in a U.
TEST_F(SeabedStart, AnchorFiveCentimetresAboveTheSeabed) {
  Check(Load(Scene("0", "", Vec3(-3, 0, 0.05), "1 0 3", 7, 35)), 2, 0);
  Check(Load(Scene("0", "", Vec3(-3, 0, 0.05), "-1 0 0.3", 7, 35)), 20, 0);
}

// Issue 11, case one (100 m, TMS 3.5 m above a seabed at -40 m, ROV 20 m away 0.2 m above
// it), and a free end hanging 1.1 m onto the seabed (a vertical drop: a right-angle corner).
TEST_F(SeabedStart, LongLineAndFreeEnd) {
  Check(Load(Scene("-40", "", Vec3(0, 0, -36.5), "20 0 -39.8", 100, 100)), 70, -40);
  Check(Load(Scene("0", "", Vec3(0, 0, 1.1), "", 5, 25)), 15, 0);
}

// A seabed plane tilted 10 degrees (down along +x): the flat shape is lifted onto it, and the
// nodes go by chords along the lifted path.
TEST_F(SeabedStart, TiltedPlaneSeabed) {
  const double alpha = 10 * M_PI / 180, tn = std::tan(alpha);  // surface z = -x tan(alpha)
  const std::string plane =
      R"(<geom name="ground" type="plane" size="20 20 0.1" euler="0 )" + Fmt(alpha) + R"( 0"/>)";
  Check(Load(Scene("ground", plane, Vec3(-3, 0, 3 * tn + 0.05), "3 0 " + Fmt(-3 * tn + 2), 12, 60)),
        0);
}

// models/seabed_hfield.xml (60 m, EAc 2e5, over a sloping rough hfield seabed): the shape
// lies on the lower of the heights under the ends, lifted onto the ground's bumps.
TEST_F(SeabedStart, RoughHfieldSeabedModel) {
  std::ifstream in(MJTETHER_MODELS_DIR "/seabed_hfield.xml");
  std::stringstream s;
  s << in.rdbuf();
  std::string xml = s.str();
  const std::string png = "file=\"seabed_hfield.png\"";
  ASSERT_NE(xml.find(png), std::string::npos);
  xml.replace(xml.find(png), png.size(), "file=\"" MJTETHER_MODELS_DIR "/seabed_hfield.png\"");
  Check(Load(xml, "seabed_hfield.xml"), 0);
}

}  // namespace
}  // namespace mjtether
