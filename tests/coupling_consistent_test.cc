// A light vehicle on a stiff tether at the vehicle's step (issue 11 item 1; docs/coupling.md,
// "What was tried and did not work"). The consistent coupling of the implicit integrators was
// attempted on branch issue11c and not merged (it biased this very scene's end tension by 44%);
// this file keeps the measurement that holds on the code as it is, as a regression test for
// any later coupling.
//
// The issue's four BlueROV2 cases (EA 6e4 ... 1e8 within 1% of the 0.1 ms run) are
// BlueRov2/CouplingCases in tests/coupling_test.cc (the same harness, tests/coupling_scene.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "coupling_scene.h"
#include "mujoco_fixture.h"

namespace mjtether {
namespace {

using LightVehicle = testing::MuJoCoFixture;

// A light vehicle on stiff short segments, the kind the scene fuzzer finds: a 3 kg vehicle
// (added mass 1.5-2.5 kg, in water with a 0.3 m/s current) 4.98 m from the top end of a 5 m
// tether of ten 0.5 m segments, EA 2e7 (k_end 4e7 N/m, m_eff 4.5 kg: omega h = 6.0 at 2 ms), the
// top end surging 0.3 m, 20 N of thrust pulling the tether taut from the start. At 2 ms against
// the same scene at 0.2 ms, sampled every 0.05 s for 3 s: the vehicle within 1 cm (0.2% of the
// tether; measured 0.31 mm implicit, 0.24 mm bdf2), and with `implicit` the vehicle-end tension
// within 2% of the reference's largest from 0.5 s on (about 29 N; measured 0.22%).
// bdf2's end tension is NOT asserted: in this scene it rings between 0 and 35 N at 2 ms and at
// 0.2 ms alike (the vehicle's position does not: it integrates the force), 62% off the 0.2 ms
// implicit run; open, docs/coupling.md. implicit2 is refused here (omega h 6 > its limit 4).
TEST_F(LightVehicle, OnStiffShortSegmentsAgreesWithItsFineStep) {
  for (const char* integrator : {"implicit", "bdf2"}) {
    auto xml = [&](double h) {
      return std::string("<mujoco><option timestep=\"") + std::to_string(h) +
             R"("/><custom>
<text name="water" data="density=1025 current=0.3,0,0"/>
<text name="vehicle:rov" data="volume=0.00296 cob=0,0,0.02 added_mass=1.5,2,2.5,0.002,0.002,0.002 linear_damping=3,3,3,0.01,0.01,0.01 quadratic_damping=10,10,10,0.01,0.01,0.01 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=5 segments=10 diameter=0.01 mass_per_length=0.1 EA=2e7 Cdn=1.2 Cdt=0.01 Can=1 integrator=)" +
             integrator + R"("/>
<text name="motion:tms" data="x=0.3,3,0"/>
<text name="thrust:thr" data="t=0 ctrl=20"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="4.97 0 -0.3"><freejoint/><inertial pos="0 0 0" mass="3" diaginertia="0.01 0.01 0.01"/><site name="att"/><site name="thr"/></body>
</worldbody><actuator><motor name="thr" site="thr" gear="1 0 0 0 0 0"/></actuator></mujoco>)";
    };
    std::string stopped;
    mjModel* fine = Load(xml(0.0002), "fine.xml");
    ASSERT_NE(fine, nullptr);
    const std::vector<Sample> ref = RunScene(fine, 3, &stopped);
    ASSERT_EQ(stopped, "");
    mjModel* m = Load(xml(0.002), "light.xml");
    ASSERT_NE(m, nullptr);
    const std::vector<Sample> got = RunScene(m, 3, &stopped);
    ASSERT_EQ(stopped, "") << integrator;
    ASSERT_EQ(got.size(), ref.size());
    double pos_err = 0, tension_err = 0, tension_ref = 0;
    for (size_t i = 0; i < got.size(); ++i) {
      pos_err = std::max(pos_err, (got[i].pos - ref[i].pos).norm());
      if (ref[i].t >= 0.5) {
        tension_err = std::max(tension_err, std::abs(got[i].tension - ref[i].tension));
        tension_ref = std::max(tension_ref, std::abs(ref[i].tension));
      }
    }
    std::printf("%s: position %.2f mm, tension %.3f N of %.2f N (%.2f%%)\n", integrator,
                pos_err * 1e3, tension_err, tension_ref, 100 * tension_err / tension_ref);
    EXPECT_LT(pos_err, 0.01) << integrator;
    if (std::string(integrator) == "implicit") {
      EXPECT_LT(tension_err, 0.02 * tension_ref) << integrator;
    }
  }
}

}  // namespace
}  // namespace mjtether
