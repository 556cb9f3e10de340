// A light vehicle on a stiff tether at the vehicle's step, and the momentum of a free body on a
// taut tether (issue 11 item 1; docs/coupling.md). With integrator=implicit or bdf2 and omega h
// >= 1 the end node B is stepped inside the tether's step with the body's effective mass (the
// consistent coupling, plugin/plugin.cc EvaluateLead; with bdf2 end node B takes a
// backward-Euler step inside the BDF2 step); below that, and with the other integrators, the
// body gets the held end force as before.
//
// The issue's four BlueROV2 cases (EA 6e4 ... 1e8 within 1% of the 0.1 ms run) are
// BlueRov2/CouplingCases in tests/coupling_test.cc (the same harness, tests/coupling_scene.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "coupling_scene.h"
#include "mujoco_fixture.h"

namespace mjtether {
namespace {

// The oscillation of the body of AnchoredBodyXml (below): the half range of qpos[axis] (its
// position along x, y or z [m]) over [from, until] s, whether the scene took the consistent
// coupling, and the largest slow-mode correction on the way [N]; amplitude NAN where the scene
// does not load or diverges.
struct Oscillation {
  double amplitude = NAN;
  bool consistent = false;
  double correction = 0;
};

class LightVehicle : public testing::MuJoCoFixture {
 protected:
  Oscillation Oscillate(const std::string& xml, const char* name, int axis, double from,
                        double until) {
    Oscillation o;
    mjModel* m = Load(xml, name);
    if (!m) return o;
    o.consistent = GetCouplingLimit(m, 0, 1).consistent;
    mjData* d = Make(m);
    double lo = INFINITY, hi = -INFINITY;
    while (d->time < until) {
      Step(m, d);
      if (CheckDivergence(m, d)) return o;
      o.correction = std::max(o.correction, GetReactions(m, d, 0).correction_b.norm());
      if (d->time >= from) lo = std::min(lo, d->qpos[axis]), hi = std::max(hi, d->qpos[axis]);
    }
    o.amplitude = (hi - lo) / 2;
    return o;
  }
  // The same scene at the 2 ms step and at 0.1 ms (the reference), xml(step) giving its MJCF.
  template <typename Xml>
  std::pair<Oscillation, Oscillation> CoarseAndFine(Xml xml, const char* name, int axis,
                                                    double from, double until) {
    return {Oscillate(xml("0.002"), name, axis, from, until),
            Oscillate(xml("0.0001"), name, axis, from, until)};
  }
  // A scene at the 2 ms step and at 0.2 ms (the reference), `scene` its MJCF after the
  // <option> element: the coupling each run took at end B and its samples every `interval` s
  // over `duration` s (the test fails where a scene does not load or a run stops).
  struct StepPair {
    CouplingLimit coarse, fine;
    std::vector<Sample> got, ref;
  };
  StepPair AtTwoSteps(const std::string& scene, const char* name, double duration,
                      double interval) {
    StepPair p;
    auto at = [&](const char* step) {
      return Load(std::string("<mujoco><option timestep=\"") + step + "\"/>" + scene, name);
    };
    mjModel* coarse = at("0.002");
    mjModel* fine = at("0.0002");
    EXPECT_NE(coarse, nullptr);
    EXPECT_NE(fine, nullptr);
    if (!coarse || !fine) return p;
    p.coarse = GetCouplingLimit(coarse, 0, 1);
    p.fine = GetCouplingLimit(fine, 0, 1);
    std::string stopped;
    p.got = RunScene(coarse, duration, &stopped, interval);
    EXPECT_EQ(stopped, "") << "at 2 ms";
    p.ref = RunScene(fine, duration, &stopped, interval);
    EXPECT_EQ(stopped, "") << "at 0.2 ms";
    EXPECT_EQ(p.got.size(), p.ref.size());
    return p;
  }
  // The bounce tests' scene (below) with a body of mass [kg] started at x = pos [m]: its
  // amplitude over 0.4-0.5 s at 2 ms within tolerance (relative) of the 0.1 ms run's.
  void ExpectBounceHeld(const char* integrator, const char* mass, const char* pos,
                        const char* inertia, double tolerance);
};

// A free body at pos ("x y z") with its site "hook", on a 10 m tether "t" (diameter 0.01 m) from
// the world's site "anchor" at the origin, no water; the scene of the momentum, heavy node and
// bounce tests below. step [s], gravity [m/s^2] along x, mass_per_length [kg/m], EA [N], pos
// [m], mass [kg], inertia [kg m^2] (each principal moment).
std::string AnchoredBodyXml(const std::string& step, const std::string& gravity, int segments,
                            const std::string& mass_per_length, const std::string& EA,
                            const std::string& integrator, const std::string& pos,
                            const std::string& mass, const std::string& inertia) {
  return R"(<mujoco><option timestep=")" + step + R"(" gravity=")" + gravity + R"( 0 0"/>
<custom><text name="tether:t" data="ends=anchor,hook length=10 segments=)" +
         std::to_string(segments) + " diameter=0.01 mass_per_length=" + mass_per_length +
         " EA=" + EA + " integrator=" + integrator + R"("/></custom>
<worldbody><site name="anchor"/>
<body name="v" pos=")" + pos + R"("><freejoint/>
<inertial pos="0 0 0" mass=")" + mass + R"(" diaginertia=")" + inertia + " " + inertia + " " +
         inertia + R"("/><site name="hook"/></body>
</worldbody></mujoco>)";
}

// explicit's consistent coupling (session 27): end node B, carrying a body, ends each advance
// where MuJoCo's Euler step will put the body, x_B(t) + dt v_B(t + dt), whatever the substep
// count, so that the plugin's move of the node onto the site at the next call changes nothing
// but a_other's lag. With the node's own path over the substeps (x + sum h v_k) the two parted
// by dt (v_mean - v+) each step, and the move pumped held-out seed 14999 from 10 N to 40 kN
// (docs/coupling.md, session 27). Engine only: a dry 10 m line of 10 segments (EA 1e7 N,
// 0.5 kg/m) stretched 1 cm between a fixed end A and a 20 kg body, one 2 ms advance. Tolerance:
// rounding (with the node's own path the offset was 8.1e-4 m, the node having moved 1.7e-3 m).
TEST(ExplicitConsistentCoupling, EndNodeBEndsTheAdvanceWhereMuJoCosEulerStepPutsTheBody) {
  TetherParams p;
  p.length = 10;
  p.segments = 10;
  p.diameter = 0.02;
  p.mass_per_length = 0.5;
  p.EA = 1e7;
  p.effects = kAxial;
  p.integrator = Integrator::kExplicit;
  Environment env;
  std::string error;
  const std::optional<Tether> attached = Tether::Create(p, env, &error);
  ASSERT_TRUE(attached) << error;
  const Tether t = attached->WithDynamicEndB();
  const double dt = 0.002;
  ASSERT_GT(t.SubstepsFor(dt), 1);
  EndInertia body;
  body.mass = 20 * Eigen::Matrix3d::Identity();
  Ends from;
  from.b.pos = Vec3(10.01, 0, 0);
  std::vector<double> x(3 * t.nodes()), v(3 * t.nodes()), work(t.WorkspaceSize());
  t.InitialShape(from, x.data(), v.data());
  Ends to = from;
  to.time = dt;
  from.body_b = to.body_b = &body;
  const int N = t.segments();
  const Vec3 start(x.data() + 3 * N);
  ASSERT_TRUE(t.Advance(x.data(), v.data(), from, to, dt, work.data()).ok);
  const Vec3 end(x.data() + 3 * N), velocity(v.data() + 3 * N);
  std::printf("end node B moved %g m\n", (end - start).norm());
  EXPECT_GT((end - start).norm(), 1e-4);  // the body moved
  EXPECT_NEAR((end - (start + dt * velocity)).norm(), 0, 1e-12);
}

// The largest distance between the two runs' vehicles [m], and the largest relative difference
// of their vehicle-end tensions from `from` [s] on, over the common samples.
struct Agreement {
  double position = 0, tension = 0;
};
Agreement Compare(const std::vector<Sample>& got, const std::vector<Sample>& ref, double from) {
  Agreement a;
  for (size_t i = 0; i < got.size() && i < ref.size(); ++i) {
    a.position = std::max(a.position, (got[i].pos - ref[i].pos).norm());
    if (ref[i].t >= from - 1e-9) {
      a.tension = std::max(a.tension, std::abs(got[i].tension - ref[i].tension) / ref[i].tension);
    }
  }
  return a;
}

// A light vehicle on stiff short segments, the kind the scene fuzzer finds: a 3 kg vehicle
// (added mass 1.5-2.5 kg, in water with a 0.3 m/s current) 4.98 m from the top end of a 5 m
// tether of ten 0.5 m segments, EA 2e7 (k_end 4e7 N/m, m_eff 4.5 kg: omega h = 6.0 at 2 ms), the
// top end surging 0.3 m, 20 N of thrust pulling the tether taut from the start. At 2 ms against
// the same scene at 0.2 ms, sampled every 0.05 s for 3 s: the vehicle within 1 cm (0.2% of the
// tether; measured 0.30 mm implicit, 0.45 mm bdf2), and the vehicle-end tension within 2% of
// the largest of `implicit`'s 0.2 ms run from 0.5 s on (about 29 N; measured with the
// consistent coupling at 2 ms, omega h 6: implicit 0.19%, bdf2 0.19%; the held force gave
// implicit 0.22% and bdf2 a tension ringing between 0 and 35 N, 62% off). The reference is
// implicit's: bdf2's own 0.2 ms run (omega h 0.6, the held force) still rings, 62% off,
// printed, not asserted (docs/coupling.md). implicit2 (consistent coupling from omega h 0.5,
// session 10 s10i2; refused here before, omega h 6 > its held-force limit 4): 0.18 mm, 0.19%,
// and its own 0.2 ms run (omega h 0.6, also consistent) 0.19% off implicit's.
TEST_F(LightVehicle, OnStiffShortSegmentsAgreesWithItsFineStep) {
  std::vector<Sample> implicit_fine;  // the tension reference of both integrators
  for (const char* integrator : {"implicit", "bdf2", "implicit2"}) {
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
    if (implicit_fine.empty()) implicit_fine = ref;
    double pos_err = 0, tension_err = 0, tension_ref = 0, fine_err = 0;
    for (size_t i = 0; i < got.size(); ++i) {
      pos_err = std::max(pos_err, (got[i].pos - ref[i].pos).norm());
      if (ref[i].t >= 0.5) {
        tension_err = std::max(tension_err, std::abs(got[i].tension - implicit_fine[i].tension));
        fine_err = std::max(fine_err, std::abs(ref[i].tension - implicit_fine[i].tension));
        tension_ref = std::max(tension_ref, std::abs(implicit_fine[i].tension));
      }
    }
    std::printf("%s: position %.2f mm; tension against implicit at 0.2 ms: %.3f N of %.2f N "
                "(%.2f%%) at 2 ms, %.3f N (%.2f%%) at 0.2 ms\n",
                integrator, pos_err * 1e3, tension_err, tension_ref,
                100 * tension_err / tension_ref, fine_err, 100 * fine_err / tension_ref);
    EXPECT_LT(pos_err, 0.01) << integrator;
    EXPECT_LT(tension_err, 0.02 * tension_ref) << integrator;
  }
}

// A light vehicle carried by a current on a long tether: the scene fuzzer's seed 9779 (draw 2),
// a 4.6 kg vehicle (added mass 1.6-4.4 kg) in a 1.8 m/s current on 136 m of tether in 84
// segments (node B 0.28 kg with 0.25 kg normal added mass), EA 1.27e8: omega h = 7.1 at 2 ms
// (the consistent coupling), 0.71 at 0.2 ms (the held force). The current accelerates the
// vehicle from rest, so end node B's inertia m_B a_B is about the vehicle-end tension (0.3-3 N
// from 0.2 s on). The consistent coupling had the body carry the node's inertia, the held force
// does not: at 2 ms the tension was 35% below the 0.2 ms run's and the vehicle 1.5 cm behind,
// and both the consistent coupling and the held force converged in h, to answers 35% apart
// (0.371 and 0.572 N at 0.5 s; the gap halves with twice the segments: 1/N, the node's mass).
// Now end node B's inertia is out of the consistent coupling's step too (EvaluateLead): at 2 ms
// against 0.2 ms, 0.2-0.7 s, sampled every 0.05 s (before the snap at 0.8 s), the tension
// within 2% (measured 1.7% implicit and bdf2, 1.4% implicit2; with the node's inertia in the
// step 37% implicit and bdf2) and the vehicle within 5 mm (measured 2.3-2.9 mm, 18 mm before;
// it moves 0.9 m). implicit2 uses the consistent coupling at 0.2 ms as well (omega h 0.71 >=
// 0.5): it agreed before too (1.8%), the two runs then having the same end.
TEST_F(LightVehicle, CarriedByTheCurrentAgreesWithItsFineStep) {
  for (const char* integrator : {"implicit", "bdf2", "implicit2"}) {
    auto xml = [&](double h) {
      return std::string("<mujoco><option timestep=\"") + std::to_string(h) +
             R"("/><custom>
<text name="water" data="density=1025 current=-0.2277824642,-1.811013007,0"/>
<text name="vehicle:rov" data="volume=0.004492436294 cob=0,0,0.01663535798 added_mass=4.373301258,1.566714605,3.895604688,0.006369872788,0.006369872788,0.006369872788 linear_damping=7.618741564,7.618741564,7.618741564,0.02123290929,0.02123290929,0.02123290929 quadratic_damping=14.18267567,14.18267567,14.18267567,0.02123290929,0.02123290929,0.02123290929 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=136.1483308 segments=84 diameter=0.01941511529 mass_per_length=0.3401230409 EA=127127793.7 Cdn=1.2 Cdt=0.01 Can=1 damping=31.60214217 integrator=)" +
             integrator + R"("/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="-33.87136283 79.21992894 -26.65504456"><freejoint/><inertial pos="0 0 0" mass="4.603588038" diaginertia="0.02123290929 0.02123290929 0.02123290929"/><site name="att"/></body>
</worldbody></mujoco>)";
    };
    std::string stopped;
    mjModel* fine = Load(xml(0.0002), "fine.xml");
    ASSERT_NE(fine, nullptr);
    const std::vector<Sample> ref = RunScene(fine, 0.7, &stopped);
    ASSERT_EQ(stopped, "");
    mjModel* m = Load(xml(0.002), "current.xml");
    ASSERT_NE(m, nullptr);
    const std::vector<Sample> got = RunScene(m, 0.7, &stopped);
    ASSERT_EQ(stopped, "") << integrator;
    ASSERT_EQ(got.size(), ref.size());
    const Agreement a = Compare(got, ref, 0.2);
    const double pos_err = a.position, tension_err = a.tension;
    std::printf("%s: position %.2f mm of %.3f m, tension %.2f%% (0.2-0.7 s)\n", integrator,
                pos_err * 1e3, (ref.back().pos - ref.front().pos).norm(), 100 * tension_err);
    EXPECT_LT(pos_err, 0.005) << integrator;
    EXPECT_LT(tension_err, 0.02) << integrator;
  }
}

// explicit's consistent coupling without end node B's inertia (session 32): the scene fuzzer's
// seed 10173 (draw 2) with its tether as long as the span (it starts stretched 1.7%) and
// damping_ratio=1, a 4.7 kg vehicle (m_eff 6.7 kg with its added mass) at rest in a 1.18 m/s
// current on 11.6 m of tether in 7 segments (end node B 1.2 kg with 0.9 kg normal added mass),
// EA 3.3e6: omega h = 1.1 at 2 ms and h (damping/L0)/m_eff = 0.65, so explicit takes the
// consistent coupling at 2 ms and at 0.2 ms, the held force at 0.02 ms (asserted), where the
// reference is run. The current drives the vehicle from rest at about 3.6 m/s^2, so end node
// B's inertia m_B a_B is about 6 N of the 25 N vehicle-end tension: with the node's inertia in
// explicit's step (until session 32, the implicit schemes having left it out since session 11)
// the 2 ms run started at 19.4 N against 25.4 N and the vehicle was 5.1 cm off the reference
// within 1 s (0.2 ms likewise: two models, each converged). Asserted at 2 ms against 0.02 ms,
// sampled every 0.05 s for 1 s: the vehicle within 5 mm (it moves 0.79 m; measured 1.5 mm, 51
// mm before) and the tension within 5% from 0.2 s on (3.5-7 N; measured 3.3%, 21% before).
TEST_F(LightVehicle, ExplicitCarriesNoEndNodeInertiaAndAgreesWithItsFineStep) {
  auto xml = [&](double h) {
    return std::string("<mujoco><option timestep=\"") + std::to_string(h) +
           R"("/><custom>
<text name="water" data="density=1025 current=0.1768729858,1.168179588,0"/>
<text name="vehicle:rov" data="volume=0.004726629976 cob=0,0,0.01678830094 added_mass=1.982351717,4.3437642,3.498393526,0.006668125005,0.006668125005,0.006668125005 linear_damping=3.362030422,3.362030422,3.362030422,0.02222708335,0.02222708335,0.02222708335 quadratic_damping=14.44466124,14.44466124,14.44466124,0.02222708335,0.02222708335,0.02222708335 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=11.5761 segments=7 diameter=0.03639993264 mass_per_length=1.430040071 EA=3323304.355 Cdn=1.2 Cdt=0.01 Can=1 damping_ratio=1 integrator=explicit"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="-7.762412618 -1.120210433 -8.514475915"><freejoint/><inertial pos="0 0 0" mass="4.731733072" diaginertia="0.02222708335 0.02222708335 0.02222708335"/><site name="att"/><site name="thr"/></body>
</worldbody></mujoco>)";
  };
  std::string stopped;
  mjModel* fine = Load(xml(0.00002), "fine.xml");
  ASSERT_NE(fine, nullptr);
  EXPECT_FALSE(GetCouplingLimit(fine, 0, 1).consistent);
  const std::vector<Sample> ref = RunScene(fine, 1, &stopped);
  ASSERT_EQ(stopped, "");
  mjModel* m = Load(xml(0.002), "explicit.xml");
  ASSERT_NE(m, nullptr);
  EXPECT_TRUE(GetCouplingLimit(m, 0, 1).consistent);
  const std::vector<Sample> got = RunScene(m, 1, &stopped);
  ASSERT_EQ(stopped, "");
  ASSERT_EQ(got.size(), ref.size());
  const Agreement a = Compare(got, ref, 0.2);
  std::printf("explicit: position %.2f mm of %.3f m, tension %.2f%% (0.2-1 s)\n",
              a.position * 1e3, (ref.back().pos - ref.front().pos).norm(), 100 * a.tension);
  EXPECT_LT(a.position, 0.005);
  EXPECT_LT(a.tension, 0.05);
}

// A heavily damped tether's end on a vehicle (the scene fuzzer's seed 1065; session 13): 240
// segments of 4.75 cm, EA 5460 N, damping 618 N s (damping/L0 = 1.3e4 N s/m on the end
// segment), a 25.7 kg vehicle (m_eff 39.3 kg with its added mass) towed by a 1.7 m/s current.
// omega h is only 0.11 at 2 ms, but h (damping/L0)/m_eff = 0.66: the held force gives the body
// the damper's force of the last step, and its velocity lags the end node's by a fraction of
// their relative velocity that this number sets (1 mm/s of lag is 13 N here). With the held
// force the vehicle-end tension at 0.8 s read 49 N at 2 ms and 22 N at 0.2 ms, against 5.2 N at
// 0.02 ms. From h (damping/L0)/m_eff = 0.025 on every integrator with the consistent coupling
// takes it (kLeadFromDamping, plugin/plugin.cc). Asserted: the coupling is consistent at 2 ms
// and held at 0.02 ms (0.0066), where the reference is run (implicit2); at 2 ms each of
// implicit2, bdf2 and implicit within 5 mm of the reference's vehicle (it travels 0.56 m;
// measured 2.0 mm) and its tension within 4% from 0.3 s on (about 5 N; measured 2.0-2.1%).
TEST_F(LightVehicle, HeavilyDampedEndTakesTheConsistentCouplingAndAgreesWithItsFineStep) {
  auto xml = [&](double h, const char* integrator) {
    return std::string("<mujoco><option timestep=\"") + std::to_string(h) +
           R"("/><custom>
<text name="water" data="density=1025 current=1.710982405,0.1366513112,0"/>
<text name="vehicle:rov" data="volume=0.02467059139 cob=0,0,0.02951672181 added_mass=16.92993673,24.06902209,13.56203507,0.1120238811,0.1120238811,0.1120238811 linear_damping=32.52945196,32.52945196,32.52945196,0.3734129369,0.3734129369,0.3734129369 quadratic_damping=44.65088939,44.65088939,44.65088939,0.3734129369,0.3734129369,0.3734129369 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=11.39554254 segments=240 diameter=0.0147388481 mass_per_length=0.4630903689 EA=5460.080665 Cdn=1.2 Cdt=0.01 Can=1 EI=0.8270511622 EAc=5460.080665 damping=618.2529584 integrator=)" +
           integrator + R"("/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="-2.488161699 0.1836622656 -8.64929372"><freejoint/><inertial pos="0 0 0" mass="25.7160562" diaginertia="0.3734129369 0.3734129369 0.3734129369"/><site name="att"/></body>
</worldbody></mujoco>)";
  };
  const double L0 = 11.39554254 / 240, damping = 618.2529584;  // [m], [N s]
  std::string stopped;
  mjModel* fine = Load(xml(0.00002, "implicit2"), "fine.xml");
  ASSERT_NE(fine, nullptr);
  const CouplingLimit held = GetCouplingLimit(fine, 0, 1);
  EXPECT_NEAR(held.damping_h, 0.00002 * damping / (L0 * held.m_eff), 1e-12);
  EXPECT_LT(held.damping_h, 0.025);
  EXPECT_FALSE(held.consistent);
  const std::vector<Sample> ref = RunScene(fine, 0.7, &stopped);
  ASSERT_EQ(stopped, "");
  for (const char* integrator : {"implicit2", "bdf2", "implicit"}) {
    mjModel* m = Load(xml(0.002, integrator), "damped.xml");
    ASSERT_NE(m, nullptr);
    const CouplingLimit c = GetCouplingLimit(m, 0, 1);
    EXPECT_LT(c.omega_h, 0.5) << integrator;  // not consistent for its stiffness
    EXPECT_NEAR(c.damping_h, 0.002 * damping / (L0 * c.m_eff), 1e-12) << integrator;
    EXPECT_TRUE(c.consistent) << integrator << ": h damping/(L0 m_eff) = " << c.damping_h;
    const std::vector<Sample> got = RunScene(m, 0.7, &stopped);
    ASSERT_EQ(stopped, "") << integrator;
    ASSERT_EQ(got.size(), ref.size());
    const Agreement a = Compare(got, ref, 0.3);
    const double pos_err = a.position, tension_err = a.tension;
    std::printf("%s: position %.2f mm of %.3f m, tension %.2f%% (0.3-0.7 s, about %.1f N)\n",
                integrator, pos_err * 1e3, (ref.back().pos - ref.front().pos).norm(),
                100 * tension_err, ref.back().tension);
    EXPECT_LT(pos_err, 0.005) << integrator;
    EXPECT_LT(tension_err, 0.04) << integrator;
  }
}

// The converse (session 42): a stiff end damper on a stiff end, where the consistent coupling's
// step would damp the body-end mode more than the damper does. The scene fuzzer's held-out seed
// 12117 with damping_ratio=1, as its ringing warning advises: bdf2, 41 segments of 4.6 m, EA
// 4.2e7 N, a 101 kg vehicle (m_eff 170 kg) at the end of a line started 0.035% stretched under
// a surging TMS, which rings in tension and compression (EAc = EA). h (damping/L0)/m_eff =
// 0.0995 at 2 ms, above kLeadFromDamping's 0.025, took the consistent coupling until session 41,
// whose backward-Euler step damps the body-end mode (omega h 0.465) by a ratio of about 0.23
// against the damper's 0.107: the vehicle-end tension over 0.8-1 s read 948 N against 1096 N at
// 0.2 ms (13.5% low). The held force reads 1096.2 N. Asserted: the held force at 2 ms (kappa
// z^2 = 0.216 > d), the 0.8-1 s mean tension within 2% of the 0.2 ms run's (the held force
// there too: d = 0.00995), and the vehicle within 1 cm of it all along.
TEST_F(LightVehicle, StiffEndDamperKeepsTheHeldForceWhereTheCouplingStepDampsTheEndMode) {
  const std::string scene = R"(<custom>
<text name="water" data="density=1025 seabed=-80.92116886"/>
<text name="vehicle:rov" data="volume=0.1015651269 cob=0,0,0.04659858662 added_mass=71.78478104,86.55343971,68.43171852,1.098585155,1.098585155,1.098585155 linear_damping=30.76945686,30.76945686,30.76945686,3.661950516,3.661950516,3.661950516 quadratic_damping=111.2856991,111.2856991,111.2856991,3.661950516,3.661950516,3.661950516 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=186.7842495 segments=41 diameter=0.0345260913 mass_per_length=1.70435855 EA=41779652.34 Cdn=1.2 Cdt=0.01 Can=1 integrator=bdf2 EI=0.001565500825 EAc=41779652.34 damping_ratio=1"/>
<text name="motion:tms" data="x=0.4101341135,4.168716106,0"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="162.6944743 47.75978518 -78.49782678"><freejoint/><inertial pos="0 0 0" mass="101.1854886" diaginertia="3.661950516 3.661950516 3.661950516"/><site name="att"/></body>
</worldbody></mujoco>)";
  auto mean_tension = [](const std::vector<Sample>& run, double from) {
    double sum = 0;
    int n = 0;
    for (const Sample& s : run) {
      if (s.t > from + 1e-9) sum += s.tension, ++n;
    }
    return n > 0 ? sum / n : NAN;
  };
  const StepPair p = AtTwoSteps(scene, "damped_end.xml", 1.0, 0.002);
  const CouplingLimit& c = p.coarse;
  EXPECT_GE(c.damping_h, 0.025);                  // a stiff damper on the body's step
  EXPECT_GT(c.omega_h * c.omega_h, c.damping_h);  // kappa z^2 > d (kappa 1 with bdf2)
  EXPECT_LT(c.omega_h, 1.0);                      // below bdf2's own kLeadFrom
  EXPECT_FALSE(c.consistent) << "h damping/(L0 m_eff) = " << c.damping_h;
  EXPECT_FALSE(p.fine.consistent);
  ASSERT_FALSE(p.got.empty());
  const double T = mean_tension(p.got, 0.8), T_ref = mean_tension(p.ref, 0.8);
  const Agreement a = Compare(p.got, p.ref, 0.8);
  std::printf("0.8-1 s mean tension %.2f N against %.2f N; vehicle %.2f mm off at most\n", T,
              T_ref, a.position * 1e3);
  EXPECT_NEAR(T, T_ref, 0.02 * T_ref);
  EXPECT_LT(a.position, 0.01);
}

// Where the damper is very stiff on the body's step the consistent coupling stays, whatever the
// mode (kHeldDamperMax, session 42): held-out seed 14719 (bdf2 stepping as backward Euler, 58
// segments of 7.5 cm, EA 1.1e5 N, damping 174 N s, a 5.7 kg vehicle, m_eff 8.5 kg, in a 1 m/s
// current above a seabed): d = h (damping/L0)/m_eff = 0.546 and kappa z^2 = 0.674 at 2 ms. With
// the held force (the end-mode rule alone) the vehicle ended 157 mm off its 0.2 ms self; with
// the consistent coupling 4 mm. Asserted: consistent at 2 ms and at 0.2 ms (d 0.055 >= kappa
// z^2 0.0067), and the vehicle within 2 cm of the 0.2 ms run over 1 s.
TEST_F(LightVehicle, VeryStiffEndDamperTakesTheConsistentCouplingWhateverTheEndMode) {
  const std::string scene = R"(<custom>
<text name="water" data="density=1025 current=0.463377746,-0.9192537855,0 seabed=-6.30335659"/>
<text name="vehicle:rov" data="volume=0.005453290432 cob=0,0,0.01787412872 added_mass=3.301560486,2.753246519,5.375843631,0.009122091198,0.009122091198,0.009122091198 linear_damping=5.539920473,5.539920473,5.539920473,0.03040697066,0.03040697066,0.03040697066 quadratic_damping=16.37357947,16.37357947,16.37357947,0.03040697066,0.03040697066,0.03040697066 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=4.356424131 segments=58 diameter=0.009305492068 mass_per_length=0.1998870648 EA=107143.5176 Cdn=1.2 Cdt=0.01 Can=1 integrator=bdf2 EI=97.17614585 EAc=107143.5176 damping=173.580024"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="-0.9190841202 0.1216740898 -2.014500156"><freejoint/><inertial pos="0 0 0" mass="5.710506672" diaginertia="0.03040697066 0.03040697066 0.03040697066"/><site name="att"/></body>
</worldbody></mujoco>)";
  const StepPair p = AtTwoSteps(scene, "very_damped_end.xml", 1.0, 0.01);
  const CouplingLimit& c = p.coarse;
  EXPECT_GT(c.omega_h * c.omega_h, c.damping_h);  // the end-mode rule alone would hold it
  EXPECT_GE(c.damping_h, 0.25);
  EXPECT_TRUE(c.consistent) << "h damping/(L0 m_eff) = " << c.damping_h;
  EXPECT_TRUE(p.fine.consistent);
  ASSERT_FALSE(p.got.empty());
  const Agreement a = Compare(p.got, p.ref, 0.8);
  std::printf("vehicle %.2f mm off at most, tension %.2f%% from 0.8 s\n", a.position * 1e3,
              100 * a.tension);
  EXPECT_LT(a.position, 0.02);
}

// The momentum balance of a free body at end B of a tether anchored at end A (no gravity, no
// water): the body starts at (10.001, 0, 0) moving 0.1 m/s away from the anchor; after a first
// step (which sets the initial shape and, with bdf2, its history), 250 more steps. Nothing but
// the anchor acts on body + tether, so their momentum changes by the anchor's impulse,
// -sum h F_a. bdf2's momentum is its scheme's: its balance M (3 v_n+1 - 4 v_n + v_n-1)/2 =
// h f_n+1 conserves M (3 v_n - v_n-1)/2 on the nodes between the ends (end node B takes a
// backward-Euler step, as the body does); the others M v_n. node_b: end node B counted (its
// inertia is in the step). stopped: the divergence message, if any.
struct MomentumBalance {
  Eigen::Vector3d change = Eigen::Vector3d::Zero(), impulse = Eigen::Vector3d::Zero();
  double peak = 0;      // [N s] norm of the largest impulse reached, component by component
  double mismatch = 0;  // [N s] |change - impulse|
  std::string stopped;
};
MomentumBalance RunMomentumBalance(mjModel* m, mjData* d, double body_mass, bool bdf2,
                                   bool node_b) {
  MomentumBalance r;
  d->qvel[0] = 0.1;  // [m/s]
  const Tether* t = GetTether(m, 0);
  const double h = m->opt.timestep;
  std::vector<double> before(3 * t->nodes());
  auto momentum = [&]() {
    Eigen::Vector3d p = body_mass * Eigen::Vector3d(d->qvel[0], d->qvel[1], d->qvel[2]);
    const double* v = NodeVelocities(m, d, 0);
    for (int i = 1; i < t->nodes() - (node_b ? 0 : 1); ++i) {
      Eigen::Vector3d vi(v + 3 * i);
      if (bdf2 && i < t->nodes() - 1) vi = 1.5 * vi - 0.5 * Eigen::Vector3d(&before[3 * i]);
      p += t->node_mass(i) * vi;
    }
    return p;
  };
  // The first step sets the initial shape (the body's 0.1 m/s, end node's too) and steps the
  // tether ahead by backward Euler (bdf2 has no history yet): the velocities before it are the
  // initial shape's.
  {
    Ends e;
    e.b.pos = Eigen::Vector3d(10.001, 0, 0);
    e.b.vel = Eigen::Vector3d(0.1, 0, 0);
    std::vector<double> x0(before.size());
    t->InitialShape(e, x0.data(), before.data());
  }
  mj_step(m, d);
  const Eigen::Vector3d p0 = momentum();
  Eigen::Vector3d peak = Eigen::Vector3d::Zero();
  for (int k = 0; k < 250; ++k) {
    const double* v = NodeVelocities(m, d, 0);
    std::copy(v, v + before.size(), before.begin());
    mj_step(m, d);
    if (auto why = CheckDivergence(m, d)) {
      r.stopped = *why;
      return r;
    }
    r.impulse -= h * GetReactions(m, d, 0).force_a;
    peak = peak.cwiseMax(r.impulse.cwiseAbs());
  }
  r.change = momentum() - p0;
  r.peak = peak.norm();
  r.mismatch = (r.change - r.impulse).norm();
  return r;
}

// Momentum: a free 5 kg body (no gravity, no water, no damping) 10.001 m from a fixed anchor on
// a 10 m tether of ten 1 m segments, EA 1e7 (k_end 1e7 N/m: omega h = 2.8 at 2 ms), given
// 0.1 m/s away from the anchor, 0.5 s at 2 ms. Nothing but the anchor acts on body + tether,
// so their momentum changes by the anchor's impulse on the tether, -sum h F_a (F_a the
// tether's force on the anchor over each step). With the consistent coupling (end node B in
// the tether's step with the body's effective mass, docs/coupling.md) the body's velocity
// change is end node B's, so the balance is exact up to the Newton tolerance: asserted within
// 1% of the impulse. (The held force of main lost 0.53 N s of 0.94 N s here: the body felt
// the end force one step late; issue11c's attempt 0.23 N s.) bdf2's momentum is its
// scheme's (below): measured 2.8e-12 N s; on M v_n it reads 0.018 N s, the tether nodes' half
// velocity change in the backward-Euler first step, M (v_0 - v_-1)/2. With BDF2's history on
// end node B (before) the body kept accelerating after the snap: 0.68 N s from nothing.
// The last case adds heavy axial damping (damping 500 N s, c_a = 500 kg/s per 1 m segment,
// 0.7 of the segment's critical damping against a node) with bdf2: its Newton matrix is then
// not symmetric on the end segment (docs/coupling.md), and a step accepted without
// iterating is only right if the solve used the whole matrix.
// implicit2 (s10i2): its nodes' momentum is M v, changed by the stages' impulses, (1 - gamma) h
// and gamma h times the forces at Y1 and Y2, on end node B as on the others (end node B takes
// SDIRK's velocity and the body's position step x + h v+); end A's reported force is that
// impulse over the step (StepStatus::impulse_a). Measured 1.9e-13 N s (damping 500: 1.2e-12)
// of 0.52 N s. With end A's force at t + h alone, as the other schemes report it, the balance
// read 0.51 N s off (the anchor's segment is taut at the first stage and slack at the end of
// the snap's steps): the "lost impulse" that kept implicit2 off the consistent coupling in
// session 8 was probably that bookkeeping. explicit (session 10): the substeps' impulse on end
// A, each substep's force at its start, reported as its mean over the MuJoCo step.
TEST_F(LightVehicle, MomentumChangeIsTheAnchorsImpulse) {
  for (const char* integrator :
       {"implicit", "bdf2", "bdf2 damping=500", "implicit2", "implicit2 damping=500", "explicit"}) {
    // explicit at 1 ms (omega h 1.4; at 2 ms, 2.8, it is refused): the consistent coupling in
    // its substeps, end A's reported force their mean.
    const char* step = std::string(integrator) == "explicit" ? "0.001" : "0.002";
    const std::string xml =
        AnchoredBodyXml(step, "0", 10, "0.05", "1e7", integrator, "10.001 0 0", "5", "0.1");
    mjModel* m = Load(xml, "momentum.xml");
    ASSERT_NE(m, nullptr);
    // End node B is not counted (session 11, s11coup; explicit since session 32): its inertia
    // is taken out of the step, the node and the body moving as the body's mass alone, as with
    // the held force (counted, the balance read 1.9e-3 N s off of 0.39 N s with implicit, its
    // m_B dv_B; explicit, whose step kept the node's inertia until session 32 and which was
    // counted with the node until then, now reads 7.1e-3 N s off of 1.46 N s so counted).
    const MomentumBalance b =
        RunMomentumBalance(m, Make(m), 5, std::string(integrator).rfind("bdf2", 0) == 0, false);
    ASSERT_EQ(b.stopped, "") << integrator;
    std::printf("%s: momentum change %.4f N s, anchor's impulse %.4f N s (largest %.4f), "
                "mismatch %.2e N s\n",
                integrator, b.change.x(), b.impulse.x(), b.peak, b.mismatch);
    EXPECT_GT(b.peak, 0.3);  // the tether stopped and turned the body (about 1 N s)
    // Measured 1e-12 N s or less (bdf2 with damping 500: 1.2e-6 N s, its Newton tolerance);
    // the end node's inertia left in the step reads 0.5%.
    EXPECT_LT(b.mismatch, 1e-5 * b.peak) << integrator;
  }
}

// An end node heavier than the body (session 23): a free 0.2 kg body (no gravity, no water)
// 10.001 m from a fixed anchor on a 10 m tether of ten 1 m segments of 1 kg/m, so that end node
// B (half a segment, 0.5 kg) outweighs the body 2.5 times, EA 5000 N (k_end 5000 N/m: omega h =
// 0.32 at 2 ms, below every integrator's own threshold for the consistent coupling), given
// 0.1 m/s away from the anchor, 0.5 s at 2 ms. The held force gives the body end node B's
// forces without its inertia m_B a_B, which here is larger than the body's own: the node's
// momentum comes from nowhere, and the fine-step self of a run at omega h >= 1 (consistent,
// the node's inertia kept, EndInertia) was another model (the scene fuzzer's seeds 974, 3509,
// 3576, 4576, 6231, 6282, 7896, 9051 disagreed by up to 0.9 m). Every integrator with a
// consistent coupling now takes it where the node is heavier than the body's lightest
// effective mass (CouplingLimit::heavy_node), and the body carries the node: the momentum of
// body and every node, end node B included, changes by the anchor's impulse. Measured: see the
// printout; with the held force (before) the mismatch was the node's lost momentum.
TEST_F(LightVehicle, HeavyEndNodeIsCarriedByTheBodyAtAnyOmegaH) {
  for (const char* integrator : {"implicit", "bdf2", "implicit2", "explicit"}) {
    const std::string xml =
        AnchoredBodyXml("0.002", "0", 10, "1", "5000", integrator, "10.001 0 0", "0.2", "0.01");
    mjModel* m = Load(xml, "heavy_node.xml");
    ASSERT_NE(m, nullptr);
    const CouplingLimit c = GetCouplingLimit(m, 0, 1);
    EXPECT_NEAR(c.m_eff, 0.2, 1e-9) << integrator;
    EXPECT_LT(c.omega_h, 0.5) << integrator;  // below every integrator's lead threshold
    EXPECT_TRUE(c.heavy_node) << integrator;
    EXPECT_TRUE(c.consistent) << integrator;
    // Body and every node, end node B included (its inertia is in the step when it is
    // heavier than the body).
    const MomentumBalance b =
        RunMomentumBalance(m, Make(m), 0.2, std::string(integrator) == "bdf2", true);
    ASSERT_EQ(b.stopped, "") << integrator;
    std::printf("%s (omega h %.2f): momentum change %.5f N s, anchor's impulse %.5f N s "
                "(largest %.5f), mismatch %.2e N s\n",
                integrator, c.omega_h, b.change.x(), b.impulse.x(), b.peak, b.mismatch);
    EXPECT_GT(b.peak, 0.005) << integrator;  // the tether pulled the body back
    EXPECT_LT(b.mismatch, 1e-5 * b.peak) << integrator;
  }
}

// A body on a taut 10 m line of 180 segments (EA 1e7 N, 0.05 kg/m), pulled outward by 100
// m/s^2 along x, started at rest beyond its static stretch: it bounces on the whole line. At 2 ms
// the consistent coupling (end segment omega h above 1), at 0.1 ms the held force (the
// reference, no numerical damping).
void LightVehicle::ExpectBounceHeld(const char* integrator, const char* mass, const char* pos,
                                    const char* inertia, double tolerance) {
  const auto [c, f] = CoarseAndFine(
      [&](const char* step) {
        return AnchoredBodyXml(step, "100", 180, "0.05", "1e7", integrator,
                               std::string(pos) + " 0 0", mass, inertia);
      },
      "bounce.xml", 0, 0.4, 0.5);
  const double coarse = c.amplitude, fine = f.amplitude;
  std::printf("%s, %s kg: bounce amplitude over 0.4-0.5 s %.4f mm at 2 ms, %.4f mm at 0.1 ms\n",
              integrator, mass, 1e3 * coarse, 1e3 * fine);
  EXPECT_TRUE(c.consistent) << integrator;
  EXPECT_FALSE(f.consistent) << integrator;  // the held force: the reference
  EXPECT_GT(fine, 0.018) << integrator;      // the bounce kept its 20 mm
  EXPECT_NEAR(coarse, fine, tolerance * fine) << integrator;
}

// The consistent coupling's slow-mode correction (session 34, SlowModeCorrection in
// plugin/plugin.cc). A 667 kg body on a taut 10 m line of 180 segments (EA 1e7 N), pulled
// outward by a 100 m/s^2 "gravity" along x so that the line stays taut (static stretch 67 mm),
// started 20 mm beyond it at rest: it bounces on the whole line at omega = sqrt((EA/L)/m) = 38.7
// rad/s (z = omega h = 0.077 at 2 ms, z^2 = 0.006) while the end segment's omega h is 1.04,
// where every integrator that has it takes the consistent coupling. The body's force then
// depends on where end node B ends the step, and MuJoCo's x+ = x + h v+ damps the bounce by
// 1/(1 + kappa z^2) in energy per step (kappa 1 for implicit and bdf2, 1/2 for implicit2 and
// nearly so for explicit's many substeps): after 0.5 s, 250 steps, its amplitude would be 47%
// (kappa 1) or 69% of the start's. The correction cancels that. Asserted: the amplitude over
// the last 0.1 s at 2 ms within 0.25% of the 0.1 ms run's (the held force, no numerical
// damping; the line has no damping of its own here). Measured: within 0.064% with every
// integrator; without the correction 51% (implicit, bdf2) and 72% (implicit2, explicit);
// without its (I + kappa h^2 W K)^-1, which over-corrects by (kappa z^2)^2 per step, 0.46%
// high (bdf2; mutation slow-mode-no-denominator); with backward Euler's kappa for implicit2
// 39% high. The 0.25% tells the exact correction from the one without the inverse.
TEST_F(LightVehicle, BounceOnATautLineIsNotDampedByTheConsistentCoupling) {
  for (const char* integrator : {"implicit", "bdf2", "implicit2", "explicit"})
    ExpectBounceHeld(integrator, "667", "10.0867", "10", 0.0025);
}

// The slow-mode correction up to z^2 = 0.02 with every integrator (session 36). The bounce
// above on a 267 kg body: omega = sqrt((EA/L)/m) = 61 rad/s, z^2 = 0.015 at 2 ms, started 20 mm
// beyond the static stretch (27 mm). With backward Euler's kappa = 1 (implicit, bdf2) that is
// above kappa z^2 = 0.01, the slow-mode bound until session 35, and the coupling damped the
// bounce by 1/(1 + z^2) in energy per step: 3.94 mm of its 20 mm were left after 0.5 s.
// implicit2 (kappa 1/2) had the correction there already, and so had explicit (kappa < 1/2; not
// run here: at 2 ms this scene rings after a snap and diverges with explicit, as its load warning
// says it may). The bound is now also z^2 <= 0.02 (kSlowModeZ2Max): symplectic Euler's own
// energy error, which the correction brings back, depends on z, not on kappa z^2. Asserted: the
// amplitude over 0.4-0.5 s at 2 ms within 1% of the 0.1 ms run's. Measured: +0.12% (implicit),
// +0.22% (bdf2), +0.06% (implicit2); with the old bound -80%, -80%, +0.06%.
TEST_F(LightVehicle, BounceJustAboveTheOldSlowModeBoundIsNotDamped) {
  for (const char* integrator : {"implicit", "bdf2", "implicit2"})
    ExpectBounceHeld(integrator, "267", "10.0467", "4", 0.01);
}

// A stop that blamed "the motion" of a body nothing moves (session 36). The test above's scene
// with explicit (coupling omega h 1.64, above half explicit's limit: its load warning says it
// may chatter; the line undamped): with the slow-mode correction the bounce keeps its amplitude,
// 8-11 segments near the body go slack at its lowest tension where the 0.1 ms run has none,
// their snaps grow to 1.1e7 N, and at 0.324 s the body is thrown at 78 m/s. The stop said
// "that motion is too fast for the step; reduce <option timestep> ... or slow the motion", and
// there is no motion to slow. Asserted: the stop names the body as thrown and advises implicit
// and damping_ratio=1, not slowing a motion; and the advice holds: with damping_ratio=1 the
// same scene runs to 0.5 s and ends within 1 mm of the 0.1 ms run (measured 10.0402 against
// 10.0403 m), as implicit does.
TEST_F(LightVehicle, ThrownFreeBodyIsToldWhatThrewIt) {
  const std::string xml =
      AnchoredBodyXml("0.002", "100", 180, "0.05", "1e7", "explicit", "10.0467 0 0", "267", "4");
  mjModel* m = Load(xml, "thrown.xml");
  ASSERT_NE(m, nullptr);
  const std::optional<std::string> stop = testing::StepUntilDivergence(m, Make(m), 0.5);
  ASSERT_TRUE(stop.has_value());
  EXPECT_TRUE(Contains(*stop, "too fast for the step")) << *stop;
  EXPECT_TRUE(Contains(*stop, "nothing prescribes body 'v'")) << *stop;
  EXPECT_TRUE(Contains(*stop, "integrator=implicit")) << *stop;
  EXPECT_TRUE(Contains(*stop, "damping_ratio=1")) << *stop;
  EXPECT_FALSE(Contains(*stop, "slow the motion")) << *stop;
  double end[2];
  const char* steps[2] = {"0.002", "0.0001"};
  for (int k = 0; k < 2; ++k) {
    mjModel* md = Load(AnchoredBodyXml(steps[k], "100", 180, "0.05", "1e7",
                                       "explicit damping_ratio=1", "10.0467 0 0", "267", "4"),
                       "thrown_damped.xml");
    ASSERT_NE(md, nullptr);
    mjData* d = Make(md);
    const std::optional<std::string> s = testing::StepUntilDivergence(md, d, 0.5);
    ASSERT_FALSE(s.has_value()) << *s;
    end[k] = d->qpos[0];
  }
  std::printf("thrown body: %s\nwith damping_ratio=1: x %.5f m at 2 ms, %.5f m at 0.1 ms\n",
              stop->c_str(), end[0], end[1]);
  EXPECT_NEAR(end[0], end[1], 0.001);
}

// The slow-mode correction on a line heavier than the body (session 35). Its model is a body on
// a light spring, so the obvious restriction is to lines lighter than the body; measured, it is
// wrong: the correction still takes most of the coupling's damping away. A 5 kg body on a 10 m
// line of 1 kg/m (10 kg, 180 segments, end node 0.028 kg), EA 1e5 N (line stiffness K = EA/L =
// 1e4 N/m; end segment omega h 1.2 at 2 ms: the consistent coupling), pulled outward by 100
// m/s^2 along x, started at 10.095 m on a uniformly stretched line (the static stretch under the
// body's 500 N and the line's own weight is 0.1 m): it bounces by about 10 mm. The slow
// mode is the line's own (a fixed-free rod with a tip mass: beta L tan(beta L) = 2, omega = 34
// rad/s, not the light spring's sqrt(K/m) = 45). Amplitude over 0.4-0.5 s at 2 ms against the
// 0.1 ms run (the held force), measured: with the correction 17.6% low (implicit), 10.5% (bdf2),
// 8.7% (implicit2), 8.5% (explicit); without it 50%, 44%, 26%, 25% low. What is left is the
// line's own numerical damping and K overstating the heavy line's dynamic stiffness. Asserted:
// the correction applied, and the amplitude within 20% of the fine step's, which every version
// without the correction on heavy lines fails. In the long fuzzer runs, withdrawing it where the
// line outweighs the body (Tether::LineOutweighs, not kept) fixed held-out seed 12117 and
// moved 246 scenes: 63 closer to their fine step, 183 further (docs/coupling.md, session 35).
TEST_F(LightVehicle, SlowModeCorrectionAlsoHoldsTheBounceOfALineHeavierThanTheBody) {
  for (const char* integrator : {"implicit", "bdf2", "implicit2", "explicit"}) {
    const auto [c, f] = CoarseAndFine(
        [&](const char* step) {
          return AnchoredBodyXml(step, "100", 180, "1", "1e5", integrator, "10.095 0 0", "5",
                                 "0.1");
        },
        "heavy_line.xml", 0, 0.4, 0.5);
    const double coarse = c.amplitude, fine = f.amplitude;
    std::printf("%s: heavy line, bounce amplitude over 0.4-0.5 s %.4f mm at 2 ms, %.4f mm at "
                "0.1 ms; largest correction %.3g N\n",
                integrator, 1e3 * coarse, 1e3 * fine, c.correction);
    EXPECT_TRUE(c.consistent) << integrator;
    EXPECT_FALSE(f.consistent) << integrator;
    EXPECT_GT(c.correction, 1) << integrator;  // [N] (8-16 N measured)
    EXPECT_GT(fine, 0.0085) << integrator;     // the bounce (9-9.8 mm measured)
    EXPECT_NEAR(coarse, fine, 0.2 * fine) << integrator;
  }
}

// The slow-mode correction mode by mode (session 35): a vehicle's swing across a taut line is
// slow where its bounce along it is not. A 5 kg body on a 10 m line of 40 segments (EA 1e6 N,
// 0.05 kg/m; end segment omega h 1.8 at 2 ms: the consistent coupling), pulled outward by 1000
// m/s^2 along x (tension 5 kN, static stretch 5 cm), started 1 m to the side at rest: it swings
// as a pendulum, omega^2 = T/(l m) = 100 /s^2 (z^2 = 4e-4), while its bounce along the line has
// z^2 = h^2 EA/(L m) = 0.08, above kSlowModeMax. With the bound h^2 lambda_max(W)
// lambda_max(K) of session 34 the whole correction was off here, and the coupling damped the
// swing by kappa z^2/2 in amplitude per step. Asserted: the swing's amplitude over 1.4-2 s at 2
// ms within 1% of the 0.1 ms run's (the held force). Measured: 0.01% (implicit), 0.52% high
// (bdf2), 0.25% (implicit2), 0.22% (explicit); with session 34's bound 16% low (implicit),
// 15.6% (bdf2), 8.1% (implicit2, explicit) (docs/coupling.md, session 35).
TEST_F(LightVehicle, SwingAcrossATautLineIsNotDampedWhereItsBounceIsFast) {
  for (const char* integrator : {"implicit", "bdf2", "implicit2", "explicit"}) {
    const auto [c, f] = CoarseAndFine(
        [&](const char* step) {
          return AnchoredBodyXml(step, "1000", 40, "0.05", "1e6", integrator, "10.000125 1 0",
                                 "5", "0.1");
        },
        "swing.xml", 1, 1.4, 2);
    const double coarse = c.amplitude, fine = f.amplitude;
    std::printf("%s: swing amplitude over 1.4-2 s %.4f m at 2 ms, %.4f m at 0.1 ms\n", integrator,
                coarse, fine);
    EXPECT_TRUE(c.consistent) << integrator;
    EXPECT_FALSE(f.consistent) << integrator;
    EXPECT_GT(fine, 0.9) << integrator;  // the swing kept its 1 m
    EXPECT_NEAR(coarse, fine, 0.01 * fine) << integrator;
  }
}

// Tether::LineStiffness, the K of the slow-mode correction, on a straight line of 8 segments
// stretched by a strain e between two fixed sites (dry, no gravity): every segment carries
// T = EA e, so the line's stiffness at end B is EA/L0 along it (the segments' EA/l0 in series)
// and T/l across it (their geometric stiffnesses T/l_j in series, l = L0 (1 + e) the stretched
// length), to round-off. Slack by the same strain it is zero (no first-order stiffness), and
// Tether::AllTaut is false.
TEST_F(LightVehicle, LineStiffnessOfAStraightTautLineIsItsSeriesStiffness) {
  const double EA = 2e6, L0 = 8;  // [N], [m]
  for (double e : {1e-3, -1e-3}) {
    std::ostringstream xml;
    xml.precision(17);
    xml << R"(<mujoco><option timestep="0.002" gravity="0 0 0"/>
<custom><text name="tether:t" data="ends=a,b length=8 segments=8 diameter=0.01
  mass_per_length=0.1 EA=2e6 integrator=implicit"/></custom>
<worldbody><site name="a"/><site name="b" pos=")"
        << L0 * (1 + e) << R"( 0 0"/></worldbody></mujoco>)";
    mjModel* m = Load(xml.str(), "line_stiffness.xml");
    ASSERT_NE(m, nullptr);
    mjData* d = Make(m);
    mj_forward(m, d);  // the initial (straight) shape
    const double* x = NodePositions(m, d, 0);
    ASSERT_NE(x, nullptr);
    const Mat3 K = GetTether(m, 0)->LineStiffness(x);
    // AllTaut, the correction's check at the step's end, says the same as K != 0.
    EXPECT_EQ(GetTether(m, 0)->AllTaut(x), e > 0);
    if (e < 0) {
      EXPECT_TRUE(K.isZero(0)) << K;
      continue;
    }
    const double T = EA * e, along = EA / L0, across = T / (L0 * (1 + e));
    EXPECT_NEAR(K(0, 0), along, 1e-9 * along);
    EXPECT_NEAR(K(1, 1), across, 1e-9 * along);
    EXPECT_NEAR(K(2, 2), across, 1e-9 * along);
    EXPECT_NEAR(K(0, 1), 0, 1e-9 * along);
  }
}

}  // namespace
}  // namespace mjtether
