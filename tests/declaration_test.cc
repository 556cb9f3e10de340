// Tests of the declaration parser: every class of bad input gets a message naming the key
// and, for numbers, the allowed range.
#include <cmath>

#include <gtest/gtest.h>

#include <ostream>

#include "declaration.h"
#include "param_name.h"

namespace mjtether {
namespace {

const char* kExample =
    "ends=tms_port,rov_attach length=40 segments=40\n"
    "            diameter=0.02 mass_per_length=0.35 EA=2e5 EAc=2e5 EI=0.5 damping=50\n"
    "            Cdn=1.2 Cdt=0.01 Can=1.0 integrator=implicit";

Environment Wet() {
  Environment env;
  env.wet = true;
  env.water.current = Vec3(0.3, 0, 0);
  env.water.has_seabed = true;
  env.water.seabed = -60;
  return env;
}

TEST(Declaration, ParsesTheDocumentedExample) {
  DeclarationError e;
  std::optional<TetherDeclaration> d = ParseTether(kExample, Wet(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(d->site_a, "tms_port");
  EXPECT_EQ(d->site_b, "rov_attach");
  EXPECT_EQ(d->params.segments, 40);
  EXPECT_DOUBLE_EQ(d->params.EA, 2e5);
  EXPECT_DOUBLE_EQ(d->params.EAc, 2e5);
  EXPECT_DOUBLE_EQ(d->params.EI, 0.5);
  EXPECT_DOUBLE_EQ(d->params.Can, 1.0);
  EXPECT_EQ(d->params.integrator, Integrator::kImplicit);
  // Every effect the declaration calls for, and no clamp.
  EXPECT_EQ(EffectsToString(d->params.effects),
            "axial,damping,bending,weight,buoyancy,drag,added_mass,current,seabed,compression");
}

TEST(Declaration, DryScenesHaveNoHydrodynamics) {
  DeclarationError e;
  Environment dry;
  std::optional<TetherDeclaration> d = ParseTether(kExample, dry, &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(EffectsToString(d->params.effects), "axial,damping,bending,weight,compression");
}

TEST(Declaration, ZeroCoefficientsTurnEffectsOff) {
  DeclarationError e;
  std::optional<TetherDeclaration> d = ParseTether(
      "ends=a,free length=1 segments=1 diameter=0.01 mass_per_length=0.1 EA=1e3 EI=0 "
      "damping=0 Cdn=0 Cdt=0 Can=0",
      Wet(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_TRUE(d->params.free_end);
  EXPECT_EQ(EffectsToString(d->params.effects), "axial,weight,buoyancy,seabed");
}

TEST(Declaration, ExplicitEffectsReplaceDefaults) {
  DeclarationError e;
  std::optional<TetherDeclaration> d =
      ParseTether(std::string(kExample) + " effects=axial,drag", Wet(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(d->params.effects, unsigned(kAxial | kDrag));
}

struct BadCase {
  const char* what;
  std::string text;
  const char* key;       // the key the message must name
  const char* fragment;  // and a fragment it must contain (the range, the allowed values)
};
void PrintTo(const BadCase& c, std::ostream* os) { *os << c.what << ": " << c.text; }

class BadTether : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadTether, IsRejectedWithKeyAndRange) {
  const BadCase& c = GetParam();
  DeclarationError e;
  EXPECT_FALSE(ParseTether(c.text, Wet(), &e)) << c.what;
  EXPECT_EQ(e.key, c.key) << c.what << ": " << e.message;
  EXPECT_NE(e.message.find(c.key), std::string::npos) << e.message;
  EXPECT_NE(e.message.find(c.fragment), std::string::npos) << c.what << ": " << e.message;
}

std::string With(const std::string& replace, const std::string& by) {
  std::string s = kExample;
  s.replace(s.find(replace), replace.size(), by);
  return s;
}

// EAc declares the compression effect (last in the list); without it there is none, and an
// effects= list without 'compression' turns it off.
TEST(Declaration, EAcTurnsCompressionOn) {
  DeclarationError e;
  std::optional<TetherDeclaration> d = ParseTether(With("EAc=2e5 ", ""), Environment(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(d->params.EAc, 0);
  EXPECT_EQ(EffectsToString(d->params.effects), "axial,damping,bending,weight");
  d = ParseTether(std::string(kExample) + " effects=axial,bending", Environment(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(d->params.effects, unsigned(kAxial | kBending));
}

INSTANTIATE_TEST_SUITE_P(
    Declaration, BadTether,
    ::testing::Values(
        BadCase{"unknown key", std::string(kExample) + " colour=red", "colour", "allowed keys"},
        BadCase{"not a number", With("EA=2e5", "EA=abc"), "EA", "not a number"},
        BadCase{"trailing junk", With("EA=2e5", "EA=2e5N"), "EA", "not a number"},
        BadCase{"NaN", With("EA=2e5", "EA=nan"), "EA", "not a finite number"},
        BadCase{"infinity", With("EA=2e5", "EA=inf"), "EA", "not a finite number"},
        BadCase{"overflow", With("EA=2e5", "EA=1e999"), "EA", "not a finite number"},
        BadCase{"negative", With("EA=2e5", "EA=-1"), "EA", "(0, 1e+13]"},
        BadCase{"zero where not allowed", With("length=40", "length=0"), "length", "(0, 100000]"},
        BadCase{"negative EI", With("EI=0.5", "EI=-0.5"), "EI", "[0, 1e+12]"},
        BadCase{"segments < 1", With("segments=40", "segments=0"), "segments", "[1, 100000]"},
        BadCase{"huge segments", With("segments=40", "segments=1e9"), "segments",
                "[1, 100000]"},
        BadCase{"fractional segments", With("segments=40", "segments=2.5"), "segments",
                "whole number"},
        BadCase{"missing key", With("EA=2e5 ", ""), "EA", "missing required key"},
        BadCase{"duplicate key", std::string(kExample) + " EA=3e5", "EA", "twice"},
        BadCase{"one end", With("ends=tms_port,rov_attach", "ends=tms_port"), "ends",
                "two site names"},
        BadCase{"same site twice", With("ends=tms_port,rov_attach", "ends=a,a"), "ends",
                "both ends"},
        BadCase{"free end A", With("ends=tms_port,rov_attach", "ends=free,b"), "ends",
                "only end B"},
        BadCase{"bad integrator", With("integrator=implicit", "integrator=rk9"), "integrator",
                "bdf2 (default), implicit, implicit2, explicit, rk4"},
        BadCase{"bad clamp", std::string(kExample) + " clamp=C", "clamp", "A, B, both"},
        BadCase{"clamp without EI", With("EI=0.5", "EI=0") + " clamp=A", "clamp", "EI > 0"},
        BadCase{"clamp a free end",
                With("ends=tms_port,rov_attach", "ends=a,free") + " clamp=B", "clamp",
                "free"},
        BadCase{"unknown effect", std::string(kExample) + " effects=axial,magic", "effects",
                "allowed"},
        BadCase{"effect without coefficient", With("EI=0.5", "EI=0") + " effects=axial,bending",
                "effects", "EI > 0"},
        BadCase{"no axial", std::string(kExample) + " effects=drag", "effects", "axial"},
        BadCase{"EAc not a number", With("EAc=2e5", "EAc=stiff"), "EAc",
                "not a number"},
        BadCase{"EAc NaN", With("EAc=2e5", "EAc=nan"), "EAc", "not a finite number"},
        BadCase{"EAc zero", With("EAc=2e5", "EAc=0"), "EAc", "(0, 1e+13]"},
        BadCase{"EAc negative", With("EAc=2e5", "EAc=-2e5"), "EAc", "(0, 1e+13]"},
        BadCase{"EAc huge", With("EAc=2e5", "EAc=1e14"), "EAc", "(0, 1e+13]"},
        BadCase{"compression without EAc", With("EAc=2e5 ", "") + " effects=axial,compression",
                "effects", "EAc > 0"},
        BadCase{"damping ratio negative", With("damping=50", "damping_ratio=-0.1"),
                "damping_ratio", "[0, 10]"},
        BadCase{"damping ratio huge", With("damping=50", "damping_ratio=11"), "damping_ratio",
                "[0, 10]"},
        BadCase{"damping and damping ratio", With("damping=50", "damping=50 damping_ratio=1"),
                "damping_ratio", "exclude each other"}),
    [](const ::testing::TestParamInfo<BadCase>& info) {
      return testing::ParamName(info.param.what);
    });

// damping_ratio is the damping of the segment axial mode (MoorDyn's BA = -zeta): c = zeta L0
// sqrt(EA mu), here 0.5 x 1 m x sqrt(2e5 x 0.35) = 132.29 N s; 0 declares no damping effect.
TEST(Declaration, DampingRatioSetsTheSegmentModeDamping) {
  DeclarationError e;
  std::optional<TetherDeclaration> d =
      ParseTether(With("damping=50", "damping_ratio=0.5"), Wet(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_NEAR(d->params.damping, 0.5 * 1.0 * std::sqrt(2e5 * 0.35), 1e-9);
  EXPECT_DOUBLE_EQ(d->params.damping_ratio, 0.5);
  EXPECT_NE(d->params.effects & kDamping, 0u);
  d = ParseTether(With("damping=50", "damping_ratio=0"), Wet(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(d->params.damping, 0.0);
  EXPECT_EQ(d->params.effects & kDamping, 0u);
}

TEST(Declaration, MalformedTextIsRejected) {
  DeclarationError e;
  EXPECT_FALSE(ParseTether("ends=a,b length 40", Wet(), &e));
  EXPECT_NE(e.message.find("'length' is not of the form key=value"), std::string::npos)
      << e.message;
  EXPECT_FALSE(ParseTether("ends=a,b length=", Wet(), &e));
  EXPECT_NE(e.message.find("needs both a key and a value"), std::string::npos) << e.message;
}

TEST(Declaration, WaterKeysAreChecked) {
  DeclarationError e;
  std::optional<Water> w = ParseWater("density=1025 current=0.3,0,0 seabed=-60", &e);
  ASSERT_TRUE(w) << e.message;
  EXPECT_TRUE(w->has_seabed);
  EXPECT_DOUBLE_EQ(w->current.x(), 0.3);
  EXPECT_FALSE(ParseWater("current=0.3,0", &e));
  EXPECT_EQ(e.key, "current");
  EXPECT_FALSE(ParseWater("density=-1", &e));
  EXPECT_NE(e.message.find("(0, 10000]"), std::string::npos) << e.message;
  EXPECT_FALSE(ParseWater("seabed_friction=0.5", &e));
  EXPECT_EQ(e.key, "seabed");
  EXPECT_FALSE(ParseWater("salinity=35", &e));
  EXPECT_NE(e.message.find("allowed keys"), std::string::npos) << e.message;
}

}  // namespace
}  // namespace mjtether
