// Honest start-up (issue 11, item 3): the initial shape lies on the seabed instead of below
// it, scenes that cannot start are refused at load with their cause, a stretched start is
// warned about with its strain and tension, and a divergence names its likely cause.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mujoco_fixture.h"
#include "param_name.h"

namespace mjtether {
namespace {

using testing::MuJoCoFixture;
using testing::StepUntilDivergence;

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

const char* kIntegrators[] = {"implicit", "implicit2", "explicit", "rk4"};

// A tether from a TMS site to an ROV site, both fixed in the world, in water with a seabed.
std::string SeabedXml(const std::string& integrator, double length, int segments, const Vec3& a,
                      const Vec3& b, double seabed) {
  std::ostringstream s;
  s.precision(12);
  s << R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025 seabed=)"
    << seabed << R"("/>
    <text name="tether:u" data="ends=tms,rov length=)"
    << length << " segments=" << segments
    << R"( diameter=0.03 mass_per_length=1.0 EA=1e6 Cdn=1.2 Cdt=0.01 integrator=)" << integrator
    << R"("/>
  </custom><worldbody>
    <site name="tms" pos=")"
    << a.x() << " " << a.y() << " " << a.z() << R"("/>
    <site name="rov" pos=")"
    << b.x() << " " << b.y() << " " << b.z() << R"("/>
  </worldbody></mujoco>)";
  return s.str();
}

// Net weight per length of the tether above [N/m]: (mu - rho pi d^2/4) g.
constexpr double kWet = (1.0 - 1025 * 3.14159265358979323846 * 0.03 * 0.03 / 4) * 9.81;

class StartUp : public MuJoCoFixture, public ::testing::WithParamInterface<const char*> {
 protected:
  // Loads the scene, checks the initial shape (no node below the seabed, every segment at most
  // L0 long, total chord length within 1% of L: the shape is the declared tether, not a
  // stretched or shortened one) and returns the number of nodes resting on the seabed.
  int CheckInitialShape(mjModel* m, mjData* d, double seabed) {
    mj_forward(m, d);
    const Tether* t = GetTether(m, 0);
    const double* x = NodePositions(m, d, 0);
    const double L0 = t->rest_segment_length();
    double total = 0;
    int grounded = 0;
    for (int i = 0; i < t->nodes(); ++i) {
      // 1e-9 m: the seabed height goes through the XML text (12 digits).
      EXPECT_GE(x[3 * i + 2], seabed - 1e-9) << "node " << i << " starts below the seabed";
      if (x[3 * i + 2] < seabed + 1e-9) ++grounded;
      if (i == 0) continue;
      const double l = std::hypot(std::hypot(x[3 * i] - x[3 * i - 3], x[3 * i + 1] - x[3 * i - 2]),
                                  x[3 * i + 2] - x[3 * i - 1]);
      EXPECT_LE(l, L0 * (1 + 1e-9)) << "segment " << i - 1 << " starts stretched";
      total += l;
    }
    // Chords of a curved line are shorter than its arcs by ~L0^2 kappa^2/24 each; 1% is far
    // above that for these shapes and far below a shape that dropped length.
    EXPECT_NEAR(total, t->params().length, 0.01 * t->params().length);
    return grounded;
  }

  // Runs `seconds` and checks: no divergence, and no node deeper in the seabed than 20 times
  // the static penetration of a resting line, w/k = 27 um (README, seabed slam: rests at
  // seabed - w/k). A grounded node starts at zero penetration, so it sinks to w/k (case one:
  // measured exactly w/k); where long steep hanging parts meet the seabed (case two), their
  // settling onto the discrete equilibrium presses the touchdown region 7-13 w/k deep during
  // the first second. The old start put nodes 4 m and 45 m deep.
  void RunAndCheckPenetration(mjModel* m, mjData* d, double seabed, double seconds) {
    const double allowed = 20 * kWet / 1e5;  // [m] k = 1e5 N/m^2 (default seabed_stiffness)
    const Tether* t = GetTether(m, 0);
    double deepest = 0;
    while (d->time < seconds) {
      mj_step(m, d);
      std::optional<std::string> message = CheckDivergence(m, d);
      ASSERT_FALSE(message) << *message;
      const double* x = NodePositions(m, d, 0);
      for (int i = 0; i < t->nodes(); ++i) deepest = std::max(deepest, seabed - x[3 * i + 2]);
    }
    std::printf("%s: deepest penetration %.3g m (allowed %.3g m)\n", GetParam(), deepest, allowed);
    EXPECT_LE(deepest, allowed);
  }
};

// Issue 11, case one: 100 m, 100 segments, TMS 3.5 m above a seabed at -40 m, ROV 20 m away
// just above the seabed. The catenary of 100 m would hang ~45 m into the seabed; every
// integrator used to stop at t = 0.002 s.
TEST_P(StartUp, LongTetherNearTheSeabedStartsOnItAndRuns) {
  const double seabed = -40;
  mjModel* m = Load(
      SeabedXml(GetParam(), 100, 100, Vec3(0, 0, seabed + 3.5), Vec3(20, 0, seabed + 0.2), seabed),
      "case_one.xml");
  mjData* d = Make(m);
  const int grounded = CheckInitialShape(m, d, seabed);
  // Excess length on the seabed: L - (hA + hB + H) = 100 - 23.7 = 76.3 m at least lies flat
  // (76 nodes of 1 m); the hanging parts add a little more.
  EXPECT_GE(grounded, 76);
  RunAndCheckPenetration(m, d, seabed, 2.0);
}

// Issue 11, case two: a seabed that the initial catenary crosses by 4 m (60 m, span 15 m).
TEST_P(StartUp, SeabedThroughTheCatenaryStartsOnItAndRuns) {
  const Vec3 a(0, 0, 0), b(15, 0, 0);
  // The lowest point of the catenary without a seabed, from the engine's own initial shape.
  double low = 0;
  {
    mjModel* m0 = Load(SeabedXml(GetParam(), 60, 60, a, b, -1000), "no_seabed.xml");
    mjData* d0 = Make(m0);
    mj_forward(m0, d0);
    const double* x = NodePositions(m0, d0, 0);
    for (int i = 0; i <= 60; ++i) low = std::min(low, x[3 * i + 2]);
  }
  const double seabed = low + 4;
  mjModel* m = Load(SeabedXml(GetParam(), 60, 60, a, b, seabed), "case_two.xml");
  mjData* d = Make(m);
  EXPECT_GE(CheckInitialShape(m, d, seabed), 2);
  RunAndCheckPenetration(m, d, seabed, 2.0);
}

INSTANTIATE_TEST_SUITE_P(Integrators, StartUp, ::testing::ValuesIn(kIntegrators),
                         testing::StringParamName());

// ---------------------------------------------------------------------------------------------
// Refused at load (CLI exit code 2, cause named) and warned about.

int RunCli(const std::string& xml, const std::string& name, std::string* output) {
  const std::string dir = ::testing::TempDir() + "/startup_" + std::to_string(getpid());
  std::system(("mkdir -p " + dir).c_str());
  const std::string path = dir + "/" + name, out = dir + "/" + name + ".out";
  std::ofstream(path) << xml;
  const int status = std::system(
      (std::string(MJTETHER_CLI) + " run " + path + " --duration 0.1 > " + out + " 2>&1").c_str());
  std::ifstream f(out);
  std::stringstream s;
  s << f.rdbuf();
  *output = s.str();
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string LineXml(const std::string& tether_keys, const Vec3& b, const std::string& water = "") {
  std::ostringstream s;
  s << R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025 )"
    << water << R"("/>
    <text name="tether:u" data="ends=a,b )"
    << tether_keys << R"("/></custom><worldbody><site name="a"/>
    <site name="b" pos=")"
    << b.x() << " " << b.y() << " " << b.z() << R"("/></worldbody></mujoco>)";
  return s.str();
}

const char* kLine = "segments=20 diameter=0.02 mass_per_length=0.5 EA=1e5 Cdn=1.2";

TEST(StartUpRefusal, EndsFartherApartThanLengthTimesOnePlusMaxStrainExitWith2) {
  std::string out;
  EXPECT_EQ(RunCli(LineXml(std::string("length=10 ") + kLine, Vec3(25, 0, 0)), "short.xml", &out),
            2)
      << out;
  EXPECT_TRUE(Contains(out, "short.xml: <text name=\"tether:u\">: key 'length' = 10 m")) << out;
  EXPECT_TRUE(Contains(out, "start 25 m apart, more than length x (1 + max_strain) = 20 m")) << out;
}

TEST(StartUpRefusal, AnEndOrAVehicleBelowTheSeabedExitWith2) {
  std::string out;
  EXPECT_EQ(RunCli(LineXml(std::string("length=30 ") + kLine, Vec3(20, 0, -10), "seabed=-5"),
                   "end_below.xml", &out),
            2)
      << out;
  EXPECT_TRUE(Contains(out, "end B (site 'b') starts at z = -10 m, 5 m below the seabed")) << out;
  const std::string vehicle = R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="seabed=-5"/><text name="vehicle:rov" data="volume=0.01"/>
    </custom><worldbody><body name="rov" pos="0 0 -6"><freejoint/>
    <geom type="sphere" size="0.2" mass="10"/></body></worldbody></mujoco>)";
  EXPECT_EQ(RunCli(vehicle, "vehicle_below.xml", &out), 2) << out;
  EXPECT_TRUE(Contains(out, "<text name=\"vehicle:rov\">: body 'rov' starts at z = -6 m")) << out;
}

// A diameter in millimetres (8 for 8 mm; the parser's range stops at 10 m): mean density
// 0.5 / (pi 8^2/4) = 0.0099 kg/m^3.
TEST(StartUpRefusal, DiameterInMillimetresAndTooManySegmentsExitWith2) {
  std::string out;
  EXPECT_EQ(
      RunCli(LineXml("length=30 segments=20 diameter=8 mass_per_length=0.5 EA=1e5", Vec3(20, 0, 0)),
             "mm.xml", &out),
      2)
      << out;
  EXPECT_TRUE(Contains(out, "key 'diameter' = 8 m with mass_per_length = 0.5 kg/m")) << out;
  EXPECT_TRUE(Contains(out, "give the diameter in metres")) << out;
  // 1 m in 1000 segments of 1 mm with a 2 cm diameter: L0 = d/20.
  EXPECT_EQ(RunCli(LineXml("length=1 segments=1000 diameter=0.02 mass_per_length=0.5 EA=1e5",
                           Vec3(0.9, 0, 0)),
                   "many.xml", &out),
            2)
      << out;
  EXPECT_TRUE(Contains(out, "key 'segments' = 1000 makes segments of 0.001 m")) << out;
  EXPECT_TRUE(Contains(out, "use at most 500 segments")) << out;
}

// A start stretched by 2%: the run goes on, with a warning giving the strain and EA x strain.
TEST(StartUpWarning, StretchedStartIsWarnedWithStrainAndTension) {
  std::string out;
  EXPECT_EQ(RunCli(LineXml(std::string("length=10 ") + kLine, Vec3(10.2, 0, 0)), "taut.xml", &out),
            0)
      << out;
  EXPECT_TRUE(Contains(out, "mjtether: warning: ")) << out;
  EXPECT_TRUE(Contains(out, "starts stretched, far from equilibrium")) << out;
  EXPECT_TRUE(Contains(out, "a strain of 0.02 and a tension EA x strain = 2000 N")) << out;
}

// An attachment site far off its body (a pos in centimetres: "-23 0 10" for "-0.23 0 0.1") is
// warned at load with the lever arm and the body's reach; no shipped model is. The site is then
// sqrt(23^2 + 10^2) = 25.08 m from the box's centre, whose bounding sphere is
// sqrt(0.23^2 + 0.17^2 + 0.13^2) = 0.314 m; the limit is 3 x 0.314 + 1 = 1.94 m. (The
// hostile-input generator's site moved 38 m off a vehicle stopped at the first step, told only to
// reduce the step below 1e-4 s.)
class StartUpLever : public MuJoCoFixture {};

std::string ReadModel(const std::string& name) {
  std::ifstream f(std::string(MJTETHER_MODELS_DIR) + "/" + name);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

bool AnyWarningHas(const mjModel* m, const std::string& text, std::string* all) {
  bool found = false;
  for (const std::string& w : Warnings(m)) {
    *all += w + "\n";
    found = found || Contains(w, text);
  }
  return found;
}

TEST_F(StartUpLever, ASiteInCentimetresIsWarnedAndNoShippedModelIs) {
  std::string xml = ReadModel("minimal_rov.xml");
  const std::string from = R"(<site name="rov_attach" pos="-0.23 0 0.1"/>)";
  ASSERT_NE(xml.find(from), std::string::npos) << "models/minimal_rov.xml changed: fix the test";
  xml.replace(xml.find(from), from.size(), R"(<site name="rov_attach" pos="-23 0 10"/>)");
  std::string all;
  EXPECT_TRUE(AnyWarningHas(Load(xml, "cm.xml"), "end B (site 'rov_attach') is 25.0", &all))
      << all;
  EXPECT_TRUE(Contains(all, "of body 'rov', whose geoms reach 0.31")) << all;
  EXPECT_TRUE(Contains(all, "check the site's pos")) << all;
  for (const char* name :
       {"bluerov2_heavy.xml", "bluerov2_heavy_winch.xml", "hfield_rock.xml",
        "manoeuvre_dive_return.xml", "manoeuvre_station_keeping.xml", "manoeuvre_surge_snap.xml",
        "manoeuvre_turn_wrap.xml", "minimal_rov.xml", "rov_tether.xml", "seabed_hfield.xml",
        "workclass_rov_tms.xml", "workclass_rov_tms_winch.xml"}) {
    std::string shipped;
    EXPECT_FALSE(AnyWarningHas(Load(ReadModel(name), std::string(MJTETHER_MODELS_DIR) + "/" + name),
                               "check the site's pos", &shipped))
        << name << ": " << shipped;
  }
}

// ---------------------------------------------------------------------------------------------
// A divergence names its likely cause instead of "reduce the time step".

class StartUpDivergence : public MuJoCoFixture {
 protected:
  std::string RunUntilDivergence(const std::string& xml, double seconds) {
    mjModel* m = Load(xml, "scene.xml");
    if (!m) return "refused at load";  // Load has failed the test with the message
    return StepUntilDivergence(m, Make(m), seconds).value_or("");
  }
};

// A vehicle on a 20 m tether (EA = 1e6 N, so EA x max_strain = 1e6 N) pushed by 1e7 N.
TEST_F(StartUpDivergence, ThrustBeyondWhatTheTetherHoldsIsNamed) {
  const std::string xml = R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025"/>
    <text name="vehicle:rov" data="volume=0.1 added_mass=50,50,50,1,1,1
          linear_damping=50,50,50,5,5,5"/>
    <text name="tether:u" data="ends=tms,att length=20 segments=20 diameter=0.02
          mass_per_length=0.5 EA=1e6 Cdn=1.2 integrator=implicit"/>
    <text name="thrust:thr" data="t=0,0.1 ctrl=0,1e7"/>
  </custom><worldbody><site name="tms"/>
    <body name="rov" pos="15 0 0"><freejoint/><inertial pos="0 0 0" mass="100"
      diaginertia="5 5 5"/><site name="att"/><site name="thr"/></body>
  </worldbody><actuator><motor name="thr" site="thr" gear="1 0 0 0 0 0"/></actuator></mujoco>)";
  const std::string message = RunUntilDivergence(xml, 2);
  ASSERT_FALSE(message.empty()) << "no divergence";
  EXPECT_TRUE(Contains(message, "thrust beyond what the tether holds")) << message;
  EXPECT_TRUE(Contains(message, "body 'rov'")) << message;
  EXPECT_TRUE(Contains(message, "EA x max_strain = 1e+06 N")) << message;
  EXPECT_FALSE(Contains(message, "Reduce <option timestep>")) << message;
}

// The scene fuzzer's seed 6 (implicit2, 12 segments, EA x max_strain = 1.76e8 N, an 8.5 kg
// vehicle with a thrust ramp from 0 at 0.1 s to 1.77e8 N at 0.4 s): at 2 ms it stops at
// 0.106 s, when the thrust is 3.5e6 N, 2% of what the tether holds (the vehicle, at 925 m/s,
// makes its end's drag too stiff for the step). The cause named is the schedule, not the step,
// and the claim that a smaller step diverges too is checked: at 0.2 ms it diverges at 0.398 s,
// past what the tether holds. (Until session 29 the scene was seed 593, rk4 at coupling omega h
// 0.68, which diverged at 0.134 s at 2 ms and now is refused at load: rk4's limit is 0.5.)
TEST_F(StartUpDivergence, ThrustScheduleBeyondWhatTheTetherHoldsIsNamedBeforeItIsReached) {
  auto scene = [](const char* step) {
    return std::string(R"(<mujoco><option timestep=")") + step + R"("/><custom>
    <text name="water" data="density=1025 seabed=-4.356093718"/>
    <text name="vehicle:rov" data="volume=0.008368073654 cob=0,0,0.02040554401
      added_mass=2.955660571,8.416120565,3.365227996,0.01768930998,0.01768930998,0.01768930998
      linear_damping=15.20598649,15.20598649,15.20598649,0.0589643666,0.0589643666,0.0589643666
      quadratic_damping=21.33979411,21.33979411,21.33979411,0.0589643666,0.0589643666,0.0589643666
      coriolis=0"/>
    <text name="tether:t" data="ends=tms_site,att length=15.46241707 segments=12
      diameter=0.04750132456 mass_per_length=2.875140633 EA=176027342.3 Cdn=1.2 Cdt=0.01
      Can=1 integrator=implicit2 EI=0.003415685833 EAc=176027342.3 damping=5.675400107"/>
    <text name="thrust:thr" data="t=0.1,0.4 ctrl=0,177063139.1"/>
    </custom><worldbody><body name="tms" mocap="true"><site name="tms_site"/></body>
    <body name="rov" pos="4.064953908 14.93377433 -1.132244863"><freejoint/>
      <inertial pos="0 0 0" mass="8.496587473" diaginertia="0.0589643666 0.0589643666
      0.0589643666"/><site name="att"/><site name="thr"/></body></worldbody>
    <actuator><motor name="thr" site="thr"
      gear="0.4830720039 0.8734424581 -0.06115317966 0 0 0"/></actuator></mujoco>)";
  };
  const std::string message = RunUntilDivergence(scene("0.002"), 1);
  ASSERT_FALSE(message.empty()) << "no divergence";
  const std::string prefix =
      "thrust beyond what the tether holds: the thrust: schedules push body 'rov' with up to ";
  ASSERT_TRUE(Contains(message, prefix)) << message;
  // The schedule's peak (gear of unit length x 1.7706e8) and the thrust at the stop, below
  // half of EA x max_strain, so the check on the thrust now (Diagnose's first) did not apply.
  const char* peak = message.c_str() + message.find(prefix) + prefix.size();
  char* rest = nullptr;
  EXPECT_NEAR(std::strtod(peak, &rest), 1.77063e8, 1e3) << message;
  ASSERT_EQ(std::string(rest, 4), " N (") << message;
  EXPECT_LT(std::strtod(rest + 4, nullptr), 0.5 * 1.76027342e8) << message;
  EXPECT_FALSE(Contains(message, "Reduce <option timestep>")) << message;
  // A 10x smaller step diverges too, for the same cause.
  const std::string fine = RunUntilDivergence(scene("0.0002"), 1);
  EXPECT_TRUE(Contains(fine, "thrust beyond what the tether holds")) << fine;
}

// A thrust schedule beyond what the tether holds is warned at load (session 15): the scene
// fuzzer's seed 9153 (implicit2, 63 segments, EA x max_strain = 3.44e5 N, a 169 kg vehicle
// with a thrust ramp to 6.46e5 N) ran to its end at 2 ms with no word, while the same scene at
// 0.2 ms diverges at 0.743 s with "thrust beyond what the tether holds": the 2 ms step damps
// the snap that strains the line past max_strain. The warning names the tether, the body, the
// schedule's peak and what the tether holds, and says that the outcome depends on the step;
// the fine run bears that out. Below half of what the tether holds: no warning.
std::string Seed9153(const char* step, const char* peak) {
  return std::string(R"(<mujoco><option timestep=")") + step + R"("/><custom>
    <text name="water" data="density=1025 current=-0.9491971175,-0.08408695242,0
      seabed=-48.54385855"/>
    <text name="vehicle:rov" data="volume=0.1629168322 cob=0,0,0.05523493325
      added_mass=78.03486475,99.6157602,81.66236854,2.570627634,2.570627634,2.570627634
      linear_damping=123.8722548,123.8722548,123.8722548,8.56875878,8.56875878,8.56875878
      quadratic_damping=156.3585149,156.3585149,156.3585149,8.56875878,8.56875878,8.56875878
      coriolis=0"/>
    <text name="tether:t" data="ends=tms_site,att length=90.75296207 segments=63
      diameter=0.01718114791 mass_per_length=0.6396206197 EA=344275.0664 Cdn=1.2 Cdt=0.01 Can=1
      integrator=implicit2"/>
    <text name="motion:tms" data="y=0.1147967678,6.603896733,0"/>
    <text name="thrust:thr" data="t=0.1,0.4 ctrl=0,)" + peak + R"("/>
    </custom><worldbody><body name="tms" mocap="true"><site name="tms_site"/></body>
    <body name="rov" pos="-15.20576483 6.049550848 -26.29602523"><freejoint/>
      <inertial pos="0 0 0" mass="168.5161392" diaginertia="8.56875878 8.56875878 8.56875878"/>
      <site name="att"/><site name="thr"/></body></worldbody>
    <actuator><motor name="thr" site="thr"
      gear="-0.4576245903 -0.121136211 -0.8808551258 0 0 0"/></actuator></mujoco>)";
}

TEST_F(StartUpDivergence, ThrustScheduleBeyondWhatTheTetherHoldsIsWarnedAtLoad) {
  auto warning = [](const mjModel* m) {
    std::string found;
    for (const std::string& w : Warnings(m)) {
      if (Contains(w, "the thrust: schedules push body")) found = w;
    }
    return found;
  };
  mjModel* m = Load(Seed9153("0.002", "645875.164"), "scene9153.xml");
  const std::string w = warning(m);
  EXPECT_TRUE(Contains(w, "scene9153.xml: <text name=\"tether:t\">")) << w;
  // The gear is a unit vector: the peak is the schedule's ctrl.
  EXPECT_TRUE(Contains(w, "push body 'rov' (end B) with up to 645875 N")) << w;
  EXPECT_TRUE(Contains(w, "more than EA x max_strain = 344275 N, what this tether holds")) << w;
  EXPECT_TRUE(Contains(w, "depend on <option timestep>: compare with a smaller one")) << w;
  // What the warning says a smaller step shows: the snap the 2 ms step damps strains the line
  // past max_strain, and the cause named is the thrust, not the step.
  const std::string fine = RunUntilDivergence(Seed9153("0.0002", "645875.164"), 1);
  EXPECT_TRUE(Contains(fine, "thrust beyond what the tether holds")) << fine;
  // Between half and all of what the tether holds (0.8 x 344275 N): the snap-load warning.
  const std::string snap = warning(Load(Seed9153("0.002", "275420"), "snap.xml"));
  EXPECT_TRUE(Contains(snap, "with up to 275420 N, more than half of EA x max_strain")) << snap;
  EXPECT_TRUE(Contains(snap, "reduce the schedule below 172138 N")) << snap;
  // Below half (0.45 x): nothing.
  EXPECT_EQ(warning(Load(Seed9153("0.002", "154924"), "below.xml")), "");
}

// A TMS heaving with a 1000 m amplitude on a 20 m tether to a fixed site.
TEST_F(StartUpDivergence, HugePrescribedMotionIsNamed) {
  const std::string xml = R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025"/>
    <text name="tether:u" data="ends=tms_site,b length=20 segments=20 diameter=0.02
          mass_per_length=0.5 EA=1e6 Cdn=1.2 integrator=implicit"/>
    <text name="motion:tms" data="x=1000,10,0 ramp=1"/>
  </custom><worldbody><body name="tms" mocap="true"><site name="tms_site"/></body>
    <site name="b" pos="15 0 0"/></worldbody></mujoco>)";
  const std::string message = RunUntilDivergence(xml, 5);
  ASSERT_FALSE(message.empty()) << "no divergence";
  EXPECT_TRUE(Contains(message, "body 'tms'")) << message;
  EXPECT_TRUE(Contains(message, "prescribed motion") || Contains(message, "too fast for the step"))
      << message;
  EXPECT_FALSE(Contains(message, "Reduce <option timestep> (now")) << message;
}

// The scene fuzzer's seed 391: a 65 kg vehicle 54.6 m from a TMS on 29.1 m of tether (EA
// 4.35e8 N, implicit), a start stretched by 87.5% (3.8e8 N), the TMS heaving 0.66 m. The start
// throws the vehicle 33 m in the first step. Before session 22 that move counted as a teleport:
// the tether restarted from a new initial shape between the thrown ends, stretched 172%, and
// the stop blamed the TMS's motion. The cause named is the stretched start.
TEST_F(StartUpDivergence, AVehicleThrownByAStretchedStartIsNamedAsTheStart) {
  const std::string xml = R"(<mujoco><option timestep="0.002"/><custom>
    <text name="water" data="density=1025"/>
    <text name="vehicle:rov" data="volume=0.06 added_mass=34,36,38,1,1,1
          linear_damping=60,60,60,2,2,2 quadratic_damping=80,80,80,2,2,2"/>
    <text name="tether:t" data="ends=tms_site,att length=29.12390722 segments=13
          diameter=0.02851903456 mass_per_length=1.426373962 EA=435238168.3 Cdn=1.2 Cdt=0.01
          Can=1 integrator=implicit"/>
    <text name="motion:tms" data="y=0.6607288025,2.731675325,0"/>
  </custom><worldbody>
    <body name="tms" mocap="true"><site name="tms_site"/></body>
    <body name="rov" pos="-11.87548566 49.57486772 -19.59368751"><freejoint/>
      <inertial pos="0 0 0" mass="65.3" diaginertia="2 2 2"/><site name="att"/></body>
  </worldbody></mujoco>)";
  const std::string message = RunUntilDivergence(xml, 1);
  ASSERT_FALSE(message.empty()) << "no divergence";
  EXPECT_TRUE(Contains(message, "start-up strain: the tether started stretched by 0.875"))
      << message;
  EXPECT_FALSE(Contains(message, "prescribed motion")) << message;
}

// A body that MuJoCo moves is not teleported, however hard it is pushed: the user applies
// 2.5e8 N to the 100 kg vehicle for one step (xfrc_applied), so that the step moves it 10 m
// away from the TMS, along its new velocity of 5000 m/s; the tether's last look at it saw it
// at rest. The tether must feel that pull at the next call (its end segment stretched past
// max_strain: a divergence), not restart silently from a
// new initial shape between the moved ends, as it did when only the velocity before the step
// could explain a move. A move of qpos by hand (velocity unchanged) is still a teleport and
// restarts the tether (25 m apart on 20 m: within length x (1 + max_strain)).
TEST_F(StartUpDivergence, ABodyMovedByItsVelocityIsNotATeleportAndOneMovedByHandIs) {
  const std::string xml = R"(<mujoco><option timestep="0.002" gravity="0 0 0"/><custom>
    <text name="tether:u" data="ends=tms,att length=20 segments=20 diameter=0.02
          mass_per_length=0.5 EA=1e6 integrator=implicit"/>
  </custom><worldbody><site name="tms"/>
    <body name="rov" pos="15 0 0"><freejoint/><inertial pos="0 0 0" mass="100"
      diaginertia="5 5 5"/><site name="att"/></body>
  </worldbody></mujoco>)";
  for (const bool by_hand : {false, true}) {
    mjModel* m = Load(xml, "scene.xml");
    mjData* d = Make(m);
    for (int i = 0; i < 10; ++i) Step(m, d);
    ASSERT_FALSE(CheckDivergence(m, d));
    const double x0 = d->qpos[0];
    if (by_hand) {
      d->qpos[0] += 10;  // 10 m further, at rest
    } else {
      d->xfrc_applied[6 * 1 + 0] = 100 * 10 / (0.002 * 0.002);  // [N] m dx / h^2
      Step(m, d);
      d->xfrc_applied[6 * 1 + 0] = 0;
      ASSERT_NEAR(d->qpos[0] - x0, 10, 0.5);  // moved by MuJoCo, the tether not yet told
    }
    Step(m, d);  // the callback sees the moved body
    const std::optional<std::string> stop = CheckDivergence(m, d);
    if (by_hand) {
      EXPECT_FALSE(stop) << *stop;
    } else {
      // (What it names as the cause is not checked: the force was the user's, xfrc_applied,
      // which Diagnose does not read.)
      EXPECT_TRUE(stop) << "the pull was not felt: the tether restarted";
    }
  }
}

// A heavy line hanging from a heaving TMS to a fixed site 10 m below it, dry. Its weight makes
// the strain at the top exceed the mean by w L / (2 EA) = 9.81 x 10 / 4000 = 0.025 (static)
// and the start rings about that, so the top segment crosses max_strain = 0.1 while the mean
// strain (span / length - 1) is still well below it: before, the message blamed the step.
// The diagnosis's spread at the crossing is w |dz| / EA ~ 0.05 (plus the wave 2 v / c
// <= 2 x 0.31 / 44.7 = 0.014), so the pull is named from a mean strain of ~0.035.
TEST_F(StartUpDivergence, HangingLinePulledPastMaxStrainAtTheTopIsNamedAsPulled) {
  const std::string xml = R"(<mujoco><option timestep="0.002"/><custom>
    <text name="tether:u" data="ends=tms_site,b length=10 segments=10 diameter=0.02
          mass_per_length=1 EA=2e3 damping=20 max_strain=0.1"/>
    <text name="motion:tms" data="z=1,20,0"/>
  </custom><worldbody><body name="tms" mocap="true"><site name="tms_site"/></body>
    <site name="b" pos="0 0 -10"/></worldbody></mujoco>)";
  const std::string message = RunUntilDivergence(xml, 25);
  std::printf("%s\n", message.c_str());
  ASSERT_FALSE(message.empty()) << "no divergence";
  EXPECT_TRUE(Contains(message, "strain beyond max_strain")) << message;
  EXPECT_TRUE(Contains(message, "the ends were pulled")) << message;
  EXPECT_TRUE(Contains(message, "prescribed motion of body 'tms'")) << message;
  EXPECT_FALSE(Contains(message, "Reduce <option timestep>")) << message;
}

// ---------------------------------------------------------------------------------------------
// Compressed starts with EAc (session 10, s10open; docs/scene_fuzzer.md, "one-two segments and
// stretched starts"). A tether of 10 m with EAc between ends 6 m apart.

std::string CompressedXml(int segments, const std::string& integrator, double timestep) {
  std::ostringstream s;
  s << R"(<mujoco><option timestep=")" << timestep << R"("/><custom>
    <text name="water" data="density=1025"/>
    <text name="vehicle:rov" data="volume=0.0195 added_mass=10,10,10,0.1,0.1,0.1
          linear_damping=20,20,20,1,1,1 coriolis=0"/>
    <text name="tether:u" data="ends=tms_site,att length=10 segments=)"
    << segments << R"( diameter=0.01 mass_per_length=0.1
          EA=1e6 EAc=1e6 EI=0.01 Cdn=1.2 Cdt=0.01 Can=1 integrator=)"
    << integrator << R"("/>
  </custom><worldbody><body name="tms" mocap="true"><site name="tms_site"/></body>
    <body name="rov" pos="4.8 0 -3.6"><freejoint/><inertial pos="0 0 0" mass="20"
          diaginertia="0.3 0.3 0.3"/><site name="att"/></body></worldbody></mujoco>)";
  return s.str();
}

// One segment cannot hang 10 m between ends 6 m apart: it starts as a strut compressed by 0.4,
// pushing with EAc x 0.4 = 4e5 N, far beyond its Euler load pi^2 EI / L^2 = 9.9e-4 N. Before,
// the run launched the vehicle with that force (fuzz seed 7190: 8.6 MN into 470 kg).
TEST(StartUpRefusal, OneSegmentCompressedBeyondItsEulerLoadExitWith2NamingTheFix) {
  std::string out;
  EXPECT_EQ(RunCli(CompressedXml(1, "implicit", 0.002), "strut.xml", &out), 2) << out;
  EXPECT_TRUE(Contains(out, "strut.xml: <text name=\"tether:u\">: starts compressed")) << out;
  EXPECT_TRUE(Contains(out, "a compressive strain of 0.4 and a force EAc x strain = 400000 N"))
      << out;
  EXPECT_TRUE(Contains(out, "beyond its Euler buckling load")) << out;
  EXPECT_TRUE(Contains(out, "use at least 2 segments")) << out;
  EXPECT_TRUE(Contains(out, "or remove EAc")) << out;
  // Without EAc the short chord is slack: no force, no refusal.
  std::string xml = CompressedXml(1, "implicit", 0.002);
  xml.replace(xml.find(" EAc=1e6"), 8, "");
  EXPECT_EQ(RunCli(xml, "slack.xml", &out), 0) << out;
}

// Two segments with EAc: the catenary walk of chords L0 fails on this deep U (Newton's slope
// turns negative past its bottom), and the start used to keep the arc spacing, chords of
// 0.995 and 0.72 L0, the second pushing with EAc x 0.28 = 2.8e5 N. Now the V of two straight legs: both chords
// L0 (to round-off; since session 24 the chain at rest, each leg stretched by its tension),
// and the run agrees with its fine-step self (the fuzzer's criterion:
// position within 5 cm, the vehicle-end tension over the last 0.2 s within max(0.5 N, 5%)).
TEST(StartUpShape, TwoSegmentsWithEAcOnAShortSpanStartAsAVeeAndAgreeWithTheFineStep) {
  struct Result {
    Vec3 rov;
    double tension = 0;
  };
  auto run = [](double timestep) {
    testing::LoadedScene scene(CompressedXml(2, "implicit", timestep), "vee.xml");
    mjModel* m = scene.m;
    mjData* d = scene.d;
    mj_forward(m, d);
    const double* x = NodePositions(m, d, 0);
    for (int k = 0; k < 2; ++k) {
      const double chord = std::hypot(std::hypot(x[3 * k + 3] - x[3 * k], x[3 * k + 4] - x[3 * k + 1]),
                                      x[3 * k + 5] - x[3 * k + 2]);
      // The chain at rest (Tether::HangChain): each leg stretched by its tension, the middle
      // node's weight over 2 sin(angle), divided by EA: 4.8e-6 here. Never shorter than L0.
      EXPECT_GE(chord, 5.0 - 1e-9) << "segment " << k;
      EXPECT_LT(chord, 5.0 * (1 + 1e-5)) << "segment " << k;
    }
    EXPECT_LT(x[5], -3.6) << "the middle node hangs below the chord";
    Result r;
    const int steps = static_cast<int>(std::lround(1.0 / timestep));
    const int from = steps - static_cast<int>(std::lround(0.2 / timestep));
    for (int k = 0; k < steps; ++k) {
      mj_step(m, d);
      std::optional<std::string> message = CheckDivergence(m, d);
      EXPECT_FALSE(message) << *message;
      if (message) break;
      if (k >= from) r.tension += GetReactions(m, d, 0).tension_b / (steps - from);
    }
    r.rov = Vec3(d->xpos + 3 * mj_name2id(m, mjOBJ_BODY, "rov"));
    return r;
  };
  const Result coarse = run(0.002), fine = run(0.0002);
  std::printf("vee: rov %.4f %.4f %.4f / %.4f %.4f %.4f m, tension %.4f / %.4f N\n",
              coarse.rov.x(), coarse.rov.y(), coarse.rov.z(), fine.rov.x(), fine.rov.y(),
              fine.rov.z(), coarse.tension, fine.tension);
  EXPECT_LE((coarse.rov - fine.rov).norm(), 0.05);
  EXPECT_LE(std::abs(coarse.tension - fine.tension),
            std::max(0.5, 0.05 * std::max(coarse.tension, fine.tension)));
}

// Two segments with EAc whose arc-spaced middle node would sit below the seabed (fuzz seed
// 7095: 101.7 m of line from an anchor 48.7 m above the seabed to an end 13.7 m above it):
// the seabed walk finds no bracket and used to keep the arc spacing, chords 0.79 and 0.96 L0.
// Now projected onto chords of L0 with the node lifted onto the seabed (and, at these
// full-precision values, nudged sideways once: the projection stalls in the ends' plane).
TEST(StartUpShape, TwoSegmentsWithEAcOverTheSeabedStartAtChordsOfL0OnIt) {
  TetherParams p;
  p.length = 101.66817087257775;
  p.segments = 2;
  p.diameter = 0.01480483154;
  p.mass_per_length = 0.3645806722;
  p.EA = p.EAc = 2896.178072;
  p.EI = 5.465518655;
  p.effects = kAxial | kWeight | kBuoyancy | kCompression | kSeabed;
  Environment env;
  env.wet = true;
  env.water.has_seabed = true;
  env.water.seabed = -48.671847327980835;
  std::string error;
  std::optional<Tether> t = Tether::Create(p, env, &error);
  ASSERT_TRUE(t) << error;
  std::vector<double> x(9), v(9);
  Ends ends;
  ends.b.pos = Vec3(39.865552058042795, -7.1303744654466419, -34.95756439569832);
  t->InitialShape(ends, x.data(), v.data());
  for (int k = 0; k < 2; ++k) {
    const double chord = (Vec3(&x[3 * k + 3]) - Vec3(&x[3 * k])).norm();
    EXPECT_NEAR(chord / (p.length / 2), 1.0, 1e-9) << "segment " << k;
  }
  EXPECT_GE(x[5], env.water.seabed - 1e-12) << "the middle node starts below the seabed";
}

}  // namespace
}  // namespace mjtether
