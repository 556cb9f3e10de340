// Vehicle-tether coupling and the time-step advisor (issue 11, items 1 and 2; docs/coupling.md).
//
// The cases are the issue's: the BlueROV2 Heavy of models/bluerov2_heavy.xml (11.5 kg, added
// mass in the armature) started 29.5 m out on its 30 m tether of 1 m segments, its four
// horizontal thrusters at 40 N, the tether's EA (and EAc) set to 6e4, 1e6, 1e7 and 1e8 N, every
// integrator, at the model's 2 ms step against the same scene at 0.1 ms.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "coupling_scene.h"
#include "mujoco_fixture.h"

namespace mjtether {
namespace {

class CouplingCases : public ::testing::TestWithParam<std::tuple<const char*, const char*>> {};

// Each case either agrees with its 0.1 ms self within 1% or is refused at load, by Attach, with
// the limit and the fix. Agreement: at every sample (0.05 s) the vehicle within 1% of the
// reference's own displacement from the start (about 0.8 m in 1.5 s), and from t = 0.5 s on,
// once the tether has come taut out of its initial catenary, the vehicle-end tension within
// 1% of the reference's (about 110 N; 1% is the issue's criterion). 1.5 s shows the chatter:
// on the code before this work explicit and rk4 at EA 1e7 and 1e8 swung between 2 and 20 kN
// from t = 0.1 s on and exited 0.
TEST_P(CouplingCases, AgreeWithTheFineStepOrAreRefusedAtLoad) {
  const auto [EA, integrator] = GetParam();
  InstallErrorHandlers();
  std::string error;
  testing::ModelPtr m(LoadModelFromString(BlueRovXml(EA, integrator, 0.002), "case.xml", &error));
  if (!m) {
    // Refused: only the explicit schemes, above the coupling limit, naming it and the fix.
    EXPECT_TRUE(std::string(integrator) == "explicit" || std::string(integrator) == "rk4" ||
                std::string(integrator) == "implicit2")
        << error;
    EXPECT_TRUE(Contains(error, "case.xml: <text name=\"tether:umbilical\">")) << error;
    EXPECT_TRUE(Contains(error, "omega h = ")) << error;
    const std::string name = integrator;
    EXPECT_TRUE(Contains(error, name == "rk4"         ? "limit 0.5"
                                : name == "implicit2" ? "limit 1"
                                                      : "limit 2"))
        << error;
    EXPECT_TRUE(Contains(error, "use integrator=implicit")) << error;
    EXPECT_TRUE(Contains(error, "<option timestep> <= ")) << error;
    std::printf("EA %s %s: refused at load\n", EA, integrator);
    return;
  }
  // The 0.1 ms reference, only for a case that loads (rk4 at EA 1e8 is refused at 0.1 ms too:
  // omega h 0.53 against its limit 0.5).
  testing::ModelPtr fine(LoadModelFromString(BlueRovXml(EA, integrator, 1e-4), "fine.xml", &error));
  ASSERT_NE(fine, nullptr) << error;
  std::string stopped;
  const std::vector<Sample> ref = RunScene(fine.get(), 1.5, &stopped);
  fine.reset();
  ASSERT_EQ(stopped, "") << "the 0.1 ms reference must run";

  const std::vector<Sample> got = RunScene(m.get(), 1.5, &stopped);
  m.reset();
  ASSERT_EQ(stopped, "");
  ASSERT_EQ(got.size(), ref.size());
  const double travel = (ref.back().pos - ref.front().pos).norm();
  double pos_err = 0, tension_err = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    ASSERT_NEAR(got[i].t, ref[i].t, 1e-9);
    pos_err = std::max(pos_err, (got[i].pos - ref[i].pos).norm());
    if (ref[i].t >= 0.5) {
      tension_err = std::max(tension_err,
                             std::abs(got[i].tension - ref[i].tension) / std::abs(ref[i].tension));
    }
  }
  std::printf("EA %s %s: position %.2f mm (%.2f%% of %.3f m travel), tension %.3f%%\n", EA,
              integrator, pos_err * 1e3, 100 * pos_err / travel, travel, 100 * tension_err);
  EXPECT_LT(pos_err, 0.01 * travel);
  EXPECT_LT(tension_err, 0.01);
}

INSTANTIATE_TEST_SUITE_P(BlueRov2, CouplingCases,
                         ::testing::Combine(::testing::Values("6e4", "1e6", "1e7", "1e8"),
                                            ::testing::Values("explicit", "rk4", "implicit",
                                                              "implicit2", "bdf2")),
                         [](const auto& info) {
                           std::string ea = std::get<0>(info.param);
                           ea[ea.find('e')] = '_';
                           return "EA" + ea + "_" + std::get<1>(info.param);
                         });

using Coupling = testing::MuJoCoFixture;

// The scene fuzzer's seed 491 with its tether as long as its span and damping_ratio=1
// (tests/step_check/near_taut_start.xml): 65 segments of implicit2 on an 11 kg vehicle, coupling
// omega 919 rad/s, so the consistent coupling at 2 ms (omega h 1.84) and the held end force at
// 0.5 ms (0.46, below kLeadFromImplicit2).
std::string NearTautXml(const char* timestep) {
  std::ifstream f(std::string(MJTETHER_STEP_CHECK_DIR) + "/near_taut_start.xml");
  std::stringstream xml;
  xml << f.rdbuf();
  EXPECT_FALSE(xml.str().empty()) << "tests/step_check/near_taut_start.xml";
  return Replace(Replace(xml.str(), "timestep=\"0.002\"",
                         std::string("timestep=\"") + timestep + "\""),
                 "integrator=implicit2", "damping_ratio=1 integrator=implicit2");
}

// The mean vehicle-end tension over the last 0.2 s of 1 s (each step's, as GetReactions reads it).
double LateMeanTension(mjModel* m, mjData* d) {
  double sum = 0;
  int n = 0;
  while (d->time < 1 - 1e-9) {
    mj_step(m, d);
    if (d->time > 0.8 + 1e-9) sum += GetReactions(m, d, 0).tension_b, ++n;
  }
  return sum / n;
}

// A step changed after loading (m->opt.timestep set by the user's code) keeps the coupling
// chosen for the step at load, and the result is not the scene's at the new step: loaded at
// 2 ms and run at 0.5 ms the consistent coupling stays and reads 17.4 N, against 23.2 N loaded at
// 0.5 ms (the command line's 0.2 and 0.02 ms: 23.27 and 23.30 N). RunWarnings says so, naming
// both steps and the coupling with its omega h at each; the model loaded at its step has no such
// warning. Before session 44 nothing was said.
TEST_F(Coupling, AStepChangedAfterLoadingIsWarnedWithTheCouplingItKept) {
  mjModel* changed = Load(NearTautXml("0.002"), "near_taut.xml");
  mjModel* loaded = Load(NearTautXml("0.0005"), "near_taut.xml");
  ASSERT_TRUE(changed && loaded);
  EXPECT_TRUE(StepWarnings(changed).empty());
  changed->opt.timestep = 0.0005;
  ASSERT_TRUE(GetCouplingLimit(changed, 0, 1).consistent);
  ASSERT_FALSE(GetCouplingLimit(loaded, 0, 1).consistent);
  mjData* dc = Make(changed);
  mjData* dl = Make(loaded);
  const double t_changed = LateMeanTension(changed, dc), t_loaded = LateMeanTension(loaded, dl);
  ASSERT_FALSE(CheckDivergence(changed, dc));
  ASSERT_FALSE(CheckDivergence(loaded, dl));
  EXPECT_GT(std::abs(t_changed - t_loaded), 0.05 * t_loaded)
      << t_changed << " N loaded at 2 ms, " << t_loaded << " N loaded at 0.5 ms: if they agree, "
      << "the warning's claim that results may differ needs another example";
  EXPECT_TRUE(StepWarnings(loaded).empty());
  const std::vector<std::string> w = RunWarnings(changed, dc);
  ASSERT_FALSE(w.empty());
  EXPECT_NE(w[0].find("near_taut.xml: <option timestep> is 0.0005 s, not the 0.002 s the tethers "
                      "were attached with"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("tether 't' end B: consistent coupling at coupling omega h 1.838"),
            std::string::npos) << w[0];
  EXPECT_NE(w[0].find(", now 0.4596"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("LoadModel with the override option.timestep"), std::string::npos) << w[0];
  // Set back, the warning goes.
  changed->opt.timestep = 0.002;
  EXPECT_TRUE(StepWarnings(changed).empty());
}

// The advisor's figures against their formula: k_end = EA/L0; m_eff = 1/lambda_max(W), with
// W = J M^-1 J^T of a free body at a site r from its centre of mass (body at rest, identity
// orientation): W = I/(m + a) + [r]x^T diag(1/(J_i + A_i)) [r]x, m = 11.5 kg, a = 5.5 kg (the
// isotropic added mass in the armature), J = 0.16 kg m^2, A = 0.12 kg m^2, r = (-0.229, 0,
// 0.1) m; omega = sqrt(k_end/m_eff); omega h at 2 ms. Rounding only: 1e-9.
TEST_F(Coupling, LimitMatchesItsFormula) {
  mjModel* m = Load(BlueRovXml("1e6", "explicit", 0.002));
  ASSERT_NE(m, nullptr);
  const CouplingLimit c = GetCouplingLimit(m, 0, 1);
  EXPECT_EQ(c.body, mj_name2id(m, mjOBJ_BODY, "rov"));
  EXPECT_DOUBLE_EQ(c.k_end, 1e6 / 1.0);
  Eigen::Matrix3d rx;  // [r]x
  const Eigen::Vector3d r(-0.229, 0, 0.1);
  rx << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  const Eigen::Matrix3d W = Eigen::Matrix3d::Identity() / (11.5 + 5.5) +
                            rx * (Eigen::Matrix3d::Identity() / (0.16 + 0.12)) * rx.transpose();
  const double lambda = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(W).eigenvalues().maxCoeff();
  EXPECT_NEAR(c.m_eff, 1 / lambda, 1e-9 / lambda);
  EXPECT_NEAR(c.omega, std::sqrt(1e6 * lambda), 1e-9 * c.omega);
  EXPECT_NEAR(c.omega_h, 0.002 * std::sqrt(1e6 * lambda), 1e-9);
  EXPECT_TRUE(c.applies);
  EXPECT_EQ(c.limit, 2.0);
  // End A is on the mocap boat: no coupling figure.
  EXPECT_LT(GetCouplingLimit(m, 0, 0).body, 0);
  // 0.26 at 6e4: not the chatter warning, but (since session 19) the held force's, from
  // kCouplingAccurate = 0.1 (this case is within 0.65% of its fine step: the warning is the
  // fuzzer's rate, not this scene's error); bdf2 there: none. 1.06 at 1e6, above half the
  // limit: the chatter warning.
  mjModel* m1 = Load(BlueRovXml("6e4", "explicit", 0.002), "held.xml");
  ASSERT_NE(m1, nullptr);
  ASSERT_EQ(Warnings(m1).size(), 1u);
  EXPECT_TRUE(Contains(Warnings(m1)[0], "held end force at coupling omega h = 0.26"))
      << Warnings(m1)[0];
  EXPECT_FALSE(Contains(Warnings(m1)[0], "may chatter")) << Warnings(m1)[0];
  mjModel* quiet = Load(BlueRovXml("6e4", "bdf2", 0.002), "quiet.xml");
  ASSERT_NE(quiet, nullptr);
  EXPECT_TRUE(Warnings(quiet).empty());
  mjModel* m2 = Load(BlueRovXml("1e6", "explicit", 0.002), "warn.xml");
  ASSERT_NE(m2, nullptr);
  ASSERT_EQ(Warnings(m2).size(), 1u);
  const std::string w = Warnings(m2)[0];
  EXPECT_TRUE(Contains(w, "warn.xml: <text name=\"tether:umbilical\">")) << w;
  EXPECT_TRUE(Contains(w, "end B on body 'rov'")) << w;
  EXPECT_TRUE(Contains(w, "may chatter")) << w;
  EXPECT_TRUE(Contains(w, "integrator=implicit")) << w;
}

// A stiff rod's end is stiffer across the line than along it, and the advisor takes the larger
// (Tether::EndBendingStiffness, session 37): 100 segments of L0 = 4 cm, EA 3e3 N, EI 400 N m^2
// on a 3 kg body (site at its centre of mass, m_eff = 3 kg): EI/L0^3 = 6.25e6 N/m against EA/L0
// = 7.5e4, omega h 2.89 at 2 ms where EA/L0 alone gives 0.32. implicit takes the consistent
// coupling (from 1), explicit is refused (limit 2) with the bending named as k_end and "a
// smaller EI"; without EI the same line is the held force's at 0.32. Held-out seed 12434 (EI
// 467 on 3.6 cm segments of EA 3.2e3 N, a 2.3 kg body) read 0.35, got the held force and ended
// 0.31 m off its fine step; the consistent coupling takes it to 6 mm.
TEST_F(Coupling, AStiffRodsBendingIsTheEndsStiffness) {
  auto xml = [](const std::string& integrator, const std::string& EI) {
    return "<mujoco><option timestep=\"0.002\"/><custom><text name=\"tether:t\" "
           "data=\"ends=a,b length=4 segments=100 diameter=0.02 mass_per_length=0.3 EA=3e3 " +
           EI + " integrator=" + integrator +
           "\"/></custom><worldbody><body name=\"anchor\" mocap=\"true\"><site name=\"a\"/>"
           "</body><body name=\"rov\" pos=\"3.9 0 0\"><freejoint/><inertial pos=\"0 0 0\" "
           "mass=\"3\" diaginertia=\"0.01 0.01 0.01\"/><site name=\"b\"/></body></worldbody>"
           "</mujoco>";
  };
  const double L0 = 0.04, k_bending = 400 / (L0 * L0 * L0);  // [m], [N/m]
  mjModel* m = Load(xml("implicit", "EI=400"), "rod.xml");
  ASSERT_NE(m, nullptr);
  const CouplingLimit c = GetCouplingLimit(m, 0, 1);
  EXPECT_TRUE(c.bending);
  EXPECT_NEAR(c.k_end, k_bending, 1e-9 * k_bending);
  EXPECT_NEAR(c.m_eff, 3, 1e-9);
  EXPECT_NEAR(c.omega_h, 0.002 * std::sqrt(k_bending / 3), 1e-9);
  EXPECT_TRUE(c.consistent);
  mjModel* cable = Load(xml("implicit", ""), "cable.xml");
  ASSERT_NE(cable, nullptr);
  const CouplingLimit a = GetCouplingLimit(cable, 0, 1);
  EXPECT_FALSE(a.bending);
  EXPECT_NEAR(a.k_end, 3e3 / L0, 1e-9 * 3e3 / L0);
  EXPECT_FALSE(a.consistent);
  std::string error;
  mjModel* refused = LoadModelFromString(xml("explicit", "EI=400"), "rod_explicit.xml", &error);
  EXPECT_EQ(refused, nullptr);
  if (refused) models_.push_back(refused);
  EXPECT_TRUE(Contains(error, "limit 2")) << error;
  EXPECT_TRUE(Contains(error, "k_end = EI/(L0^2 w) (bending across the line")) << error;
  EXPECT_TRUE(Contains(error, "or fewer segments or a smaller EI")) << error;
}

// An implicit tether has no coupling limit (measured stable and within 1% at omega h = 10.6):
// it loads without a warning and the figure is still reported.
TEST_F(Coupling, ImplicitTethersAreNotLimited) {
  mjModel* m = Load(BlueRovXml("1e8", "implicit", 0.002));
  ASSERT_NE(m, nullptr);
  const CouplingLimit c = GetCouplingLimit(m, 0, 1);
  EXPECT_FALSE(c.applies);
  EXPECT_TRUE(c.consistent);  // omega h >= kLeadFrom = 1 on a free body
  EXPECT_GT(c.omega_h, 10);
  EXPECT_TRUE(Warnings(m).empty());
}

// implicit2 with the consistent coupling (a free body at end B, end A on the mocap boat; from
// omega h 0.5, session 10 s10i2): the BlueROV2 at EA 1e8 (omega h 10.6), refused before by
// kCouplingLimitImplicit2 = 4, loads without a limit or a warning (its agreement with the
// 0.1 ms run is BlueRov2/CouplingCases.../EA1_8_implicit2: 2.2 mm, 0.14%). Where the consistent
// coupling does not apply (MuJoCo's RK4, which calls the callback at t + h/2) the held force
// keeps its limit (1 since session 15, 4 before) and the refusal names bdf2 first.
TEST_F(Coupling, Implicit2IsLimitedOnlyWithTheHeldForce) {
  mjModel* m = Load(BlueRovXml("1e8", "implicit2", 0.002));
  ASSERT_NE(m, nullptr);
  const CouplingLimit c = GetCouplingLimit(m, 0, 1);
  EXPECT_FALSE(c.applies);
  EXPECT_TRUE(c.consistent);
  EXPECT_GT(c.omega_h, 10);
  EXPECT_TRUE(Warnings(m).empty());
  std::string xml = BlueRovXml("1e8", "implicit2", 0.002);
  const size_t at = xml.find("integrator=\"Euler\"");  // the model's <option>
  ASSERT_NE(at, std::string::npos);
  xml.replace(at, 18, "integrator=\"RK4\"");
  std::string error;
  mjModel* rk = LoadModelFromString(xml, "rk4.xml", &error);
  EXPECT_EQ(rk, nullptr);
  if (rk) models_.push_back(rk);
  EXPECT_TRUE(Contains(error, "rk4.xml: <text name=\"tether:umbilical\">")) << error;
  EXPECT_TRUE(Contains(error, "integrator=implicit2 with end B on body 'rov'")) << error;
  EXPECT_TRUE(Contains(error, "limit 1")) << error;
  EXPECT_TRUE(Contains(error, "use integrator=bdf2 (the default) or implicit")) << error;
  EXPECT_TRUE(Contains(error, "<option timestep> <= ")) << error;
}

// The time step a stop message advises, "<option timestep> <= X s" (its last one); 0 if none.
double AdvisedStep(const std::string& message) {
  const std::string key = "<option timestep> <= ";
  const size_t at = message.rfind(key);
  return at == std::string::npos ? 0 : std::atof(message.c_str() + at + key.size());
}

// The seabed under end node B, where the node touches it, is a spring and damper on the body
// (Tether::EndSeabedStiffness, EndSeabedDamping; session 38), and the consistent coupling is
// taken where either is stiff on the body's step: max(omega_s h, h c_s/m_eff) >= 0.7
// (kLeadFromSeabed). One segment of L0 = 36 m on an 8 kg body (no added mass: m_eff = 8 kg):
// seabed_stiffness 1e5 N/m^2 over L0/2 is k_s = 1.8e6 N/m, omega_s h 0.95 at 2 ms; its damping,
// critical for the tether's 0.2 kg/m, 2 sqrt(1e5 x 0.2) L0/2 = 5.1e3 N s/m, gives h c_s/m_eff
// 1.27. A seabed of 2.5e4 N/m^2 (omega_s h 0.47) takes it from a damping of 155.6 N s/m^2
// (h c_s/m_eff 1.4) and not from 55.6 (0.5). rk4 (no consistent coupling) is not refused for a
// seabed the body may never reach. The body, thrust down and out at 2 kN, lands on the seabed
// through its end node at about 25 m/s: the contact's damping ratio 5.1e3/(2 sqrt(1.8e6 x 8)) =
// 0.67 gives a restitution of exp(-0.67 pi/sqrt(1 - 0.67^2)) = 0.06, a rebound of 1.5 m/s
// against the 210 m/s^2 that press it down: 5 mm. With the held force (before session 38) it
// bounced 0.21 m off the seabed and its end tension averaged 9.5% off its 0.2 ms self over
// 0.2-0.6 s; the scene fuzzer's seed 9022 (bdf2, one 56 m segment, a 7.7 kg vehicle) read 38%.
TEST_F(Coupling, TheSeabedUnderTheEndNodeTakesTheConsistentCoupling) {
  auto xml = [](const std::string& integrator, double step, const std::string& seabed) {
    std::ostringstream s;
    s << "<mujoco><option timestep=\"" << step << "\"/><custom><text name=\"water\" "
      << "data=\"density=1025" << seabed << "\"/><text name=\"tether:t\" data=\"ends=a,b "
      << "length=36 segments=1 diameter=0.01 mass_per_length=0.2 EA=4000 integrator="
      << integrator << "\"/><text name=\"thrust:thr\" data=\"t=0,0.05 ctrl=0,2000\"/>"
      << "</custom><worldbody><body name=\"tms\" mocap=\"true\"><site name=\"a\"/></body>"
      << "<body name=\"rov\" pos=\"30 0 -3\"><freejoint/><inertial pos=\"0 0 0\" mass=\"8\" "
      << "diaginertia=\"0.05 0.05 0.05\"/><site name=\"b\"/></body></worldbody><actuator>"
      << "<motor name=\"thr\" site=\"b\" gear=\"0.6 0 -0.8 0 0 0\"/></actuator></mujoco>";
    return s.str();
  };
  const double k_s = 1e5 * 18, c_s = 2 * std::sqrt(1e5 * 0.2) * 18;  // [N/m], [N s/m]
  mjModel* m = Load(xml("bdf2", 0.002, " seabed=-5"), "seabed.xml");
  ASSERT_NE(m, nullptr);
  const CouplingLimit c = GetCouplingLimit(m, 0, 1);
  EXPECT_NEAR(c.k_end, 4000 / 36.0, 1e-9);  // the line's own, not the seabed's
  EXPECT_NEAR(c.seabed_omega_h, 0.002 * std::sqrt(k_s / 8), 1e-9);
  EXPECT_NEAR(c.seabed_damping_h, 0.002 * c_s / 8, 1e-9);
  EXPECT_TRUE(c.consistent);
  mjModel* open = Load(xml("bdf2", 0.002, ""), "open.xml");
  ASSERT_NE(open, nullptr);
  const CouplingLimit a = GetCouplingLimit(open, 0, 1);
  EXPECT_EQ(a.seabed_omega_h, 0);
  EXPECT_EQ(a.seabed_damping_h, 0);
  EXPECT_FALSE(a.consistent);
  for (const auto& [damping, consistent] : {std::pair{155.6, true}, std::pair{55.6, false}}) {
    std::ostringstream seabed;
    seabed << " seabed=-5 seabed_stiffness=2.5e4 seabed_damping=" << damping;
    mjModel* soft = Load(xml("bdf2", 0.002, seabed.str()), "soft.xml");
    ASSERT_NE(soft, nullptr);
    const CouplingLimit s = GetCouplingLimit(soft, 0, 1);
    EXPECT_NEAR(s.seabed_omega_h, 0.002 * std::sqrt(2.5e4 * 18 / 8), 1e-9);
    EXPECT_NEAR(s.seabed_damping_h, 0.002 * damping * 18 / 8, 1e-9);
    EXPECT_EQ(s.consistent, consistent) << damping;
  }
  // rk4 keeps the held force: warned at load, stopped where the node lands (CheckSeabedEnd),
  // with the advice; the step it advises runs through the landing.
  mjModel* rk4 = Load(xml("rk4", 0.002, " seabed=-5"), "seabed_rk4.xml");
  ASSERT_NE(rk4, nullptr);
  EXPECT_FALSE(GetCouplingLimit(rk4, 0, 1).consistent);
  // (Among the thrust's and the undeclared vehicle's.)
  int seabed_warnings = 0;
  for (const std::string& w : Warnings(rk4)) {
    seabed_warnings += Contains(w, "the run stops if the node touches the seabed");
  }
  EXPECT_EQ(seabed_warnings, 1);
  for (mjModel* quiet : {m, open}) {
    for (const std::string& w : Warnings(quiet)) {
      EXPECT_FALSE(Contains(w, "touches the seabed")) << w;
    }
  }
  std::string stop;
  RunScene(rk4, 0.6, &stop, 0.002);
  EXPECT_TRUE(Contains(stop, "seabed_rk4.xml: tether 't' stopped at t = 0.1")) << stop;
  EXPECT_TRUE(Contains(stop, "its end node B touched the seabed, and body 'rov'")) << stop;
  EXPECT_TRUE(Contains(stop, "omega h = 0.948683 and h c/m_eff = 1.27279")) << stop;
  EXPECT_TRUE(Contains(stop, "Use integrator=bdf2 (the default) or implicit")) << stop;
  const double advised = AdvisedStep(stop);
  EXPECT_GT(advised, 0);
  mjModel* cured = Load(xml("rk4", advised, " seabed=-5"), "seabed_rk4_cured.xml");
  ASSERT_NE(cured, nullptr);
  std::string cured_stop;
  RunScene(cured, 0.6, &cured_stop, 0.002);
  EXPECT_EQ(cured_stop, "");
  // The landing: from the first contact on, the body never rises 2 cm (4x the rebound above)
  // over the seabed, and its end tension over 0.2-0.6 s (the landing and the slide until the
  // tether takes the load) averages within 5% of the 0.2 ms run's.
  std::string stopped;
  const std::vector<Sample> run = RunScene(m, 0.6, &stopped, 0.002);
  ASSERT_EQ(stopped, "");
  mjModel* fine = Load(xml("bdf2", 0.0002, " seabed=-5"), "seabed_fine.xml");
  ASSERT_NE(fine, nullptr);
  const std::vector<Sample> ref = RunScene(fine, 0.6, &stopped, 0.002);
  ASSERT_EQ(stopped, "");
  ASSERT_EQ(run.size(), ref.size());
  bool landed = false;
  double rise = -INFINITY, mean = 0, mean_ref = 0;  // [m], [N], [N]
  int n = 0;
  for (size_t i = 0; i < run.size(); ++i) {
    landed = landed || run[i].pos.z() < -5;
    if (landed) rise = std::max(rise, run[i].pos.z() + 5);
    if (run[i].t < 0.2 - 1e-9) continue;
    mean += run[i].tension, mean_ref += ref[i].tension, ++n;
  }
  ASSERT_TRUE(landed);
  EXPECT_LT(rise, 0.02);
  mean /= n, mean_ref /= n;
  EXPECT_NEAR(mean, mean_ref, 0.05 * mean_ref);
}

// The chatter warning above half the limit, and the refusal at it, advise a step that leaves
// every coupling warning behind: kCouplingAccurate / omega. Until session 28 they advised
// limit / omega, the largest step that loads, which for the warning was above the step that
// warned (rk4 seed 913 at omega h 0.71 was told "<= 0.00226 s" at 0.002 s and grew from 11 N to
// 47 kN in 3 s). The BlueROV2 at EA 1e6 with explicit (omega h 1.06 of 2, the consistent
// coupling) and at EA 1.5e5 with rk4 (0.41 of 0.5, the held force; 0.58 at EA 3e5 until session
// 29 lowered rk4's limit from 0.8): each warns with the measured rate, and at the advised step
// loads silent.
TEST_F(Coupling, TheChatterWarningAdvisesAStepThatLeavesTheWarnedBand) {
  for (const auto& [EA, integrator] : {std::pair<std::string, std::string>{"1e6", "explicit"},
                                       {"1.5e5", "rk4"}}) {
    SCOPED_TRACE(integrator);
    mjModel* m = Load(BlueRovXml(EA, integrator, 0.002), integrator + ".xml");
    ASSERT_NE(m, nullptr);
    const CouplingLimit c = GetCouplingLimit(m, 0, 1);
    ASSERT_GE(c.omega_h, 0.5 * c.limit);
    ASSERT_LT(c.omega_h, c.limit);
    ASSERT_EQ(Warnings(m).size(), 1u);
    const std::string w = Warnings(m)[0];
    EXPECT_TRUE(Contains(w, "may chatter; the scene fuzzer finds ")) << w;
    const double advised = AdvisedStep(w);
    EXPECT_LE(advised, kCouplingAccurate / c.omega) << w;  // rounded down (StepAtMost)
    EXPECT_GE(advised, 0.99 * kCouplingAccurate / c.omega) << w;
    EXPECT_LT(advised, 0.002) << w;
    mjModel* followed = Load(BlueRovXml(EA, integrator, advised), integrator + "_followed.xml");
    ASSERT_NE(followed, nullptr);
    EXPECT_LT(GetCouplingLimit(followed, 0, 1).omega_h, kCouplingAccurate);
    EXPECT_TRUE(Warnings(followed).empty()) << Warnings(followed)[0];
  }
  // The refusal advises the same step (it advised the limit's, which loads into the warned
  // band) and still names the limit: rk4 at EA 1e6, omega h 1.06 of 0.5.
  std::string error;
  mjModel* refused = LoadModelFromString(BlueRovXml("1e6", "rk4", 0.002), "refused.xml", &error);
  EXPECT_EQ(refused, nullptr);
  if (refused) models_.push_back(refused);
  EXPECT_TRUE(Contains(error, "limit 0.5")) << error;
  EXPECT_TRUE(Contains(error, "; the limit is at ")) << error;
  const double advised = AdvisedStep(error);
  ASSERT_GT(advised, 0) << error;
  mjModel* followed = Load(BlueRovXml("1e6", "rk4", advised), "refused_followed.xml");
  ASSERT_NE(followed, nullptr);
  EXPECT_TRUE(Warnings(followed).empty()) << Warnings(followed)[0];
}

// rk4 is refused from coupling omega h 0.5 (0.8 until session 29): the scene fuzzer's rk4 runs
// at 0.5-0.8 were off their 10x smaller step in 7 of 85 (8.2% on the tuned seeds and on the
// held-out ones alike; seed 913 grew from 11 N to 47 kN in 3 s with exit 0), against 6 of 138
// at 0.25-0.5. The BlueROV2 at EA 3e5 (omega h 0.58) is refused, naming the limit and the cures;
// at EA 1.5e5 (0.41) it loads, warned.
TEST_F(Coupling, Rk4IsRefusedWhereTheFuzzerFindsItsWorstBand) {
  std::string error;
  mjModel* refused = LoadModelFromString(BlueRovXml("3e5", "rk4", 0.002), "rk4.xml", &error);
  EXPECT_EQ(refused, nullptr);
  if (refused) models_.push_back(refused);
  EXPECT_TRUE(Contains(error, "rk4.xml: <text name=\"tether:umbilical\">: integrator=rk4"))
      << error;
  EXPECT_TRUE(Contains(error, "limit 0.5 (the scene fuzzer found 7 in 85 rk4 runs at omega h "
                              "0.5-0.8 off their 10x smaller step")) << error;
  EXPECT_TRUE(Contains(error, "; use integrator=implicit or bdf2")) << error;
  mjModel* m = Load(BlueRovXml("1.5e5", "rk4", 0.002), "rk4_below.xml");
  ASSERT_NE(m, nullptr);
  const CouplingLimit c = GetCouplingLimit(m, 0, 1);
  EXPECT_NEAR(c.omega_h, 0.41, 0.01);
  EXPECT_EQ(c.limit, 0.5);
}

// Chatter at run time: a scene loaded at a step the advisor accepts (0.25 ms: omega h = 0.42,
// below kLeadFromExplicit, so the held force), then run at 2 ms (a user changing <option
// timestep> after loading), chatters; the work
// balance at the vehicle's end finds energy the tether did not give and stops the run with
// the tether, the body and the setting to change. Before this work it ran on with the tension
// swinging between 2 and 20 kN.
TEST_F(Coupling, ChatterIsStoppedWithTetherBodyAndSetting) {
  mjModel* m = Load(BlueRovXml("1e7", "explicit", 0.00025), "chatter.xml");
  ASSERT_NE(m, nullptr);
  m->opt.timestep = 0.002;
  std::string stopped;
  RunScene(m, 1.5, &stopped);
  std::printf("%s\n", stopped.c_str());
  EXPECT_TRUE(Contains(stopped,
                       "chatter.xml: tether 'umbilical': coupling chatter at end B on "
                       "body 'rov'"))
      << stopped;
  EXPECT_TRUE(Contains(stopped, "work balance does not explain it")) << stopped;
  EXPECT_TRUE(Contains(stopped, "Use integrator=bdf2 (the default) or implicit")) << stopped;
  // Of the cure, what holds at every omega h (session 43; it said "the end node is solved with
  // the body", which holds from omega h 1 only).
  EXPECT_TRUE(Contains(stopped, "(no coupling limit, stable at every omega h measured; the end "
                                "node is solved with the body from omega h 1)"))
      << stopped;
  // The step advised is below the one that chattered (it was 2.5x above it: limit/omega).
  const double advised = AdvisedStep(stopped);
  EXPECT_GT(advised, 0) << stopped;
  EXPECT_LE(advised, 0.5 * 0.002) << stopped;
}

// A chatter below the stability limit (scene fuzzer seed 924: a 2.26 kg vehicle on a 9-segment
// explicit tether, omega h = 0.81 against the limit 2) with the held force: the run stops with
// the true figures, and the step it advises is below the one that chattered (until session 9
// it advised limit/omega = 5 ms, 2.5 times the 2 ms that chattered). bdf2, the setting it
// names first, runs the same scene to the end. Since session 10 (s10exp) explicit loaded at
// 2 ms takes the consistent coupling there (omega h >= kLeadFromExplicit) and runs it to the
// end too; the held force is had by loading at 1 ms (omega h 0.40) and stepping at 2 ms.
std::string Seed924Xml(const char* integrator) {
  std::string xml =
      "<mujoco><option timestep=\"0.002\"/><custom>"
      "<text name=\"water\" data=\"density=1025\"/>"
      "<text name=\"vehicle:rov\" data=\"volume=0.002217139692 cob=0,0,0.01312114918 "
      "added_mass=1.481038828,2.032150941,0.9647036476,0.00194459592,0.00194459592,"
      "0.00194459592 "
      "linear_damping=1.96010725,1.96010725,1.96010725,0.006481986402,0.006481986402,"
      "0.006481986402 "
      "quadratic_damping=8.823433485,8.823433485,8.823433485,"
      "0.006481986402,0.006481986402,0.006481986402"
      " coriolis=0\"/>"
      "<text name=\"tether:t\" data=\"ends=tms_site,att length=7.97453262 segments=9 "
      "diameter=0.01606724379 mass_per_length=0.1762521353 EA=463988.9284 Cdn=1.2 "
      "Cdt=0.01 Can=1 integrator=explicit EI=0.04735500942 EAc=463988.9284 "
      "damping=1.147381773\"/>"
      "</custom><worldbody>"
      "<body name=\"tms\" mocap=\"true\"><site name=\"tms_site\"/></body>"
      "<body name=\"rov\" pos=\"2.543447906 4.088357426 "
      "-2.612497169\"><freejoint/><inertial pos=\"0 0 0\" mass=\"2.25899682\" "
      "diaginertia=\"0.006481986402 0.006481986402 0.006481986402\"/><site "
      "name=\"att\"/><site name=\"thr\"/></body>"
      "</worldbody></mujoco>";
  const std::string from = "integrator=explicit";
  xml.replace(xml.find(from), from.size(), std::string("integrator=") + integrator);
  return xml;
}

TEST_F(Coupling, ChatterBelowTheLimitAdvisesASmallerStepAndBdf2) {
  std::string xml = Seed924Xml("explicit");
  xml = Replace(xml, "timestep=\"0.002\"", "timestep=\"0.001\"");
  mjModel* m = Load(xml, "seed924.xml");
  ASSERT_NE(m, nullptr);
  m->opt.timestep = 0.002;
  std::string stopped;
  RunScene(m, 4, &stopped);
  std::printf("%s\n", stopped.c_str());
  EXPECT_TRUE(Contains(stopped, "seed924.xml: tether 't': coupling chatter at end B on body "
                                "'rov'")) << stopped;
  EXPECT_TRUE(Contains(stopped, "below the integrator's stability limit omega h = 2")) << stopped;
  EXPECT_TRUE(Contains(stopped, "Use integrator=bdf2 (the default) or implicit")) << stopped;
  const double advised = AdvisedStep(stopped);
  EXPECT_GT(advised, 0) << stopped;
  EXPECT_LE(advised, 0.5 * 0.002) << stopped;

  mjModel* b = Load(Seed924Xml("bdf2"), "seed924_bdf2.xml");
  ASSERT_NE(b, nullptr);
  std::string stopped_bdf2;
  const std::vector<Sample> ref = RunScene(b, 4, &stopped_bdf2);
  EXPECT_EQ(stopped_bdf2, "");

  // explicit loaded at 2 ms: the consistent coupling, to the end, with the vehicle-end tension
  // of bdf2's run over the last second within the fuzzer's tolerance max(0.5 N, 5%) (measured
  // 1.24 N against bdf2's; the held force chattered at 6 N).
  mjModel* e = Load(Seed924Xml("explicit"), "seed924_lead.xml");
  ASSERT_NE(e, nullptr);
  std::string stopped_lead;
  const std::vector<Sample> got = RunScene(e, 4, &stopped_lead);
  EXPECT_EQ(stopped_lead, "");
  ASSERT_EQ(got.size(), ref.size());
  double worst = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    if (got[i].t >= 3) worst = std::max(worst, std::abs(got[i].tension - ref[i].tension));
  }
  std::printf("seed 924 explicit at 2 ms, consistent coupling: tension within %.3f N of bdf2's\n",
              worst);
  EXPECT_LT(worst, 0.5);
}

// The yanked-vehicle scene of the tests below: dry, no gravity, an 11.5 kg body on a 10 m
// tether of 1 m segments (EA 1e7 N, no damping) from a mocap anchor, `integrator` at step h.
std::string YankXml(const std::string& integrator, double h) {
  return R"(<mujoco><option timestep=")" + std::to_string(h) + R"(" gravity="0 0 0"/>
  <custom><text name="tether:t" data="ends=anchor,hook length=10 segments=10 diameter=0.01
        mass_per_length=0.05 EA=1e7 integrator=)" +
         integrator + R"("/></custom>
  <worldbody><body name="a" mocap="true"><site name="anchor"/></body>
    <body name="v" pos="10.2 0 0"><freejoint/>
      <inertial pos="0 0 0" mass="11.5" diaginertia="0.16 0.16 0.16"/>
      <site name="hook" pos="-0.2 0 0"/></body></worldbody></mujoco>)";
}

// A step as MJCF text, to all 17 digits (the fuzzer's scenes are written so).
std::string ExactText(double value) {
  std::ostringstream text;
  text.precision(17);
  text << value;
  return text.str();
}

// Scene fuzzer seed 3244 (session 19): a 326 kg vehicle drifting with a 2.1 m/s current on 4
// explicit segments of EA 2.7e8 N, its TMS swaying 6 cm. At a 1 ms step (coupling omega h
// 0.2498, the held end force, below the advisor's half limit 1) its vehicle-end tension rang
// from 16 N to 18 kN within 1 s, and the run ended with exit 0: the chatter check did not see
// it (its energy scale was the site's kinetic energy, 680 J for the drifting vehicle, against
// 39 J the coupling made; since session 39 it balances in the site's moving frame and stops
// this run at 0.495 s, see Seed6876Xml below). Attach now warns from omega h kCouplingAccurate = 0.1, with the
// figures and two cures; both are checked here against the 0.1 ms run: bdf2 at the same 1 ms,
// and explicit at the step the warning advises. Tolerance: the fuzzer's, max(0.5 N, 5%) on
// the mean tension over the last 0.2 s of 1 s (measured: 15.84 N at 0.1 ms; bdf2 at 1 ms
// 15.7 N, explicit at 0.4 ms 15.8 N; explicit at 1 ms 11,000 N).
std::string Seed3244Xml(const std::string& integrator, double timestep) {
  return "<mujoco><option timestep=\"" + ExactText(timestep) +
         "\"/><custom>"
         "<text name=\"water\" data=\"density=1025 current=-1.718026506,-1.261338446,0\"/>"
         "<text name=\"vehicle:rov\" data=\"volume=0.3219588817 cob=0,0,0.06881964656 "
         "added_mass=149.5110764,108.3661018,238.2818374,7.718487297,7.718487297,7.718487297 "
         "linear_damping=613.5090605,613.5090605,613.5090605,25.72829099,25.72829099,"
         "25.72829099 quadratic_damping=242.7273673,242.7273673,242.7273673,25.72829099,"
         "25.72829099,25.72829099 coriolis=0\"/>"
         "<text name=\"tether:t\" data=\"ends=tms_site,att length=39.14797 segments=4 "
         "diameter=0.007831548963 mass_per_length=0.1236929884 EA=265295530.8 Cdn=1.2 "
         "Cdt=0.01 Can=1 integrator=" +
         integrator +
         " EI=587.8988412 EAc=265295530.8\"/>"
         "<text name=\"motion:tms\" data=\"y=0.06014836977,7.365251882,0\"/>"
         "</custom><worldbody>"
         "<body name=\"tms\" mocap=\"true\"><site name=\"tms_site\"/></body>"
         "<body name=\"rov\" pos=\"0.07764216082 -6.982194247 -11.41909726\"><freejoint/>"
         "<inertial pos=\"0 0 0\" mass=\"325.9397391\" diaginertia=\"25.72829099 "
         "25.72829099 25.72829099\"/><site name=\"att\"/><site name=\"thr\"/></body>"
         "</worldbody></mujoco>";
}

// The vehicle-end tension averaged over the last `window` s of `duration` s [N], from
// RunScene's samples at every step; "" in *stopped unless the run stopped.
double MeanEndTension(mjModel* m, double duration, double window, std::string* stopped) {
  const std::vector<Sample> samples = RunScene(m, duration, stopped, m->opt.timestep);
  const size_t w = std::min(samples.size(), size_t(std::llround(window / m->opt.timestep)));
  double sum = 0;
  for (size_t i = samples.size() - w; i < samples.size(); ++i) sum += samples[i].tension;
  return sum / double(w);
}

bool WarnsHeldForce(const mjModel* m) {
  for (const std::string& w : Warnings(m)) {
    if (Contains(w, "held end force at coupling omega h")) return true;
  }
  return false;
}

// The load warning names the step that brings the coupling to omega h kCouplingAccurate, rounded
// down to three significant digits (so at most 1% below it, and never above).
void ExpectNamesTheAdvisedStep(const std::string& warning, const CouplingLimit& c) {
  const double advised = AdvisedStep(warning), bound = kCouplingAccurate / c.omega;
  EXPECT_LE(advised, bound) << warning;
  EXPECT_GE(advised, 0.99 * bound) << warning;
}

// Each run's mean vehicle-end tension over the last 0.2 s of 1 s agrees with the fine run's
// within the scene fuzzer's tolerance, max(0.5 N, 5%), and no run stops.
void ExpectEachAgreesWithTheFineRun(mjModel* fine, std::initializer_list<mjModel*> runs) {
  std::string stopped;
  const double ref = MeanEndTension(fine, 1.0, 0.2, &stopped);
  ASSERT_EQ(stopped, "");
  const double tol = std::max(0.5, 0.05 * ref);
  for (mjModel* m : runs) {
    EXPECT_NEAR(MeanEndTension(m, 1.0, 0.2, &stopped), ref, tol);
    EXPECT_EQ(stopped, "");
  }
}

TEST_F(Coupling, HeldForceWhereItIsOftenOffIsWarnedAndBothCuresHold) {
  mjModel* coarse = Load(Seed3244Xml("explicit", 0.001), "seed3244.xml");
  ASSERT_NE(coarse, nullptr);
  const std::vector<std::string> warnings = Warnings(coarse);
  std::string held;
  for (const std::string& w : warnings) {
    if (Contains(w, "held end force at coupling omega h")) held = w;
  }
  std::printf("%s\n", held.c_str());
  EXPECT_TRUE(Contains(held, "seed3244.xml: <text name=\"tether:t\">: integrator=explicit with "
                             "end B on body 'rov': held end force at coupling omega h = 0.2498"))
      << held;
  EXPECT_TRUE(Contains(held, "use integrator=bdf2 (the default) or implicit")) << held;
  // The advised step: 0.1 / omega (omega = 249.8 rad/s, GetCouplingLimit's).
  const CouplingLimit c = GetCouplingLimit(coarse, 0, 1);
  EXPECT_FALSE(c.consistent);
  const double advised = kCouplingAccurate / c.omega;
  ExpectNamesTheAdvisedStep(held, c);

  mjModel* fine = Load(Seed3244Xml("explicit", 1e-4), "seed3244_fine.xml");
  mjModel* bdf2 = Load(Seed3244Xml("bdf2", 0.001), "seed3244_bdf2.xml");
  // Rounded down to a whole number of 0.1 ms (so that 1 s is whole steps).
  const double small = std::floor(advised / 1e-4) * 1e-4;
  mjModel* cured = Load(Seed3244Xml("explicit", small), "seed3244_small.xml");
  ASSERT_TRUE(fine && bdf2 && cured);
  EXPECT_FALSE(WarnsHeldForce(fine));
  EXPECT_FALSE(WarnsHeldForce(bdf2));
  EXPECT_FALSE(WarnsHeldForce(cured));
  // What the warning says of its cure is what the cure does (session 43; until then it said
  // "the end node is solved with the body"): bdf2 has no coupling limit, and at omega h 0.25
  // holds the end force as explicit does.
  EXPECT_TRUE(Contains(held, "no coupling limit, so no chatter to grow; below omega h 1 they "
                             "hold the end force too"))
      << held;
  const CouplingLimit b = GetCouplingLimit(bdf2, 0, 1);
  EXPECT_EQ(b.limit, 0);
  EXPECT_FALSE(b.consistent);
  EXPECT_LT(b.omega_h, 1);
  ExpectEachAgreesWithTheFineRun(fine, {bdf2, cured});
}

// Scene fuzzer seed 6876 (session 39): a 2454 kg vehicle (3673 kg with its added mass) that sinks
// at up to 0.15 m/s on 11 explicit segments of EA 4.9e8 N, the held end force at coupling
// omega h 0.45 (below kLeadFromExplicit, warned at load). At 2 ms the vehicle-end tension
// grows from 51 N to 62 kN in 2 s; at 0.2 ms it holds 51 N. The chatter check did not see it:
// in the world frame the balance was a random walk of +-0.1 J, the drift velocity times the
// held force's lag on the force, against a scale of the body's kinetic energy (15-55 J).
// Balanced each step in the frame moving with the site it rises steadily from 0.7 s
// (docs/coupling.md, session 39). Checked: the run stops with the chatter named before 1 s
// (the tension then 5-10x the true one, not 1000x), and both cures it names (bdf2; the step
// it advises, 0.1/omega) agree with the 0.2 ms run within the fuzzer's tolerance, max(0.5 N,
// 5%) on the mean vehicle-end tension over the last 0.2 s of 1 s, without a stop.
std::string Seed6876Xml(const std::string& integrator, double timestep) {
  return "<mujoco><option timestep=\"" + ExactText(timestep) +
         "\"/><custom>"
         "<text name=\"water\" data=\"density=1025 seabed=-2.018445569\"/>"
         "<text name=\"vehicle:rov\" data=\"volume=2.343044309 cob=0,0,0.1348773379 "
         "added_mass=2289.253778,1484.122745,1219.302418,223.1849639,223.1849639,223.1849639 "
         "linear_damping=2916.332556,2916.332556,2916.332556,743.9498796,743.9498796,"
         "743.9498796 quadratic_damping=932.3346844,932.3346844,932.3346844,743.9498796,"
         "743.9498796,743.9498796 coriolis=0\"/>"
         "<text name=\"tether:t\" data=\"ends=tms_site,att length=28.63337074 segments=11 "
         "diameter=0.03756324844 mass_per_length=1.740891158 EA=487678368.5 Cdn=1.2 Cdt=0.01 "
         "Can=1 integrator=" +
         integrator +
         " EI=8.33145158 EAc=487678368.5\"/>"
         "</custom><worldbody>"
         "<body name=\"tms\" mocap=\"true\"><site name=\"tms_site\"/></body>"
         "<body name=\"rov\" pos=\"-1.906563665 17.56214604 6.138193959\"><freejoint/>"
         "<inertial pos=\"0 0 0\" mass=\"2453.674542\" diaginertia=\"743.9498796 743.9498796 "
         "743.9498796\"/><site name=\"att\"/><site name=\"thr\"/></body>"
         "</worldbody></mujoco>";
}

TEST_F(Coupling, AChatterUnderADriftingVehicleIsStoppedAndBothCuresAgree) {
  mjModel* coarse = Load(Seed6876Xml("explicit", 0.002), "seed6876.xml");
  ASSERT_NE(coarse, nullptr);
  EXPECT_TRUE(WarnsHeldForce(coarse));
  std::string stopped;
  RunScene(coarse, 2, &stopped);
  std::printf("%s\n", stopped.c_str());
  EXPECT_TRUE(Contains(stopped, "seed6876.xml: tether 't': coupling chatter at end B on body "
                                "'rov' at t = 0."))
      << stopped;
  EXPECT_TRUE(Contains(stopped, "Use integrator=bdf2 (the default) or implicit")) << stopped;
  const double advised = AdvisedStep(stopped);
  const CouplingLimit c = GetCouplingLimit(coarse, 0, 1);
  EXPECT_LE(advised, kCouplingAccurate / c.omega) << stopped;
  EXPECT_GE(advised, 0.99 * kCouplingAccurate / c.omega) << stopped;

  mjModel* fine = Load(Seed6876Xml("explicit", 2e-4), "seed6876_fine.xml");
  mjModel* bdf2 = Load(Seed6876Xml("bdf2", 0.002), "seed6876_bdf2.xml");
  // Rounded down to a whole number of 0.1 ms (so that 1 s is whole steps).
  mjModel* cured =
      Load(Seed6876Xml("explicit", std::floor(advised / 1e-4) * 1e-4), "seed6876_small.xml");
  ASSERT_TRUE(fine && bdf2 && cured);
  ExpectEachAgreesWithTheFineRun(fine, {bdf2, cured});
}

// The other side of the balance in the moving frame (session 39): per step it gains the
// staggered step's own -(h/2) F . dv, which a thrust that takes a body to speed against its
// tether makes large, and whose sum is bounded by the boundary term (h/2) F . (v - v_start).
// Scene fuzzer seed 603 at 0.2 ms (rk4, 116 segments of EA 3.1e7 N, a 1678 kg vehicle thrust
// with up to 20 MN, which it takes to 116 m/s; its 2 ms run agrees with this one): with the
// moving frame's balance alone the run stopped with a "coupling chatter" at 0.215 s (372 J
// against a scale of 93 J), like 19 other scenes of the long runs, 14 of them with thrust.
// Counted with the boundary term the balance is negative: the run goes on.
TEST_F(Coupling, AThrustThatTakesTheVehicleToSpeedIsNoChatter) {
  const std::string xml =
      "<mujoco><option timestep=\"0.0002\"/><custom>"
      "<text name=\"water\" data=\"density=1025 current=-0.4550727018,-1.63638969,0\"/>"
      "<text name=\"vehicle:rov\" data=\"volume=1.645889237 cob=0,0,0.1188310463 "
      "added_mass=1311.598164,1657.161035,1070.960062,118.4730611,118.4730611,118.4730611 "
      "linear_damping=1671.407306,1671.407306,1671.407306,394.9102038,394.9102038,"
      "394.9102038 quadratic_damping=723.6919004,723.6919004,723.6919004,394.9102038,"
      "394.9102038,394.9102038 coriolis=0\"/>"
      "<text name=\"tether:t\" data=\"ends=tms_site,att length=27.13212704 segments=116 "
      "diameter=0.02838729984 mass_per_length=0.4774917724 EA=30519869.64 Cdn=1.2 Cdt=0.01 "
      "Can=1 integrator=rk4 EI=1.225819423 EAc=30519869.64 damping=4.822939332\"/>"
      "<text name=\"motion:tms\" data=\"z=0.2413045963,2.068296484,0\"/>"
      "<text name=\"thrust:thr\" data=\"t=0.1,0.4 ctrl=0,19957943.08\"/>"
      "</custom><worldbody>"
      "<body name=\"tms\" mocap=\"true\"><site name=\"tms_site\"/></body>"
      "<body name=\"rov\" pos=\"-0.6592901312 3.373374415 -10.22073692\"><freejoint/>"
      "<inertial pos=\"0 0 0\" mass=\"1677.991526\" diaginertia=\"394.9102038 394.9102038 "
      "394.9102038\"/><site name=\"att\"/><site name=\"thr\"/></body>"
      "</worldbody><actuator><motor name=\"thr\" site=\"thr\" gear=\"0.3402982144 "
      "0.4329855753 -0.8346979195 0 0 0\"/></actuator></mujoco>";
  mjModel* m = Load(xml, "seed603.xml");
  ASSERT_NE(m, nullptr);
  std::string stopped;
  const std::vector<Sample> run = RunScene(m, 0.4, &stopped);
  EXPECT_EQ(stopped, "");
  ASSERT_FALSE(run.empty());
  // The thrust did take it to speed: from rest to beyond 50 m/s in 0.4 s.
  const double speed = (run.back().pos - run[run.size() - 2].pos).norm() / 0.05;
  std::printf("seed 603 at 0.2 ms: %.1f m/s at 0.4 s, %s\n", speed,
              stopped.empty() ? "not stopped" : stopped.c_str());
  EXPECT_GT(speed, 50);
}

// implicit2's held end force (session 39, Tether::AddEndImpulse): scene fuzzer seed 1423, a
// 3942 kg vehicle (7259 kg with its added mass) sinking from rest at about 0.1 m/s^2 on 5
// segments of EA 4.3e8 N, the held force at coupling omega h 0.42. The force at the end of
// implicit2's step read the vehicle-end tension 15.19 N at 2 ms, 15.89 at 1 ms, 16.33 at 0.5 ms,
// 16.54 at 0.2 ms and 16.58 at 0.1 ms, where implicit and bdf2 read 16.590 N at every one of
// these steps: the node next to the vehicle takes a stage inertia of several times its m a.
// The mean of the stages as the scheme weighs them reads 16.590 N at 2 ms. Checked: the mean
// vehicle-end tension over 0.8-1 s at 2 ms within 0.5% of the 0.1 ms run's (measured 0.001%; at
// t = 1 s the force at the step's end was 8.4% off), and the same for end A on the fixed TMS
// (0.001%; 0.95% off before).
std::string Seed1423Xml(double timestep) {
  return "<mujoco><option timestep=\"" + ExactText(timestep) +
         "\"/><custom>"
         "<text name=\"water\" data=\"density=1025 seabed=-20.31519626\"/>"
         "<text name=\"vehicle:rov\" data=\"volume=3.767344269 cob=0,0,0.1579728422 "
         "added_mass=2432.089261,3695.271069,3317.095652,491.9060491,491.9060491,491.9060491 "
         "linear_damping=1972.909777,1972.909777,1972.909777,1639.68683,1639.68683,1639.68683 "
         "quadratic_damping=1278.965216,1278.965216,1278.965216,1639.68683,1639.68683,"
         "1639.68683 coriolis=0\"/>"
         "<text name=\"tether:t\" data=\"ends=tms_site,att length=7.653722193 segments=5 "
         "diameter=0.02396007514 mass_per_length=0.8523615458 EA=433479613.6 Cdn=1.2 "
         "Cdt=0.01 Can=1 integrator=implicit2 EI=0.2499895405 EAc=433479613.6\"/>"
         "</custom><worldbody>"
         "<body name=\"tms\" mocap=\"true\"><site name=\"tms_site\"/></body>"
         "<body name=\"rov\" pos=\"-0.4352910749 4.630677657 0.8505749207\"><freejoint/>"
         "<inertial pos=\"0 0 0\" mass=\"3942.278444\" diaginertia=\"1639.68683 1639.68683 "
         "1639.68683\"/><site name=\"att\"/><site name=\"thr\"/></body>"
         "</worldbody></mujoco>";
}

// Mean end tensions (A, B) over the last `window` s of `duration` s, sampled every step.
std::pair<double, double> MeanTensions(mjModel* m, double duration, double window) {
  mjData* d = mj_makeData(m);
  const long long steps = std::llround(duration / m->opt.timestep);
  const long long from = steps - std::llround(window / m->opt.timestep);
  double a = 0, b = 0;
  for (long long i = 1; i <= steps; ++i) {
    Step(m, d);
    if (i <= from) continue;
    const EndReactions r = GetReactions(m, d, 0);
    a += r.tension_a;
    b += r.tension_b;
  }
  mj_deleteData(d);
  return {a / double(steps - from), b / double(steps - from)};
}

TEST_F(Coupling, Implicit2sHeldForceIsTheForceItsNodesTook) {
  mjModel* coarse = Load(Seed1423Xml(0.002), "seed1423.xml");
  mjModel* fine = Load(Seed1423Xml(1e-4), "seed1423_fine.xml");
  ASSERT_TRUE(coarse && fine);
  EXPECT_FALSE(GetCouplingLimit(coarse, 0, 1).consistent);  // the held force
  const auto [a2, b2] = MeanTensions(coarse, 1, 0.2);
  const auto [a0, b0] = MeanTensions(fine, 1, 0.2);
  std::printf("seed 1423, implicit2: end B %.4f N at 2 ms, %.4f N at 0.1 ms; end A %.4f, %.4f N\n",
              b2, b0, a2, a0);
  EXPECT_NEAR(b2, b0, 0.005 * b0);
  EXPECT_NEAR(a2, a0, 0.005 * a0);
}

// Scene fuzzer held-out seed 14999 (session 27): a 14 kg vehicle on 6 explicit segments of EA
// 7.6e6 N (Can 1) under a heaving TMS. At 2 ms explicit takes the consistent coupling (coupling
// omega h 0.92, from kLeadFromExplicit 0.5) in 7 substeps. With end node B on its own path over
// the substeps (x + sum h v_k) and moved onto the site (x + h v+) at each call, the
// vehicle-end tension grew from 10 N to 40 kN in 3 s with exit 0: over 0.8-1 s 294.6 N against
// 10.89 N at 0.2 ms. With the node on MuJoCo's Euler path (Tether::Advance) it is 10.68 N.
// Checked here: the run as drawn agrees with its 0.2 ms self within the fuzzer's tolerance,
// max(0.5 N, 5%) on the mean vehicle-end tension over the last 0.2 s of 1 s, and within 5 cm
// in position; Attach still warns of explicit's consistent coupling below half its limit (the
// fuzzer's rate there), and both cures it names hold.
std::string Seed14999Xml(const std::string& integrator, double timestep) {
  return "<mujoco><option timestep=\"" + ExactText(timestep) +
         "\"/><custom>"
         "<text name=\"water\" data=\"density=1025 current=0.3140594723,-0.668995154,0 "
         "seabed=-22.48590293\"/>"
         "<text name=\"vehicle:rov\" data=\"volume=0.01400108374 cob=0,0,0.02412033477 "
         "added_mass=9.2301667,5.868854286,10.41251798,0.04082128393,0.04082128393,"
         "0.04082128393 linear_damping=7.990095345,7.990095345,7.990095345,0.1360709464,"
         "0.1360709464,0.1360709464 quadratic_damping=29.81676566,29.81676566,29.81676566,"
         "0.1360709464,0.1360709464,0.1360709464 coriolis=0\"/>"
         "<text name=\"tether:t\" data=\"ends=tms_site,att length=10.71957013 segments=6 "
         "diameter=0.03374159287 mass_per_length=1.215552849 EA=7571156.875 Cdn=1.2 Cdt=0.01 "
         "Can=1 integrator=" +
         integrator +
         " EI=5.549799111 EAc=7571156.875\"/>"
         "<text name=\"motion:tms\" data=\"z=0.8469851452,4.63047093,0\"/>"
         "</custom><worldbody>"
         "<body name=\"tms\" mocap=\"true\"><site name=\"tms_site\"/></body>"
         "<body name=\"rov\" pos=\"-2.741133279 -0.4076464186 -2.868848133\"><freejoint/>"
         "<inertial pos=\"0 0 0\" mass=\"14.03298282\" diaginertia=\"0.1360709464 "
         "0.1360709464 0.1360709464\"/><site name=\"att\"/></body>"
         "</worldbody></mujoco>";
}

std::string LeadWarning(const mjModel* m) {
  for (const std::string& w : Warnings(m)) {
    if (Contains(w, "consistent coupling at coupling omega h")) return w;
  }
  return "";
}

TEST_F(Coupling, ExplicitsConsistentCouplingAgreesAtSevenSubstepsAndIsWarnedBelowHalfItsLimit) {
  mjModel* coarse = Load(Seed14999Xml("explicit", 0.002), "seed14999.xml");
  ASSERT_NE(coarse, nullptr);
  const CouplingLimit c = GetCouplingLimit(coarse, 0, 1);
  EXPECT_TRUE(c.consistent);
  const std::string lead = LeadWarning(coarse);
  std::printf("%s\n", lead.c_str());
  EXPECT_TRUE(Contains(lead, "seed14999.xml: <text name=\"tether:t\">: integrator=explicit with "
                             "end B on body 'rov': consistent coupling at coupling omega h = "
                             "0.92"))
      << lead;
  EXPECT_TRUE(Contains(lead, "7 tether substep(s)")) << lead;
  EXPECT_TRUE(Contains(lead, "use integrator=bdf2 (the default) or implicit")) << lead;
  const double advised = kCouplingAccurate / c.omega;
  ExpectNamesTheAdvisedStep(lead, c);

  mjModel* fine = Load(Seed14999Xml("explicit", 2e-4), "seed14999_fine.xml");
  mjModel* bdf2 = Load(Seed14999Xml("bdf2", 0.002), "seed14999_bdf2.xml");
  // Rounded down to a whole number of 0.1 ms (so that 1 s is whole steps): 0.2 ms.
  const double small = std::floor(advised / 1e-4) * 1e-4;
  mjModel* cured = Load(Seed14999Xml("explicit", small), "seed14999_small.xml");
  ASSERT_TRUE(fine && bdf2 && cured);
  EXPECT_EQ(LeadWarning(fine), "");  // the held force there (omega h 0.09)
  EXPECT_EQ(LeadWarning(bdf2), "");
  // The cure as the warning describes it (session 43): bdf2 at omega h 0.92 has no limit and
  // holds the end force (kLeadFrom 1).
  EXPECT_TRUE(Contains(lead, "(no coupling limit; below omega h 1 they hold the end force"))
      << lead;
  EXPECT_FALSE(GetCouplingLimit(bdf2, 0, 1).consistent);
  EXPECT_EQ(GetCouplingLimit(bdf2, 0, 1).limit, 0);
  EXPECT_EQ(LeadWarning(cured), "");
  ExpectEachAgreesWithTheFineRun(fine, {coarse, bdf2, cured});
  // The vehicle at 3 s (the growth took it 0.25 m off): within 5 cm of the 0.2 ms run's.
  const int body = mj_name2id(coarse, mjOBJ_BODY, "rov");
  Eigen::Vector3d at[2];
  int k = 0;
  for (mjModel* m : {coarse, fine}) {
    mjData* d = mj_makeData(m);
    while (d->time < 3.0 - 0.5 * m->opt.timestep) mj_step(m, d);
    EXPECT_FALSE(CheckDivergence(m, d));
    at[k++] = Eigen::Vector3d(d->xpos + 3 * body);
    mj_deleteData(d);
  }
  EXPECT_LT((at[0] - at[1]).norm(), 0.05) << at[0].transpose() << " | " << at[1].transpose();
}

// A free vehicle yanked by a taut stiff tether gains no energy beyond the work done on it.
// Dry, no gravity: an 11.5 kg body (inertia 0.16 kg m^2, tether site 0.2 m off its centre)
// on a 10 m tether of 1 m segments, EA = 1e7 N, no damping, straight at its rest length; end A
// (a mocap body) is pulled 5 mm away along the tether in 50 ms (smoothstep), then held. The
// energy of body and tether (kinetic of both, elastic of the tether) may rise by the work
// end A did on the tether, sum of -(F_n + F_n+1)/2 . (x_n+1 - x_n), and not more: tolerance 1%
// of that work (the trapezoid's own error: 0.3% at 0.125 ms with every integrator). Each
// integrator at 2 ms, or, where the advisor refuses that, at the largest of 0.5 and 0.25 ms it
// accepts (explicit 0.5 ms, omega h 0.92; rk4 0.25 ms, 0.46: at 0.5 ms rk4 gained 8%).
// implicit2 at 2 ms has the consistent coupling (omega h 3.7, s10i2): 1.25e-3 J beyond 0.194 J
// (0.64%; the held force 1.1e-5 J); its end A force is the step's mean (the stages' impulse).
// explicit has it too from omega h 0.5 (s10exp), its end A force the mean over its substeps:
// 1.39e-3 J beyond 0.190 J (0.73%). With end A's force at the MuJoCo step's end instead, the
// trapezoid read 0.163 J of work where the converged run's end A did 0.189 J, a 9% "gain" that
// was bookkeeping (YankedVehicleOnExplicitGainsNothingOverItsFineStep below checks the energy
// itself against the converged run).
TEST_F(Coupling, YankedVehicleGainsNoEnergyBeyondTheWork) {
  for (const char* integrator : {"implicit", "implicit2", "bdf2", "rk4", "explicit"}) {
    for (double h : {0.002, 0.0005, 0.00025}) {
      const std::string xml = YankXml(integrator, h);
      std::string error;
      mjModel* m = LoadModelFromString(xml, "yank.xml", &error);
      if (!m) {
        EXPECT_TRUE(Contains(error, "omega h")) << error;
        continue;
      }
      models_.push_back(m);
      mjData* d = Make(m);
      const Tether* t = GetTether(m, 0);
      // The body's kinetic energy from its velocities (centre of mass at the origin, isotropic
      // inertia), at the state after the step: with the consistent coupling the tether is
      // then at the same time as the body (a mj_forward would step it ahead), with the held
      // force it lags one step until mj_forward brings it there.
      auto energy = [&]() {
        const double* x = NodePositions(m, d, 0);
        Ends ends;
        const Eigen::Vector3d vb(d->qvel), wb(d->qvel + 3);
        return 0.5 * 11.5 * vb.squaredNorm() + 0.5 * 0.16 * wb.squaredNorm() +
               t->KineticEnergy(x, NodeVelocities(m, d, 0)) + t->PotentialEnergy(x, ends);
      };
      auto catch_up = [&]() {
        if (TetherTime(m, d, 0) < d->time) mj_forward(m, d);
      };
      mj_step(m, d);  // the initial shape at t = 0 (the mocap end still at rest)
      catch_up();
      const double E0 = energy();
      double work = 0, worst = -INFINITY;
      Eigen::Vector3d xa(NodePositions(m, d, 0)), fa = GetReactions(m, d, 0).force_a;
      const int steps = static_cast<int>(std::lround(0.5 / h));
      for (int i = 1; i <= steps; ++i) {
        const double s = std::min(i * h / 0.05, 1.0);
        const Eigen::Vector3d xn(-0.005 * s * s * (3 - 2 * s), 0, 0);
        for (int k = 0; k < 3; ++k) d->mocap_pos[k] = xn[k];
        mj_step(m, d);
        catch_up();  // the tether's energy and reactions at the new state
        ASSERT_FALSE(CheckDivergence(m, d)) << *CheckDivergence(m, d);
        // End A's work along the path of the tether's end node A (the mocap body's position at
        // the tether's time; with the consistent coupling the tether moved it on to t + h).
        const Eigen::Vector3d fn = GetReactions(m, d, 0).force_a, xe(NodePositions(m, d, 0));
        work -= 0.5 * (fa + fn).dot(xe - xa);
        xa = xe;
        fa = fn;
        worst = std::max(worst, energy() - E0 - work);
      }
      std::printf("%s at %g s: work %.4f J, largest gain beyond it %.3g J\n", integrator, h, work,
                  worst);
      EXPECT_GT(work, 0.05);  // the yank did work (measured 0.17-0.21 J: the body follows)
      EXPECT_LT(worst, 0.01 * work) << integrator << " at " << h;
      break;  // the largest accepted step only
    }
  }
}

// The yanked vehicle of the test above (the same scene), with integrator=explicit and the
// consistent coupling (omega h 0.92 at 0.5 ms and 1.84 at 1 ms, both >= kLeadFromExplicit).
// The work end A does is that of the converged run, implicit at a tenth of the step (its own
// gain beyond its sampled work is 0.3%): once end A is held (from 50 ms) nothing does work,
// and the energy of body and tether (end node B at the body's site) may not exceed the
// converged run's at any step, tolerance 1% of the work. Measured: 0.180 J and 0.174 J at
// 0.5 s against the converged 0.190 J (the coupling's first-order step at the body dissipates).
// While end A moves the explicit run leads the converged one by up to 2.7% (0.5 ms) and 5.7%
// (1 ms) of the work: printed, not asserted (it ends below it).
// Energy of the 11.5 kg body (inertia 0.16 kg m^2, centre of mass at its origin) and of its
// tether [J], with end node B where the next step starts it, at the body's site `hook`: the
// consistent coupling of explicit steps end node B by the substeps and the body by MuJoCo's
// Euler step, about h^2 a/2 apart, and the next step puts the node on the site.
double EnergyWithEndAtSite(const mjModel* m, mjData* d, const Tether& t, int hook) {
  std::vector<double> xs(NodePositions(m, d, 0), NodePositions(m, d, 0) + 3 * t.nodes());
  mj_kinematics(m, d);
  for (int k = 0; k < 3; ++k) xs[3 * t.segments() + k] = d->site_xpos[3 * hook + k];
  const Eigen::Vector3d vb(d->qvel), wb(d->qvel + 3);
  return 0.5 * 11.5 * vb.squaredNorm() + 0.5 * 0.16 * wb.squaredNorm() +
         t.KineticEnergy(xs.data(), NodeVelocities(m, d, 0)) + t.PotentialEnergy(xs.data(), Ends());
}

struct YankEnergy {
  std::vector<double> gain;  // [J] energy minus the initial, at each coarse step
  double work = 0;           // [J] end A's work, trapezoid of the sampled force
};
YankEnergy RunYank(const char* integrator, double h, int stride) {
  YankEnergy out;
  const std::string xml = YankXml(integrator, h);
  std::string error;
  mjModel* m = LoadModelFromString(xml, "yank.xml", &error);
  EXPECT_NE(m, nullptr) << error;
  if (!m) return out;
  mjData* d = mj_makeData(m);
  const Tether* t = GetTether(m, 0);
  const int hook = mj_name2id(m, mjOBJ_SITE, "hook");
  auto energy = [&]() { return EnergyWithEndAtSite(m, d, *t, hook); };
  auto catch_up = [&]() {
    if (TetherTime(m, d, 0) < d->time) mj_forward(m, d);
  };
  mj_step(m, d);
  catch_up();
  const double E0 = energy();
  Eigen::Vector3d xa(NodePositions(m, d, 0)), fa = GetReactions(m, d, 0).force_a;
  const int steps = static_cast<int>(std::lround(0.5 / h));
  for (int i = 1; i <= steps; ++i) {
    const double s = std::min(i * h / 0.05, 1.0);
    d->mocap_pos[0] = -0.005 * s * s * (3 - 2 * s);
    mj_step(m, d);
    catch_up();
    EXPECT_FALSE(CheckDivergence(m, d));
    const Eigen::Vector3d fn = GetReactions(m, d, 0).force_a, xe(NodePositions(m, d, 0));
    out.work -= 0.5 * (fa + fn).dot(xe - xa);
    xa = xe;
    fa = fn;
    if (i % stride == 0) out.gain.push_back(energy() - E0);
  }
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
  return out;
}

TEST(CouplingExplicit, YankedVehicleOnExplicitGainsNothingOverItsFineStep) {
  for (double h : {0.0005, 0.001}) {
    const YankEnergy got = RunYank("explicit", h, 1);
    const YankEnergy ref = RunYank("implicit", h / 10, 10);
    ASSERT_EQ(got.gain.size(), ref.gain.size());
    // From 50 ms on end A is held: the work is done, and the energy may not exceed it.
    double held = -INFINITY, pulled = -INFINITY;
    for (size_t i = 0; i < got.gain.size(); ++i) {
      const double excess = got.gain[i] - ref.gain[i];
      ((i + 1) * h >= 0.05 ? held : pulled) = std::max((i + 1) * h >= 0.05 ? held : pulled,
                                                       excess);
    }
    std::printf("explicit at %g s: energy gain %.4f J at 0.5 s (converged run %.4f J, its work "
                "%.4f J); largest excess over the converged run while pulled %.3g J, held %.3g J\n",
                h, got.gain.back(), ref.gain.back(), ref.work, pulled, held);
    EXPECT_GT(ref.work, 0.05);
    EXPECT_LT(held, 0.01 * ref.work) << h;
  }
}

// The scene fuzzer's seed 530 (draw 2: implicit, an 8.2 kg vehicle with translational added
// masses 7.0, 3.0 and 5.3 kg on 114 segments of EA 5.1e8 over 0.27 m: the consistent coupling
// at omega h 26). The added mass's anisotropic remainder is a force on the body's own last
// acceleration (plugin/vehicles.cc); lagged in a_other it fed back through the end's stiffness
// and the vehicle-end force rang from 50 N to 30 kN in 0.17 s at 2 ms, where the 0.2 ms run
// stays at 60-70 N (session 16; the fuzzer's oracle, which compares the last 0.2 s of 1 s,
// passed it because the line went slack and settled). With the passive forces taken at the
// step's time (EvaluateLead, kKnownAccel) the 2 ms run's largest vehicle-end force from 0.05 s
// on stays within 1.5x the 0.2 ms run's, and their means over 0.2-0.4 s agree within 5%.
TEST(CouplingConsistent, AnisotropicAddedMassDoesNotRingTheStiffEnd) {
  const std::string xml = R"(<mujoco><option timestep="0.002"/><custom>
<text name="water" data="density=1025 current=0.8282669675,0.1216925143,0"/>
<text name="vehicle:rov" data="volume=0.007865055376 cob=0,0,0.02018940484 added_mass=6.952161324,3.000914923,5.308311008,0.01677210559,0.01677210559,0.01677210559 linear_damping=8.461556785,8.461556785,8.461556785,0.05590701865,0.05590701865,0.05590701865 quadratic_damping=20.89011848,20.89011848,20.89011848,0.05590701865,0.05590701865,0.05590701865 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=30.28929464 segments=114 diameter=0.04052961833 mass_per_length=2.808385811 EA=509917703.8 Cdn=1.2 Cdt=0.01 Can=1 integrator=implicit EI=0.6455838468 EAc=509917703.8"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="8.085534879 8.89762979 3.652132133"><freejoint/><inertial pos="0 0 0" mass="8.22944506" diaginertia="0.05590701865 0.05590701865 0.05590701865"/><site name="att"/><site name="thr"/></body>
</worldbody></mujoco>)";
  struct Trace {
    double peak = 0, mean = 0;
  };
  auto run = [&](double step) {
    std::string scene = xml;
    const std::string from = "timestep=\"0.002\"";
    scene.replace(scene.find(from), from.size(), "timestep=\"" + std::to_string(step) + "\"");
    std::string error;
    mjModel* m = LoadModelFromString(scene, "seed530.xml", &error);
    EXPECT_NE(m, nullptr) << error;
    Trace t;
    if (!m) return t;
    EXPECT_TRUE(GetCouplingLimit(m, 0, 1).consistent);
    mjData* d = mj_makeData(m);
    int samples = 0;
    while (d->time < 0.4 - 0.5 * step) {
      mj_step(m, d);
      EXPECT_FALSE(CheckDivergence(m, d));
      const double T = GetReactions(m, d, 0).tension_b;
      if (d->time > 0.05) t.peak = std::max(t.peak, T);
      if (d->time > 0.2 + 0.5 * step) t.mean += T, ++samples;
    }
    t.mean /= samples;
    mj_deleteData(d);
    Detach(m);
    mj_deleteModel(m);
    return t;
  };
  const Trace coarse = run(0.002), fine = run(0.0002);
  std::printf("seed 530: vehicle-end force from 0.05 s, peak %.1f N at 2 ms, %.1f N at 0.2 ms; "
              "mean over 0.2-0.4 s %.2f and %.2f N\n",
              coarse.peak, fine.peak, coarse.mean, fine.mean);
  EXPECT_LT(coarse.peak, 1.5 * fine.peak);
  EXPECT_NEAR(coarse.mean, fine.mean, 0.05 * fine.mean);
}

// A closed system: the same body, flying out at 0.1 m/s (and 0.05 m/s across) on the same
// taut tether from a fixed anchor, no damping, 0.5 s: nothing does work, so the energy may
// not rise. integrator=explicit at 1 ms (omega h 1.84): with the consistent coupling it never
// rises above its start (it falls: the coupling integrates the body's end with a first-order
// step); measured with the held force at the same step: +9%.
TEST(CouplingExplicit, FreeBodyOnTautTetherGainsNoEnergy) {
  const std::string xml = R"(<mujoco><option timestep="0.001" gravity="0 0 0"/>
  <custom><text name="tether:t" data="ends=anchor,hook length=10 segments=10 diameter=0.01
        mass_per_length=0.05 EA=1e7 integrator=explicit"/></custom>
  <worldbody><site name="anchor"/>
    <body name="v" pos="10.2 0 0"><freejoint/>
      <inertial pos="0 0 0" mass="11.5" diaginertia="0.16 0.16 0.16"/>
      <site name="hook" pos="-0.2 0 0"/></body></worldbody></mujoco>)";
  std::string error;
  mjModel* m = LoadModelFromString(xml, "closed.xml", &error);
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  d->qvel[0] = 0.1;
  d->qvel[1] = 0.05;
  const Tether* t = GetTether(m, 0);
  const int hook = mj_name2id(m, mjOBJ_SITE, "hook");
  auto energy = [&]() { return EnergyWithEndAtSite(m, d, *t, hook); };
  mj_step(m, d);
  const double E0 = energy();
  double top = E0;
  for (int i = 0; i < 500; ++i) {
    mj_step(m, d);
    ASSERT_FALSE(CheckDivergence(m, d));
    top = std::max(top, energy());
  }
  std::printf("closed: energy %.4f J at the start, at most %.4f J, %.4f J at 0.5 s\n", E0, top,
              energy());
  EXPECT_GT(E0, 0.05);  // the body's 0.072 J
  EXPECT_LT(top - E0, 1e-3 * E0);
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
}

// The seabed's stiffness is in the explicit and rk4 stable steps, and so in their automatic
// substeps: omega_seabed = sqrt(k L0 / m) on the lightest dynamic node (m = mu L0), and the
// undamped explicit stable step 0.5 * 2 / omega (symplectic Euler's safety factor) with
// omega^2 = 4 EA/(L0 m) + k L0/m (tether.cc).
TEST(Advisor, SeabedStiffnessIsInTheStableStepAndSubsteps) {
  TetherParams p;
  p.length = 10;
  p.segments = 10;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e3;
  p.integrator = Integrator::kExplicit;
  Environment env;
  env.wet = true;
  env.water.has_seabed = true;
  env.water.seabed_stiffness = 1e6;  // [N/m^2] stiffer than the axial chain here
  env.water.seabed_damping = 0;
  p.effects = kAxial | kSeabed;
  std::string error;
  std::optional<Tether> t = Tether::Create(p, env, &error);
  ASSERT_TRUE(t) << error;
  const double m = 1.0 * 1.0, L0 = 1.0;
  EXPECT_NEAR(t->stability_terms().w_seabed, std::sqrt(1e6 * L0 / m), 1e-9);
  EXPECT_NEAR(t->stability_terms().w_axial, std::sqrt(4 * 1e3 / (L0 * m)), 1e-9);
  const double w = std::sqrt(4 * 1e3 / (L0 * m) + 1e6 * L0 / m);
  EXPECT_NEAR(t->ExplicitStabilityLimit(), 2 / w, 1e-12);
  EXPECT_NEAR(t->ExplicitStableStep(), 0.5 * 2 / w, 1e-12);
  EXPECT_EQ(t->SubstepsFor(0.002), static_cast<int>(std::ceil(0.002 / (0.5 * 2 / w) - 1e-9)));
  p.effects = kAxial;
  std::optional<Tether> dry = Tether::Create(p, env, &error);
  EXPECT_GT(t->SubstepsFor(0.002), dry->SubstepsFor(0.002));
  p.effects = kAxial | kSeabed;
  p.integrator = Integrator::kRK4;
  std::optional<Tether> rk4 = Tether::Create(p, env, &error);
  EXPECT_NEAR(rk4->stability_terms().w_seabed, std::sqrt(1e6 * L0 / m), 1e-9);
  EXPECT_LT(rk4->ExplicitStableStep(), 0.8 * 2.9 / w);  // RK4: about 2.8/omega, factor 0.8
  EXPECT_GT(rk4->ExplicitStableStep(), 0.8 * 2.7 / w);
}

// Automatic substeps much slower than real time are reported at load with the cheaper setting:
// 200 segments of 5 cm with heavy axial damping, explicit, at 2 ms. The estimate is substeps/h
// times the nodes times 25 ns per node and step (explicit, measured in the accuracy/cost sweep).
TEST_F(Coupling, SlowAutomaticSubstepsAreReportedWithTheCheaperSetting) {
  mjModel* m = Load(R"(<mujoco><option timestep="0.002"/>
  <custom><text name="tether:slow" data="ends=a,b length=10 segments=200 diameter=0.01
        mass_per_length=0.1 EA=1e6 damping=2000 integrator=explicit"/></custom>
  <worldbody><site name="a"/><site name="b" pos="9.9 0 0"/></worldbody></mujoco>)",
                    "slow.xml");
  ASSERT_NE(m, nullptr);
  const Tether* t = GetTether(m, 0);
  const double cost = t->SubstepsFor(0.002) / 0.002 * t->nodes() * 25e-9;
  EXPECT_NEAR(EstimatedCostPerSecond(*t, 0.002), cost, 1e-12 * cost);
  ASSERT_GT(cost, 1);
  ASSERT_EQ(Warnings(m).size(), 1u);
  const std::string w = Warnings(m)[0];
  EXPECT_TRUE(Contains(w, "slow.xml: <text name=\"tether:slow\">: integrator=explicit takes "))
      << w;
  EXPECT_TRUE(Contains(w, "slower than real time; integrator=implicit takes one step")) << w;
}

// Through the CLI: a refused case exits with 2 and prints the limit and the fix; info prints
// each limit of the advisor.
int RunCli(const std::string& args, std::string* output) {
  const std::string out = ::testing::TempDir() + "/coupling_cli_" + std::to_string(getpid());
  const int status = std::system(
      (std::string(MJTETHER_CLI) + " " + args + " > " + out + " 2>&1 < /dev/null").c_str());
  std::ifstream f(out);
  std::stringstream s;
  s << f.rdbuf();
  *output = s.str();
  std::remove(out.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// The CLI on a BlueROV2 scene written to the test's temporary directory as `name`: its exit
// code, and what it printed in *output.
int RunCliOn(const std::string& command, const std::string& name, const std::string& EA,
             const char* integrator, std::string* output) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << BlueRovXml(EA, integrator, 0.002);
  return RunCli(command + " " + path, output);
}

TEST(CouplingCli, RefusalExitsWith2AndInfoPrintsEachLimit) {
  std::string output;
  EXPECT_EQ(RunCliOn("run --duration 0.1", "coupling_refused.xml", "1e7", "explicit", &output),
            2)
      << output;
  EXPECT_TRUE(Contains(output, "omega h = ")) << output;
  EXPECT_TRUE(Contains(output, "use integrator=implicit or bdf2 (stable")) << output;
  EXPECT_EQ(RunCliOn("info", "coupling_ok.xml", "1e7", "implicit", &output), 0) << output;
  EXPECT_TRUE(Contains(output, "stable step from: axial omega ")) << output;
  EXPECT_TRUE(Contains(output, "estimated cost ")) << output;
  EXPECT_TRUE(Contains(output, "coupling at end B (body 'rov'): k_end = EA/L0 = 1e+07 N/m"))
      << output;
  // Which coupling the body gets: consistent at omega h 3.36 (>= kLeadFrom), held at 0.26.
  EXPECT_TRUE(Contains(output, "; consistent coupling (end node B solved with the body")) << output;
  EXPECT_TRUE(Contains(output, "; no limit")) << output;
  EXPECT_EQ(RunCliOn("info", "coupling_held.xml", "6e4", "implicit", &output), 0) << output;
  EXPECT_TRUE(Contains(output, "; held end force; no limit for implicit")) << output;
}

}  // namespace
}  // namespace mjtether
