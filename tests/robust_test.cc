// Robustness: the time-step advisor, divergence reports, bad input through the command line,
// concurrency, and a long run of the default scene with flat memory.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "mjtether.h"
#include "mujoco_fixture.h"

namespace mjtether {
namespace {

// Loads models from strings, deletes them and their data at the end of the test.
using Scene = testing::MuJoCoFixture;

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

std::string Fmt(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// A 20 m line of 40 segments between two world sites in air, sagging; `extra` is appended to
// the declaration.
std::string LineXml(const std::string& extra, double timestep = 0.002,
                    const std::string& stiffness = "EA=1e6 segments=40") {
  std::ostringstream s;
  s << R"(<mujoco><option timestep=")" << timestep << R"("/><custom>
      <text name="tether:line" data="ends=a,b length=20 diameter=0.02
            mass_per_length=0.5 damping=10 )"
    << stiffness << " " << extra << R"("/></custom>
    <worldbody><site name="a" pos="0 0 0"/><site name="b" pos="15 0 0"/></worldbody>
    </mujoco>)";
  return s.str();
}

// ---------------------------------------------------------------------------------------------
// Time-step advisor

// An explicit tether whose fixed `substeps` make its step longer than its stable step gets
// one warning naming the file, the tether, the stable step and the stability limit it is taken
// from, and the setting to change; the advice is
// right: with the substeps it recommends the run stays finite, with the declared ones it
// diverges.
TEST_F(Scene, AdvisorWarnsWhenFixedSubstepsExceedTheLimit) {
  mjModel* m = Load(LineXml("integrator=explicit substeps=2"), "coarse.xml");
  ASSERT_NE(m, nullptr);
  const double limit = GetTether(m, 0)->ExplicitStableStep();
  ASSERT_GT(0.001, limit);  // 2 substeps of 1 ms are too long: the case is real
  const std::vector<std::string> warnings = Warnings(m);
  ASSERT_EQ(warnings.size(), 1u);
  const std::string& w = warnings[0];
  EXPECT_TRUE(Contains(w, "coarse.xml: <text name=\"tether:line\">")) << w;
  EXPECT_TRUE(Contains(w, "stable step " + Fmt(limit) + " s")) << w;
  const double bound = GetTether(m, 0)->ExplicitStabilityLimit();
  EXPECT_TRUE(Contains(w, "of the stability limit " + Fmt(bound) + " s")) << w;
  EXPECT_TRUE(Contains(w, "slack tether gains energy")) << w;
  const int advised = static_cast<int>(std::ceil(0.002 / limit));
  EXPECT_TRUE(Contains(w, "substeps >= " + std::to_string(advised))) << w;
  EXPECT_TRUE(Contains(w, "integrator=implicit")) << w;

  // The declared setting diverges within 0.2 s; the advised one is stable for 1 s.
  mjData* d = Make(m);
  while (d->time < 0.2 && !CheckDivergence(m, d)) mj_step(m, d);
  EXPECT_TRUE(CheckDivergence(m, d));
  mjModel* fixed =
      Load(LineXml("integrator=explicit substeps=" + std::to_string(advised)), "fixed.xml");
  EXPECT_TRUE(Warnings(fixed).empty());
  mjData* e = Make(fixed);
  while (e->time < 1) mj_step(fixed, e);
  EXPECT_FALSE(CheckDivergence(fixed, e));
}

// The same for max_step; no warning for automatic substeps or for the implicit integrator,
// whatever the step.
TEST_F(Scene, AdvisorCoversMaxStepAndIsSilentOtherwise) {
  mjModel* m = Load(LineXml("integrator=explicit max_step=0.001"));
  ASSERT_EQ(Warnings(m).size(), 1u);
  const std::string w = Warnings(m)[0];
  const size_t at = w.find("max_step <= ");
  ASSERT_NE(at, std::string::npos) << w;
  // The advised max_step, taken literally, loads without the warning. (It is rounded down,
  // StepAtMost; here six digits would have read below the bound as well: the rounding itself is
  // checked by Coupling.TheChatterWarningAdvisesAStepThatLeavesTheWarnedBand.)
  const std::string advised = w.substr(at + 12, w.find(',', at) - at - 12);
  mjModel* followed = Load(LineXml("integrator=explicit max_step=" + advised), "followed.xml");
  EXPECT_TRUE(Warnings(followed).empty()) << advised << " | " << Warnings(followed)[0];
  mjModel* automatic = Load(LineXml("integrator=explicit"));
  EXPECT_TRUE(Warnings(automatic).empty());
  const Tether* t = GetTether(automatic, 0);
  // Automatic substeps: the smallest count whose step is within the limit.
  const int n = t->SubstepsFor(0.002);
  EXPECT_LE(0.002 / n, t->ExplicitStableStep());
  EXPECT_GT(0.002 / (n - 1), t->ExplicitStableStep());
  mjModel* implicit = Load(LineXml("integrator=implicit substeps=1"));
  EXPECT_TRUE(Warnings(implicit).empty());
}

// A tether with bending but no compression gets one warning naming the file, the tether and
// the remedy (EAc), since its slack segments can shorten at zero tension; declaring EAc
// silences it, and so does a tether without bending. The shipped default scene declares EAc
// and loads without any warning.
TEST_F(Scene, AdvisorWarnsAboutBendingWithoutCompression) {
  mjModel* m = Load(LineXml("EI=0.1"), "bend.xml");
  ASSERT_NE(m, nullptr);
  ASSERT_EQ(Warnings(m).size(), 1u);
  const std::string w = Warnings(m)[0];
  EXPECT_TRUE(Contains(w, "bend.xml: <text name=\"tether:line\">")) << w;
  EXPECT_TRUE(Contains(w, "EAc")) << w;
  EXPECT_TRUE(Warnings(Load(LineXml("EI=0.1 EAc=1e6"))).empty());
  EXPECT_TRUE(Warnings(Load(LineXml(""))).empty());
  std::ifstream f(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml");
  std::stringstream xml;
  xml << f.rdbuf();
  mjModel* scene = Load(xml.str(), "rov_tether.xml");
  ASSERT_NE(scene, nullptr);
  EXPECT_EQ(Warnings(scene).size(), 0u);
}

// An explicit tether that would need more than 1e5 substeps per MuJoCo step is refused at
// load time with the count and what to change (it would otherwise run for hours).
TEST_F(Scene, AbsurdAutomaticSubstepsAreRefused) {
  std::string error;
  mjModel* m = LoadModelFromString(LineXml("integrator=explicit", 0.002, "EA=1e13 segments=1000"),
                                   "stiff.xml", &error);
  ASSERT_EQ(m, nullptr);
  EXPECT_TRUE(Contains(error, "stiff.xml: <text name=\"tether:line\">")) << error;
  EXPECT_TRUE(Contains(error, "more than 100000")) << error;
  EXPECT_TRUE(Contains(error, "integrator=implicit")) << error;
}

// A max_step so small that one MuJoCo step would take more than 1e5 tether steps (it is within
// the key's range (0, 1]) is refused the same way, for any integrator, instead of hanging the
// first mj_step (found by the fuzzer: max_step=1e-54 also overflowed the step count).
TEST_F(Scene, TinyMaxStepIsRefused) {
  for (const char* integrator : {"implicit", "rk4"}) {
    std::string error;
    mjModel* m = LoadModelFromString(
        LineXml(std::string("integrator=") + integrator + " max_step=1e-54"), "tiny.xml", &error);
    ASSERT_EQ(m, nullptr) << integrator;
    EXPECT_TRUE(Contains(error, "tiny.xml: <text name=\"tether:line\">")) << error;
    EXPECT_TRUE(Contains(error, "'max_step'")) << error;
    EXPECT_TRUE(Contains(error, "more than 100000")) << error;
  }
}

// ---------------------------------------------------------------------------------------------
// Divergence at run time

// A run that diverges stops with a message naming the file, the tether, the time, the node and
// what to change; the tether then applies no force.
TEST_F(Scene, DivergenceMessageNamesTetherTimeNodeAndRemedy) {
  mjModel* m = Load(LineXml("integrator=explicit substeps=1"), "unstable.xml");
  mjData* d = Make(m);
  std::optional<std::string> message;
  while (d->time < 1 && !(message = CheckDivergence(m, d))) mj_step(m, d);
  ASSERT_TRUE(message);
  EXPECT_TRUE(Contains(*message, "unstable.xml: tether 'line' diverged at t = ")) << *message;
  EXPECT_TRUE(Contains(*message, " at node ")) << *message;
  EXPECT_TRUE(Contains(*message, "of 41")) << *message;
  EXPECT_TRUE(Contains(*message, "stable step")) << *message;
  EXPECT_TRUE(Contains(*message, "integrator=implicit")) << *message;
}

// Energy blow-up: a node given more kinetic energy than the tether can hold is reported as
// such, naming that node (a state an unstable scheme reaches before any NaN). The time step is
// 0.1 us so that the node moves 9 mm in it: no strain check can see it first.
TEST_F(Scene, KineticEnergyBlowUpIsReported) {
  mjModel* m = Load(LineXml("integrator=implicit", 1e-7), "blowup.xml");
  mjData* d = Make(m);
  for (int k = 0; k < 10; ++k) mj_step(m, d);
  ASSERT_FALSE(CheckDivergence(m, d));
  const Tether* t = GetTether(m, 0);
  // EnergyBound for fixed ends: elastic at max_strain, gravity over the length.
  Ends ends;
  const double bound = t->EnergyBound(ends, ends);
  // Node 17 moving sideways with 100 times the bound (9e4 m/s).
  double* v = const_cast<double*>(NodeVelocities(m, d, 0));
  v[3 * 17 + 1] = std::sqrt(2 * 100 * bound / t->node_mass(17));
  mj_step(m, d);
  std::optional<std::string> message = CheckDivergence(m, d);
  ASSERT_TRUE(message);
  EXPECT_TRUE(Contains(*message, "at node 17 of 41 (kinetic energy blow-up)")) << *message;
  EXPECT_TRUE(Contains(*message, "Reduce <option timestep>")) << *message;
  // The other implicit schemes are offered to implicit2 only (the next test).
  EXPECT_FALSE(Contains(*message, "integrator=bdf2")) << *message;
}

// Scene fuzzer seed 9828: 50 segments of 9 cm of a 5.3 mm line whose bending is stiffer than
// its segments' axial stiffness (EI 195 N m^2, EA = EAc = 1.1e4 N: EI/(EA L0^2) = 2.1), hanging
// from a fixed point to a 62 kg vehicle. Until session 40 implicit2 stopped on it at 1, 0.5 and
// 0.2 ms; with its held force the mean of its stages (plugin.cc, HeldMean) it runs. With EI
// 400 N m^2 (EI/(EA L0^2) = 4.4) implicit2 still stops at 1, 0.5 and 0.2 ms, so a smaller step
// is not the cure: the message offers bdf2 and implicit, and both run that scene for 1 s at
// 1 ms without a stop.
std::string StiffBendingXml(const std::string& integrator, const char* EI = "400") {
  return R"(<mujoco><option timestep="0.001"/><custom>
<text name="water" data="density=1025 seabed=-22.26191359"/>
<text name="vehicle:rov" data="volume=0.06141264348 cob=0,0,0.03964731087 added_mass=34.97415707,34.67230522,44.44549201,0.4898224484,0.4898224484,0.4898224484 linear_damping=57.53726373,57.53726373,57.53726373,1.632741495,1.632741495,1.632741495 quadratic_damping=80.56034955,80.56034955,80.56034955,1.632741495,1.632741495,1.632741495 coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=4.509174033 segments=50 diameter=0.005319332508 mass_per_length=0.02990473424 EA=11259.58792 Cdn=1.2 Cdt=0.01 Can=1 integrator=)" +
         integrator + R"( EI=)" + EI + R"( EAc=11259.58792"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="0.7328520468 -0.6478611772 -2.236035756"><freejoint/><inertial pos="0 0 0" mass="62.32197507" diaginertia="1.632741495 1.632741495 1.632741495"/><site name="att"/></body>
</worldbody></mujoco>)";
}

TEST_F(Scene, Implicit2StoppedWhereTheOtherImplicitSchemesRunIsToldToUseThem) {
  mjModel* m = Load(StiffBendingXml("implicit2"), "scene9828_EI400.xml");
  std::optional<std::string> stop = testing::StepUntilDivergence(m, Make(m), 1);
  ASSERT_TRUE(stop) << "implicit2 ran 1 s at 1 ms";
  EXPECT_TRUE(Contains(*stop, "Reduce <option timestep> (now 0.001 s)")) << *stop;
  EXPECT_TRUE(Contains(*stop, "or use integrator=bdf2 (the default) or implicit")) << *stop;
  for (const char* other : {"bdf2", "implicit"}) {
    mjModel* o = Load(StiffBendingXml(other), std::string("scene9828_") + other + ".xml");
    mjData* d = Make(o);
    const std::optional<std::string> other_stop = testing::StepUntilDivergence(o, d, 1);
    EXPECT_FALSE(other_stop) << other << ": " << *other_stop;
    EXPECT_NEAR(d->time, 1, 1e-9) << other;
  }
}

// Seed 9828 as drawn (EI 195 N m^2): implicit2 at 1 ms runs 1 s and its end tensions at 1 s
// agree with bdf2's at 0.1 ms within 1%, the issue's criterion (measured 0.03%).
TEST_F(Scene, Implicit2RunsSeed9828AsDrawn) {
  mjModel* m = Load(StiffBendingXml("implicit2", "195.3971797"), "scene9828.xml");
  // The reference loaded at its own step (its coupling is chosen at load: StepWarnings).
  std::string fine_xml = StiffBendingXml("bdf2", "195.3971797");
  const std::string coarse_step = "timestep=\"0.001\"";
  fine_xml.replace(fine_xml.find(coarse_step), coarse_step.size(), "timestep=\"0.0001\"");
  mjModel* fine = Load(fine_xml, "scene9828_fine.xml");
  ASSERT_TRUE(m && fine);
  ASSERT_EQ(fine->opt.timestep, 1e-4);
  mjData* d = Make(m);
  mjData* f = Make(fine);
  const std::optional<std::string> stop = testing::StepUntilDivergence(m, d, 1);
  ASSERT_FALSE(stop) << *stop;
  ASSERT_FALSE(testing::StepUntilDivergence(fine, f, 1));
  const EndReactions r = GetReactions(m, d, 0), rf = GetReactions(fine, f, 0);
  EXPECT_NEAR(r.tension_a, rf.tension_a, 0.01 * rf.tension_a);
  EXPECT_NEAR(r.tension_b, rf.tension_b, 0.01 * rf.tension_b);
}

// ---------------------------------------------------------------------------------------------
// Bad input through the command line: exit code 2 and a message naming the file, the element,
// the key and the allowed range. One case per class of error, for tethers and for the water.

int RunCli(const std::string& args, std::string* output) {
  const std::string out = ::testing::TempDir() + "/robust_cli_" + std::to_string(getpid());
  const int status = std::system(
      (std::string(MJTETHER_CLI) + " " + args + " > " + out + " 2>&1 < /dev/null").c_str());
  std::ifstream f(out);
  std::stringstream s;
  s << f.rdbuf();
  *output = s.str();
  std::remove(out.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

const char* kGoodTether =
    "ends=a,b length=10 segments=10 diameter=0.02 mass_per_length=0.5 EA=1e5 EI=0.1 "
    "damping=5 Cdn=1.2 Cdt=0.01 Can=1";
const char* kGoodWater = "density=1025 current=0.3,0,0 seabed=-20";

struct BadInput {
  const char* name;     // test name
  std::string water;    // text of <text name="water">; empty: none
  std::string tether;   // text of <text name="tether:u">
  const char* element;  // the element the message must name
  const char* key;      // the key it must name ('' quoted), or empty
  const char* allowed;  // the allowed range or values it must give
  std::string sites = R"(<site name="a"/><site name="b" pos="8 0 0"/>)";
};

std::string Replace(std::string text, const std::string& what, const std::string& by) {
  const size_t at = text.find(what);
  EXPECT_NE(at, std::string::npos) << what;
  if (at != std::string::npos) text.replace(at, what.size(), by);
  return text;
}
std::string BadTether(const std::string& what, const std::string& by) {
  return Replace(kGoodTether, what, by);
}
std::string BadWater(const std::string& what, const std::string& by) {
  return Replace(kGoodWater, what, by);
}

class CliBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(CliBadInput, ExitsWith2NamingFileElementKeyAndRange) {
  const BadInput& c = GetParam();
  const std::string path = ::testing::TempDir() + "/bad_" + c.name + ".xml";
  {
    std::ofstream f(path);
    f << "<mujoco><custom>";
    if (!c.water.empty()) f << "<text name=\"water\" data=\"" << c.water << "\"/>";
    f << "<text name=\"tether:u\" data=\"" << c.tether << "\"/></custom><worldbody>" << c.sites
      << "</worldbody></mujoco>";
  }
  for (const char* command : {"info ", "run "}) {
    std::string output;
    const std::string args = command + path + (command[0] == 'r' ? " --duration 0.01" : "");
    EXPECT_EQ(RunCli(args, &output), 2) << output;
    EXPECT_TRUE(Contains(output, path + ": <text name=\"" + c.element + "\">")) << output;
    if (*c.key) {
      EXPECT_TRUE(Contains(output, std::string("'") + c.key + "'")) << output;
    }
    EXPECT_TRUE(Contains(output, c.allowed)) << output;
    EXPECT_EQ(std::count(output.begin(), output.end(), '\n'), 1) << "one line: " << output;
  }
}

std::string BadName(const ::testing::TestParamInfo<BadInput>& info) { return info.param.name; }

INSTANTIATE_TEST_SUITE_P(
    Tether, CliBadInput,
    ::testing::Values(
        BadInput{"missing_key", kGoodWater, BadTether("EA=1e5 ", ""), "tether:u", "EA",
                 "missing required key"},
        BadInput{"unknown_key", kGoodWater, std::string(kGoodTether) + " colour=red", "tether:u",
                 "colour", "allowed keys: ends, length"},
        BadInput{"not_a_number", kGoodWater, BadTether("length=10", "length=ten"), "tether:u",
                 "length", "not a number"},
        BadInput{"nan", kGoodWater, BadTether("diameter=0.02", "diameter=nan"), "tether:u",
                 "diameter", "not a finite number"},
        BadInput{"infinity", kGoodWater, BadTether("mass_per_length=0.5", "mass_per_length=inf"),
                 "tether:u", "mass_per_length", "not a finite number"},
        BadInput{"negative", kGoodWater, BadTether("damping=5", "damping=-5"), "tether:u",
                 "damping", "[0, 1e+12]"},
        BadInput{"zero", kGoodWater, BadTether("EA=1e5", "EA=0"), "tether:u", "EA", "(0, 1e+13]"},
        BadInput{"negative_EAc", kGoodWater, std::string(kGoodTether) + " EAc=-1e5", "tether:u",
                 "EAc", "(0, 1e+13]"},
        BadInput{"huge_segments", kGoodWater, BadTether("segments=10", "segments=1e9"), "tether:u",
                 "segments", "[1, 100000]"},
        BadInput{"fractional_segments", kGoodWater, BadTether("segments=10", "segments=10.5"),
                 "tether:u", "segments", "whole number"},
        BadInput{"huge_coefficient", kGoodWater, BadTether("Cdn=1.2", "Cdn=1e9"), "tether:u", "Cdn",
                 "[0, 100]"},
        BadInput{"bad_word", kGoodWater, std::string(kGoodTether) + " integrator=rk5", "tether:u",
                 "integrator", "bdf2 (default), implicit, implicit2, explicit, rk4"},
        BadInput{"missing_site", kGoodWater, BadTether("ends=a,b", "ends=a,c"), "tether:u", "ends",
                 "no site named 'c'"},
        BadInput{"same_site_twice", kGoodWater, BadTether("ends=a,b", "ends=b,b"), "tether:u",
                 "ends", "both ends are on site 'b'"},
        BadInput{"one_site", kGoodWater, BadTether("ends=a,b", "ends=a"), "tether:u", "ends",
                 "two site names A,B"},
        BadInput{"malformed_pair", kGoodWater, BadTether("EI=0.1", "EI 0.1"), "tether:u", "",
                 "'EI' is not of the form key=value"},
        BadInput{"empty_value", kGoodWater, BadTether("EI=0.1", "EI="), "tether:u", "EI",
                 "needs both a key and a value"},
        BadInput{"duplicate_key", kGoodWater, std::string(kGoodTether) + " EA=2e5", "tether:u",
                 "EA", "given twice"},
        BadInput{"exclusive_keys", kGoodWater,
                 std::string(kGoodTether) + " substeps=2 max_step=0.001", "tether:u", "substeps",
                 "exclude each other"},
        BadInput{"effect_not_available", "", std::string(kGoodTether) + " effects=axial,drag",
                 "tether:u", "effects", "needs a water declaration"},
        BadInput{"absurd_explicit_substeps", kGoodWater,
                 Replace(BadTether("segments=10", "segments=1000"), "EA=1e5", "EA=1e13") +
                     " integrator=explicit",
                 "tether:u", "", "more than 100000"}),
    BadName);

INSTANTIATE_TEST_SUITE_P(
    Water, CliBadInput,
    ::testing::Values(BadInput{"water_unknown_key", std::string(kGoodWater) + " salinity=35",
                               kGoodTether, "water", "salinity", "allowed keys: density"},
                      BadInput{"water_not_a_number", BadWater("density=1025", "density=x"),
                               kGoodTether, "water", "density", "not a number"},
                      BadInput{"water_nan", BadWater("seabed=-20", "seabed=nan"), kGoodTether,
                               "water", "seabed", "not a finite number"},
                      BadInput{"water_infinity", BadWater("current=0.3,0,0", "current=inf,0,0"),
                               kGoodTether, "water", "current", "not a finite number"},
                      BadInput{"water_negative", std::string(kGoodWater) + " seabed_friction=-1",
                               kGoodTether, "water", "seabed_friction", "[0, 10]"},
                      BadInput{"water_zero", BadWater("density=1025", "density=0"), kGoodTether,
                               "water", "density", "(0, 10000]"},
                      BadInput{"water_huge", BadWater("current=0.3,0,0", "current=1e6,0,0"),
                               kGoodTether, "water", "current", "[-1000, 1000]"},
                      BadInput{"water_short_vector", BadWater("current=0.3,0,0", "current=0.3,0"),
                               kGoodTether, "water", "current", "3 numbers"},
                      BadInput{"water_malformed", std::string(kGoodWater) + " seabed", kGoodTether,
                               "water", "", "'seabed' is not of the form key=value"},
                      BadInput{"water_seabed_keys_without_seabed",
                               BadWater("seabed=-20", "seabed_stiffness=1e5"), kGoodTether, "water",
                               "seabed", "no 'seabed' height"}),
    BadName);

// MuJoCo's own checks cover names given twice (two tethers of one name, two water texts, two
// sites of one name): exit code 2 and MuJoCo's message naming the file and the name.
TEST(CliBadInputMuJoCo, DuplicateNamesExitWith2) {
  const std::string path = ::testing::TempDir() + "/bad_duplicates.xml";
  const std::string tether = std::string("<text name=\"tether:u\" data=\"") + kGoodTether + "\"/>";
  const std::string sites = R"(<site name="a"/><site name="b" pos="8 0 0"/>)";
  struct Case {
    std::string custom, sites, name;
  };
  for (const Case& c :
       {Case{tether + tether, sites, "tether:u"},
        Case{"<text name=\"water\" data=\"density=1\"/><text name=\"water\" data=\"density=2\"/>" +
                 tether,
             sites, "water"},
        Case{tether, sites + R"(<site name="b" pos="1 0 0"/>)", "b"}}) {
    std::ofstream(path) << "<mujoco><custom>" << c.custom << "</custom><worldbody>" << c.sites
                        << "</worldbody></mujoco>";
    std::string output;
    EXPECT_EQ(RunCli("info " + path, &output), 2) << output;
    EXPECT_TRUE(Contains(output, path)) << output;
    EXPECT_TRUE(Contains(output, "repeated name")) << output;
    EXPECT_TRUE(Contains(output, "Object name = " + c.name)) << output;
  }
}

// A file that is not MJCF, and one that does not exist.
TEST(CliBadInputMuJoCo, MalformedXmlAndMissingFileExitWith2) {
  const std::string path = ::testing::TempDir() + "/bad_xml.xml";
  std::ofstream(path) << "<mujoco><custom><text name=\"tether:u\" data=\"ends=a,b\"></mujoco>";
  std::string output;
  EXPECT_EQ(RunCli("run " + path + " --duration 1", &output), 2) << output;
  EXPECT_TRUE(Contains(output, path + ": XML parse error")) << output;
  EXPECT_EQ(RunCli("run /nonexistent/model.xml --duration 1", &output), 2) << output;
  EXPECT_TRUE(Contains(output, "/nonexistent/model.xml")) << output;
}

// The advisor's warning is printed by the command line; the run goes on (and here diverges,
// exit code 1, with the divergence message).
TEST(CliAdvisor, WarningIsPrintedAndDivergenceExitsWith1) {
  const std::string path = ::testing::TempDir() + "/advisor.xml";
  std::ofstream(path) << LineXml("integrator=explicit substeps=1");
  std::string output;
  EXPECT_EQ(RunCli("run " + path + " --duration 1", &output), 1) << output;
  EXPECT_TRUE(Contains(output, "mjtether: warning: " + path + ": <text name=\"tether:line\">"))
      << output;
  EXPECT_TRUE(Contains(output, "tether 'line' diverged at t = ")) << output;
}

// ---------------------------------------------------------------------------------------------
// Concurrency

std::string ReadModel(const char* file) {
  std::ifstream f(std::string(MJTETHER_MODELS_DIR) + "/" + file);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A second scene with an explicit tether in a current, hanging a free vehicle.
const char* kExplicitScene = R"(<mujoco><option timestep="0.002"/>
  <custom><text name="water" data="current=0.5,0.2,0"/>
    <text name="tether:t" data="ends=top,hook length=6 segments=12 diameter=0.02
          mass_per_length=0.8 EA=1e5 EI=0.2 damping=20 Cdn=1.2 Cdt=0.02 Can=1
          integrator=explicit"/></custom>
  <worldbody><site name="top" pos="0 0 0"/>
    <body name="v" pos="2 0 -5"><freejoint/><geom type="sphere" size="0.2" mass="20"/>
      <site name="hook"/></body></worldbody></mujoco>)";

// Two models and four mjData stepped from four threads at once give the same results, bit for
// bit, as the same runs one after another (the callback keeps all state in mjData and takes
// scratch memory from mjData's stack).
TEST_F(Scene, FourThreadsMatchSequentialRunsBitForBit) {
  mjModel* models[2] = {Load(ReadModel("rov_tether.xml"), "rov.xml"),
                        Load(kExplicitScene, "explicit.xml")};
  ASSERT_TRUE(models[0] && models[1]);
  const int steps = 1500;
  // Different initial velocities so that the four runs differ.
  auto start = [&](int k) {
    mjModel* m = models[k % 2];
    mjData* d = Make(m);
    d->qvel[0] = 0.1 * k;
    return d;
  };
  auto run = [&](int k, mjData* d) {
    for (int s = 0; s < steps; ++s) mj_step(models[k % 2], d);
  };
  std::vector<mjData*> sequential, parallel;
  for (int k = 0; k < 4; ++k) {
    sequential.push_back(start(k));
    run(k, sequential.back());
  }
  for (int k = 0; k < 4; ++k) parallel.push_back(start(k));
  std::vector<std::thread> threads;
  for (int k = 0; k < 4; ++k) threads.emplace_back(run, k, parallel[k]);
  for (std::thread& t : threads) t.join();
  for (int k = 0; k < 4; ++k) {
    const mjModel* m = models[k % 2];
    const mjData* a = sequential[k];
    const mjData* b = parallel[k];
    EXPECT_FALSE(CheckDivergence(m, a));
    EXPECT_EQ(std::memcmp(a->qpos, b->qpos, sizeof(mjtNum) * m->nq), 0) << "run " << k;
    EXPECT_EQ(std::memcmp(a->qvel, b->qvel, sizeof(mjtNum) * m->nv), 0) << "run " << k;
    EXPECT_EQ(std::memcmp(a->userdata, b->userdata, sizeof(mjtNum) * m->nuserdata), 0)
        << "run " << k;
  }
  // The runs really differ from each other (so the comparison could fail).
  EXPECT_NE(std::memcmp(sequential[0]->qpos, sequential[2]->qpos, sizeof(mjtNum) * models[0]->nq),
            0);
}

// ---------------------------------------------------------------------------------------------
// A long run of the default scene: 2 simulated minutes by default, one hour with
// MJTETHER_LONG=1 (CTest label "long").

long ResidentKiB() {
  std::ifstream f("/proc/self/statm");
  long size = 0, resident = 0;
  f >> size >> resident;
  return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

// Energy and tension stay bounded, and neither grows from the first half of the run (after a
// 30 s transient) to the second: the second half's largest tension and largest tether +
// vehicle energy are at most 10% above the first half's (the scene settles into a steady swing
// down current, so an honest run repeats itself; a slow numerical instability would grow).
// Tension never exceeds the energy-balance bound of the vehicle's catch (below). Memory is
// flat: mjData's stack high-water mark does not move after the first second and the process's
// resident size grows by less than 1 MiB.
TEST_F(Scene, DefaultSceneLongRunIsBoundedWithFlatMemory) {
  const char* env = std::getenv("MJTETHER_LONG");
  const double duration = env && std::string(env) == "1" ? 3600 : 120;
  mjModel* m = Load(ReadModel("rov_tether.xml"), "rov_tether.xml");
  mjData* d = Make(m);
  const int k = FindTether(m, "umbilical");
  const Tether* t = GetTether(m, k);
  const int rov = mj_name2id(m, mjOBJ_BODY, "rov");
  const double M = m->body_mass[rov], g = 9.81;
  // Catch bound: the vehicle (no buoyancy in MuJoCo 2.2) can fall at most from its start to
  // the TMS's depth minus the tether length, h <= 18 m; energy balance against the tether's
  // spring k = EA/L gives the stretch d with k d^2/2 = M g (h + d) and T = k d. The current
  // also does work on the vehicle; we add a factor 1.5 for it.
  const double kspring = t->params().EA / t->params().length, h = 18;
  const double stretch = (M * g + std::sqrt(M * g * M * g + 2 * kspring * M * g * h)) / kspring;
  const double tension_bound = 1.5 * kspring * stretch;
  std::vector<double> T(t->segments());
  double tmax[2] = {0, 0}, emax[2] = {0, 0};
  long stack_after_1s = -1, rss_after_1s = 0;
  while (d->time < duration) {
    mj_step(m, d);
    ASSERT_FALSE(CheckDivergence(m, d)) << *CheckDivergence(m, d);
    if (stack_after_1s < 0 && d->time >= 1) {
      stack_after_1s = d->maxuse_stack;
      rss_after_1s = ResidentKiB();
    }
    if (d->time < 30) continue;
    const int half = d->time < 30 + (duration - 30) / 2 ? 0 : 1;
    GetTensions(m, d, k, T.data());
    tmax[half] = std::max(tmax[half], *std::max_element(T.begin(), T.end()));
    const double* x = NodePositions(m, d, k);
    const double* v = NodeVelocities(m, d, k);
    Ends ends;  // potential energy without clamps: ends unused
    const double vehicle =
        0.5 * M * (d->qvel[0] * d->qvel[0] + d->qvel[1] * d->qvel[1] + d->qvel[2] * d->qvel[2]) +
        M * g * d->qpos[2];
    const double energy = t->KineticEnergy(x, v) + t->PotentialEnergy(x, ends) + vehicle;
    // Energies are negative (below z = 0); compare magnitudes above the lowest possible state.
    const double lowest = -M * g * (10.5 + 20 * 1.1);
    emax[half] = std::max(emax[half], energy - lowest);
  }
  EXPECT_LT(tmax[0], tension_bound);
  EXPECT_LT(tmax[1], tension_bound);
  EXPECT_LE(tmax[1], 1.1 * tmax[0]) << "first half " << tmax[0] << " N, second " << tmax[1];
  EXPECT_LE(emax[1], 1.1 * emax[0]) << "first half " << emax[0] << " J, second " << emax[1];
  EXPECT_EQ(d->maxuse_stack, stack_after_1s);
  EXPECT_LT(ResidentKiB() - rss_after_1s, 1024);
  std::printf(
      "simulated %.0f s: max tension %.1f / %.1f N (bound %.0f N), energy above "
      "floor %.1f / %.1f J, stack %ld doubles, RSS %+ld KiB\n",
      duration, tmax[0], tmax[1], tension_bound, emax[0], emax[1],
      static_cast<long>(d->maxuse_stack), ResidentKiB() - rss_after_1s);
}

}  // namespace
}  // namespace mjtether
