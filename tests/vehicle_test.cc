// Vehicles (Fossen hydrodynamics), prescribed motion and thrust schedules, through MuJoCo.
// Models inline; each result is compared with a closed form.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mjtether.h"
#include "mujoco_fixture.h"
#include "rov_controller.h"  // examples/: the controller example's control law
#include "vehicle_declaration.h"

namespace mjtether {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRho = 1025;  // [kg/m^3]
constexpr double kG = 9.81;    // [m/s^2]

class VehicleTest : public testing::MuJoCoFixture {
 protected:
  std::string LoadError(const std::string& xml) {
    std::string error;
    mjModel* m = LoadModelFromString(xml, "bad.xml", &error);
    if (m) {
      Detach(m);
      mj_deleteModel(m);
    }
    return error;
  }
};

// The BlueROV2 of Wu (2018), as in models/bluerov2_heavy.xml: 11.5 kg, 0.16 kg m^2.
constexpr double kMass = 11.5, kInertia = 0.16;
const char* kAddedMass = "5.5,12.7,14.57,0.12,0.12,0.12";
const char* kLinear = "4.03,6.22,5.18,0.07,0.07,0.07";
const char* kQuadratic = "18.18,21.66,36.99,1.55,1.55,1.55";

struct Scene {
  double volume = kMass / kRho;  // [m^3] neutral by default
  std::string cob = "0,0,0.02";
  std::string added_mass = kAddedMass;
  std::string linear = kLinear;
  std::string quadratic = kQuadratic;
  std::string current = "0,0,0";
  std::string gravity = "0 0 -9.81";
  std::string quat = "1 0 0 0";
  std::string option = "";  // extra <option> attributes
  std::string integrator = "Euler";  // MuJoCo's
  double timestep = 0.002;
};

std::string VehicleXml(const Scene& s) {
  std::ostringstream x;
  x.precision(17);
  x << R"(<mujoco><option timestep=")" << s.timestep << R"(" gravity=")" << s.gravity
    << R"(" integrator=")" << s.integrator << R"(" )" << s.option << R"(/><custom>
      <text name="water" data="density=1025 current=)"
    << s.current << R"("/>
      <text name="vehicle:rov" data="volume=)"
    << s.volume << " cob=" << s.cob << " added_mass=" << s.added_mass
    << " linear_damping=" << s.linear << " quadratic_damping=" << s.quadratic << R"("/></custom>
    <worldbody><body name="rov" pos="0 0 -10" quat=")"
    << s.quat << R"("><freejoint/>
      <inertial pos="0 0 0" mass=")"
    << kMass << R"(" diaginertia=")" << kInertia << " " << kInertia << " " << kInertia << R"("/>
      <geom type="sphere" size="0.2" contype="0" conaffinity="0"/>
    </body></worldbody></mujoco>)";
  return x.str();
}

Vec3 Position(const mjData* d) { return Vec3(d->qpos); }
Vec3 Velocity(const mjData* d) { return Vec3(d->qvel); }

// ---------------------------------------------------------------------------------------------
// Statics and terminal speeds

// Declared neutral buoyancy (rho V = m) with the centre of buoyancy straight above the centre
// of gravity: weight and buoyancy cancel to round-off (~1e-15 m g), so over 60 s the body may
// move by ~1e-12 m. Bound: 1e-9 m and 1e-9 rad, far below any physical drift and far above
// round-off.
TEST_F(VehicleTest, NeutralVehicleAtRestStaysPut) {
  mjModel* m = Load(VehicleXml(Scene()));
  mjData* d = Make(m);
  while (d->time < 60) mj_step(m, d);
  EXPECT_LT((Position(d) - Vec3(0, 0, -10)).norm(), 1e-9);
  EXPECT_LT(Vec3(d->qpos[4], d->qpos[5], d->qpos[6]).norm(), 1e-9);  // quaternion vector part
}

// Net weight W = (m - rho V) g sinks the body at the speed where heave damping balances it:
// W = D_l w + D_q w^2, w = (-D_l + sqrt(D_l^2 + 4 D_q W)) / (2 D_q) (Fossen's D(nu) nu, heave
// only). Steady state is a fixed point of the Euler step, so after 15 s (~20 time constants
// (m + A3)/(D_l + 2 D_q w) = 0.7 s) the match is to 1e-6.
TEST_F(VehicleTest, HeavyVehicleSinksAtTerminalSpeed) {
  for (const char* linear : {kLinear, "0,0,0,0,0,0"}) {
    Scene s;
    s.linear = linear;
    s.volume = (kMass - 1.0) / kRho;  // 1 kg heavy: W = 9.81 N
    mjModel* m = Load(VehicleXml(s));
    mjData* d = Make(m);
    while (d->time < 15) mj_step(m, d);
    const double W = 1.0 * kG, Dl = linear == kLinear ? 5.18 : 0, Dq = 36.99;
    const double w = (-Dl + std::sqrt(Dl * Dl + 4 * Dq * W)) / (2 * Dq);  // [m/s]
    EXPECT_NEAR(-d->qvel[2], w, 1e-6 * w) << "linear damping " << linear;
    EXPECT_NEAR(d->qvel[0], 0, 1e-12);
  }
}

// A neutral vehicle at rest in a uniform current u is carried along: its velocity relative to
// the water obeys (m + A) dv_r/dt = -(D_l + D_q |v_r|) v_r from v_r = -u, whose solution is
// |v_r|(t) = a u / ((a + b u) e^{a t/M} - b u) with a = D_l, b = D_q, M = m + A. Surge (x:
// A1 = 5.5 kg, all in the armature) and sway (y: A2 = 12.7 kg, 7.2 kg of it applied
// explicitly with the previous step's acceleration). Tolerance: forward Euler's first-order
// error is below h/(2 tau) u ~ 1.6e-3 u (tau = M/(a + 2 b |v_r|) >= 0.6 s, h = 2 ms); seen:
// 3e-4 u (surge), 6e-4 u (sway). Without the added mass the error would be ~0.1 u.
TEST_F(VehicleTest, CurrentCarriesTheVehicleAsItsDampingAndAddedMassSay) {
  struct Axis {
    int i;
    const char* current;
    double A, a, b;
  };
  const double u = 0.5;  // [m/s]
  for (const Axis& ax :
       {Axis{0, "0.5,0,0", 5.5, 4.03, 18.18}, Axis{1, "0,0.5,0", 12.7, 6.22, 21.66}}) {
    Scene s;
    s.current = ax.current;
    mjModel* m = Load(VehicleXml(s));
    mjData* d = Make(m);
    const double M = kMass + ax.A;
    double worst = 0;
    while (d->time < 10) {
      mj_step(m, d);
      const double vr = ax.a * u / ((ax.a + ax.b * u) * std::exp(ax.a * d->time / M) - ax.b * u);
      worst = std::max(worst, std::abs((u - d->qvel[ax.i]) - vr));
    }
    EXPECT_LT(worst, 2e-3 * u) << "axis " << ax.i;
    EXPECT_NEAR(d->qvel[2], 0, 1e-9);
  }
}

// ---------------------------------------------------------------------------------------------
// Added mass

// Added mass twice the body's mass (and up to 2.5 times, with 0.5 m applied explicitly) under
// a known force: the acceleration is F/(m + A_i) along each body axis, and the torque about
// yaw gives tau/(I + A6). The body is turned (yaw 30 deg, roll 20 deg) so that the body and
// world axes differ. No gravity, no damping. Velocities after 2 s, relative error: the
// explicit remainder's lag converges geometrically (ratio dA/(m + a_iso) = 1/6), adding
// ~h/t = 1e-3 at most (seen 1.4e-4); the armature axes are exact to round-off (seen 1e-14).
TEST_F(VehicleTest, AddedMassTwiceTheBodyMassIsStableAndCorrect) {
  Scene s;
  s.gravity = "0 0 0";
  s.volume = 0;
  const double A[6] = {2 * kMass, 2 * kMass, 2.5 * kMass, 2 * kInertia, 2 * kInertia, 2 * kInertia};
  std::ostringstream am;
  am.precision(17);
  for (int i = 0; i < 6; ++i) am << (i ? "," : "") << A[i];
  s.added_mass = am.str();
  s.linear = s.quadratic = "0,0,0,0,0,0";
  // yaw 30 deg then roll 20 deg
  const Eigen::Quaterniond q =
      Eigen::AngleAxisd(kPi / 6, Vec3::UnitZ()) * Eigen::AngleAxisd(kPi / 9, Vec3::UnitX());
  std::ostringstream quat;
  quat.precision(17);
  quat << q.w() << " " << q.x() << " " << q.y() << " " << q.z();
  s.quat = quat.str();
  const Eigen::Matrix3d R = q.toRotationMatrix();
  for (int axis = 0; axis < 3; ++axis) {
    mjModel* m = Load(VehicleXml(s));
    mjData* d = Make(m);
    const double F = 10;  // [N] along body axis `axis`, at the centre of mass
    const Vec3 f = F * R.col(axis);
    const double t_end = 2;
    while (d->time < t_end - 1e-9) {
      for (int i = 0; i < 3; ++i) d->xfrc_applied[6 + i] = f[i];
      mj_step(m, d);
    }
    const Vec3 v = Velocity(d);
    const double expected = F * d->time / (kMass + A[axis]);
    EXPECT_NEAR(v.dot(R.col(axis)), expected, 1e-3 * expected) << "axis " << axis;
    EXPECT_LT((v - v.dot(R.col(axis)) * R.col(axis)).norm(), 1e-9) << "axis " << axis;
    EXPECT_TRUE(std::isfinite(d->qpos[0]));
  }
  // Yaw torque about the body's z-axis: w_z = tau t / (I + A6), exact (armature).
  mjModel* m = Load(VehicleXml(s));
  mjData* d = Make(m);
  const double tau = 0.5;  // [N m]
  const Vec3 t_world = tau * R.col(2);
  while (d->time < 2 - 1e-9) {
    for (int i = 0; i < 3; ++i) d->xfrc_applied[6 + 3 + i] = t_world[i];
    mj_step(m, d);
  }
  EXPECT_NEAR(d->qvel[5], tau * d->time / (kInertia + A[5]), 1e-9);
}

// The BlueROV2's added mass is anisotropic: 5.5 kg of it (the smallest) goes into the armature,
// and heave keeps an explicit remainder of 9.07 kg, 0.53 of m + 5.5 (applied from the last step's
// acceleration). A constant 10 N heave force from rest then gives v = F t / (m + A_heave) with
// each of MuJoCo's integrators. With RK4 the remainder once took its acceleration across RK4's
// predicted stage states, which fed the lagged force back through RK4's extrapolation: the
// hostile-input generator found models/minimal_rov.xml sinking at 70 m/s under
// <option integrator="RK4">. The lag costs one step of the remainder's force, (9.07/28.6)
// F h ~ 6e-3 N s of 0.7 N s: 1e-2 relative bounds it; measured about 1e-3 for each integrator.
TEST_F(VehicleTest, AnisotropicAddedMassIsRightWithEveryMuJoCoIntegrator) {
  for (const char* integrator : {"Euler", "implicit", "RK4"}) {
    Scene s;
    s.gravity = "0 0 0";
    s.volume = 0;
    s.linear = s.quadratic = "0,0,0,0,0,0";
    s.integrator = integrator;
    mjModel* m = Load(VehicleXml(s));
    mjData* d = Make(m);
    const double F = 10;  // [N] heave, at the centre of mass
    // By step count: a blow-up makes MuJoCo reset the data, time and all.
    for (int k = 0; k < 1000; ++k) {
      d->xfrc_applied[6 + 2] = F;
      mj_step(m, d);
    }
    ASSERT_NEAR(d->time, 2, 1e-9) << integrator << ": MuJoCo reset the simulation";
    const double expected = F * d->time / (kMass + 14.57);
    EXPECT_NEAR(d->qvel[2], expected, 1e-2 * expected) << integrator;
    EXPECT_NEAR(d->qvel[0], 0, 1e-9) << integrator;
  }
}

// ---------------------------------------------------------------------------------------------
// Buoyancy moment

// The centre of buoyancy z_b = 0.02 m above the centre of gravity rights the vehicle: small
// roll oscillations have the period T = 2 pi sqrt((I_xx + A4) / (rho g V z_b)) (no damping).
// 2 deg amplitude: the large-amplitude correction is theta^2/16 = 8e-5; Euler's period error
// ~ (w h)^2 ~ 3e-5 (seen: 8e-5 T). Tolerance 0.1% of T.
TEST_F(VehicleTest, BuoyancyRightsTheVehicleWithThePendulumPeriod) {
  Scene s;
  s.linear = s.quadratic = "0,0,0,0,0,0";
  s.timestep = 0.001;
  const double theta0 = 2 * kPi / 180;
  std::ostringstream quat;
  quat.precision(17);
  quat << std::cos(theta0 / 2) << " " << std::sin(theta0 / 2) << " 0 0";
  s.quat = quat.str();
  mjModel* m = Load(VehicleXml(s));
  mjData* d = Make(m);
  const double T = 2 * kPi * std::sqrt((kInertia + 0.12) / (kMass * kG * 0.02));  // [s]
  // Upward zero crossings of the roll rate after the first.
  std::vector<double> crossings;
  double previous = d->qvel[3];
  while (d->time < 3.5 * T) {
    mj_step(m, d);
    if (previous < 0 && d->qvel[3] >= 0) {
      crossings.push_back(d->time - m->opt.timestep * d->qvel[3] / (d->qvel[3] - previous));
    }
    previous = d->qvel[3];
  }
  ASSERT_GE(crossings.size(), 3u);
  EXPECT_NEAR((crossings.back() - crossings.front()) / (crossings.size() - 1), T, 1e-3 * T);
}

// ---------------------------------------------------------------------------------------------
// Declarations

TEST_F(VehicleTest, MuJoCoFluidModelOnAVehicleIsAnError) {
  Scene s;
  s.option = R"(density="1025" viscosity="0.001")";
  const std::string error = LoadError(VehicleXml(s));
  EXPECT_NE(error.find("bad.xml: <text name=\"vehicle:rov\">"), std::string::npos) << error;
  EXPECT_NE(error.find("density"), std::string::npos) << error;
  EXPECT_NE(error.find("viscosity"), std::string::npos) << error;
}

TEST_F(VehicleTest, BadVehicleDeclarationsNameTheKey) {
  struct Case {
    std::string data;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {"volume=-1", "key 'volume'"},
      {"volume=abc", "key 'volume'"},
      {"cob=0,0", "key 'cob'"},
      {"added_mass=1,2,3,4,5", "key 'added_mass'"},
      {"linear_damping=1,2,3,4,5,nan", "key 'linear_damping'"},
      {"quadratic_damping=1,2,3,4,5,-6", "key 'quadratic_damping'"},
      {"mass=3", "unknown key 'mass'"},
      // sway added mass 40 kg above surge's 0: more than 0.9 (m + 0) explicit
      {"added_mass=0,40,0,0,0,0", "key 'added_mass'"},
  };
  for (const Case& c : cases) {
    const std::string xml = R"(<mujoco><custom><text name="water" data="density=1025"/>
        <text name="vehicle:rov" data=")" +
                            c.data + R"("/></custom>
        <worldbody><body name="rov"><freejoint/><geom type="sphere" size="0.1" mass="11.5"/>
        </body></worldbody></mujoco>)";
    const std::string error = LoadError(xml);
    EXPECT_NE(error.find("bad.xml: <text name=\"vehicle:rov\">"), std::string::npos) << error;
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.data << ": " << error;
  }
  // A body that is not there, not free, or a scene without water.
  EXPECT_NE(LoadError(R"(<mujoco><custom><text name="water" data="density=1025"/>
      <text name="vehicle:nobody" data="volume=1"/></custom></mujoco>)")
                .find("no body named 'nobody'"),
            std::string::npos);
  EXPECT_NE(LoadError(R"(<mujoco><custom><text name="water" data="density=1025"/>
      <text name="vehicle:arm" data="volume=1"/></custom><worldbody><body name="arm">
      <joint type="hinge"/><geom size="0.1" mass="1"/></body></worldbody></mujoco>)")
                .find("free joint"),
            std::string::npos);
  EXPECT_NE(LoadError(R"(<mujoco><custom><text name="vehicle:rov" data="volume=1"/></custom>
      <worldbody><body name="rov"><freejoint/><geom size="0.1" mass="1"/></body></worldbody>
      </mujoco>)")
                .find("needs water"),
            std::string::npos);
}

TEST_F(VehicleTest, BadMotionAndThrustDeclarationsNameTheKey) {
  struct Case {
    std::string text;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {R"(<text name="motion:ship" data="x=1,0,0"/>)", "key 'x'"},
      {R"(<text name="motion:ship" data="x=-1,5,0"/>)", "key 'x'"},
      {R"(<text name="motion:ship" data="x=1,5"/>)", "key 'x'"},
      {R"(<text name="motion:ship" data="x=1,5,0 csv=a.csv"/>)", "key 'csv'"},
      {R"(<text name="motion:ship" data="csv=does_not_exist.csv"/>)", "key 'csv'"},
      {R"(<text name="motion:ship" data="ramp=3"/>)", "needs x, y, z"},
      {R"(<text name="motion:hull" data="x=1,5,0"/>)", "not a mocap body"},
      {R"(<text name="thrust:push" data="t=0,1 ctrl=1"/>)", "as many values"},
      {R"(<text name="thrust:push" data="t=1,0 ctrl=1,2"/>)", "key 't'"},
      {R"(<text name="thrust:push" data="ctrl=1,2"/>)", "missing required key 't'"},
      {R"(<text name="thrust:nothing" data="t=0 ctrl=1"/>)", "no actuator named 'nothing'"},
  };
  for (const Case& c : cases) {
    const std::string xml = "<mujoco><custom>" + c.text + R"(</custom><worldbody>
        <body name="ship" mocap="true"><geom size="0.1" contype="0" conaffinity="0"/></body>
        <body name="hull"><freejoint/><geom size="0.1" mass="1"/><site name="s"/></body>
        </worldbody><actuator><motor name="push" site="s" gear="1 0 0 0 0 0"/></actuator>
        </mujoco>)";
    const std::string error = LoadError(xml);
    EXPECT_NE(error.find("bad.xml: <text name="), std::string::npos) << error;
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.text << ": " << error;
  }
}

// ---------------------------------------------------------------------------------------------
// Prescribed motion and thrust schedules

// The harmonic motion with its start ramp: zero offset and velocity at t = 0, the plain
// harmonic after the ramp, and Velocity the derivative of Offset (central difference, error
// O(dt^2 w^3 a) ~ 1e-9).
TEST(Motion, RampedHarmonicStartsAtRestAndVelocityIsTheDerivative) {
  MotionParams p;
  DeclarationError e;
  std::optional<MotionParams> parsed = ParseMotion("x=2,10,0.5 z=1,8,1", &e);
  ASSERT_TRUE(parsed) << e.message;
  std::string error;
  std::optional<Motion> mo = Motion::Create(*parsed, "", &error);
  ASSERT_TRUE(mo) << error;
  EXPECT_DOUBLE_EQ(mo->ramp(), 10);  // default: the longest period
  EXPECT_EQ(mo->Offset(0).norm(), 0);
  EXPECT_EQ(mo->Velocity(0).norm(), 0);
  const double t = 13;
  EXPECT_NEAR(mo->Offset(t).x(), 2 * std::sin(2 * kPi * t / 10 + 0.5), 1e-12);
  EXPECT_NEAR(mo->Offset(t).z(), std::sin(2 * kPi * t / 8 + 1), 1e-12);
  for (double time : {0.3, 2.0, 7.5, 9.99, 12.0}) {
    const double dt = 1e-5;
    const Vec3 fd = (mo->Offset(time + dt) - mo->Offset(time - dt)) / (2 * dt);
    EXPECT_LT((fd - mo->Velocity(time)).norm(), 1e-8) << "t = " << time;
  }
}

TEST(Motion, ScheduleIsPiecewiseLinearWithSteps) {
  DeclarationError e;
  std::optional<Schedule> s = ParseSchedule("t=1,2,2,4 ctrl=0,10,-5,5", &e);
  ASSERT_TRUE(s) << e.message;
  EXPECT_EQ(s->At(0), 0);
  EXPECT_DOUBLE_EQ(s->At(1.5), 5);
  EXPECT_DOUBLE_EQ(s->At(2), -5);  // the step takes the later value
  EXPECT_DOUBLE_EQ(s->At(3), 0);
  EXPECT_EQ(s->At(10), 5);
}

// A table motion from a CSV file, and the tether end on the moving body: Prescribe places the
// mocap body at its initial position plus the interpolated offset, sets the scheduled ctrl, and
// the tether's end node moves with the motion's exact velocity (not a finite difference).
TEST_F(VehicleTest, PrescribeMovesMocapBodiesAndTheTetherEndFollowsExactly) {
  const std::string csv = ::testing::TempDir() + "mjtether_motion.csv";
  {
    std::ofstream f(csv);
    f << "time,x,y,z\n0,0,0,0\n1,1,0,0.5\n3,1,2,0.5\n";
  }
  const std::string xml = R"(<mujoco><option timestep="0.01"/><custom>
      <text name="motion:ship" data="csv=)" +
                          csv + R"("/>
      <text name="thrust:push" data="t=0,1 ctrl=0,20"/>
      <text name="tether:line" data="ends=fairlead,tip length=5 segments=5 diameter=0.01
            mass_per_length=0.1 EA=1e4"/></custom>
      <worldbody><body name="ship" mocap="true" pos="1 2 3">
        <geom size="0.1" contype="0" conaffinity="0"/><site name="fairlead"/></body>
      <body name="hull" pos="1 2 -1"><freejoint/><geom size="0.1" mass="1"/><site name="tip"/>
      </body></worldbody>
      <actuator><motor name="push" site="tip" gear="1 0 0 0 0 0"/></actuator></mujoco>)";
  mjModel* m = Load(xml);
  mjData* d = Make(m);
  const int k = FindTether(m, "line");
  while (d->time < 2 - 1e-9) {
    Step(m, d);
    if (d->time > 0.5 && d->time < 0.9) {
      // Between rows 0 and 1: velocity (1, 0, 0.5) [m/s] exactly.
      const double* v0 = NodeVelocities(m, d, k);
      ASSERT_NE(v0, nullptr);
      // The tether's time is the last callback's, one step behind the mocap placement.
      EXPECT_NEAR(v0[0], 1, 1e-12);
      EXPECT_NEAR(v0[2], 0.5, 1e-12);
    }
  }
  Prescribe(m, d);
  EXPECT_NEAR(d->mocap_pos[0], 2, 1e-12);     // 1 + x offset 1
  EXPECT_NEAR(d->mocap_pos[1], 2 + 1, 1e-9);  // halfway from y = 0 to 2 between t = 1 and 3
  EXPECT_NEAR(d->mocap_pos[2], 3.5, 1e-12);
  EXPECT_EQ(d->ctrl[0], 20);
}

}  // namespace
}  // namespace mjtether

namespace mjtether {
namespace {

// The Munk moment of the added mass, -(v_r x A_v v_r): moving along surge with A3 > A1, a
// pitch angle theta gives heave velocity w ~ U theta and the moment (A3 - A1) U^2 theta, which
// overturns the vehicle against its righting moment W z_b theta once
// U > U_c = sqrt(W z_b / (A3 - A1)) = 0.50 m/s for the BlueROV2 of Wu (2018) (Fossen 2011,
// C_A of a diagonal M_A; the classic instability of a body moving along its axis of least added
// mass). A body-fixed surge force F = D_l U + D_q U^2 holds the speed U; the vehicle starts pitched
// 1 deg. At 0.7 U_c the pitch stays below 5 deg for 30 s; at 1.4 U_c it passes 30 deg; with
// coriolis=0 (no C_A) 1.4 U_c stays below 5 deg too.
TEST_F(VehicleTest, MunkMomentOverturnsPitchAboveTheCriticalSpeed) {
  const double Uc = std::sqrt(kMass * kG * 0.02 / (14.57 - 5.5));  // [m/s]
  struct Case {
    double speed;
    bool coriolis;
    bool overturns;
  };
  for (const Case& c :
       {Case{0.7 * Uc, true, false}, Case{1.4 * Uc, true, true}, Case{1.4 * Uc, false, false}}) {
    Scene s;
    if (!c.coriolis) s.quadratic = std::string(kQuadratic) + " coriolis=0";
    const double theta0 = kPi / 180;
    std::ostringstream quat;
    quat.precision(17);
    quat << std::cos(theta0 / 2) << " 0 " << std::sin(theta0 / 2) << " 0";
    s.quat = quat.str();
    mjModel* m = Load(VehicleXml(s));
    mjData* d = Make(m);
    const double F = 4.03 * c.speed + 18.18 * c.speed * c.speed;  // [N]
    d->qvel[0] = c.speed;
    double max_pitch = 0;
    while (d->time < 30) {
      const double* R = d->xmat + 9;                                      // body 1, row-major
      for (int i = 0; i < 3; ++i) d->xfrc_applied[6 + i] = F * R[3 * i];  // along body x
      mj_step(m, d);
      // pitch: angle of the body x-axis out of the horizontal plane
      max_pitch = std::max(max_pitch, std::abs(std::asin(d->xmat[9 + 6])));
    }
    if (c.overturns) {
      EXPECT_GT(max_pitch, kPi / 6) << "U = " << c.speed;
    } else {
      EXPECT_LT(max_pitch, kPi / 36) << "U = " << c.speed << " coriolis " << c.coriolis;
    }
  }
}

}  // namespace
}  // namespace mjtether

namespace mjtether {
namespace {

std::string ReadModel(const std::string& file) {
  std::ifstream f(std::string(MJTETHER_MODELS_DIR) + "/" + file);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// The surge-until-taut manoeuvre (models/manoeuvre_surge_snap.xml) against the same run
// without the tether (its declaration renamed so that mjtether ignores it). Without the tether
// the vehicle runs at its terminal speed (71 N of thrust: 1.8 m/s) for 11 s and ends farther
// than L + 5 m from the surface point. With it, the vehicle can never be farther than the
// stretched length L (1 + T_max/EA) plus the attachment's offset (0.25 m), and once the thrust
// stops the stretched tether pulls it back (its surge velocity turns negative), which without
// the tether never happens (the vehicle glides to rest: velocity >= 0 up to 1 mm/s).
TEST_F(VehicleTest, SurgeUntilTautShowsTheTethersPull) {
  const std::string xml = ReadModel("manoeuvre_surge_snap.xml");
  ASSERT_FALSE(xml.empty());
  std::string untethered = xml;
  const size_t at = untethered.find("name=\"tether:umbilical\"");
  ASSERT_NE(at, std::string::npos);
  untethered.replace(at, 11, "name=\"none:");
  struct Result {
    double max_distance = 0, min_vx_after = 1e9, max_tension = 0;
  };
  auto run = [&](const std::string& text, const char* name) {
    mjModel* m = Load(text, name);
    mjData* d = Make(m);
    const int surface = mj_name2id(m, mjOBJ_SITE, "surface");
    const int rov = mj_name2id(m, mjOBJ_BODY, "rov");
    Result r;
    while (d->time < 30) {
      Step(m, d);
      EXPECT_FALSE(CheckDivergence(m, d));
      const Vec3 p(d->xpos + 3 * rov), s(d->site_xpos + 3 * surface);
      r.max_distance = std::max(r.max_distance, (p - s).norm());
      if (d->time > 13) r.min_vx_after = std::min(r.min_vx_after, d->qvel[0]);
      if (TetherCount(m) > 0)
        r.max_tension = std::max(r.max_tension, GetReactions(m, d, 0).tension_b);
    }
    return r;
  };
  const Result with = run(xml, "surge.xml"), without = run(untethered, "surge_free.xml");
  const double L = 30, EA = 6e4;
  std::printf(
      "max distance %.2f m with the tether, %.2f m without; T_max %.1f N; min v_x "
      "after the thrust %.3f / %.3f m/s\n",
      with.max_distance, without.max_distance, with.max_tension, with.min_vx_after,
      without.min_vx_after);
  EXPECT_LT(with.max_distance, L * (1 + with.max_tension / EA) + 0.25);
  EXPECT_GT(without.max_distance, L + 5);
  EXPECT_LT(with.min_vx_after, 0);
  EXPECT_GT(without.min_vx_after, -1e-3);
}

}  // namespace
}  // namespace mjtether

namespace mjtether {
namespace {

// The controller example (examples/rov_controller.h, run by examples/rov_pid.cc): the
// BlueROV2 Heavy of models/bluerov2_heavy.xml holds 10 m depth and heading 0 while the pilot
// pushes 20 N of surge from t = 2 s; its 30 m tether, slack at the start (12.8 m between the
// ends, under 2 N at the vehicle), comes taut (ends more than 0.97 L apart, tension above
// 15 N: the tether then holds most of the 20 N). Bound: 0.05 m of depth error after the first
// 5 s, the hold an inspection pilot expects. The disturbances are the tether's vertical pull
// (up to 7 N, which alone would move the vehicle 7/kp = 0.12 m under the proportional term),
// the 1.8 N of buoyancy and the boat's heave through the tether; the integral, the rate term
// and the feed-forward of the pull read from mjtether::GetReactions keep it inside the bound
// (seen: 0.0065 m; 0.029 m without the feed-forward, which the test checks is worse).
TEST_F(VehicleTest, ControllerHoldsDepthWhileTheTetherGoesSlackToTaut) {
  struct Result {
    double worst = 0, tension_early = 0, tension_late = 0, ratio_early = 1, ratio_late = 0;
  };
  auto run = [&](bool feed_forward) {
    mjModel* m = Load(ReadModel("bluerov2_heavy.xml"), "bluerov2_heavy.xml");
    mjData* d = Make(m);
    rov::DepthHeadingController controller(m, "rov", "umbilical");
    EXPECT_TRUE(controller.ok());
    controller.feed_forward_tether = feed_forward;
    const int body = mj_name2id(m, mjOBJ_BODY, "rov");
    const int k = FindTether(m, "umbilical");
    const int a = mj_name2id(m, mjOBJ_SITE, "boat_reel"),
              b = mj_name2id(m, mjOBJ_SITE, "tether_attach");
    mj_forward(m, d);
    rov::Setpoint sp;
    sp.depth = d->xpos[3 * body + 2];
    Result r;
    while (d->time < 60) {
      sp.surge = d->time > 2 ? 20 : 0;
      Prescribe(m, d);
      controller.Compute(m, d, sp, m->opt.timestep);
      mj_step(m, d);
      EXPECT_FALSE(CheckDivergence(m, d));
      const double z = d->xpos[3 * body + 2];
      const double ratio = (Vec3(d->site_xpos + 3 * a) - Vec3(d->site_xpos + 3 * b)).norm() / 30;
      const double tension = GetReactions(m, d, k).tension_b;
      if (d->time > 5) r.worst = std::max(r.worst, std::abs(z - sp.depth));
      if (d->time < 3) {
        r.tension_early = std::max(r.tension_early, tension);
        r.ratio_early = std::min(r.ratio_early, ratio);
      }
      if (d->time > 30) {
        r.tension_late = std::max(r.tension_late, tension);
        r.ratio_late = std::max(r.ratio_late, ratio);
      }
    }
    return r;
  };
  const Result with = run(true), without = run(false);
  std::printf(
      "depth error %.4f m (%.4f m without the tether feed-forward); tension %.2f N "
      "early, %.2f N late; ends %.2f L then %.3f L apart\n",
      with.worst, without.worst, with.tension_early, with.tension_late, with.ratio_early,
      with.ratio_late);
  EXPECT_LT(with.worst, 0.05);
  EXPECT_GT(without.worst, with.worst);
  EXPECT_LT(with.tension_early, 2);
  EXPECT_LT(with.ratio_early, 0.5);
  EXPECT_GT(with.tension_late, 15);
  EXPECT_GT(with.ratio_late, 0.97);
}

}  // namespace
}  // namespace mjtether

namespace mjtether {
namespace {

// Station keeping in a 0.5 m/s cross current (models/manoeuvre_station_keeping.xml) with the
// example's controller: after 20 s (the tether's drag builds up over the first ~30 s as it
// bows) the vehicle stays within 0.15 m of its start (a third of its length), 0.05 m in
// depth, 5 deg in heading. Seen: 0.078 m, 0.0005 m, 3.8 deg.
TEST_F(VehicleTest, ControllerKeepsStationInACrossCurrent) {
  mjModel* m = Load(ReadModel("manoeuvre_station_keeping.xml"), "station.xml");
  mjData* d = Make(m);
  rov::DepthHeadingController controller(m, "rov", "umbilical");
  ASSERT_TRUE(controller.ok());
  const int body = mj_name2id(m, mjOBJ_BODY, "rov");
  mj_forward(m, d);
  rov::Setpoint sp;
  sp.station = true;
  sp.x = d->xpos[3 * body], sp.y = d->xpos[3 * body + 1], sp.depth = d->xpos[3 * body + 2];
  double drift = 0, depth = 0, heading = 0;
  while (d->time < 60) {
    Prescribe(m, d);
    controller.Compute(m, d, sp, m->opt.timestep);
    mj_step(m, d);
    if (d->time < 20) continue;
    const double* p = d->xpos + 3 * body;
    drift = std::max(drift, std::hypot(p[0] - sp.x, p[1] - sp.y));
    depth = std::max(depth, std::abs(p[2] - sp.depth));
    heading = std::max(heading, std::abs(std::atan2(d->xmat[9 * body + 3], d->xmat[9 * body])));
  }
  EXPECT_GT(GetReactions(m, d, 0).tension_b, 3);  // the current does load the tether
  EXPECT_LT(drift, 0.15);
  EXPECT_LT(depth, 0.05);
  EXPECT_LT(heading, 5 * kPi / 180);
}

}  // namespace
}  // namespace mjtether
