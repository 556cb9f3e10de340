// The default integrator, bdf2 (issue 17 item 1; docs/numerics.md): second order at backward
// Euler's cost per step, its history in mjData.
//
// - order of convergence ~2 against a converged reference (backward Euler's ~1 alongside);
// - a 5 Hz transverse wave keeps its amplitude over the time it takes to travel 10 m;
// - mj_copyData and mj_resetData carry the history: bit-identical runs;
// - a winch payout and haul-in with bdf2 stays within the winch tests' tolerances (a regrid
//   restarts the scheme with one backward-Euler step).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "mjtether.h"
#include "mujoco_fixture.h"
#include "reference_scenes.h"

namespace mjtether {
namespace {

using namespace reference_scenes;

double Rms(const std::vector<double>& a, const std::vector<double>& b, size_t from) {
  double s = 0;
  for (size_t i = from; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s / (a.size() - from));
}

// The fairlead tension's RMS error of one engine run of scene s (N segments, integrator at step
// h) against a reference run of the same scene, over the scene's error window (from
// s.error_from). NaN, with a test failure, where the run stopped or sampled differently.
double FairleadError(const Scene& s, int N, const char* integrator, double h,
                     const reference_scenes::Run& ref) {
  const reference_scenes::Run r = RunEngine(s, N, integrator, h, 0, false);
  EXPECT_TRUE(r.ok) << integrator << " at " << h << " s";
  EXPECT_EQ(r.T.size(), ref.T.size()) << integrator << " at " << h << " s";
  if (!r.ok || r.T.size() != ref.T.size()) return NAN;
  return Rms(r.T, ref.T, std::lround(s.error_from / s.sample));
}

// Observed order on the fixed comparison line (tests/reference_scenes.h) at 20 segments, 20 s
// (the error over 10-20 s, after the start-up snap): the fairlead tension's RMS error against
// rk4 at 0.25 ms (fourth order: its time error is ~(0.25/1)^4 of rk4 at 1 ms, far below what
// is measured here) at h = 4, 2 and 1 ms. Second order halves the step and quarters the
// error: log2 of the ratios within 1.6-2.4 (the ratio of a second-order error settles to 4 as
// h -> 0; the higher-order terms are a few % at these steps). Backward Euler, run alongside,
// is first order, and at these steps still short of it (its damping of the line's axial modes
// dominates: measured 0.4-0.6): below 1.3, so the test tells the two apart.
TEST(Bdf2, ObservedOrderIsTwo) {
  Scene s = LineScene();
  s.duration = 20;
  const int N = 20;
  const reference_scenes::Run ref = RunEngine(s, N, "rk4", 0.002, 0.00025, false);
  ASSERT_TRUE(ref.ok);
  for (const char* integrator : {"bdf2", "implicit"}) {
    std::vector<double> err;
    for (double h : {0.004, 0.002, 0.001}) err.push_back(FairleadError(s, N, integrator, h, ref));
    const double p1 = std::log2(err[0] / err[1]), p2 = std::log2(err[1] / err[2]);
    std::printf("%s: error %.4g, %.4g, %.4g N at 4, 2, 1 ms: order %.2f, %.2f\n", integrator,
                err[0], err[1], err[2], p1, p2);
    if (std::string(integrator) == "bdf2") {
      EXPECT_NEAR(p1, 2, 0.4);
      EXPECT_NEAR(p2, 2, 0.4);
    } else {
      EXPECT_LT(p1, 1.3);
      EXPECT_LT(p2, 1.3);
    }
  }
}

// The issue's wave: a 5 Hz transverse wave at 100 N on a 1 kg/m line (wave speed
// c = sqrt(T/mu) = 10 m/s) for the 1 s it takes to travel 10 m, at 2 ms. A dry, undamped string
// of 1 m between fixed ends (stretched to T = 100 N, EA = 1e6 N) in its fundamental
// (f = c/2L = 5 Hz), 20 segments, plucked to 1 mm at rest in the shape of the discrete mode,
// sin(pi i/N); no gravity. The exact semi-discrete motion keeps its amplitude (no damping; the
// axial coupling of a 1 mm pluck changes the tension by 1e-5 relative). Amplitude: at the
// middle node, sqrt(y^2 + (ydot/omega)^2) with the discrete mode's omega =
// 2 sqrt(T/(mu L0^2)) sin(pi/(2 N)). BDF2's amplification factor at omega h = 0.063 predicts
// 0.998 after 500 steps; backward Euler's (1 + (omega h)^2)^(-1/2) predicts 0.37. Asserted:
// bdf2 >= 0.99 (the issue asks 0.9), backward Euler <= 0.45 (the test's own control).
TEST(Bdf2, KeepsThe5HzWaveWhereBackwardEulerDampsIt) {
  const double T = 100, mu = 1, EA = 1e6, L = 1, h = 0.002;
  const int N = 20;
  const double span = L * (1 + T / EA);
  const double L0 = L / N, omega = 2 * std::sqrt(T / (mu * L0 * L0)) * std::sin(kPi / (2 * N));
  ASSERT_NEAR(omega / (2 * kPi), 5, 0.02);  // [Hz] the discrete fundamental
  for (const char* integrator : {"bdf2", "implicit"}) {
    Environment env;
    env.gravity = Vec3::Zero();
    std::ostringstream decl;
    decl << "ends=a,b length=" << L << " segments=" << N << " diameter=0.01 mass_per_length="
         << mu << " EA=" << EA << " integrator=" << integrator;
    std::string error;
    std::optional<Tether> t = reference_scenes::TetherFrom(decl.str(), env, &error);
    ASSERT_TRUE(t) << error;
    Ends ends;
    ends.a.pos = Vec3(0, 0, 0);
    ends.b.pos = Vec3(span, 0, 0);
    std::vector<double> x(3 * (N + 1)), v(3 * (N + 1), 0.0), work(t->WorkspaceSize());
    std::vector<double> history(t->HistorySize() + 1, 0.0);
    for (int i = 0; i <= N; ++i) {
      x[3 * i] = span * i / N;
      x[3 * i + 1] = 1e-3 * std::sin(kPi * i / N);
      x[3 * i + 2] = 0;
    }
    const int mid = N / 2;
    auto amplitude = [&]() {
      return std::hypot(x[3 * mid + 1], v[3 * mid + 1] / omega);
    };
    const double a0 = amplitude();
    for (int k = 0; k < 500; ++k) {
      ASSERT_TRUE(t->Advance(x.data(), v.data(), ends, ends, h, work.data(), history.data()).ok);
    }
    const double kept = amplitude() / a0;
    std::printf("%s: %.4f of the amplitude kept after 1 s (10 m of travel)\n", integrator, kept);
    if (std::string(integrator) == "bdf2") {
      EXPECT_GE(kept, 0.99);
      EXPECT_LE(kept, 1.0 + 1e-3);  // and no growth
    } else {
      EXPECT_LE(kept, 0.45);
    }
  }
}

// Galilean invariance of the end segments' damping (session 18; scene fuzzer seed 658). A
// damped line (10 m, 100 segments, damping 20 N s, EA 1e4 N) falling in water from straight
// between two ends 9 m apart, run twice: with the ends at rest in still water, and with the
// ends, the nodes and the current all moving at U = (1, 0.5, 0) m/s. The physics is the same
// in the moving frame (drag acts on the velocity relative to the current, the added mass on the
// node's acceleration, and the ends' Hermite curve is exact for a constant velocity), so the
// end tensions must be the same at every step up to rounding.
// The implicit steps take the damping, in their Newton iterations past the first (where a
// segment goes slack or taut within the step), on the backward difference of each segment's
// length from the step's start. bdf2's dynamic nodes start from the extrapolated x-hat and
// implicit2's second stage from x~; an end that started from x_n (bdf2) or from its position
// at t + gamma h (implicit2) read a spurious rate along the end segment of U/2 or 1.4 U:
// measured before the fix, 3.3 and 2.6 N apart within 0.3 s (150 steps). After it: 3e-7 and 1e-5 N, rounding
// of the translated coordinates, which the slack segments' switching amplifies by ~10 every
// 50 ms as the line starts to snap (1.3 N by 1 s): so the comparison stops at 0.3 s, with a
// tolerance of 1e-3 N, 100x the rounding measured there and 1/2600 of the error.
TEST(ImplicitSchemes, TheEndSegmentsDampingIsGalileanInvariant) {
  const int N = 100, steps = 150;
  const double h = 0.002, span = 9;  // [s], [m]
  const Vec3 U(1, 0.5, 0);           // [m/s]
  for (const char* integrator : {"implicit", "bdf2", "implicit2"}) {
    double worst = 0;  // [N]
    std::vector<double> at_rest;
    for (int moving = 0; moving < 2; ++moving) {
      Environment env;
      env.wet = true;
      if (moving) env.water.current = U;
      std::ostringstream decl;
      decl << "ends=a,b length=10 segments=" << N
           << " diameter=0.02 mass_per_length=0.5 EA=1e4 damping=20 Cdn=1.2 Cdt=0.01 Can=1"
           << " integrator=" << integrator;
      std::string error;
      std::optional<Tether> t = reference_scenes::TetherFrom(decl.str(), env, &error);
      ASSERT_TRUE(t) << error;
      const Vec3 u = moving ? U : Vec3::Zero();
      std::vector<double> x(3 * (N + 1)), v(3 * (N + 1)), work(t->WorkspaceSize());
      std::vector<double> history(t->HistorySize() + 1, 0.0);
      // A straight start between the ends (the line then falls and swings: Newton iterates).
      for (int i = 0; i <= N; ++i) {
        for (int k = 0; k < 3; ++k) v[3 * i + k] = u[k];
        x[3 * i] = span * i / N;
        x[3 * i + 1] = 0;
        x[3 * i + 2] = 0;
      }
      Ends now;
      now.a.pos = Vec3(0, 0, 0);
      now.b.pos = Vec3(span, 0, 0);
      now.a.vel = now.b.vel = u;
      for (int k = 0; k < steps; ++k) {
        Ends next = now;
        next.time = now.time + h;
        next.a.pos += h * u;
        next.b.pos += h * u;
        ASSERT_TRUE(t->Advance(x.data(), v.data(), now, next, h, work.data(), history.data()).ok)
            << integrator << " step " << k;
        now = next;
        const double T = t->Reactions(x.data(), v.data(), now, work.data()).tension_b;
        if (!moving) {
          at_rest.push_back(T);
        } else {
          worst = std::max(worst, std::abs(T - at_rest[k]));
        }
      }
    }
    std::printf("%s: end B tension, moving frame against rest: largest difference %.3g N\n",
                integrator, worst);
    EXPECT_LT(worst, 1e-3) << integrator;
  }
}

// A declaration without `integrator` gets bdf2; `implicit` is still backward Euler by name, and
// an unknown name lists bdf2 first as the default.
TEST(Bdf2, IsTheDefaultAndImplicitStaysBackwardEuler) {
  DeclarationError e;
  const std::string base = "ends=a,b length=10 segments=10 diameter=0.02 mass_per_length=1 EA=1e5";
  std::optional<TetherDeclaration> d = ParseTether(base, Environment(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(d->params.integrator, Integrator::kBdf2);
  EXPECT_STREQ(IntegratorName(d->params.integrator), "bdf2");
  d = ParseTether(base + " integrator=implicit", Environment(), &e);
  ASSERT_TRUE(d) << e.message;
  EXPECT_EQ(d->params.integrator, Integrator::kImplicit);
  EXPECT_FALSE(ParseTether(base + " integrator=bdf3", Environment(), &e));
  EXPECT_NE(e.message.find("allowed: bdf2 (default), implicit, implicit2, explicit, rk4"),
            std::string::npos)
      << e.message;
}

std::string DefaultModelWith(const std::string& integrator) {
  std::ifstream f(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml");
  std::stringstream s;
  s << f.rdbuf();
  std::string xml = s.str();
  const size_t at = xml.find("integrator=implicit");
  EXPECT_NE(at, std::string::npos);
  return xml.replace(at, 19, "integrator=" + integrator);
}

using Bdf2MuJoCo = testing::MuJoCoFixture;
using Implicit2MuJoCo = testing::MuJoCoFixture;

// mj_copyData carries bdf2's history (it is in mjData::userdata): a copy stepped on reproduces
// the original bit for bit, as does a run after mj_resetData (the default scene: slack and
// taut segments, seabed, current, a free vehicle). The history is really there: the block is
// larger than with backward Euler by HistorySize() doubles.
TEST_F(Bdf2MuJoCo, CopyAndResetAreBitIdentical) {
  mjModel* m = Load(DefaultModelWith("bdf2"));
  mjModel* be = Load(DefaultModelWith("implicit"));
  ASSERT_TRUE(m && be);
  const Tether* t = GetTether(m, 0);
  EXPECT_EQ(t->HistorySize(), 1 + 6 * t->nodes());
  EXPECT_EQ(m->nuserdata - be->nuserdata, t->HistorySize());
  ExpectCopyIsBitIdentical(m);
  ExpectResetIsBitIdentical(m);
}

// implicit2 holds the vehicle's end with its stages' mean carried through the advance before's
// (plugin.cc, HeldMean; session 40): that mean and its step are state in mjData, which copies
// and resets must carry like the nodes'.
TEST_F(Implicit2MuJoCo, CarriedHeldMeanIsCopiedAndReset) {
  mjModel* m = Load(DefaultModelWith("implicit2"));
  ASSERT_NE(m, nullptr);
  ExpectCopyIsBitIdentical(m);
  ExpectResetIsBitIdentical(m);
}

// A winch with bdf2: the winch tests' hanging weight (tests/winch_test.cc, EveryIntegrator:
// 10 m, L0 = 1 m, mu = 1 kg/m, EA = 1e6 N, damping 2e3 N s, 50 kg on a slide)
// settled on its damped slide for 3 s, then free, paid out then hauled in at 0.5 m/s for 6 s
// each, crossing 2-3 regrids each way (each restarts the
// scheme with one backward-Euler step). Asserted as there: the deployed length within 1e-9 m
// of the ramped speed profile's sum, and the drum tension within 0.5% of the static m g +
// mu g L once the ramp's transient has decayed (from 4 s).
TEST_F(Bdf2MuJoCo, WinchPayoutAndHaulInWithinTheWinchTolerances) {
  const double g = 9.81, mass = 50, mu = 1;
  const std::string xml = R"(<mujoco><option timestep="0.002" gravity="0 0 -9.81"/><custom>
  <text name="tether:line" data="ends=drum,hook length=10 segments=10 diameter=0.02
        mass_per_length=1 EA=1e6 damping=2e3 integrator=bdf2"/>
  <text name="winch:line" data="end=A mode=speed actuator=w min_length=5 max_length=30
        max_speed=1 max_accel=0.5"/>
  </custom><worldbody><site name="drum"/>
  <body name="weight" pos="0 0 -10"><joint name="z" type="slide" axis="0 0 1" damping="4000"/>
  <geom type="sphere" size="0.1" mass="50"/><site name="hook"/></body>
  </worldbody><actuator><motor name="w" joint="z" gear="0"/></actuator></mujoco>)";
  mjModel* m = Load(xml);
  ASSERT_NE(m, nullptr);
  mjData* d = Make(m);
  // Settled on the damped slide for 3 s, then free (as WinchTest::Settle).
  d->ctrl[0] = 0;
  while (d->time < 3) mj_step(m, d);
  m->dof_damping[0] = 0;
  const double h = m->opt.timestep;
  for (double v : {0.5, -0.5}) {
    d->ctrl[0] = v;
    double L = GetWinch(m, d, 0).length, speed = GetWinch(m, d, 0).payout_speed;
    const int segments0 = GetWinch(m, d, 0).segments;
    double worst = 0;
    for (int k = 0; k < 3000; ++k) {
      mj_step(m, d);
      speed = v > speed ? std::min(v, speed + 0.5 * h) : std::max(v, speed - 0.5 * h);
      L += speed * h;
      const WinchState w = GetWinch(m, d, 0);
      ASSERT_NEAR(w.length, L, 1e-9);
      if (k * h < 4) continue;
      const double T = GetReactions(m, d, 0).tension_a;
      const double expected = mass * g + mu * g * w.length;
      worst = std::max(worst, std::abs(T - expected) / expected);
    }
    const int regrids = std::abs(GetWinch(m, d, 0).segments - segments0);
    std::printf("bdf2 v = %+.1f: %d regrids, tension error %.3g%%\n", v, regrids, 100 * worst);
    EXPECT_GE(regrids, 2);
    EXPECT_LE(worst, 0.005) << "v = " << v;
    ASSERT_FALSE(CheckDivergence(m, d).has_value()) << *CheckDivergence(m, d);
  }
}

// An overdamped segment mode steps as backward Euler with bdf2 and implicit2
// above their own onsets (Tether::StepsAsBackwardEuler, kSecondOrderMaxDampingRatioBdf2 and
// ...Implicit2; docs/limitations.md, session 29).
// Scene fuzzer seed 10116 reduced: 2.94 m of 7 mm line in 39 segments of 7.5 cm between two
// fixed ends (length equal to the span), in a 0.37 m/s current, axial damping 100 N s (segment
// damping ratio 15.5). Before, bdf2 at 0.2 ms read a largest tension of 133 N at 0.3 s and an
// end tension alternating step by step (6.4 and 72 N at 0.096 s) where backward Euler and
// explicit read 21 N; implicit2 at 30 N s (ratio 4.7) read 47 N. Each integrator's largest
// tension over 0.2-0.3 s is now within 2% of backward Euler's at 100 N s (measured: 23.86 N;
// bdf2 at 100 N s 23.86, implicit2 at 30 N s 23.93; bdf2 at 15 N s and implicit2 at 5 N s,
// ratios 2.3 and 0.8, which keep their own steps, 23.98 and 23.99: the damping moves it by
// 0.5%), and its end B tension changes by less than 1% from one step to the next (measured
// 0.08%; the alternation was 10x). bdf2 at 60 N s (ratio 9.3, below its onset 10: its own
// step, session 30) is held to the same.
std::string OverdampedLine(const char* integrator, double damping) {
  std::ostringstream s;
  s << R"(<mujoco><option timestep="0.0002"/><custom>
    <text name="water" data="density=1025 current=-0.3428750236,0.1520420392,0"/>
    <text name="tether:t" data="ends=a,b length=2.94081 segments=39 diameter=0.007076181903
      mass_per_length=0.07938433257 EA=91427.43162 Cdn=1.2 Cdt=0.01 Can=1 EI=0.002232605851
      EAc=91427.43162 damping=)"
    << damping << " integrator=" << integrator << R"("/>
    </custom><worldbody><body name="ta" mocap="true"><site name="a"/></body>
    <body name="tb" mocap="true" pos="-0.4135244169 1.044696358 -2.71771773"><site name="b"/>
    </body></worldbody></mujoco>)";
  return s.str();
}

struct LineRun {
  double largest = 0;      // [N] largest segment tension over the last 0.1 s
  double alternation = 0;  // [-] largest |T_B(n+1) - T_B(n)| / T_B(n) over the last 0.1 s
  bool backward_euler = false;
};

LineRun RunOverdampedLine(const char* integrator, double damping) {
  LineRun r;
  testing::LoadedScene s(OverdampedLine(integrator, damping));
  if (!s.d) return r;
  r.backward_euler = GetTether(s.m, 0)->StepsAsBackwardEuler();
  double last = NAN;
  while (s.d->time < 0.3 - 1e-9) {
    if (!s.Step()) return r;
    if (s.d->time < 0.2) continue;
    std::vector<double> T(GetTether(s.m, 0)->segments());
    GetTensions(s.m, s.d, 0, T.data());
    for (double Tj : T) r.largest = std::max(r.largest, Tj);
    const double tb = GetReactions(s.m, s.d, 0).tension_b;
    if (std::isfinite(last)) r.alternation = std::max(r.alternation, std::abs(tb - last) / last);
    last = tb;
  }
  return r;
}

TEST(SecondOrderSchemes, AnOverdampedSegmentModeStepsAsBackwardEuler) {
  const LineRun be = RunOverdampedLine("implicit", 100);
  ASSERT_GT(be.largest, 15);  // measured 21 N
  for (const auto& [integrator, damping, overdamped] :
       {std::tuple<const char*, double, bool>{"bdf2", 100, true}, {"implicit2", 30, true},
        {"bdf2", 60, false}, {"bdf2", 15, false}, {"implicit2", 5, false}}) {
    SCOPED_TRACE(std::string(integrator) + " at damping " + std::to_string(damping));
    const LineRun got = RunOverdampedLine(integrator, damping);
    EXPECT_EQ(got.backward_euler, overdamped);
    std::printf("%s, damping %g N s: largest tension %.4g N (backward Euler at 100 N s %.4g N), "
                "step-to-step change of the end tension %.3g\n",
                integrator, damping, got.largest, be.largest, got.alternation);
    EXPECT_NEAR(got.largest, be.largest, 0.02 * be.largest);
    EXPECT_LT(got.alternation, 0.01);
  }
}

// Each scheme at its own onset (session 30): bdf2 keeps its step up to a damping ratio of 10
// (kSecondOrderMaxDampingRatioBdf2; right at 10.9 on the line above), implicit2 only up to 3.
// The fixed comparison line of Bdf2.ObservedOrderIsTwo with its damping raised 25-fold, to
// 25,000 N s (segment axial mode damping ratio 5 at 20 segments). Session 29 stepped every
// bdf2 tether above 3 as backward Euler, which made it exactly as accurate as
// integrator=implicit, and the accuracy/cost line at 320 segments (ratio 3.2) read bdf2's
// fairlead error at 10 ms as 1.35 N instead of 0.047 N. Asserted: bdf2's fairlead tension RMS
// error against rk4 at 0.25 ms is at most half of integrator=implicit's at each of 4, 2 and
// 1 ms (measured 0.27, 0.28 and 0.22 of it), and implicit2's is backward Euler's to 1e-12
// relative (it takes the same step).
TEST(SecondOrderSchemes, Bdf2KeepsItsStepUpToItsOwnOnset) {
  Scene s = LineScene();
  s.duration = 20;
  const std::string from_decl = "damping=1000 ", to_decl = "damping=25000 ";
  const size_t at = s.declaration.find(from_decl);
  ASSERT_NE(at, std::string::npos);
  s.declaration.replace(at, from_decl.size(), to_decl);
  const int N = 20;
  const reference_scenes::Run ref = RunEngine(s, N, "rk4", 0.002, 0.00025, false);
  ASSERT_TRUE(ref.ok);
  auto error = [&](const char* integrator, double h) {
    return FairleadError(s, N, integrator, h, ref);
  };
  for (double h : {0.004, 0.002, 0.001}) {
    const double be = error("implicit", h), bdf2 = error("bdf2", h), sdirk = error("implicit2", h);
    std::printf("damping ratio 5, %g ms: bdf2 error %.4g N, implicit2 %.4g N, backward Euler "
                "%.4g N (bdf2 %.2f of it)\n",
                1e3 * h, bdf2, sdirk, be, bdf2 / be);
    EXPECT_LE(bdf2, 0.5 * be) << "bdf2 at " << h << " s";
    EXPECT_NEAR(sdirk, be, 1e-12 * be) << "implicit2 at " << h << " s";
  }
}

// The README's 0.01% row keeps its time error: the fixed line at 320 segments (segment damping
// ratio 3.2) with bdf2 at 10 ms, against the same line at 1 ms, over 10-60 s. Session 29's
// limit of 3 made this row first order without a test noticing (docs/accuracy_cost.md, session
// 30: 1.35 N against 640 segments where the row says 0.047 N). Tolerance: the row's own
// target, 0.01% of the line's mean tension (588 N): 0.059 N, for the step's error alone.
// Measured 0.020 N (the accuracy/cost sweep's time error for this row against its Richardson
// reference, 0.0202 N); as backward Euler, 1.34 N.
TEST(SecondOrderSchemes, TheReadmesFinestRowKeepsItsTimeError) {
  const Scene s = LineScene();
  const int N = 320;
  const reference_scenes::Run fine = RunEngine(s, N, "bdf2", 0.001, 0, false);
  ASSERT_TRUE(fine.ok);
  const size_t from = std::lround(s.error_from / s.sample);
  double mean = 0;
  for (size_t i = from; i < fine.T.size(); ++i) mean += fine.T[i] / (fine.T.size() - from);
  const double err = FairleadError(s, N, "bdf2", 0.01, fine);
  std::printf("320 segments, bdf2: 10 ms against 1 ms %.4g N RMS (mean tension %.1f N)\n", err,
              mean);
  EXPECT_LT(err, 1e-4 * mean);
}

}  // namespace
}  // namespace mjtether
