// Tests that close the holes the mutation catalogue (tools/mutations.cfg, docs/mutation.md)
// found: each checks one force term, end reaction or output against an independent reference
// (a closed form, a statics balance written out here from the declaration, or a boundary of a
// documented range), so that the planted bug named in its comment fails it.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "declaration.h"
#include "engine_sim.h"
#include "make_tether.h"
#include "mjtether.h"
#include "mjtether_vehicles.h"
#include "mujoco_fixture.h"
#include "tether.h"
#include "vehicle_declaration.h"

namespace mjtether {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kG = 9.81;

// engine_sim.h's tether with its state and workspace, its ends moved at a constant velocity.
struct Tow : Sim {
  using Sim::Sim;
  // Every node (and the ends) moving at u.
  void SetVelocity(const Vec3& u) {
    for (int i = 0; i < tether.nodes(); ++i) {
      for (int c = 0; c < 3; ++c) v[3 * i + c] = u[c];
    }
    ends.a.vel = ends.b.vel = u;
  }
  // Advances by `steps` steps of h with the attached ends moving at their velocities.
  bool Run(double h, int steps) {
    for (int k = 0; k < steps; ++k) {
      Ends to = ends;
      to.a.pos += h * ends.a.vel;
      to.b.pos += h * ends.b.vel;
      const StepStatus s = tether.Advance(x.data(), v.data(), ends, to, h, work.data());
      if (!s.ok) {
        ADD_FAILURE() << "step " << k << ", node " << s.node << ": " << s.reason;
        return false;
      }
      ends = to;
    }
    return true;
  }
};

Environment Water(bool gravity) {
  Environment env;
  env.wet = true;
  env.water.density = 1025;
  if (!gravity) env.gravity = Vec3::Zero();
  return env;
}

// ---------------------------------------------------------------------------------------------
// Tangential drag. A straight tether (free end B) towed along its own axis at U: every point
// moves at U along the tangent, so there is no normal drag and the towing force is the
// tangential Morison drag of the whole length (Morison et al. 1950 with the reference area
// pi d per length, as MoorDyn's Cdt):
//   F = 1/2 rho Cdt pi d U^2 L.
// The model integrates it over the stretched length, longer by the strain F/EA = 2e-5; after
// the start transient has decayed (2 s, 16 times the damping time 1/(zeta w) = 0.12 s of the
// first axial mode) the tow force is within 1e-3 of F. Catches a tangential drag without its
// pi (68% low) or 10% off.
class TowedAlongItsAxis : public ::testing::TestWithParam<Integrator> {};

TEST_P(TowedAlongItsAxis, TowForceIsTheClosedFormTangentialDrag) {
  TetherParams p;
  p.length = 10;
  p.segments = 20;
  p.diameter = 0.02;
  p.mass_per_length = 0.3;
  p.EA = 1e6;
  p.damping = 200;
  p.Cdn = 1.2;
  p.Cdt = 0.05;
  p.free_end = true;
  p.integrator = GetParam();
  const Environment env = Water(false);  // no weight: the line stays on its axis
  Tow s(Make(p, env, "axial,damping,drag"));
  const double U = 1;              // [m/s]
  s.ends.a.axis = Vec3(-1, 0, 0);  // the line trails behind end A, along -x
  s.tether.InitialShape(s.ends, s.x.data(), s.v.data());
  s.SetVelocity(Vec3(U, 0, 0));
  ASSERT_TRUE(s.Run(0.002, 1000));
  const double F = 0.5 * env.water.density * p.Cdt * kPi * p.diameter * U * U * p.length;
  const EndReactions r = s.Reactions();
  std::printf("%s: tow force %.6g N, closed form %.6g N\n", IntegratorName(GetParam()), r.tension_a,
              F);
  EXPECT_NEAR(r.tension_a / F, 1, 1e-3);
  EXPECT_NEAR(r.force_a.x(), -F, 1e-3 * F);  // drag pulls end A back
}

// The same tow with backward Euler at a step 250 times longer (0.5 s): the steady tow is a
// fixed point of the scheme, so the force is the same closed form. The step is 5 times the
// explicit limit of the tangential drag (2 / (2 kt U l_i / m_i) = 0.19 s): only the drag's
// Jacobian in the Newton solve keeps it stable. Catches a Jacobian without its tangential
// block.
TEST(Holes, TowedAlongItsAxisAtALongImplicitStep) {
  TetherParams p;
  p.length = 10;
  p.segments = 20;
  p.diameter = 0.02;
  p.mass_per_length = 0.3;
  p.EA = 1e6;
  p.damping = 200;
  p.Cdn = 1.2;
  p.Cdt = 0.05;
  p.free_end = true;
  const Environment env = Water(false);
  Tow s(Make(p, env, "axial,damping,drag"));
  const double U = 1;
  s.ends.a.axis = Vec3(-1, 0, 0);
  s.tether.InitialShape(s.ends, s.x.data(), s.v.data());
  s.SetVelocity(Vec3(U, 0, 0));
  ASSERT_TRUE(s.Run(0.5, 40));
  const double F = 0.5 * env.water.density * p.Cdt * kPi * p.diameter * U * U * p.length;
  EXPECT_NEAR(s.Reactions().tension_a / F, 1, 1e-3);
}

// Added mass acts normal to the tether only (Morison's inertia of the displaced water; along a
// slender line it is negligible). A tether with Can = 1 (free end B, no drag, no gravity)
// accelerated along its axis at a from rest: once the start transient has decayed (2 s, 16
// damping times of the first axial mode), end A pulls the dry mass of the rest of the line
// only, mu (L - L0/2) a = 2.93 N; with added mass along the axis as well it would pull
// (mu + Can rho pi d^2/4) (L - L0/2) a = 6.0 N.
// Tolerance 1e-3: the residual of the transient.
TEST(Holes, AddedMassDoesNotActAlongTheAxis) {
  TetherParams p;
  p.length = 10;
  p.segments = 20;
  p.diameter = 0.02;
  p.mass_per_length = 0.3;
  p.EA = 1e6;
  p.damping = 200;
  p.Can = 1;
  p.free_end = true;
  Tow s(Make(p, Water(false), "axial,damping,added_mass"));
  const double a = 1;  // [m/s^2]
  s.ends.a.axis = Vec3(-1, 0, 0);
  s.tether.InitialShape(s.ends, s.x.data(), s.v.data());
  const double h = 0.002;
  for (int k = 0; k < 1000; ++k) {
    Ends to = s.ends;
    const double t1 = (k + 1) * h;
    to.a.pos = Vec3(0.5 * a * t1 * t1, 0, 0);
    to.a.vel = Vec3(a * t1, 0, 0);
    const StepStatus st = s.tether.Advance(s.x.data(), s.v.data(), s.ends, to, h, s.work.data());
    ASSERT_TRUE(st.ok) << st.reason;
    s.ends = to;
  }
  // End A's own node (half a segment) moves with the site: the pull accelerates the rest.
  const double T = p.mass_per_length * (p.length - 0.5 * p.length / p.segments) * a;
  EXPECT_NEAR(s.Reactions().tension_a / T, 1, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(Holes, TowedAlongItsAxis,
                         ::testing::Values(Integrator::kImplicit, Integrator::kExplicit),
                         [](const ::testing::TestParamInfo<Integrator>& i) {
                           return std::string(IntegratorName(i.param));
                         });

// ---------------------------------------------------------------------------------------------
// Anisotropic seabed friction. A tether lying straight on the seabed between two ends that
// move together at U, first along its axis and then across it, until it slides steadily.
// Steady sliding: the interior nodes carry no net force, so the sum of the two end reactions
// is the sum of the loads: weight, seabed normal force N and friction. Its horizontal part is
// the friction, -mu tanh(U/eps) sum N along the motion (Coulomb, smoothed over eps), and its
// vertical part sum N - w L with w the wet weight per length from the declaration. So
//   mu = -(Fa + Fb).u / (((Fa + Fb).z + w L) tanh(U/eps))
// must be the along-line coefficient when dragged along and the cross-line one when dragged
// across. Tolerance 1% (the slide is steady to 1e-4 after 20 s; the along/across
// coefficients differ by a factor 3). Catches the two coefficients swapped, one taking the
// other's value, or the along-line one halved.
TEST(Holes, SeabedFrictionAlongAndAcrossFollowTheirOwnCoefficients) {
  TetherParams p;
  p.length = 10;
  p.segments = 20;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e5;
  p.damping = 100;
  Environment env = Water(true);
  env.water.has_seabed = true;
  env.water.seabed = 0;
  env.water.seabed_friction = 0.6;        // across
  env.water.seabed_friction_axial = 0.2;  // along
  const double area = kPi * p.diameter * p.diameter / 4;
  const double w = (p.mass_per_length - env.water.density * area) * kG;  // [N/m] wet weight
  const double pen = w / env.water.seabed_stiffness;                     // [m] resting penetration
  const double U = 0.2, eps = env.water.seabed_friction_speed;
  for (int across = 0; across < 2; ++across) {
    Tow s(Make(p, env, "axial,damping,weight,buoyancy,seabed"));
    s.ends.a.pos = Vec3(0, 0, -pen);
    s.ends.b.pos = Vec3(p.length, 0, -pen);
    s.tether.InitialShape(s.ends, s.x.data(), s.v.data());
    const Vec3 u = across ? Vec3(0, 1, 0) : Vec3(1, 0, 0);
    s.ends.a.vel = s.ends.b.vel = U * u;
    ASSERT_TRUE(s.Run(0.005, 4000));
    const EndReactions r = s.Reactions();
    const Vec3 F = r.force_a + r.force_b;
    const double N = F.z() + w * p.length;
    const double mu = -F.dot(u) / (N * std::tanh(U / eps));
    const double expected = across ? env.water.seabed_friction : env.water.seabed_friction_axial;
    std::printf("dragged %s: mu %.5f (declared %.2f), sum N %.4g N of w L %.4g N\n",
                across ? "across" : "along", mu, expected, N, w * p.length);
    EXPECT_NEAR(mu, expected, 0.01 * expected) << (across ? "across" : "along");
    // Nearly all the weight rests on the seabed (the ends carry a little).
    EXPECT_NEAR(N, w * p.length, 0.1 * w * p.length);
  }
}

// ---------------------------------------------------------------------------------------------
// Net weight: a wet chain hanging still from a fixed end (end B free) hangs its whole net
// weight on the end, (m' - rho pi d^2/4) g L (Archimedes over the displaced volume of the
// whole length), here (1 - 0.322) 9.81 10 = 66.5 N. Static: the 1e-4 covers what is left of
// the settling (the stretch, 7e-5, moves no weight). Catches buoyancy or weight lumped wrongly
// at the end nodes or off by a constant.
TEST(Holes, WetChainHangsItsNetWeightOnItsEnd) {
  TetherParams p;
  p.length = 10;
  p.segments = 10;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e6;
  p.damping = 1e3;
  p.free_end = true;
  const Environment env = Water(true);
  Tow s(Make(p, env, "axial,damping,weight,buoyancy"));
  s.tether.InitialShape(s.ends, s.x.data(), s.v.data());
  ASSERT_TRUE(s.Run(0.005, 1000));
  const double area = kPi * p.diameter * p.diameter / 4;
  const double W = (p.mass_per_length - env.water.density * area) * kG * p.length;
  const EndReactions r = s.Reactions();
  EXPECT_NEAR(r.tension_a, W, 1e-4 * W);
  EXPECT_NEAR(r.force_a.z(), -W, 1e-4 * W);  // the chain pulls its end down
}

// The reported segment tension is the whole axial law, elastic and damping (Kelvin-Voigt,
// Buckham et al. 2003): one segment of rest length 1 m stretched by 1% and lengthening at
// 0.5 m/s carries EA 0.01 + (damping / L0) 0.5 = 100 + 50 N; shortened, it carries none.
TEST(Holes, ReportedTensionIsTheKelvinVoigtLaw) {
  TetherParams p;
  p.length = 1;
  p.segments = 1;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e4;
  p.damping = 100;
  const Tether t = Make(p, Environment(), "axial,damping");
  std::vector<double> x = {0, 0, 0, 1.01, 0, 0}, v = {0, 0, 0, 0.5, 0, 0}, T(1);
  t.Tensions(x.data(), v.data(), T.data());
  EXPECT_NEAR(T[0], 150, 1e-9);
  x[3] = 0.99;
  t.Tensions(x.data(), v.data(), T.data());
  EXPECT_EQ(T[0], 0);
}

// ---------------------------------------------------------------------------------------------
// The seabed under a line lying flat on it: each node is a mass on the seabed's spring and
// damper, mu l0 z'' = -k l0 (z - z_eq) - c l0 z', at rest at z_eq = -w/k (w the wet weight per
// length), with the default damping critical, c = 2 sqrt(k mu) (no added mass or drag here).
// Pressed to twice that depth and released from rest, a critically damped node returns as
// (1 + w0 t) e^(-w0 t), w0 = sqrt(k/mu) = 316 rad/s, without overshoot: it never rises above
// z_eq (1% of the penetration allows for the time discretisation at w0 h = 0.03) and is back
// at z_eq within 1% after 0.1 s (30 / w0). Catches the seabed stiffness or the default
// damping off.
TEST(Holes, SeabedUnderALineIsStiffAndCriticallyDamped) {
  TetherParams p;
  p.length = 10;
  p.segments = 10;
  p.diameter = 0.02;
  p.mass_per_length = 1;
  p.EA = 1e5;
  p.integrator = Integrator::kImplicit;
  Environment env = Water(true);
  env.water.has_seabed = true;
  env.water.seabed = 0;
  const double area = kPi * p.diameter * p.diameter / 4;
  const double w = (p.mass_per_length - env.water.density * area) * kG;  // [N/m]
  const double z_eq = -w / env.water.seabed_stiffness;
  Tow s(Make(p, env, "axial,weight,buoyancy,seabed"));
  s.ends.a.pos = Vec3(0, 0, z_eq);
  s.ends.b.pos = Vec3(p.length, 0, z_eq);
  s.tether.InitialShape(s.ends, s.x.data(), s.v.data());
  for (int i = 1; i < p.segments; ++i) s.x[3 * i + 2] = 2 * z_eq;
  double highest = -INFINITY;
  for (int k = 0; k < 1000; ++k) {
    ASSERT_TRUE(s.Run(1e-4, 1));
    for (int i = 1; i < p.segments; ++i) highest = std::max(highest, s.x[3 * i + 2]);
  }
  const int mid = p.segments / 2;
  std::printf("seabed: highest %.4g of z_eq %.4g m, at 0.1 s %.6g\n", highest, z_eq,
              s.x[3 * mid + 2]);
  EXPECT_LT(highest, z_eq - 0.01 * z_eq);  // z_eq < 0: no higher than 1% above it
  EXPECT_NEAR(s.x[3 * mid + 2], z_eq, -0.01 * z_eq);
}

// ---------------------------------------------------------------------------------------------
// The declaration parser's ranges, at their boundaries: the documented maximum is accepted and
// the next number above it refused; a bound written "(0, ..." refuses 0 itself. Catches
// ranges enforced more loosely than their messages say.
TEST(Holes, DeclaredRangesHoldAtTheirBoundaries) {
  Environment env = Water(true);
  const std::string base =
      "ends=a,b length=10 segments=10 diameter=0.02 mass_per_length=0.5 EA=1e5";
  auto ok = [&](const std::string& extra) {
    DeclarationError e;
    return ParseTether(base + " " + extra, env, &e).has_value();
  };
  struct Bound {
    const char* at_max;
    const char* above;
  };
  for (const Bound& b :
       {Bound{"Cdn=100", "Cdn=100.001"}, Bound{"Cdt=100", "Cdt=100.5"}, Bound{"Can=100", "Can=101"},
        Bound{"EI=1e12", "EI=1.01e12"}, Bound{"damping=1e12", "damping=2e12"},
        Bound{"max_strain=100", "max_strain=100.5"}, Bound{"max_step=1", "max_step=1.5"},
        Bound{"substeps=100000", "substeps=100001"}}) {
    EXPECT_TRUE(ok(b.at_max)) << b.at_max;
    EXPECT_FALSE(ok(b.above)) << b.above;
  }
  for (const char* zero : {"max_step=0", "max_strain=0", "EAc=0"}) {
    EXPECT_FALSE(ok(zero)) << zero;
  }
  DeclarationError e;
  EXPECT_FALSE(
      ParseTether("ends=a,b length=1e5 segments=100000 diameter=10 "
                  "mass_per_length=1e5 EA=1.1e13",
                  env, &e));
  EXPECT_TRUE(
      ParseTether("ends=a,b length=1e5 segments=100000 diameter=10 "
                  "mass_per_length=1e5 EA=1e13",
                  env, &e))
      << e.message;
  EXPECT_FALSE(ParseTether(base + " segments=10.5", env, &e).has_value());
  // The water: friction in [0, 10], density in (0, 1e4].
  EXPECT_TRUE(ParseWater("seabed=0 seabed_friction=10", &e).has_value());
  EXPECT_FALSE(ParseWater("seabed=0 seabed_friction=10.5", &e).has_value());
  EXPECT_FALSE(ParseWater("seabed=0 seabed_friction=-0.1", &e).has_value());
  EXPECT_FALSE(ParseWater("density=0", &e).has_value());
  EXPECT_TRUE(ParseWater("density=1e4", &e).has_value());
  EXPECT_FALSE(ParseWater("density=1.01e4", &e).has_value());
  // A vehicle's volume in [0, 1e4] m^3: a negative one would be a buoyancy that pulls down.
  EXPECT_TRUE(ParseVehicle("volume=0.05", &e).has_value());
  EXPECT_FALSE(ParseVehicle("volume=-0.05", &e).has_value());
  EXPECT_FALSE(ParseVehicle("volume=1.1e4", &e).has_value());
}

// A MuJoCo error during the run (here its stack overflows once eight boxes land on the floor
// and make contacts: <size nstack> fixes it too small for them, enough for the model at rest)
// exits with code 3 and MuJoCo's message, as the README's exit codes say.
TEST(Holes, MuJoCoErrorDuringARunExitsWith3) {
  const std::string tag = std::to_string(getpid());
  const std::string model = ::testing::TempDir() + "/mujoco_error_" + tag + ".xml";
  const std::string out = ::testing::TempDir() + "/mujoco_error_" + tag + ".txt";
  {
    std::ofstream f(model);
    f << R"(<mujoco><size nstack="1000"/><worldbody><geom type="plane" size="5 5 0.1"/>)";
    for (int i = 0; i < 8; ++i) {
      f << "<body pos=\"" << 0.25 * i << R"( 0 0.3"><freejoint/>)"
        << R"(<geom type="box" size="0.1 0.1 0.1"/></body>)";
    }
    f << "</worldbody></mujoco>";
  }
  const int status = std::system(
      (std::string(MJTETHER_CLI) + " run " + model + " --duration 1 > " + out + " 2>&1 < /dev/null")
          .c_str());
  std::ifstream f(out);
  std::stringstream text;
  text << f.rdbuf();
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 3) << text.str();
  EXPECT_NE(text.str().find("MuJoCo error"), std::string::npos) << text.str();
  std::remove(model.c_str());
  std::remove(out.c_str());
}

// ---------------------------------------------------------------------------------------------
// An ROV's static pitch in a current, against the statics of the rigid body (the lever arm of
// the tether's pull at its attachment site). The ROV (10 kg box, 0.0105 m^3: 0.5 kg buoyant,
// centre of buoyancy 0.15 m above the centre of gravity) is held against a 0.5 m/s current
// by a neutrally buoyant tether to a fixed anchor, attached at the front bottom edge
// (-0.3, 0, -0.15). At rest its linear damping in the body frame, D (u - v) with
// D = diag(40, 60, 20) N s/m, pushes it down-current, the tether pulls it forward and down at
// the site, and it pitches until the moments balance. With the tether's force F at the site
// s, buoyancy B = rho V g up at the centre of buoyancy c and the weight m g at the centre of
// gravity G, all written from the declaration:
//   force:  F + m g + B + R D R^T u = 0,
//   moment about G: (s - G) x F + (c - G) x B = 0   (damping acts at the origin = G).
// The body settles to |qvel| < 1e-7; the residuals are its inertia, 1e-4 N and 1e-5 N m
// bound them (F is 20 N, the moments 1.5 N m). The pitch also matches the angle at which the
// moment of the measured force about G is zero (bisection over the pitch: 1e-4 rad). Catches
// the reaction applied at the body's origin instead of the site (then the ROV does not
// pitch, and the moment of F about G is left over), a wrong buoyancy or centre of buoyancy,
// and damping in the wrong frame.
// The tether is declared both ways (the ROV at end B, then at end A), so that each end's
// reaction and lever arm is checked.
class RovStatics : public ::testing::TestWithParam<bool> {};

TEST_P(RovStatics, PitchInACurrentBalancesForcesAndMomentsAboutTheCentreOfGravity) {
  const bool rov_at_a = GetParam();
  const double rho = 1000, V = 0.0105, mass = 10;
  const Vec3 u(0.5, 0, 0), cob(0, 0, 0.15), site(-0.3, 0, -0.15);
  const Vec3 D(40, 60, 20);
  testing::LoadedScene s(std::string(R"(<mujoco><option timestep="0.002" integrator="Euler"/>
    <custom><text name="water" data="density=1000 current=0.5,0,0"/>
      <text name="tether:t" data="ends=)") +
                         (rov_at_a ? "attach,anchor" : "anchor,attach") +
                         R"( length=6 segments=12 diameter=0.02
            mass_per_length=0.314159 EA=1e5 damping=50 Cdn=1.2 Cdt=0.01 integrator=implicit"/>
      <text name="vehicle:rov" data="volume=0.0105 cob=0,0,0.15
            linear_damping=40,60,20,20,20,20"/></custom>
    <worldbody><site name="anchor" pos="0 0 0"/>
      <body name="rov" pos="6.2 0 1.24"><freejoint/>
        <geom type="box" size="0.3 0.2 0.15" mass="10"/>
        <site name="attach" pos="-0.3 0 -0.15"/></body>
    </worldbody></mujoco>)");
  ASSERT_NE(s.m, nullptr);
  const int body = mj_name2id(s.m, mjOBJ_BODY, "rov");
  const int attach = mj_name2id(s.m, mjOBJ_SITE, "attach");
  double still = 0;  // [s] time the body has been at rest
  for (int k = 0; k < 60000 && still < 1; ++k) {
    ASSERT_TRUE(s.Step());
    double q = 0;
    for (int i = 0; i < s.m->nv; ++i) q = std::max(q, std::abs(s.d->qvel[i]));
    still = q < 1e-7 ? still + s.m->opt.timestep : 0;
  }
  ASSERT_GE(still, 1) << "the ROV did not come to rest by t = " << s.d->time;
  mj_forward(s.m, s.d);
  const EndReactions r = GetReactions(s.m, s.d, 0);
  const Vec3 pull = rov_at_a ? r.force_a : r.force_b;  // the tether's force on the ROV
  Eigen::Matrix3d R;
  for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = s.d->xmat[9 * body + i];
  const Vec3 G(s.d->xipos + 3 * body), S(s.d->site_xpos + 3 * attach);
  const Vec3 g(0, 0, -kG), B = -rho * V * g;
  const Vec3 damping = R * D.cwiseProduct(R.transpose() * u);  // at rest: v = 0
  const Vec3 force = pull + mass * g + B + damping;
  const Vec3 moment = (S - G).cross(pull) + (R * cob).cross(B);
  const double pitch = 2 * std::atan2(s.d->qpos[5], s.d->qpos[3]);  // about y
  // The pitch at which the measured force's moment about G vanishes (it stays in the x-z plane).
  auto My = [&](double th) {
    const Eigen::Matrix3d Ry = Eigen::AngleAxisd(th, Vec3::UnitY()).toRotationMatrix();
    return ((Ry * site).cross(pull) + (Ry * cob).cross(B)).y();
  };
  double lo = -0.5, hi = 0.5;
  ASSERT_LT(My(lo) * My(hi), 0);
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (My(mid) * My(lo) > 0 ? lo : hi) = mid;
  }
  std::printf(
      "t %.1f s: F (%.4f, %.4f, %.4f) N, pitch %.5f rad (statics %.5f), residual "
      "force %.2e N, moment %.2e N m\n",
      s.d->time, pull.x(), pull.y(), pull.z(), pitch, 0.5 * (lo + hi), force.norm(), moment.norm());
  EXPECT_LT(force.norm(), 1e-4);
  EXPECT_LT(moment.norm(), 1e-5);
  EXPECT_NEAR(pitch, 0.5 * (lo + hi), 1e-4);
  EXPECT_GT(std::abs(pitch), 0.05);  // the lever arm matters here (a few degrees)
}

INSTANTIATE_TEST_SUITE_P(Holes, RovStatics, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return std::string(i.param ? "RovAtEndA" : "RovAtEndB");
                         });

// ---------------------------------------------------------------------------------------------
// The clamp moment at end A, on a body. ValidationMuJoCo.EndMomentGivesCircularArc clamps end A
// to the world and end B to a body; here the same beam is declared the other way round (end A
// on the body, end B on the world), so that the body receives end A's moment. Its two sites'
// x-axes point along the tether from A to B (-x). Under a pure end moment M the beam is a
// circular arc and the body turns by M L/EI (Euler); the lumped model's rotation is exact to
// theta^2/6 relative at 20 segments (0.1%), tolerance 0.5% as there. Catches end A's moment
// applied with the wrong sign or not at all.
TEST(Holes, EndMomentOnABodyAtEndAGivesTheCircularArc) {
  const double L = 1, EI = 1, M = kPi / 2 * EI / L;
  testing::LoadedScene s(R"(<mujoco><option timestep="0.0004" gravity="0 0 0"/><custom>
      <text name="tether:beam" data="ends=tip,root length=1 segments=20 diameter=0.01
            mass_per_length=0.1 EA=1e4 EI=1 clamp=both"/></custom>
    <worldbody><site name="root" pos="0 0 0" quat="0 0 0 1"/>
      <body name="end" pos="1 0 0">
        <joint type="slide" axis="1 0 0" damping="1"/><joint type="slide" axis="0 0 1" damping="1"/>
        <joint name="turn" type="hinge" axis="0 1 0" damping="0.5"/>
        <inertial pos="0 0 0" mass="0.5" diaginertia="1e-2 1e-2 1e-2"/>
        <site name="tip" quat="0 0 0 1"/>
      </body></worldbody></mujoco>)");
  ASSERT_NE(s.m, nullptr);
  const int body = mj_name2id(s.m, mjOBJ_BODY, "end");
  const int turn = s.m->jnt_qposadr[mj_name2id(s.m, mjOBJ_JOINT, "turn")];
  bool settled = false;
  for (int k = 0; k < 50000 && !settled; ++k) {
    s.d->xfrc_applied[6 * body + 4] = M * std::min(1.0, s.d->time / 1.0);
    ASSERT_TRUE(s.Step());
    double q = 0;
    for (int i = 0; i < s.m->nv; ++i) q = std::max(q, std::abs(s.d->qvel[i]));
    settled = s.d->time > 1.5 && q < 1e-7;
  }
  EXPECT_TRUE(settled) << "still moving at t = " << s.d->time;
  std::printf("end A on the body: rotation %.5f rad, M L/EI %.5f rad\n", s.d->qpos[turn],
              M * L / EI);
  EXPECT_NEAR(s.d->qpos[turn] / (M * L / EI), 1, 0.005);
}

// ---------------------------------------------------------------------------------------------
// The log's columns, each against what it must hold in a scene whose statics are known:
// - a dry chain (10 m, 1 kg/m, EA 1e7 N) hanging from a fixed site with its end B free: the
//   site carries the whole weight, tension_A = m g L = 98.1 N; tension_B (free end: the last
//   segment's tension) holds the last node's half segment, m g L0/2 = 4.905 N; tension_max is
//   the first segment's, m g (L - L0/2) = 93.195 N; no segment slack. The chain has settled
//   (axial period 13 ms, damped) long before t = 1 s; 1e-4 relative covers the stretch
//   (1e-5) that moves no weight.
// - a weightless tether (effects=axial) 10 m long between sites 5 m apart: every one of its 10
//   segments slack, tensions 0.
// - a sphere resting on the floor at (1, 2): its x and y exactly, its z the radius within
//   the contact's penetration (1 mm).
TEST(Holes, LogColumnsHoldTheirQuantities) {
  const std::string dir = ::testing::TempDir();
  const std::string tag = std::to_string(getpid());
  const std::string model = dir + "/log_columns_" + tag + ".xml";
  const std::string log = dir + "/log_columns_" + tag + ".csv";
  std::ofstream(model) << R"(<mujoco><option timestep="0.002"/><custom>
      <text name="tether:chain" data="ends=top,free length=10 segments=10 diameter=0.02
            mass_per_length=1 EA=1e7 damping=1e4 integrator=implicit"/>
      <text name="tether:loose" data="ends=p,q length=10 segments=10 diameter=0.02
            mass_per_length=1 EA=1e5 effects=axial"/></custom>
    <worldbody><geom type="plane" size="10 10 0.1"/>
      <site name="top" pos="0 0 20"/><site name="p" pos="-5 5 5"/><site name="q" pos="0 5 5"/>
      <body name="ball" pos="1 2 0.1"><freejoint/><geom type="sphere" size="0.1" mass="1"/></body>
    </worldbody></mujoco>)";
  const std::string cmd = std::string(MJTETHER_CLI) + " run " + model +
                          " --duration 1 --every 0.5 --log " + log + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream f(log);
  std::string header, line, last;
  std::getline(f, header);
  EXPECT_EQ(header,
            "time,ball.x,ball.y,ball.z,chain.tension_A,chain.tension_B,chain.tension_max,"
            "chain.slack_segments,loose.tension_A,loose.tension_B,loose.tension_max,"
            "loose.slack_segments");
  while (std::getline(f, line)) last = line;
  std::vector<double> c;
  std::stringstream row(last);
  for (std::string cell; std::getline(row, cell, ',');) c.push_back(std::stod(cell));
  ASSERT_EQ(c.size(), 12u) << last;
  const double W = 1 * kG * 10, L0 = 1;
  EXPECT_NEAR(c[0], 1, 1e-9);
  EXPECT_NEAR(c[1], 1, 1e-6);
  EXPECT_NEAR(c[2], 2, 1e-6);
  EXPECT_NEAR(c[3], 0.1, 1e-3);
  EXPECT_NEAR(c[4], W, 1e-4 * W);
  EXPECT_NEAR(c[5], kG * L0 / 2, 1e-4 * W);
  EXPECT_NEAR(c[6], W - kG * L0 / 2, 1e-4 * W);
  EXPECT_EQ(c[7], 0);
  EXPECT_EQ(c[8], 0);
  EXPECT_EQ(c[9], 0);
  EXPECT_EQ(c[10], 0);
  EXPECT_EQ(c[11], 10);
  std::remove(model.c_str());
  std::remove(log.c_str());
}

}  // namespace
}  // namespace mjtether
