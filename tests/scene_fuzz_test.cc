// A scene fuzzer with physical oracles (issue 11, item 5; docs/scene_fuzzer.md).
//
// Each seed makes one random but plausible ROV scene: a TMS (mocap body, sometimes heaving or
// surging by a motion: declaration) and a free vehicle of 2-5000 kg with its own vehicle:
// hydrodynamics on a tether of 1-400 segments, EA 1e3-1e9 N, EI 0-1e3 N m^2, length 0.5-3 x
// the span between them, in a current of 0-3 m/s, with a seabed below, through or above the
// initial shape (or none), a thrust of 0-2 x what the tether holds (EA x max_strain), and one
// of the five integrators (each with probability 1/5; "Draw versions" below), at a MuJoCo step
// of 2 ms for 1 s.
//
// Oracle. Every scene must end in one of these outcomes (the test prints how many of each):
//   refused      refused at load (exit 2 from the CLI) with a cause this file recomputes from
//                the scene (an end or the vehicle below the seabed, ends beyond
//                length x (1 + max_strain), a diameter or segment count out of its threshold,
//                more than 1e5 explicit substeps, a coupling omega h = sqrt(k_end/(m + a)) h
//                (k_end = EA/L0, or EI/L0^3 where larger) at the vehicle at or above the
//                advisor's limit for the integrator: explicit 2, rk4 0.5 (0.8 until
//                session 29); implicit2 none here, its consistent coupling
//                applies from 0.5, docs/coupling.md; with EAc, a segment that starts
//                compressed beyond its Euler load, StartCompression);
//   agrees       runs to the end, every value finite, no MuJoCo warning, and agrees with the
//                same scene at a 10x smaller MuJoCo step: vehicle position within
//                max(5 cm, 2% of the span) and the vehicle-end tension averaged over the last
//                0.2 s within max(0.5 N, 5%) (the issue's criterion for "silently wrong");
//                where they disagree, against the scene at 0.02 ms within that tolerance
//                plus the spread of the two refinements (0.2 vs 0.02 ms: the reference's
//                own uncertainty, e.g. a mean over snaps); where that fails too, with the
//                window moved up to a tenth of its length earlier, if the position agrees and
//                a snap at the window's edge moves either run's mean beyond the tolerance
//                (PhaseRange; counted apart as "agrees within a window moved ..."); and,
//                without a current, the tether's energy never rises above its start by more
//                than the work its ends did on it (EnergyTolerance, below);
//   warned       a stretched start that disagrees with its fine-step self (or whose fine-step
//                self stopped on the release's snap, since session 26), where the load
//                emitted the "starts stretched" warning (captured from Attach: the strain, the
//                tension, and that the outcome depends on <option timestep>, "compare with a
//                smaller one") and the same scene started unstretched (the tether as long as
//                the span) agrees: the stretch is the cause, as the warning said. Counted
//                apart from "agrees". A stretched start that disagrees also unstretched fails
//                (its class: tools/scene_fuzz_classify.py);
//   diverged     stops with a divergence message whose cause this file checks: thrust beyond
//                EA x max_strain, ends pulled beyond length x (1 + max_strain), an end moving
//                more than half of max_strain L0 per step, an end below the seabed, a stretched
//                start; an end damping too stiff for the vehicle's step (h lambda > 2, from
//                an upper bound of the end's drag and damping); the end node landing on a
//                seabed stiff on the vehicle's step under the held end force (the scene's
//                seabed_rate() >= 0.7 and the vehicle at the seabed); a coupling chatter (the
//                run-time work balance) where omega h is at
//                least half the advisor's limit; or, where the message blames the step, the
//                same scene at a 10x smaller step runs to the end, or, where that fails and
//                the message advises max_step (an explicit scheme at its automatic
//                substeps), the scene with that max_step does.
// Anything else is a failure: a refusal or divergence whose cause does not hold, a scene that
// should have been refused, a non-finite value, a MuJoCo warning (it resets the data
// silently), or a run that disagrees with its fine-step self.
//
// Seeds listed in tests/scene_fuzz_known.txt fail for a reason given there (open problems):
// they run and are counted, but not asserted.
// Seeds in tests/scene_fuzz_regressions.txt are scenes that a long run once found broken;
// they always run in addition to the fixed set.
//
// Environment: MJTETHER_SCENE_FUZZ_COUNT (default 200), MJTETHER_SCENE_FUZZ_FIRST (first
// seed, default 1), MJTETHER_SCENE_FUZZ_THREADS (default 2), MJTETHER_SCENE_FUZZ_VERBOSE=1
// (one line per scene, flushed), MJTETHER_SCENE_FUZZ_XML=1 (print each scene's MJCF instead of
// running it), MJTETHER_SCENE_FUZZ_SEEDS=a,b,c (only these seeds; "372d1": seed 372 of draw 1),
// MJTETHER_SCENE_FUZZ_START=static (every scene declares start=static; docs/static_start.md),
// MJTETHER_SCENE_FUZZ_SLACK=x (every scene's tether as long as its span times 1 + x, as
// Unstretched makes it for x = 0: the draw's lengths, 0.5-3 x the span, seldom start a line
// near taut; a measurement, not a CI setting: docs/scene_fuzzer.md, session 43).
// MJTETHER_SCENE_FUZZ_STEP=h (every scene at the MuJoCo step h instead of 2 ms, its references
// at h/10 and h/100; a measurement, not a CI setting: docs/scene_fuzzer.md, session 46).
//
// A second test runs the world draw (MakeWorld: the same scenes with a tether touching a geom
// or paid out by a winch) through the same oracle: MJTETHER_SCENE_FUZZ_WORLD_COUNT (default
// 150), plus the seeds of tests/scene_fuzz_world_regressions.txt, known failures in
// tests/scene_fuzz_world_known.txt, the variables above apply.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "mjtether.h"
#include "warning_handler.h"

namespace mjtether {
namespace {

// [s] MuJoCo step the scenes run at: 2 ms, or MJTETHER_SCENE_FUZZ_STEP (0 < h <= 2 ms), a
// measurement of the oracle at a user's smaller step (docs/scene_fuzzer.md, session 46). The
// references follow it (h/10, h/100); the draw does not (kDrawStep), so a seed is the same
// scene at every step.
double FuzzStep() {
  const char* v = std::getenv("MJTETHER_SCENE_FUZZ_STEP");
  if (!v || !*v) return 0.002;
  char* end = nullptr;
  const double h = std::strtod(v, &end);
  if (*end || !(h > 0 && h <= 0.002)) {
    std::fprintf(stderr, "MJTETHER_SCENE_FUZZ_STEP=%s: a step in (0, 0.002] s\n", v);
    std::exit(2);
  }
  return h;
}
const double kStep = FuzzStep();
constexpr double kDrawStep = 0.002;  // [s] the step the draw's limits are set for
constexpr double kDuration = 1.0;  // [s] simulated
constexpr double kThrustStart = 0.1;  // [s] the thrust ramps from 0 then to s.thrust at 0.4 s
constexpr double kAverage = 0.2;   // [s] tension averaged over the last kAverage
// Explicit tethers substep at their stability limit, which for short stiff segments is a
// microsecond: such a scene costs minutes per simulated second. Its duration is cut so that
// it costs at most kBudget node updates (substeps x nodes x stages) per run, but not below
// kMinDuration; the test counts the scenes run shortened.
constexpr double kBudget = 2e7;
constexpr double kMinDuration = 0.1;  // [s]
constexpr double kRho = 1025;         // [kg/m^3]
constexpr double kPi = 3.14159265358979323846;

struct Scene {
  unsigned long long seed = 0;
  std::string integrator;
  double span = 0, length = 0;  // [m]
  int segments = 0;
  double diameter = 0, mpl = 0, EA = 0, EI = 0, damping = 0;
  Vec3 b = Vec3::Zero();        // [m] vehicle (end B); end A at the origin
  Vec3 current = Vec3::Zero();  // [m/s]
  int seabed_kind = 0;          // 0 none, 1 below the shape, 2 through it, 3 above an end
  double seabed = 0;            // [m]
  double motion_amp = 0, motion_period = 1;  // [m], [s]; amp 0: no motion
  int motion_axis = 0;
  double mass = 0, added_min = 0;  // [kg] vehicle mass, smallest translational added mass
  double lin = 0, quad = 0, inertia = 0;  // [N s/m], [N s^2/m^2], [kg m^2] vehicle damping
  double thrust = 0;               // [N] final thrust
  Vec3 thrust_dir = Vec3::UnitX();
  double omega_h = 0;  // [-] coupling frequency at the vehicle times the step
  std::string xml;

  // The world draw (MakeWorld, "The world draw" below); all off in a draw-1 or draw-2 scene.
  bool world = false;                           // made by MakeWorld
  bool contact = false, winch = false;          // contact= on the tether, winch:t at end A
  bool static_start = false;                    // start=static declared
  // Contact: one static obstacle on the world body, named "rock".
  std::string geom;                             // sphere, capsule, cylinder or box
  Vec3 geom_pos = Vec3::Zero();                 // [m] centre
  Vec3 geom_axis = Vec3::UnitZ();               // [-] capsule and cylinder axis (unit)
  Vec3 geom_dir = -Vec3::UnitZ();  // [-] the way it was moved from the shape's middle (unit)
  Vec3 geom_size = Vec3::Zero();                // [m] radius, half-length; box: half sizes
  double geom_yaw = 0;                          // [rad] box rotation about z
  double friction = 0;                          // [-] contact_friction (0: not declared)
  bool contact_all = true;                      // contact=all, else contact=rock
  double clearance = 0;  // [m] of the initial shape's skin from the geom (< 0: starts inside)
  // Winch: mode=speed (ctrl a payout speed [m/s]) or tension (ctrl a set tension [N]).
  std::string winch_mode;
  double min_length = 0, max_length = 0;        // [m]
  double max_speed = 0, max_accel = 0, tau = 0;  // [m/s], [m/s^2], [s]
  double winch_ctrl = 0;  // [m/s] final payout speed (speed) or [N] set tension (tension)
  double ramp = 0;        // [s] the speed ramp from kThrustStart (speed mode)
  bool reverse = false;   // speed mode: the payout ramps back to -winch_ctrl by 0.8 s

  double holds() const { return EA * 1.0; }  // [N] EA x max_strain (default 1)
  double L0() const { return length / segments; }
  // [N/m] the stiffness at the vehicle's end that the advisor's coupling frequency reads:
  // EA/L0, or the bending's EI/L0^3 across the line where larger (equal segments, a pinned
  // end; Tether::EndBendingStiffness, session 37). EAc is EA in these scenes.
  // [-] the seabed under the end node on the vehicle's step where it touches (CheckSeabedEnd,
  // plugin/plugin.cc; session 38): max(omega_s h, h c_s/m_eff) with the default penalty 1e5
  // N/m^2 and its damping, critical for the tether's mass, over the node's share L0/2; 0
  // without a seabed. m_eff = m + the smallest added mass, as for omega_h.
  double seabed_rate() const {
    if (seabed_kind == 0) return 0;
    const double share = L0() / 2, m_eff = mass + added_min;  // [m], [kg]
    const double k = 1e5 * share, c = 2 * std::sqrt(1e5 * mpl) * share;  // [N/m], [N s/m]
    return std::max(std::sqrt(k / m_eff), c / m_eff) * kStep;
  }
  double k_end() const {
    const double axial = EA / L0();
    return segments > 1 && EI > 0 ? std::max(axial, EI / (L0() * L0() * L0())) : axial;
  }
};

double LogUniform(std::mt19937_64& r, double lo, double hi) {
  return std::exp(std::uniform_real_distribution<double>(std::log(lo), std::log(hi))(r));
}
double Uniform(std::mt19937_64& r, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(r);
}
bool Chance(std::mt19937_64& r, double p) { return Uniform(r, 0, 1) < p; }

// The lowest point of the initial shape without a seabed (the engine's own catenary).
double LowestPoint(const Scene& s) {
  TetherParams p;
  p.length = s.length;
  p.segments = s.segments;
  p.diameter = s.diameter;
  p.mass_per_length = s.mpl;
  p.EA = s.EA;
  p.effects = kAxial | kWeight | kBuoyancy;
  Environment env;
  env.wet = true;
  std::string error;
  std::optional<Tether> t = Tether::Create(p, env, &error);
  if (!t) return 0;
  std::vector<double> x(3 * t->nodes()), v(3 * t->nodes());
  Ends ends;
  ends.b.pos = s.b;
  t->InitialShape(ends, x.data(), v.data());
  double z = 0;
  for (int i = 0; i < t->nodes(); ++i) z = std::min(z, x[3 * i + 2]);
  return z;
}

// The initial shape of the engine's own tether (Tether::InitialShape) for the scene, node
// positions x, y, z (empty where the tether cannot be made), with the values as the MJCF gives
// them to the plugin (10 digits, Make): the seabed, and with EI also EAc = EA as declared.
// *out: the tether's parameters.
std::vector<double> InitialShapeOf(const Scene& s, TetherParams* out) {
  auto xml = [](double v) {
    std::ostringstream o;
    o.precision(10);
    o << v;
    return std::stod(o.str());
  };
  TetherParams p;
  p.length = xml(s.length);
  p.segments = s.segments;
  p.diameter = xml(s.diameter);
  p.mass_per_length = xml(s.mpl);
  p.EA = xml(s.EA);
  p.effects = kAxial | kWeight | kBuoyancy;
  if (s.EI > 0) {
    p.EAc = p.EA;
    p.EI = xml(s.EI);
    p.effects |= kCompression;
  }
  Environment env;
  env.wet = true;
  if (s.seabed_kind != 0) {
    p.effects |= kSeabed;
    env.water.has_seabed = true;
    env.water.seabed = xml(s.seabed);
  }
  *out = p;
  std::string error;
  std::optional<Tether> t = Tether::Create(p, env, &error);
  if (!t) return {};
  std::vector<double> x(3 * t->nodes()), v(3 * t->nodes());
  Ends ends;
  ends.b.pos = Vec3(xml(s.b.x()), xml(s.b.y()), xml(s.b.z()));
  t->InitialShape(ends, x.data(), v.data());
  return x;
}

// The compressive strain of the scene's most compressed segment at the start (0: none), with
// the force EAc x strain over the segment's Euler buckling load pi^2 EI / L0^2 in *over_euler:
// the initial shape of the engine's own tether (Tether::InitialShape, with the seabed and EAc =
// EA as declared), which puts every chord at L0 where it can. With one segment it is the
// geometry alone, 1 - span / length; with more, chords of L0 (walked along the catenary or the
// seabed path, else projected onto L0) unless that fails to converge.
double StartCompression(const Scene& s, double* over_euler) {
  *over_euler = 0;
  if (!(s.EI > 0)) return 0;  // no EAc declared: a short chord is slack
  TetherParams p;
  const std::vector<double> x = InitialShapeOf(s, &p);
  if (x.empty()) return 0;
  double chord = INFINITY;
  const double L0 = p.length / p.segments;
  for (int k = 0; k < s.segments; ++k) {
    chord = std::min(chord, (Vec3(&x[3 * k + 3]) - Vec3(&x[3 * k])).norm() / L0);
  }
  const double strain = std::max(0.0, 1 - chord);
  *over_euler = p.EAc * strain / (kPi * kPi * p.EI / (L0 * L0));
  return strain;
}

// Draw versions. Draw 1 (until bdf2 became the default integrator) picks one of four
// integrators. Draw 2 (the current one) makes the draw-1 scene of the seed, then, from a second
// stream of its own, replaces its integrator by bdf2 with probability 1/5: each of the five
// integrators then has probability 1/5, and a seed that is not swapped is exactly its draw-1
// scene (the first stream is consumed as before). Lists of seeds (known, regressions) name the
// draw a scene was found with ("draw=1"); a draw-1 seed that draw 2 does not swap is the same
// scene as its draw-2 self and is run once.
constexpr int kDraw = 2;  // the draw of seeds given by number (the CI range, MJTETHER_...)

bool SwapsToBdf2(unsigned long long seed) {
  std::mt19937_64 r(seed * 0xD1B54A32D192ED03ull + 777);
  return std::uniform_int_distribution<int>(0, 4)(r) == 4;
}

// A scene: its seed and its draw, with a draw-1 scene that draw 2 leaves unchanged written as
// draw 2 (the same scene).
struct SceneId {
  unsigned long long seed = 0;
  int draw = kDraw;
  bool operator<(const SceneId& o) const {
    return seed != o.seed ? seed < o.seed : draw < o.draw;
  }
};
SceneId Canonical(unsigned long long seed, int draw) {
  return {seed, draw == 1 && !SwapsToBdf2(seed) ? 2 : draw};
}
std::string Name(const SceneId& id) {
  return std::to_string(id.seed) + (id.draw == kDraw ? "" : " draw=" + std::to_string(id.draw));
}

Scene Make(unsigned long long seed, int draw = kDraw) {
  std::mt19937_64 r(seed * 0x9E3779B97F4A7C15ull + 12345);
  Scene s;
  s.seed = seed;
  const char* integrators[4] = {"explicit", "implicit", "implicit2", "rk4"};
  s.integrator = integrators[std::uniform_int_distribution<int>(0, 3)(r)];
  if (draw >= 2 && SwapsToBdf2(seed)) s.integrator = "bdf2";
  s.span = LogUniform(r, 2, 200);
  s.length = Uniform(r, 0.5, 3) * s.span;
  s.segments = static_cast<int>(std::lround(LogUniform(r, 1, 400)));
  s.diameter = LogUniform(r, 0.005, 0.05);
  // Mean density 600-3000 kg/m^3: foam-jacketed umbilicals to steel-armoured cables.
  s.mpl = Uniform(r, 600, 3000) * kPi * s.diameter * s.diameter / 4;
  s.EA = LogUniform(r, 1e3, 1e9);
  s.EI = Chance(r, 0.5) ? 0 : LogUniform(r, 1e-3, 1e3);
  s.damping = Chance(r, 0.7) ? 0 : LogUniform(r, 1, 1e3);
  // Vehicle: from the TMS down and out, elevation -80..+20 degrees.
  const double az = Uniform(r, 0, 2 * kPi), el = Uniform(r, -80, 20) * kPi / 180;
  s.b = s.span * Vec3(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  if (Chance(r, 0.7)) {
    const double c = Uniform(r, 0, 3), dir = Uniform(r, 0, 2 * kPi);
    s.current = c * Vec3(std::cos(dir), std::sin(dir), 0);
  }
  const double top = std::min(0.0, s.b.z()), low = LowestPoint(s);
  s.seabed_kind = std::uniform_int_distribution<int>(0, 3)(r);
  if (s.seabed_kind == 2 && !(low < top - 0.01)) s.seabed_kind = 1;
  if (s.seabed_kind == 1) s.seabed = std::min(low, top) - Uniform(r, 0.5, 20);
  if (s.seabed_kind == 2) s.seabed = Uniform(r, low, top);
  if (s.seabed_kind == 3) s.seabed = top + Uniform(r, 0.1, 5);
  if (Chance(r, 0.3)) {
    s.motion_amp = LogUniform(r, 0.05, 5);
    s.motion_period = Uniform(r, 2, 10);
    s.motion_axis = std::uniform_int_distribution<int>(0, 2)(r);
  }
  s.mass = LogUniform(r, 2, 5000);
  const double side = std::cbrt(s.mass / 1000);  // [m] a box of the vehicle's mass in water
  const double I = s.mass * side * side / 6;     // [kg m^2]
  const double volume = s.mass / kRho * Uniform(r, 0.97, 1.03);
  double added[3];
  for (double& a : added) a = s.mass * Uniform(r, 0.3, 1.0);
  s.added_min = std::min({added[0], added[1], added[2]});
  const double lin = s.mass * Uniform(r, 0.2, 2), quad = 0.5 * kRho * side * side;
  s.lin = lin, s.quad = quad, s.inertia = I;
  if (Chance(r, 0.6)) {
    s.thrust = Uniform(r, 0, 2) * s.holds();
    Vec3 dir = s.b.normalized() + 0.5 * Vec3(Uniform(r, -1, 1), Uniform(r, -1, 1), 0);
    s.thrust_dir = dir.normalized();
  }
  const double m_eff = s.mass + s.added_min;
  s.omega_h = std::sqrt(s.k_end() / m_eff) * kStep;

  std::ostringstream x;
  x.precision(10);
  x << "<mujoco><option timestep=\"" << kStep << "\"/><custom>\n<text name=\"water\" data=\""
    << "density=" << kRho;
  if (s.current.norm() > 0) x << " current=" << s.current.x() << "," << s.current.y() << ",0";
  if (s.seabed_kind != 0) x << " seabed=" << s.seabed;
  x << "\"/>\n<text name=\"vehicle:rov\" data=\"volume=" << volume << " cob=0,0," << 0.1 * side
    << " added_mass=" << added[0] << "," << added[1] << "," << added[2] << "," << 0.3 * I << ","
    << 0.3 * I << "," << 0.3 * I << " linear_damping=" << lin << "," << lin << "," << lin << ","
    << I << "," << I << "," << I << " quadratic_damping=" << quad << "," << quad << "," << quad
    << "," << I << "," << I << "," << I << " coriolis=0\"/>\n"
    << "<text name=\"tether:t\" data=\"ends=tms_site,att length=" << s.length
    << " segments=" << s.segments << " diameter=" << s.diameter << " mass_per_length=" << s.mpl
    << " EA=" << s.EA << " Cdn=1.2 Cdt=0.01 Can=1 integrator=" << s.integrator;
  if (s.EI > 0) x << " EI=" << s.EI << " EAc=" << s.EA;
  if (s.damping > 0) x << " damping=" << s.damping;
  // MJTETHER_SCENE_FUZZ_START=static: every scene with start=static (docs/static_start.md).
  if (const char* start = std::getenv("MJTETHER_SCENE_FUZZ_START"); start && *start) {
    x << " start=" << start;
  }
  x << "\"/>\n";
  if (s.motion_amp > 0) {
    x << "<text name=\"motion:tms\" data=\""
      << "xyz"[s.motion_axis] << "=" << s.motion_amp << "," << s.motion_period << ",0\"/>\n";
  }
  if (s.thrust > 0)
    x << "<text name=\"thrust:thr\" data=\"t=" << kThrustStart << ",0.4 ctrl=0," << s.thrust
      << "\"/>\n";
  x << "</custom><worldbody>\n<body name=\"tms\" mocap=\"true\"><site name=\"tms_site\"/></body>\n"
    << "<body name=\"rov\" pos=\"" << s.b.x() << " " << s.b.y() << " " << s.b.z()
    << "\"><freejoint/><inertial pos=\"0 0 0\" mass=\"" << s.mass << "\" diaginertia=\"" << I << " "
    << I << " " << I << "\"/><site name=\"att\"/><site name=\"thr\"/></body>\n"
    << "</worldbody>";
  if (s.thrust > 0) {
    x << "<actuator><motor name=\"thr\" site=\"thr\" gear=\"" << s.thrust_dir.x() << " "
      << s.thrust_dir.y() << " " << s.thrust_dir.z() << " 0 0 0\"/></actuator>";
  }
  x << "</mujoco>\n";
  s.xml = x.str();
  return s;
}

// The world draw (docs/scene_fuzzer.md, session 15): what users hit that draws 1 and 2 never
// declare, a tether touching a MuJoCo geom (contact=, docs/contact.md) and a winch paying it
// out or hauling it in (winch:, docs/winch.md). MakeWorld(seed) makes the draw-2 scene of the
// seed (the first two streams consumed as Make does, so the scene below is that seed's draw-2
// scene, unchanged) and then, from a third stream of its own, adds one of
//   contact (48%)  contact=all or contact=rock, contact_friction 0 (half) or 0.1-1, and one
//                  static obstacle "rock" on the world body: a sphere, capsule, cylinder or box
//                  of 2-20% of the span (a cylinder or capsule 10-100% of it long, across the
//                  chord, upright or any way), below the tether's middle (75%) or beside it
//                  (25%), placed so that the initial shape's skin is clear of it by up to
//                  min(0.5 m, 2% of the span) (half the scenes: the tether moves onto it) or
//                  inside it by up to half the diameter (the other half: a tether resting
//                  against it, pushed out at the start); both end sites outside it by
//                  2% of the span + d (ContactEndMargin; the rock halved until they are);
//   winch (48%)    winch:t at end A (the TMS's site) on a gear-0 motor "winch", mode=speed
//                  (70%: a thrust:winch schedule ramps the payout speed from 0 at kThrustStart
//                  to +-0.1-3 m/s in 0.05-0.3 s, and in 30% of these back to the opposite speed
//                  by 0.8 s) or mode=tension (a set tension of 0.3-3 x the deployed line's net
//                  weight, at least 0.3 N, from t = 0), min_length max(L0, 0.3-1 x length),
//                  max_length 1-3 x length, max_speed 0.2-5 m/s (in 85% of the scenes cut to
//                  what the step allows, a quarter segment per step: the others may be
//                  refused), max_accel 0.2-10 m/s^2, tau 0-0.5 s;
//   both (4%)      contact and a winch: refused at load (docs/winch.md);
// and, in 4% of the scenes, start=static (refused with contact or a winch,
// docs/static_start.md). The third stream draws every parameter of both kinds whatever the kind,
// so a scene's obstacle does not depend on its winch's draws or the other way round.
enum WorldKind { kWorldContact, kWorldWinch, kWorldBoth };

Vec3 Rotated(const Vec3& v, double yaw) {
  return Vec3(std::cos(yaw) * v.x() - std::sin(yaw) * v.y(),
              std::sin(yaw) * v.x() + std::cos(yaw) * v.y(), v.z());
}

// The signed distance [m] from p to the scene's obstacle (negative inside), in closed form.
double SignedDistance(const Scene& s, const Vec3& p) {
  const Vec3 q = p - s.geom_pos;
  const double radius = s.geom_size.x(), half = s.geom_size.y();
  if (s.geom == "sphere") return q.norm() - radius;
  if (s.geom == "capsule") {
    const double t = std::clamp(q.dot(s.geom_axis), -half, half);
    return (q - t * s.geom_axis).norm() - radius;
  }
  if (s.geom == "cylinder") {
    const double t = q.dot(s.geom_axis);
    const double dr = (q - t * s.geom_axis).norm() - radius, da = std::abs(t) - half;
    return std::min(std::max(dr, da), 0.0) + std::hypot(std::max(dr, 0.0), std::max(da, 0.0));
  }
  // box: half sizes geom_size, turned by geom_yaw about z
  const Vec3 local = Rotated(q, -s.geom_yaw);
  const Vec3 d(std::abs(local.x()) - s.geom_size.x(), std::abs(local.y()) - s.geom_size.y(),
               std::abs(local.z()) - s.geom_size.z());
  return Vec3(std::max(d.x(), 0.0), std::max(d.y(), 0.0), std::max(d.z(), 0.0)).norm() +
         std::min(std::max({d.x(), d.y(), d.z()}), 0.0);
}

// The clearance [m] of the tether's skin from the obstacle along the polyline x: the smallest
// signed distance of a point of a segment less the radius d/2. The signed distance of a convex
// geom is convex along a line, so a golden-section search along each segment finds its
// minimum (60 iterations: 3e-13 of the segment), as the plugin's glue does for boxes and
// cylinders (docs/contact.md, Geometry). Sampling the segment instead misses the closest point
// of a geom smaller than a segment: the first version, at quarters, read 9 mm of clearance on
// world seed 93 where a segment cut into its 0.19 m sphere.
double Clearance(const Scene& s, const std::vector<double>& x) {
  double c = INFINITY;
  const int nodes = static_cast<int>(x.size() / 3);
  constexpr double kInvPhi = 0.61803398874989484820;
  for (int i = 0; i + 1 < nodes || (nodes == 1 && i == 0); ++i) {
    const Vec3 a(&x[3 * i]);
    const Vec3 ab = nodes == 1 ? Vec3(Vec3::Zero()) : Vec3(Vec3(&x[3 * i + 3]) - a);
    auto f = [&](double t) { return SignedDistance(s, a + t * ab); };
    double lo = 0, hi = 1;
    double t1 = hi - kInvPhi * (hi - lo), t2 = lo + kInvPhi * (hi - lo);
    double f1 = f(t1), f2 = f(t2);
    for (int k = 0; k < 60; ++k) {
      if (f1 < f2) {
        hi = t2, t2 = t1, f2 = f1;
        t1 = hi - kInvPhi * (hi - lo), f1 = f(t1);
      } else {
        lo = t1, t1 = t2, f1 = f2;
        t2 = lo + kInvPhi * (hi - lo), f2 = f(t2);
      }
    }
    c = std::min({c, f(0), f(1), f(0.5 * (lo + hi))});
  }
  return c - s.diameter / 2;
}

// How far both end sites must be outside the obstacle [m]: 2% of the span plus the diameter, so
// that an end does not start against the rock. (The "end's own geom" rule, a site within L0 + d
// of a geom, applies only to geoms on the end's body, docs/contact.md: the rock is on the world
// body, the ends on the TMS and the vehicle, so L0 is not in the margin; with one or two
// segments it could not be, the middle of the line being within L0 of both ends.)
double ContactEndMargin(const Scene& s) { return 0.02 * s.span + s.diameter; }

// The winch's <text> (also rewritten by Unstretched).
std::string WinchText(const Scene& s) {
  std::ostringstream x;
  x.precision(10);
  x << "<text name=\"winch:t\" data=\"end=A mode=" << s.winch_mode
    << " actuator=winch min_length=" << s.min_length << " max_length=" << s.max_length
    << " max_speed=" << s.max_speed << " max_accel=" << s.max_accel << " tau=" << s.tau
    << "\"/>\n";
  return x.str();
}

// The net weight of the tether in water per length [N/m].
double NetWeight(const Scene& s) {
  return std::abs(s.mpl - kRho * kPi * s.diameter * s.diameter / 4) * 9.81;
}

// The obstacle's <geom> (also rewritten by Cleared).
std::string RockXml(const Scene& s) {
  std::ostringstream body;
  body.precision(10);
  const Vec3& c = s.geom_pos;
  body << "<geom name=\"rock\" type=\"" << s.geom << "\" ";
  if (s.geom == "sphere") {
    body << "pos=\"" << c.x() << " " << c.y() << " " << c.z() << "\" size=\"" << s.geom_size.x();
  } else if (s.geom == "box") {
    body << "pos=\"" << c.x() << " " << c.y() << " " << c.z() << "\" euler=\"0 0 "
         << s.geom_yaw * 180 / kPi << "\" size=\"" << s.geom_size.x() << " " << s.geom_size.y()
         << " " << s.geom_size.z();
  } else {
    const Vec3 a = c - s.geom_size.y() * s.geom_axis, b = c + s.geom_size.y() * s.geom_axis;
    body << "fromto=\"" << a.x() << " " << a.y() << " " << a.z() << " " << b.x() << " " << b.y()
         << " " << b.z() << "\" size=\"" << s.geom_size.x();
  }
  body << "\"/>\n";
  return body.str();
}

Scene MakeWorld(unsigned long long seed) {
  Scene s = Make(seed, kDraw);
  std::mt19937_64 r(seed * 0xBF58476D1CE4E5B9ull + 4242);
  s.world = true;
  const double kind_draw = Uniform(r, 0, 1);
  const WorldKind kind = kind_draw < 0.48 ? kWorldContact
                         : kind_draw < 0.96 ? kWorldWinch
                                            : kWorldBoth;
  s.contact = kind != kWorldWinch;
  s.winch = kind != kWorldContact;
  s.static_start = Chance(r, 0.04);
  // The obstacle.
  const char* types[4] = {"sphere", "capsule", "cylinder", "box"};
  s.geom = types[std::uniform_int_distribution<int>(0, 3)(r)];
  const double radius = s.span * LogUniform(r, 0.02, 0.2);
  const double half = s.span * Uniform(r, 0.05, 0.5);
  const Vec3 box(s.span * LogUniform(r, 0.02, 0.2), s.span * LogUniform(r, 0.02, 0.2),
                 s.span * LogUniform(r, 0.02, 0.2));
  s.geom_yaw = Uniform(r, 0, 2 * kPi);
  const int axis_kind = std::uniform_int_distribution<int>(0, 3)(r);
  const Vec3 any(Uniform(r, -1, 1), Uniform(r, -1, 1), Uniform(r, -1, 1));
  const bool beside = Chance(r, 0.25);
  const double side = Chance(r, 0.5) ? 1 : -1;
  const bool starts_clear = Chance(r, 0.5);
  const double depth = Uniform(r, 0, 1);
  s.friction = Chance(r, 0.5) ? 0 : Uniform(r, 0.1, 1);
  s.contact_all = Chance(r, 0.7);
  s.clearance = starts_clear ? depth * std::min(0.5, 0.02 * s.span) : -depth * 0.5 * s.diameter;
  // The winch.
  s.winch_mode = Chance(r, 0.7) ? "speed" : "tension";
  // At least L0 x (1 + 1e-8), at most the length: the plugin takes L0 from the MJCF's 10-digit
  // length, which may put a min_length of exactly L0 below it (with one segment, min_length is
  // the length, the same 10 digits).
  s.min_length = std::min(s.length, std::max(s.L0() * (1 + 1e-8), s.length * Uniform(r, 0.3, 1)));
  s.max_length = s.length * Uniform(r, 1, 3);
  s.max_speed = LogUniform(r, 0.2, 5);
  // 0.999: the plugin compares max_speed x timestep with a quarter of L0 as the MJCF's 10
  // digits give them.
  if (Chance(r, 0.85)) s.max_speed = std::min(s.max_speed, 0.999 * 0.25 * s.L0() / kDrawStep);
  s.max_accel = LogUniform(r, 0.2, 10);
  s.tau = Uniform(r, 0, 0.5);
  const double speed = (Chance(r, 0.5) ? 1 : -1) * Uniform(r, 0.1, 3);
  s.ramp = Uniform(r, 0.05, 0.3);
  s.reverse = Chance(r, 0.3);
  const double tension = LogUniform(r, 0.3, 3) * std::max(1.0, NetWeight(s) * s.length);
  s.winch_ctrl = s.winch_mode == "speed" ? speed : tension;

  if (s.contact) {
    // Axes and the direction the obstacle is moved from the tether's middle: "down" is -z less
    // its part along the chord (the chord is at most 80 degrees from horizontal, so it is not
    // 0), "across" the horizontal normal to the chord.
    const Vec3 chord = s.b.normalized();
    const Vec3 down = (-Vec3::UnitZ() + chord.z() * chord).normalized();
    const Vec3 across = chord.cross(Vec3::UnitZ()).normalized();
    s.geom_axis = axis_kind <= 1  ? across
                  : axis_kind == 2 ? Vec3(Vec3::UnitZ())
                  : (any.norm() > 1e-6 ? Vec3(any.normalized()) : across);
    const Vec3 dir = beside ? Vec3(side * across) : down;
    s.geom_dir = dir;
    TetherParams p;
    const std::vector<double> x = InitialShapeOf(s, &p);
    // The middle of the initial shape (half its polyline's length).
    Vec3 middle = 0.5 * s.b;
    if (!x.empty()) {
      double total = 0;
      const int n = static_cast<int>(x.size() / 3);
      for (int i = 0; i + 1 < n; ++i) total += (Vec3(&x[3 * i + 3]) - Vec3(&x[3 * i])).norm();
      double run = 0;
      for (int i = 0; i + 1 < n; ++i) {
        const Vec3 a(&x[3 * i]), b(&x[3 * i + 3]);
        const double l = (b - a).norm();
        if (run + l >= total / 2 && l > 0) {
          middle = a + (total / 2 - run) / l * (b - a);
          break;
        }
        run += l;
      }
    }
    // Shrink the obstacle by halves until both ends are clear of it by the margin (at most 20
    // times: 1e-6 of the drawn size).
    for (int shrink = 0; shrink < 20; ++shrink) {
      const double f = std::pow(0.5, shrink);
      s.geom_size = s.geom == "box" ? Vec3(f * box) : Vec3(f * radius, f * half, 0);
      const double extent = s.geom_size.norm();
      // The obstacle's centre at middle + D dir, D the first distance at which the clearance
      // reaches s.clearance: scanned in 400 steps over extent + span (the clearance is that
      // of the obstacle's centre on the shape, -(its inner radius + d/2), at D = 0), then 60
      // bisections (to 1e-18 of the scan's step).
      auto clearance = [&](double D) {
        s.geom_pos = middle + D * dir;
        return x.empty() ? INFINITY : Clearance(s, x);
      };
      const double step = (extent + s.span) / 400;
      double lo = 0, hi = 0;
      for (int k = 1; k <= 400; ++k) {
        hi = k * step;
        if (clearance(hi) >= s.clearance) break;
        lo = hi;
      }
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (lo + hi);
        (clearance(mid) >= s.clearance ? hi : lo) = mid;
      }
      clearance(hi);
      const double margin = ContactEndMargin(s);
      if (SignedDistance(s, Vec3::Zero()) > margin && SignedDistance(s, s.b) > margin) break;
    }
    if (!x.empty()) s.clearance = Clearance(s, x);  // as placed
  }

  // The MJCF: the draw-2 scene's, with the world's declarations added.
  std::ostringstream keys, custom, body, actuator;
  keys.precision(10);
  custom.precision(10);
  body.precision(10);
  if (s.contact) {
    keys << " contact=" << (s.contact_all ? "all" : "rock");
    if (s.friction > 0) keys << " contact_friction=" << s.friction;
  }
  if (s.static_start && s.xml.find(" start=") == std::string::npos) keys << " start=static";
  if (s.winch) {
    custom << WinchText(s);
    if (s.winch_mode == "speed") {
      custom << "<text name=\"thrust:winch\" data=\"t=" << kThrustStart << ","
             << kThrustStart + s.ramp;
      if (s.reverse) custom << ",0.6,0.8";
      custom << " ctrl=0," << s.winch_ctrl;
      if (s.reverse) custom << "," << s.winch_ctrl << "," << -s.winch_ctrl;
      custom << "\"/>\n";
    } else {
      custom << "<text name=\"thrust:winch\" data=\"t=0,1 ctrl=" << s.winch_ctrl << ","
             << s.winch_ctrl << "\"/>\n";
    }
    actuator << "<motor name=\"winch\" site=\"tms_site\" gear=\"0 0 0 0 0 0\"/>";
  }
  if (s.contact) body << RockXml(s);
  std::string& xml = s.xml;
  const size_t tether = xml.find("<text name=\"tether:t\"");
  xml.insert(xml.find("\"/>", tether), keys.str());
  xml.insert(xml.find("</custom>"), custom.str());
  xml.insert(xml.find("</worldbody>"), body.str());
  if (!actuator.str().empty()) {
    if (xml.find("</actuator>") != std::string::npos) {
      xml.insert(xml.find("</actuator>"), actuator.str());
    } else {
      xml.insert(xml.find("</mujoco>"), "<actuator>" + actuator.str() + "</actuator>");
    }
  }
  if (xml.find(" start=static") != std::string::npos) s.static_start = true;
  return s;
}

// What the world draw added, for the outcome's line ("" for a draw-2 scene).
std::string Describe(const Scene& s) {
  if (!s.world) return "";
  std::ostringstream d;
  d.precision(4);
  if (s.contact) {
    d << ", contact=" << (s.contact_all ? "all" : "rock") << " " << s.geom << " " << s.geom_size.x()
      << " m, clearance " << s.clearance << " m, friction " << s.friction;
  }
  if (s.winch) {
    d << ", winch " << s.winch_mode << " ctrl " << s.winch_ctrl << (s.reverse ? " reversed" : "")
      << ", L " << s.min_length << ".." << s.max_length << " m, max_speed " << s.max_speed;
  }
  if (s.static_start) d << ", start=static";
  return d.str();
}

// MuJoCo warnings (e.g. a bad qacc, after which MuJoCo resets the data) are counted per thread.
thread_local int t_warnings = 0;
thread_local std::string t_last_warning;
void CountWarning(const char* message) {
  ++t_warnings;
  t_last_warning = message;
}

struct Run {
  bool loaded = false, diverged = false, finite = true;
  std::string error, message;
  Vec3 vehicle = Vec3::Zero(), tms = Vec3::Zero();  // [m] at the end (or at divergence)
  double vehicle_speed = 0;                         // [m/s]
  double peak_speed = 0;  // [m/s or rad/s] largest |v| or |w| of the vehicle at a step's start
  double tension = 0;                               // [N] mean over the last kAverage
  int warnings = 0;
  bool stretched = false;       // Attach warned "starts stretched" (a strain above 0.1%)
  std::string stretch_warning;  // that warning's text, as Attach gave it (Warnings)
  std::string thrust_warning;   // Attach's warning of a thrust schedule beyond what it holds
  std::string contact_warning;  // Attach's warning of a start inside a geom it touches
  bool held_warning = false;    // Attach warned of a held end force at omega h >= 0.1
  bool lead_warning = false;    // ... or of explicit's consistent coupling at omega h 0.1-1
  std::string ring_warning;     // RingWarnings at the end: a snap rang the undamped segment mode
  // RingWarnings' other messages (session 45): a snap rang the vehicle's bounce on the taut line
  // (BounceMode), or that bounce swung by kSwingRatio x its mean tension without a watched
  // snap; the cure is the step, not damping_ratio=1: counted, judged by no twin.
  std::string bounce_warning;
  // RingWarnings' alternation watch (session 46, kAlternationRatio): an end tension that
  // alternates from step to step; counted, judged by no twin.
  std::string alternation_warning;
  double duration = kDuration;  // [s] simulated
  double deployed = 0;  // [m] a winch's deployed unstretched length at the end (0: no winch)
  // Energy balance of the tether (scenes without current, see EnergyExcess): the largest
  // E(t) - E(0) - W_ends(t) over the run [J], and the scale the tolerance is taken from.
  bool balanced = false;
  double excess = -INFINITY, gross = 0, swing = 0;  // [J]
  double work = 0;  // [J] W_ends at the end of the run (from the first step on)
  int stalled = 0;                                  // implicit steps accepted unconverged
  std::vector<double> tensions;  // [N] the vehicle-end tension after every step (PhaseRange)
};

// A run that did not go to its end cleanly: not loaded, diverged, a non-finite value or a
// MuJoCo warning.
bool Failed(const Run& r) { return !r.loaded || r.diverged || !r.finite || r.warnings > 0; }
// What stopped a run: its divergence message, or the load error.
const std::string& Why(const Run& r) { return r.message.empty() ? r.error : r.message; }

// Energy oracle. The tether's energy E = kinetic (interior nodes, normal added mass) +
// potential (elastic, bending, net weight of every node; Tether::KineticEnergy,
// PotentialEnergy) changes by the work its ends do on it, W_ends = integral of
// -(F_a . v_a + F_b . v_b) dt (F: the reactions on the sites, v: the end nodes' velocities,
// which are the sites'), minus what drag, internal
// and seabed damping and friction dissipate (never negative without a current: drag
// -c|v|v . v <= 0). The seabed's elastic energy is left out of E; it is >= 0 and 0 at the
// start (the initial shape rests on the seabed), so leaving it out only lowers E(t) - E(0).
// Hence E(t) - E(0) <= W_ends(t) at every t. W_ends is summed step by step as the reaction the
// step reported times the end node's displacement over the step, -(F_a . dx_a + F_b . dx_b):
// the reported force is the step's own (the implicit schemes' end-of-step force, whose impulse
// h F moves the end node by dx = h v_{n+1}; the mean of the substeps or stages where the
// explicit schemes report one), so this is the discrete work the scheme does on its ends.
// Until session 14 it was a trapezoid of the power F . v sampled once per step, which weighs
// the previous step's force: where the vehicle-end mode rings at the step (omega h >= 1) that
// is off by a third of the work, and seeds 3459, 9297, 9305 (implicit and bdf2 alike, 1e8 N)
// "gained" 0.3-0.8 GJ because their trapezoid read 1.05e9 J of end work where the displacement
// reads 1.63e9 J and the converged 0.2 ms run 1.62e9 J (docs/scene_fuzzer.md, session 14).
// Tolerance (EnergyTolerance): a force that varies within the step makes F . dx off by O(h) of
// the gross work; a gain by an instability is not a few percent but grows without bound. A current can put energy in through drag (F . U > 0), so scenes with a
// current are not balanced. The end nodes' kinetic energy is not in E: they move with the
// sites, and the reaction F is the force on the end node (its segment, weight, drag), not its
// inertia m_e a_e, so W_ends does not pay for 1/2 m_e v_e^2 (with 1 or 2 segments, half or a
// third of the line's mass: the long run found seeds 1460, 1920 "gaining" 70 kJ and 260 J so).
// Without them the balance is exact in continuous time: d(KE_interior + PE)/dt = W_ends' +
// the (non-positive) power of the dissipative forces on every node.
double EnergyTolerance(const Run& r) { return 0.05 * (r.gross + r.swing) + 1e-3; }

// Where the energy balance applies (without a current). Not with a winch: the deployed line
// gains and loses mass and its energy at the drum (the drum's payout carries kinetic and
// potential energy in and out and the winch segment's rest length changes under tension), none
// of which W_ends counts. Not with contact where the tether starts inside the obstacle: the
// penalty's elastic energy (k/2 per metre of the penetration squared, left out of E like the
// seabed's) is then positive at the start, and its release would read as a gain. A tether that
// starts clear of the obstacle (clearance >= 0) starts with none: leaving it out only lowers
// E(t) - E(0), and the contact's damping and friction dissipate, so the balance holds as with
// the seabed.
bool Balanced(const Scene& s) { return !s.winch && !(s.contact && s.clearance < 0); }

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// The duration that keeps the scene within kBudget node updates at the step of 2 ms. The
// explicit schemes' substeps are counted at kBudgetSafety of the stability limit whatever the
// scheme's safety factor, so that a scene (its duration, hence the instant compared) stays the
// same when a factor changes: symplectic Euler's went from 0.8 to 0.5 in session 13, which
// costs its scenes 1.6x as much.
constexpr double kBudgetSafety = 0.8;
double Duration(const mjModel* m) {
  const Tether* t = GetTether(m, 0);
  const int stages = t->params().integrator == Integrator::kRK4 ? 4 : 1;
  const double limit = t->ExplicitStabilityLimit();
  const double substeps = IsExplicit(t->params().integrator) && std::isfinite(limit)
                              ? std::max(1.0, std::ceil(kStep / (kBudgetSafety * limit) - 1e-9))
                              : double(t->SubstepsFor(kStep));
  const double per_second = substeps * t->nodes() * stages / kStep;
  return std::clamp(kBudget / per_second, kMinDuration, kDuration);
}

Run Simulate(const Scene& s, double step, double duration = -1) {
  Run run;
  std::string xml = s.xml;
  if (step != kStep) {
    std::ostringstream opt;
    opt << "timestep=\"" << step << "\"";
    std::ostringstream old;
    old << "timestep=\"" << kStep << "\"";
    xml.replace(xml.find(old.str()), old.str().size(), opt.str());
  }
  mjModel* m = LoadModelFromString(xml, "scene" + std::to_string(s.seed) + ".xml", &run.error);
  if (!m) return run;
  run.loaded = true;
  for (const std::string& w : Warnings(m)) {
    if (Contains(w, "starts stretched")) run.stretched = true, run.stretch_warning = w;
    if (Contains(w, "the thrust: schedules push body")) run.thrust_warning = w;
    if (Contains(w, "starts inside a geom it touches")) run.contact_warning = w;
    if (Contains(w, "held end force at coupling omega h")) run.held_warning = true;
    if (Contains(w, "consistent coupling at coupling omega h")) run.lead_warning = true;
  }
  mjData* d = mj_makeData(m);
  t_warnings = 0;
  run.duration = duration > 0 ? duration : Duration(m);
  const int steps = static_cast<int>(std::lround(run.duration / step));
  const int average_from =
      steps - static_cast<int>(std::lround(std::min(kAverage, run.duration / 5) / step));
  double sum = 0;
  int count = 0;
  const Tether* tether = GetTether(m, 0);
  run.balanced = s.current.norm() == 0 && Balanced(s);
  double E0 = 0, W = 0;                    // [J]
  Vec3 xa0 = Vec3::Zero(), xb0 = Vec3::Zero();  // [m] the end nodes at the last step
  std::vector<double> interior_v;          // [m/s] node velocities, the end nodes' zeroed
  bool started = false;
  for (int k = 0; k < steps; ++k) {
    run.peak_speed = std::max({run.peak_speed, Vec3(d->qvel).norm(), Vec3(d->qvel + 3).norm()});
    Step(m, d);
    if (std::optional<std::string> message = CheckDivergence(m, d)) {
      run.diverged = true;
      run.message = *message;
      break;
    }
    const double* xn = NodePositions(m, d, 0);
    const double* vn = NodeVelocities(m, d, 0);
    if (run.balanced && xn && vn) {
      // The end nodes move with the sites and their inertia is not in the reactions: their
      // kinetic energy is left out (see the energy oracle above).
      interior_v.assign(vn, vn + 3 * tether->nodes());
      std::fill(interior_v.begin(), interior_v.begin() + 3, 0.0);
      std::fill(interior_v.end() - 3, interior_v.end(), 0.0);
      const double E = tether->KineticEnergy(xn, interior_v.data()) +
                       tether->PotentialEnergy(xn, Ends());
      const EndReactions r = GetReactions(m, d, 0);
      const Vec3 xa(xn), xb(xn + 3 * tether->segments());
      if (!started) {
        E0 = E, started = true;
        run.excess = 0;
      } else {
        // The step's work on the tether's ends (the reactions act on the sites; the tether
        // feels their opposite).
        // The line's own forces: the consistent coupling's slow-mode correction is the
        // coupling's (EndReactions::correction_b), a numerical force on the body with its
        // reaction at end A that the tether's nodes never feel.
        const Vec3 fa = r.force_a + r.correction_b, fb = r.force_b - r.correction_b;
        const double wa = -fa.dot(xa - xa0), wb = -fb.dot(xb - xb0);
        run.gross += std::abs(wa) + std::abs(wb);
        W += wa + wb;
        run.excess = std::max(run.excess, E - E0 - W);
      }
      run.swing = std::max(run.swing, std::abs(E - E0));
      run.work = W;
      xa0 = xa, xb0 = xb;
    }
    run.tensions.push_back(GetReactions(m, d, 0).tension_b);
    if (k >= average_from) sum += run.tensions.back(), ++count;
    if (t_warnings > 0) break;
  }
  run.warnings = t_warnings;
  if (t_warnings > 0) run.message = t_last_warning;
  run.stalled = static_cast<int>(StallWarnings(m, d).size());
  for (const std::string& w : RingWarnings(m, d)) {
    if (Contains(w, "alternated from step to step")) {
      run.alternation_warning = w;
    } else if (run.bounce_warning.empty() && run.ring_warning.empty()) {
      (Contains(w, "bouncing on the whole line") ? run.bounce_warning : run.ring_warning) = w;
    }
  }
  run.tension = count > 0 ? sum / count : 0;
  const int rov = mj_name2id(m, mjOBJ_BODY, "rov"), tms = mj_name2id(m, mjOBJ_BODY, "tms");
  run.vehicle = Vec3(d->xpos + 3 * rov);
  run.tms = Vec3(d->xpos + 3 * tms);
  run.vehicle_speed = Vec3(d->qvel).norm();
  if (const WinchState w = GetWinch(m, d, 0); w.present) run.deployed = w.length;
  for (int i = 0; i < m->nq; ++i) run.finite = run.finite && std::isfinite(d->qpos[i]);
  for (int i = 0; i < m->nv; ++i) run.finite = run.finite && std::isfinite(d->qvel[i]);
  if (!run.diverged) {
    const double* x = NodePositions(m, d, 0);
    const int n = GetTether(m, 0)->nodes();
    for (int i = 0; x && i < 3 * n; ++i) run.finite = run.finite && std::isfinite(x[i]);
  }
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
  return run;
}

// The outcome of one scene: a class name, pass or fail, and a one-line reason.
struct Outcome {
  std::string kind;
  bool pass = false;
  std::string detail;
  bool shortened = false;  // run for less than kDuration (cost budget)
  bool stalled = false;    // the 2 ms run had implicit steps accepted unconverged
  // Attach warned that the held end force is often off at this omega h (kCouplingAccurate):
  // counted, not excused; a failure stays a failure.
  bool held = false;
  // The 2 ms run warned at its end that a snap rang the undamped segment mode (RingWarnings):
  // counted, and judged by the damped twin only where the run disagrees.
  bool rang = false;
  bool bounced = false;  // ... that a snap rang the vehicle's bounce (Run::bounce_warning)
  bool swung = false;    // ... that the vehicle's bounce swung (the same, without a snap)
  bool alternated = false;  // ... that an end tension alternated from step to step
};

// The omega h at which the advisor refuses the scene's integrator (0: no limit).
double CouplingLimitOf(const Scene& s) {
  if (s.integrator == "explicit") return kCouplingLimitExplicit;
  if (s.integrator == "rk4") return kCouplingLimitRk4;
  // implicit2: every scene has a free vehicle at end B and the TMS (a mocap body) at end A, so
  // from omega h 0.5 on the consistent coupling applies and lifts its limit (docs/coupling.md,
  // implicit2), which is above that.
  // With a winch (and with contact, refused for implicit2 here anyway) the plugin does not apply
  // the consistent coupling (AdviseCoupling, plugin/plugin.cc), so implicit2 keeps its limit.
  if (s.integrator == "implicit2") return s.winch || s.contact ? kCouplingLimitImplicit2 : 0;
  return 0;  // implicit, bdf2: no limit (docs/coupling.md)
}

// Load refusals whose cause the scene itself confirms.
Outcome CheckRefusal(const Scene& s, const std::string& error) {
  const double span = s.b.norm();
  const bool below = s.seabed_kind != 0 && (s.b.z() < s.seabed || 0 < s.seabed);
  const double density = s.mpl / (kPi * s.diameter * s.diameter / 4);
  if (Contains(error, "below the seabed")) {
    return {"refused: below the seabed", below, error};
  }
  if (Contains(error, "more than length x (1 + max_strain)")) {
    return {"refused: ends beyond length x (1 + max_strain)", span > s.length * 2, error};
  }
  if (Contains(error, "key 'segments'") && Contains(error, "x the diameter")) {
    return {"refused: segments shorter than d/10", s.L0() < 0.1 * s.diameter, error};
  }
  if (Contains(error, "key 'diameter'")) {
    return {"refused: diameter", s.diameter > s.length || density < 1.2, error};
  }
  if (Contains(error, "key 'ctrl'") && Contains(error, "[-1e+09, 1e+09]")) {
    return {"refused: thrust schedule beyond its range (1e9 N)", s.thrust > 1e9, error};
  }
  if (Contains(error, "coupling omega h = ")) {
    // The advisor's coupling frequency at the vehicle (docs/coupling.md): the site is at the
    // vehicle's centre of mass, so m_eff = m + the smallest added mass, as in Make.
    const double limit = CouplingLimitOf(s);
    return {"refused: coupling omega h >= limit", limit > 0 && s.omega_h >= 0.99 * limit, error};
  }
  if (Contains(error, "starts compressed")) {
    // CompressedStart (plugin/plugin.cc): a segment starts shorter than L0 by a strain above
    // 1e-3 with EAc, and EAc x strain beyond the segment's Euler load.
    double over_euler = 0;
    const double strain = StartCompression(s, &over_euler);
    return {"refused: starts compressed beyond the Euler load", strain > 1e-3 && over_euler > 1,
            error};
  }
  if (Contains(error, "substeps per MuJoCo step")) {
    return {"refused: explicit substeps > 1e5", s.integrator == "explicit" || s.integrator == "rk4",
            error};
  }
  // The world draw's refusals (MakeWorld).
  if (Contains(error, "key 'contact_friction' > 0 is not supported with integrator=implicit2")) {
    return {"refused: contact friction with implicit2",
            s.contact && s.friction > 0 && s.integrator == "implicit2", error};
  }
  if (Contains(error, "implicit2 is not supported with 'contact' and end B")) {
    // AdviseCoupling: implicit2 with contact= and an end on a body with degrees of freedom;
    // here the vehicle, a free body, is always end B.
    return {"refused: implicit2 with contact and the vehicle at end B",
            s.contact && s.integrator == "implicit2", error};
  }
  if (Contains(error, "the tether's key 'contact' is not supported with a winch")) {
    return {"refused: contact with a winch", s.contact && s.winch, error};
  }
  if (Contains(error, "key 'start' = static is not supported with")) {
    return {"refused: start=static with contact or a winch",
            s.static_start && (s.contact || s.winch), error};
  }
  if (Contains(error, "key 'max_speed'") && Contains(error, "more than a quarter segment")) {
    return {"refused: winch max_speed beyond a quarter segment per step",
            s.winch && s.max_speed * kStep > 0.25 * s.L0() * (1 - 1e-6), error};
  }
  if (Contains(error, "key 'min_length'") && Contains(error, "shorter than one segment")) {
    return {"refused: winch min_length shorter than a segment",
            s.winch && s.min_length < s.L0() * (1 + 1e-6), error};
  }
  if (Contains(error, "key 'min_length'/'max_length'")) {
    return {"refused: length outside the winch's limits",
            s.winch && !(s.length >= s.min_length * (1 + 1e-6) &&
                         s.length <= s.max_length * (1 - 1e-6)),
            error};
  }
  return {"refused: unrecognised cause", false, error};
}

// In a scene's MJCF, `before` + the old value + `after` replaced by the same with the new value
// (10 significant digits, as Make writes them); the MJCF emptied where the text is not found
// (the caller's run then does not load, and nothing is concluded).
void ReplaceValue(std::string* xml, const std::string& before, double old_value,
                  double new_value, const std::string& after) {
  std::ostringstream from, to;
  from.precision(10);
  to.precision(10);
  from << before << old_value << after;
  to << before << new_value << after;
  const size_t at = xml->find(from.str());
  if (at == std::string::npos) {
    xml->clear();
  } else {
    xml->replace(at, from.str().size(), to.str());
  }
}

// The scene with its tether as long as the span (no start-up strain), the rest unchanged; with
// slack > 0, as long as the span times 1 + slack (MJTETHER_SCENE_FUZZ_SLACK, a measurement of
// starts near taut: docs/scene_fuzzer.md, session 43).
Scene Unstretched(const Scene& s, double slack = 0) {
  Scene u = s;
  u.length = s.b.norm() * (1 + slack);
  ReplaceValue(&u.xml, " length=", s.length, u.length, " ");
  u.omega_h = std::sqrt(u.k_end() / (u.mass + u.added_min)) * kStep;
  if (s.winch && !u.xml.empty()) {
    // The winch's limits widened to hold the twin's length, and its max_speed cut to the
    // twin's shorter segments (a quarter segment per step) as MakeWorld cuts it.
    u.min_length = std::max(u.L0(), std::min(s.min_length, u.length));
    u.max_length = std::max(s.max_length, u.length);
    u.max_speed = std::min(s.max_speed, 0.999 * 0.25 * u.L0() / kDrawStep);
    u.xml.replace(u.xml.find(WinchText(s)), WinchText(s).size(), WinchText(u));
  }
  return u;
}

// The scene with its thrust schedule's peak at kThrottle x what the tether holds, below half
// of it (where Attach's thrust warning starts), the rest unchanged.
constexpr double kThrottle = 0.45;  // [-]
Scene Throttled(const Scene& s) {
  Scene t = s;
  t.thrust = kThrottle * s.holds();
  ReplaceValue(&t.xml, " ctrl=0,", s.thrust, t.thrust, "\"");
  return t;
}

// Where the tether's declaration `data="..."` of the fuzzer's scene sits in its xml: the
// offsets of its first and one past its last character, or false where it is not there.
bool TetherData(const std::string& xml, size_t* first, size_t* last) {
  const std::string tag = "<text name=\"tether:t\" data=\"";
  const size_t begin = xml.find(tag);
  const size_t end = begin == std::string::npos ? begin : xml.find('"', begin + tag.size());
  if (end == std::string::npos) return false;
  *first = begin + tag.size();
  *last = end;
  return true;
}

// The scene with its tether's segment axial mode critically damped, damping_ratio=1 (what
// RingWarnings advises; docs/reference.md "Internal damping"), the rest unchanged: the twin of
// a scene in which a snap rang that mode undamped. An empty xml where the declaration's form is
// not the fuzzer's own.
Scene Damped(const Scene& s) {
  Scene c = s;
  c.damping = 1.0 * s.L0() * std::sqrt(s.EA * s.mpl);  // [N s] SegmentModeDamping at zeta 1
  size_t first, last;
  if (!TetherData(c.xml, &first, &last)) {
    c.xml.clear();
    return c;
  }
  std::string data = c.xml.substr(first, last - first);
  if (const size_t at = data.find(" damping="); at != std::string::npos) {
    const size_t stop = data.find(' ', at + 1);
    data.erase(at, stop == std::string::npos ? std::string::npos : stop - at);
  }
  data += " damping_ratio=1";
  c.xml.replace(first, last - first, data);
  return c;
}

// The scene with `max_step=value` [s] declared on its tether (the advice of an explicit
// scheme's divergence at its automatic substeps); an empty xml where the declaration is not
// the fuzzer's.
Scene WithMaxStep(const Scene& s, double value) {
  Scene c = s;
  size_t first, last;
  if (!TetherData(c.xml, &first, &last)) {
    c.xml.clear();
    return c;
  }
  std::ostringstream v;
  v.precision(17);
  v << " max_step=" << value;
  c.xml.insert(last, v.str());
  return c;
}

// The world scene with its obstacle moved on, the way MakeWorld moved it from the shape's
// middle, until the initial shape's skin is clear of it by kClearedBy d: the twin of a scene
// that starts inside the rock (Attach's "starts inside a geom it touches" warning), the rest
// unchanged. An empty xml where no such place keeps both ends clear (ContactEndMargin).
constexpr double kClearedBy = 0.05;  // [-] of the diameter
Scene Cleared(const Scene& s) {
  Scene c = s;
  TetherParams p;
  const std::vector<double> x = InitialShapeOf(s, &p);
  const double target = kClearedBy * s.diameter;
  if (x.empty() || !s.contact || s.xml.empty()) {
    c.xml.clear();
    return c;
  }
  auto clearance = [&](double E) {
    c.geom_pos = s.geom_pos + E * s.geom_dir;
    return Clearance(c, x);
  };
  // Scanned in steps of a quarter of the depth to cover, then 60 bisections.
  const double step = 0.25 * std::max(1e-6, target - s.clearance);
  double lo = 0, hi = 0;
  bool found = false;
  for (int k = 1; k <= 400 && !found; ++k) {
    hi = k * step;
    found = clearance(hi) >= target;
    if (!found) lo = hi;
  }
  const double margin = ContactEndMargin(s);
  if (!found) {
    c.xml.clear();
    return c;
  }
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (clearance(mid) >= target ? hi : lo) = mid;
  }
  c.clearance = clearance(hi);
  if (!(SignedDistance(c, Vec3::Zero()) > margin && SignedDistance(c, s.b) > margin)) {
    c.xml.clear();
    return c;
  }
  const std::string from = RockXml(s), to = RockXml(c);
  c.xml.replace(c.xml.find(from), from.size(), to);
  return c;
}

// The refusals this file predicts from the scene (each must happen).
std::string ExpectedRefusal(const Scene& s) {
  if (s.seabed_kind == 3) return "an end below the seabed";
  if (s.b.norm() > 2 * s.length) return "ends beyond length x (1 + max_strain)";
  if (s.L0() < 0.1 * s.diameter) return "segments shorter than d/10";
  if (CouplingLimitOf(s) > 0 && s.omega_h >= 1.01 * CouplingLimitOf(s)) {
    return "coupling omega h >= limit";
  }
  double over_euler = 0;
  // With a winch too since session 15 (CompressedStart checks the deployed part, the declared
  // length in segments of L0: the scene's own tether).
  if (StartCompression(s, &over_euler) > 1.01e-3 && over_euler > 1.01) {
    return "starts compressed beyond the Euler load";
  }
  // The world draw's (docs/contact.md, docs/winch.md, docs/static_start.md); the margins of 1%
  // and 1e-6 keep a value that the MJCF's 10 digits put on either side of a bound out.
  if (s.contact && s.winch) return "contact with a winch";
  if (s.static_start && (s.contact || s.winch)) return "start=static with contact or a winch";
  if (s.contact && s.integrator == "implicit2") {
    return "implicit2 with contact and the vehicle (a free body) at end B";
  }
  if (s.winch && s.max_speed * kStep > 1.01 * 0.25 * s.L0()) {
    return "winch max_speed beyond a quarter segment per step";
  }
  if (s.winch && s.min_length < s.L0() * (1 - 1e-6)) return "winch min_length shorter than a segment";
  return "";
}

// The range [lo, hi] of a run's vehicle-end tension averaged over the oracle's window (the
// last kAverage, or a fifth of a shortened run) when the window is moved earlier by 0, 1, ...
// up to a tenth of its length in MuJoCo steps of 2 ms (20 ms for the full window): how much the
// oracle's mean depends on where the window starts. On a smooth history the range is small; on
// a train of snaps (a slack chain whose vehicle-end tension is spikes of a few ms every ~0.1 s,
// seeds 8875, 3711) one spike entering or leaving the window moves the mean by its impulse over
// the window, far beyond the tolerance.
struct Range {
  double lo = 0, hi = 0;
};
Range PhaseRange(const Run& r, double step) {
  const int n = static_cast<int>(r.tensions.size());
  const double window = std::min(kAverage, r.duration / 5);  // [s] as in Simulate
  const int w = static_cast<int>(std::lround(window / step));
  const int every = static_cast<int>(std::lround(kStep / step));
  const int shifts = std::max(1, static_cast<int>(std::lround(0.1 * window / kStep)));
  Range range{INFINITY, -INFINITY};
  for (int k = 0; k <= shifts; ++k) {
    const int end = n - k * every;
    if (end - w < 0 || w <= 0) break;
    double sum = 0;
    for (int i = end - w; i < end; ++i) sum += r.tensions[i];
    range.lo = std::min(range.lo, sum / w);
    range.hi = std::max(range.hi, sum / w);
  }
  return range;
}

// How far apart two ranges are (0 where they overlap).
double Gap(const Range& a, const Range& b) { return std::max({0.0, a.lo - b.hi, b.lo - a.hi}); }

// The outcome of a run that agrees but for the phase of a snap train (Compare): its window's
// mean, or the reference's, moves beyond the tolerance within that shift.
const char kSnapPhase[] =
    "agrees within a window moved by up to a tenth (a snap at its edge moves the mean beyond "
    "the tolerance)";

// A run to the end at 2 ms (coarse) against the same scene at 0.2 ms (and, where they
// disagree, at 0.02 ms), then the energy balance.
Outcome Compare(const Scene& s, const Run& coarse) {
  const Run fine = Simulate(s, kStep / 10, coarse.duration);
  if (Failed(fine)) return {"fine step failed", false, Why(fine)};
  const double dx = (coarse.vehicle - fine.vehicle).norm();
  const double dT = std::abs(coarse.tension - fine.tension);
  const double tol_x = std::max(0.05, 0.02 * s.span);
  const double tol_T = std::max(0.5, 0.05 * std::max(coarse.tension, fine.tension));
  std::ostringstream detail;
  detail << "position " << dx << " m (tol " << tol_x << "), tension " << coarse.tension << " vs "
         << fine.tension << " N (tol " << tol_T << ")";
  if (dx > tol_x || dT > tol_T) {
    // Refined reference (docs/scene_fuzzer.md, open-transient): the 0.2 ms run is a reference
    // only as far as it is converged. Run the scene again at 0.02 ms and take the spread of
    // the two refinements, |fine - finer|, as the reference's own uncertainty at that instant
    // (a tension averaged over 0.2 s of snaps or ringing is sensitive to phase: two fine runs
    // differ too). The coarse run agrees if it is within the old tolerance (of the finer run)
    // plus that spread. Where the reference is converged (fine = finer) this is the old
    // criterion against a better reference, so a coarse run that is wrong still fails.
    const Run finer = Simulate(s, kStep / 100, coarse.duration);
    if (Failed(finer)) {
      detail << "; 0.02 ms run failed: " << Why(finer);
      return {"disagrees with 10x smaller step", false, detail.str()};
    }
    const double spread_x = (fine.vehicle - finer.vehicle).norm();
    const double spread_T = std::abs(fine.tension - finer.tension);
    const double dx2 = (coarse.vehicle - finer.vehicle).norm();
    const double dT2 = std::abs(coarse.tension - finer.tension);
    const double tol_T2 = std::max(0.5, 0.05 * std::max(coarse.tension, finer.tension));
    detail << "; 0.02 ms: position " << dx2 << " m (tol " << tol_x << " + spread " << spread_x
           << "), tension " << finer.tension << " N, off by " << dT2 << " (tol " << tol_T2
           << " + spread " << spread_T << ")";
    if (dx2 > tol_x + spread_x || dT2 > tol_T2 + spread_T) {
      // The phase of a snap train (docs/scene_fuzzer.md, session 11, s11trans). Where a run's
      // own window mean moves by more than the tolerance when the window starts up to a tenth
      // of its length earlier (PhaseRange: a snap at the window's edge; the mean over a fixed
      // window then does not measure the run to that tolerance, the same history disagreeing
      // with itself), the position agrees, and the coarse run's range comes within the
      // tolerance of both references' ranges, the runs differ in when a snap falls (by less
      // than the shift), not in what the snaps deliver: counted apart, as a pass. Seeds 8875
      // (rk4) and 3711 (bdf2): the 2 ms run's snap falls 18 and 14 ms early after ~1 s with the
      // references' impulse (1.8 against 1.74 N s, 0.98 against 1.03). A coarse run whose snaps
      // deliver a wrong impulse (seed 539, explicit: 2.6-3.6 N s per snap against 0.9) or whose
      // mean drifts (913, 851) stays out of the ranges and fails.
      const Range c = PhaseRange(coarse, kStep), f = PhaseRange(fine, kStep / 10),
                  f2 = PhaseRange(finer, kStep / 100);
      detail << "; windows up to a tenth earlier: " << c.lo << ".." << c.hi << " N, 0.2 ms "
             << f.lo << ".." << f.hi << ", 0.02 ms " << f2.lo << ".." << f2.hi;
      const bool self = std::max(c.hi - c.lo, f.hi - f.lo) > tol_T || f2.hi - f2.lo > tol_T2;
      if (!(dx <= tol_x && dx2 <= tol_x + spread_x && self && Gap(c, f) <= tol_T &&
            Gap(c, f2) <= tol_T2)) {
        return {"disagrees with 10x smaller step", false, detail.str()};
      }
      if (coarse.balanced && coarse.excess > EnergyTolerance(coarse)) {
        detail << "; energy gain beyond the ends' work " << coarse.excess << " J (tol "
               << EnergyTolerance(coarse) << ")";
        return {"tether gains energy beyond the work of its ends", false, detail.str()};
      }
      return {kSnapPhase, true, detail.str()};
    }
    if (coarse.balanced && coarse.excess > EnergyTolerance(coarse)) {
      detail << "; energy gain beyond the ends' work " << coarse.excess << " J (tol "
             << EnergyTolerance(coarse) << ")";
      return {"tether gains energy beyond the work of its ends", false, detail.str()};
    }
    return {"agrees with 100x smaller step within the refinements' spread", true, detail.str()};
  }
  if (coarse.balanced) {
    detail << "; energy gain beyond the ends' work " << coarse.excess << " J (tol "
           << EnergyTolerance(coarse) << ")";
    if (coarse.excess > EnergyTolerance(coarse)) {
      return {"tether gains energy beyond the work of its ends", false, detail.str()};
    }
    return {"agrees with 10x smaller step, energy balanced", true, detail.str()};
  }
  return {"agrees with 10x smaller step", true, detail.str()};
}

long EnvLong(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::strtol(v, nullptr, 10) : fallback;
}

// The scene run kLate x longer at 2 ms and at 0.2 ms, compared at the end with the oracle's
// tolerances (position, the vehicle-end tension over the last 0.2 s): "; after the transient
// (T s): agrees|disagrees: ...". For a stretched start, whose warning says that the snap
// depends on the step: does the state after it depend on the step too? Diagnosis only, with
// MJTETHER_SCENE_FUZZ_LATE=1 (it triples the cost of those scenes). Session 10 (s10open), the
// long run's 70 stretched-start disagreements below omega h = 1: 25 agree after 3 s (the
// transient only), 44 still disagree (with the 0.2 ms run), one run stopped; no release time
// pi / (2 omega) in MuJoCo steps (1.6-101 over these) separates the two groups.
constexpr double kLate = 3;
std::string AfterTheTransient(const Scene& s, double duration) {
  const double T = kLate * duration;
  const Run c = Simulate(s, kStep, T), f = Simulate(s, kStep / 10, T);
  std::ostringstream out;
  out << "; after the transient (" << T << " s): ";
  if (Failed(c) || Failed(f)) {
    out << "run failed: " << (Failed(c) ? c.message + c.error : f.message + f.error);
    return out.str();
  }
  const double dx = (c.vehicle - f.vehicle).norm(), dT = std::abs(c.tension - f.tension);
  const double tol_x = std::max(0.05, 0.02 * s.span);
  const double tol_T = std::max(0.5, 0.05 * std::max(c.tension, f.tension));
  out << (dx <= tol_x && dT <= tol_T ? "agrees" : "disagrees") << ": position " << dx
      << " m (tol " << tol_x << "), tension " << c.tension << " vs " << f.tension << " N (tol "
      << tol_T << ")";
  return out.str();
}

// The outcome of a stretched start that disagrees with its fine-step self where the same scene
// started unstretched agrees (JudgeRuns).
const char kWarnedStretched[] =
    "warned: starts stretched, its outcome depends on the step as the warning says";

// The outcome of a run whose thrust schedule pushes the vehicle beyond what the tether holds
// (or half of it), which disagrees with its fine-step self or whose fine-step self diverges,
// where the same scene with the thrust below half of that agrees (JudgeRuns).
const char kWarnedThrust[] =
    "warned: thrust beyond what the tether holds (or half of it), its outcome depends on the "
    "step as the warning says";

// The outcome of a run in which a snap rang the undamped segment axial mode (RingWarnings),
// which disagrees with its fine-step self or whose fine-step self diverges, where the same scene
// with damping_ratio=1 (Damped) agrees (JudgeRuns).
const char kWarnedRing[] =
    "warned: a snap rang the undamped segment mode, its tensions depend on the step as the "
    "warning says";

// The outcome of a run warned of two causes, one of them a snap that rang the undamped segment
// mode (RingWarnings), where the twin with the other cause taken away disagrees too and the twin
// with both taken away (that one and damping_ratio=1) agrees: the two warnings together say
// why the run is off (JudgeWithDampingToo; session 41).
const char kWarnedStretchedRing[] =
    "warned: starts stretched and a snap rang the undamped segment mode, its outcome depends on "
    "the step as the warnings say";
const char kWarnedThrustRing[] =
    "warned: thrust beyond what the tether holds and a snap rang the undamped segment mode, its "
    "outcome depends on the step as the warnings say";
const char kWarnedInsideRing[] =
    "warned: starts inside a geom and a snap rang the undamped segment mode, its outcome depends "
    "on the step as the warnings say";

// The outcome of a run that starts inside a geom it touches (Attach warned), which disagrees
// with its fine-step self or whose fine-step self diverges, where the same scene with the
// geom moved clear of the initial shape (Cleared) agrees (JudgeRuns).
const char kWarnedInside[] =
    "warned: starts inside a geom it touches, its outcome depends on the step as the warning "
    "says";

// Whether Attach's warning of a start inside a geom (plugin.cc, ContactStartWarning) told the
// user that the outcome depends on the step and to compare with a smaller one.
bool WarnsContactStepDependence(const std::string& warning) {
  return Contains(warning, "starts inside a geom it touches") &&
         Contains(warning, "depends on <option timestep>") &&
         Contains(warning, "compare with a smaller one");
}

// Whether Attach's thrust warning (plugin.cc, WarnThrustBeyondHolds) told the user that the
// outcome depends on the step and to compare with a smaller one.
bool WarnsThrustStepDependence(const std::string& warning) {
  return Contains(warning, "the thrust: schedules push body") &&
         Contains(warning, "depend") && Contains(warning, "on <option timestep>: compare with a smaller one");
}

// Whether Attach's "starts stretched" warning (plugin.cc, kStretchWarning) told the user that
// the outcome depends on the step and to compare with a smaller one: the run was warned of
// exactly the disagreement the oracle found.
bool WarnsStepDependence(const std::string& warning) {
  return Contains(warning, "starts stretched") &&
         Contains(warning, "depend on <option timestep>") &&
         Contains(warning, "compare with a smaller one");
}

// "strain S, tension T N" as the warning gave them (for the outcome's detail).
std::string StretchOf(const std::string& warning) {
  const size_t a = warning.find("a strain of "), b = warning.find(" N at the first step");
  if (a == std::string::npos || b == std::string::npos || b < a) return "warned";
  return "warned: " + warning.substr(a, b + 2 - a);
}

thread_local bool t_shortened = false;
thread_local bool t_stalled = false;
thread_local bool t_held = false;
thread_local bool t_rang = false;
thread_local bool t_bounced = false;
thread_local bool t_swung = false;
thread_local bool t_alternated = false;

// The twin of a warned run (the scene with the warned cause taken away: Cleared, Damped),
// judged like any scene at 2 ms for `duration`: it agrees where it passes and its own run gives
// none of the warnings it was made without (`warnings`, Run members). detail: "; LABEL: agrees:
// ..." (or its outcome, or `missing` where the twin could not be made, an empty xml).
struct Twin {
  bool agrees = false;
  std::string detail;
};
Twin JudgeTwin(const Scene& twin, double duration, const std::string& label,
               const std::string& missing,
               std::initializer_list<std::string Run::*> warnings) {
  if (twin.xml.empty()) return {false, "; " + label + ": " + missing};
  const Run r = Simulate(twin, kStep, duration);
  const Outcome to = Failed(r) ? Outcome{"failed", false, Why(r)} : Compare(twin, r);
  bool quiet = true;
  for (std::string Run::*w : warnings) quiet = quiet && (r.*w).empty();
  return {to.pass && quiet,
          "; " + label + ": " + (to.pass ? "agrees: " : to.kind + ": ") + to.detail};
}

// A run warned of a cause whose twin (`twin`, the cause taken away) disagrees too, where the run
// also warned at its end that a snap rang the undamped segment mode (RingWarnings): the twin may
// ring in its turn, the disagreement then the ringing's, which the run was warned of as well
// (session 40's tuned failures 1910, 2143, 4435, 5805, 7637, 7808, 8253, 8945, 9016 and 9037,
// stretched starts whose unstretched twins rang: 2143's read 2.85 N at 2 ms, 147 N at 0.2 ms
// and 233 N at 0.02 ms). The twin with damping_ratio=1 as well, both warned causes taken away,
// is judged like any twin (all but 1910 and 9037 agreed so; 1910 is warned since session 42, its
// damped twin on the held force, DamperTakesTheLead); without a ring warning, or without
// a twin (its xml empty: the one-cause twin's detail already says why), nothing is judged
// (agrees false, no detail).
Twin JudgeWithDampingToo(const Scene& twin, const Run& coarse, const std::string& label,
                         std::string Run::*warning) {
  if (coarse.ring_warning.empty() || twin.xml.empty()) return {};
  return JudgeTwin(Damped(twin), coarse.duration, label + ", with damping_ratio=1",
                   "the declaration is not the fuzzer's", {warning, &Run::ring_warning});
}

Outcome JudgeRuns(const Scene& s) {
  const Run coarse = Simulate(s, kStep);
  t_shortened = coarse.loaded && coarse.duration < kDuration;
  t_stalled = coarse.stalled > 0;
  t_held = coarse.held_warning;
  t_rang = !coarse.ring_warning.empty();
  t_swung = Contains(coarse.bounce_warning, "swung by");
  t_bounced = !coarse.bounce_warning.empty() && !t_swung;
  t_alternated = !coarse.alternation_warning.empty();
  if (!coarse.loaded) return CheckRefusal(s, coarse.error);
  if (const std::string expected = ExpectedRefusal(s); !expected.empty()) {
    return {"not refused", false, "expected a refusal: " + expected};
  }
  if (coarse.warnings > 0) return {"MuJoCo warning", false, coarse.message};
  if (!coarse.finite) return {"non-finite", false, "non-finite value without divergence report"};
  if (coarse.diverged) {
    const std::string& msg = coarse.message;
    const double span = (coarse.vehicle - coarse.tms).norm();
    const double fast = 0.5 * 1.0 * s.L0() / kStep;  // [m/s] speed the message refers to
    const double tms_speed = 2 * kPi * s.motion_amp / s.motion_period;  // [m/s] upper bound
    if (Contains(msg, "damping too stiff for the step")) {
      // CheckEndDamping (plugin/plugin.cc): h lambda > 2 for the end's velocity-dependent force
      // on the vehicle. Recomputed as an upper bound from the scene: D <= the end node's drag,
      // 2 max(kn, kt) l |v_r| with its drag length l = half the end segment, and |v_r| <=
      // |v_vehicle| + |U|; plus the internal damping damping / L0 and the seabed's critical
      // damping 2 sqrt(k mu) (default k = 1e5 N/m^2) over the end's share L0 / 2; on the
      // effective mass m + a_min (the site at the vehicle's centre of mass, docs/coupling.md).
      // The check sees the end segment from the site where it is now to the neighbour where the
      // tether's last step left it (at most 2 L0 then, the run had not diverged by strain), so
      // l <= L0 + |v_vehicle| h / 2 (session 12: seed 288 moves its site 2.7 m in the step, and
      // the bound l <= L0 of before read h lambda 1.76 where the check found 3.53).
      // |v_vehicle|: the largest at the start of any step (which the check saw) or at the end.
      const double kn = 0.5 * kRho * 1.2 * s.diameter, kt = 0.5 * kRho * 0.01 * kPi * s.diameter;
      const double v = std::max(coarse.vehicle_speed, coarse.peak_speed);
      const double v_r = v + s.current.norm(), l = s.L0() + 0.5 * v * kStep;
      double D = 2 * std::max(kn, kt) * l * v_r + s.damping / s.L0();
      if (s.seabed_kind != 0) D += 2 * std::sqrt(1e5 * s.mpl) * s.L0() / 2;
      const double bound = kStep * D / (s.mass + s.added_min);
      return {"diverged: end damping too stiff for the step (h lambda > 2)", bound > 2, msg};
    }
    if (Contains(msg, "its own damping is too stiff for the step")) {
      // VehicleStopped (plugin/vehicles.cc): h lambda > 2 on a dof of the vehicle's own
      // damping. Recomputed as an upper bound: the speed through the water at most the body's
      // largest |v| or |w| at the start of a step (the callback sees those states) plus the
      // current, on the translational effective mass m + a_min (damping lin + 2 quad |v|) or
      // the rotational one 1.3 I (damping I + 2 I |w|).
      const double v = coarse.peak_speed + s.current.norm();
      const double translation = kStep * (s.lin + 2 * s.quad * v) / (s.mass + s.added_min);
      const double rotation = kStep * (1 + 2 * coarse.peak_speed) / 1.3;
      return {"diverged: vehicle damping too stiff for the step (h lambda > 2)",
              std::max(translation, rotation) > 2, msg};
    }
    if (Contains(msg, "steps did not converge in")) {
      // A run of stalled implicit steps (plugin.cc, kStallSteps): the step is the cause where
      // the same scene at a 10x smaller step runs to the time of the stop with no step stalled
      // (what it does later, e.g. a thrust ramp beyond what the tether holds, is another matter:
      // seed 5355 stalls from 0.002 s at 2 ms, its thrust starting at 0.1 s).
      const size_t at_stop = msg.find("stopped at t = ");
      const double t_stop =
          at_stop == std::string::npos ? 0 : std::strtod(msg.c_str() + at_stop + 15, nullptr);
      const Run fine = Simulate(s, kStep / 10, std::max(t_stop, 10 * kStep));
      const bool ok = t_stop > 0 && !Failed(fine) && fine.stalled == 0;
      return {"diverged: Newton stalled (10x smaller step runs to the stop without a stall)", ok,
              msg + (ok ? "" : " | fine step: " + Why(fine) + (fine.stalled > 0 ? " (stalled)" : ""))};
    }
    // A thrust cause also needs the thrust to act: the divergence after the ramp's start
    // (kThrustStart; Diagnose names the schedules' peak while the thrust is still ramping).
    const size_t at_t = msg.find("at t = ");
    const bool thrusting =
        at_t != std::string::npos && std::strtod(msg.c_str() + at_t + 7, nullptr) > kThrustStart;
    if (Contains(msg, "thrust beyond what the tether holds")) {
      return {"diverged: thrust beyond EA x max_strain", thrusting && s.thrust >= s.holds(), msg};
    }
    if (Contains(msg, "a snap load")) {
      return {"diverged: snap load (thrust >= EA x max_strain / 2)",
              thrusting && s.thrust >= 0.5 * s.holds(), msg};
    }
    if (Contains(msg, "the ends were pulled")) {
      // Diagnose's criterion (plugin/plugin.cc), recomputed with upper bounds: the mean strain
      // is positive and within the strain spread along the line of max_strain (1), the spread
      // being the net weight's w |dz| / EA plus twice the ends' separation speed over the
      // axial wave speed sqrt(EA / mu) (bounded by the vehicle's and the TMS's speeds).
      const double w = std::abs(s.mpl - kRho * kPi * s.diameter * s.diameter / 4) * 9.81;
      const double dz = std::abs((coarse.vehicle - coarse.tms).z());
      const double spread = w * dz / s.EA + 2 * (coarse.vehicle_speed + tms_speed) /
                                                std::sqrt(s.EA / s.mpl);
      // With a winch, the deployed length at the stop (Diagnose's).
      const double mean = span / (coarse.deployed > 0 ? coarse.deployed : s.length) - 1;
      return {"diverged: ends pulled apart", mean > 0 && mean >= 1.0 - spread * (1 + 1e-9), msg};
    }
    if (Contains(msg, "too fast for the step")) {
      return {"diverged: end motion too fast for the step",
              coarse.vehicle_speed > fast || tms_speed > fast, msg};
    }
    if (Contains(msg, "touched the seabed, and body")) {
      // CheckSeabedEnd (plugin/plugin.cc): the held end force with the seabed under the end
      // node stiff on the vehicle's step (from 0.7), stopped where the node (at the vehicle's
      // origin) touched it.
      return {"diverged: end node on a stiff seabed",
              s.seabed_kind != 0 && s.seabed_rate() >= 0.99 * 0.7 &&
                  coarse.vehicle.z() < s.seabed + 0.05,
              msg};
    }
    if (Contains(msg, "seabed penetration")) {
      return {"diverged: seabed penetration",
              s.seabed_kind != 0 && (coarse.vehicle.z() < s.seabed || coarse.tms.z() < s.seabed),
              msg};
    }
    if (Contains(msg, "coupling chatter")) {
      // The run-time work balance (docs/coupling.md): only where the advisor warned. From half
      // the limit ("may chatter") as it stands; below it, where Attach warned of the held end
      // force or of explicit's consistent coupling at omega h >= kCouplingAccurate (sessions 19
      // and 27), the message's advice is checked too: the 10x smaller step (omega h below 0.1
      // there, within the step it advises) runs to the end. Session 27: held-out seed 10311
      // (explicit, the held force at omega h 0.42, warned at load) stopped so and failed.
      const double limit = CouplingLimitOf(s);
      if (limit > 0 && s.omega_h >= 0.5 * limit) return {"diverged: coupling chatter", true, msg};
      const bool warned = limit > 0 && (coarse.held_warning || coarse.lead_warning);
      const bool cured = warned && !Failed(Simulate(s, kStep / 10, coarse.duration));
      return {"diverged: coupling chatter", cured,
              msg + (warned ? (cured ? "; warned at load, and the 10x smaller step runs"
                                     : "; warned at load, but the 10x smaller step fails too")
                            : "; not warned at load")};
    }
    if (Contains(msg, "start-up strain")) {
      return {"diverged: stretched start", s.b.norm() > s.length, msg};
    }
    if (Contains(msg, "Reduce <option timestep>") || Contains(msg, "stable step")) {
      const Run fine = Simulate(s, kStep / 10, coarse.duration);
      const bool ok = !Failed(fine);
      // An explicit scheme stopped at its automatic substeps advises max_step (a smaller MuJoCo
      // step takes substeps of the same length; plugin.cc, session 26): where the 10x smaller
      // step fails, the advised max_step must run.
      const std::string key = "or max_step=";
      if (const size_t at = msg.find(key); !ok && at != std::string::npos) {
        const double value = std::atof(msg.c_str() + at + key.size());
        const Scene cured = WithMaxStep(s, value);
        if (value > 0 && !cured.xml.empty()) {
          const Run c = Simulate(cured, kStep, coarse.duration);
          const bool runs = !Failed(c);
          return {"diverged: substep (the advised max_step runs)", runs,
                  msg + (runs ? "" : " | with max_step=" + std::to_string(value) + ": " + Why(c))};
        }
      }
      return {"diverged: step (10x smaller step runs)", ok,
              msg + (ok ? "" : " | fine step: " + Why(fine))};
    }
    return {"diverged: unrecognised cause", false, msg};
  }
  const Outcome o = Compare(s, coarse);
  if (o.pass) return o;
  // A thrust schedule beyond what the tether holds, or half of it (a snap overshoots to twice):
  // Attach warns that the run stops when the tether strains past max_strain, or runs on near it
  // with snaps whose peaks depend on the step ("compare with a smaller one"). Where the run
  // disagrees with its fine-step self, or that self diverges (seeds 9136 and 9153: the 0.2 ms
  // run resolves the snap that strains the line past max_strain, the 2 ms run damps it and
  // goes on), the same scene with the thrust at kThrottle x what the tether holds is judged
  // too: where it agrees, the thrust is the cause and the run did what its warning said, a
  // warned outcome (as for a stretched start, below); where it does not, the scene fails.
  const bool step_dependent =
      o.kind == "disagrees with 10x smaller step" || o.kind == "fine step failed";
  if (step_dependent && WarnsThrustStepDependence(coarse.thrust_warning)) {
    const Scene t = Throttled(s);
    const Run tc = Simulate(t, kStep, coarse.duration);
    const Outcome to = Failed(tc) ? Outcome{"failed", false, Why(tc)} : Compare(t, tc);
    const std::string throttled =
        "; thrust at " + std::to_string(kThrottle) + " x what it holds: " +
        (to.pass ? "agrees: " : to.kind + ": ") + to.detail;
    if (to.pass && WarnsThrustStepDependence(coarse.thrust_warning)) {
      return {kWarnedThrust, true, o.kind + ": " + o.detail + throttled};
    }
    const Twin d = JudgeWithDampingToo(t, coarse, "thrust throttled", &Run::thrust_warning);
    if (d.agrees) {
      return {kWarnedThrustRing, true, o.kind + ": " + o.detail + throttled + d.detail};
    }
    if (!coarse.stretched) return {o.kind, false, o.detail + throttled + d.detail};
  }
  // A start inside a geom the tether touches (Attach warned "starts inside a geom it touches":
  // the penalty pushes the line out within the first steps, an impulse the 2 ms step resolves
  // only roughly, like a stretched start's snap; the world draw's seeds 245, 459, 563, 602,
  // 904 and 943, 0.7-18 mm inside): the same scene with the geom moved clear of the initial
  // shape is judged too; where it agrees, the pressed start is the cause and the run did what
  // its warning said, a warned outcome; where it does not, the scene fails.
  if (step_dependent && WarnsContactStepDependence(coarse.contact_warning)) {
    const Scene cleared = Cleared(s);
    const Twin c = JudgeTwin(cleared, coarse.duration, "geom moved clear",
                             "no place keeps the ends clear", {&Run::contact_warning});
    if (c.agrees) return {kWarnedInside, true, o.kind + ": " + o.detail + c.detail};
    const Twin d =
        JudgeWithDampingToo(cleared, coarse, "geom moved clear", &Run::contact_warning);
    if (d.agrees) {
      return {kWarnedInsideRing, true, o.kind + ": " + o.detail + c.detail + d.detail};
    }
    if (!coarse.stretched) return {o.kind, false, o.detail + c.detail + d.detail};
  }
  // A snap that rang the undamped segment axial mode (RingWarnings, session 25: the 2 ms step
  // damps the ringing, the 0.2 ms step resolves it, and the slack clip turns it into mean
  // tension; seed 5957 read 20.1 N at 2 ms, 30.6 N at 0.2 ms and 24.7 N with twice the
  // segments): the run warned at its end that its tensions depend on the step and the segment
  // count, and advised damping_ratio=1. The same scene with that damping is judged too: where it
  // agrees, the undamped mode is the cause and the run did what its warning said, a warned
  // outcome; where it does not, the scene fails.
  if (step_dependent && !coarse.ring_warning.empty()) {
    const Twin c = JudgeTwin(Damped(s), coarse.duration, "with damping_ratio=1",
                             "the declaration is not the fuzzer's", {&Run::ring_warning});
    if (c.agrees) return {kWarnedRing, true, o.kind + ": " + o.detail + c.detail};
    if (!coarse.stretched) return {o.kind, false, o.detail + c.detail};
  }
  // Since session 26 also where the fine run failed (seeds 10116 and 12100, starts stretched
  // by 0.97 and 0.43: the 0.2 ms run resolves the release's snap past max_strain, the 2 ms run
  // damps it), as for a thrust above: the warning names the step as the outcome's cause.
  if (!step_dependent || !coarse.stretched) return o;
  // A stretched start (Attach warned "starts stretched": ends farther apart than the length,
  // up to max_strain = 1 in these scenes) releases EA x strain into the vehicle within a few
  // MuJoCo steps: a slingshot whose impulse the 2 ms step resolves only roughly (seed 8: a
  // mean 2.1 kN over the first 0.25 s at 2 ms, 4.2 kN at 0.2 and 0.02 ms), and the slack-taut
  // bouncing it starts can stay off for seconds (seeds 181 and 674 draw=1, explicit: 2.7e4
  // against 5.5e3 N and 530 against 45 N over 2-3 s; docs/scene_fuzzer.md, session 10). The
  // warning says so at load ("depend on <option timestep> for seconds after: compare with a
  // smaller one"). The same scene with the tether as long as the span (strain 0, no warning)
  // is judged too: where it agrees, the stretch is the cause and the run did what its warning
  // said, a warned outcome (pass, counted apart from "agrees"); where it disagrees too, the
  // scene fails in its class (tools/scene_fuzz_classify.py), the stretch being no excuse.
  const std::string after =
      EnvLong("MJTETHER_SCENE_FUZZ_LATE", 0) != 0 ? AfterTheTransient(s, coarse.duration) : "";
  Scene u = Unstretched(s);
  if (!ExpectedRefusal(u).empty()) return {o.kind, false, o.detail + after};
  const Run uc = Simulate(u, kStep, coarse.duration);
  if (Failed(uc)) return {o.kind, false, o.detail + after};
  const Outcome uo = Compare(u, uc);
  const std::string unstretched =
      "; started unstretched: " + (uo.pass ? "agrees: " : uo.kind + ": ") + uo.detail;
  if (uo.pass && WarnsStepDependence(coarse.stretch_warning)) {
    return {kWarnedStretched, true,
            StretchOf(coarse.stretch_warning) + "; " + o.kind + ": " + o.detail + after +
                unstretched};
  }
  if (!uo.pass && WarnsStepDependence(coarse.stretch_warning)) {
    const Twin d = JudgeWithDampingToo(u, coarse, "started unstretched", &Run::stretch_warning);
    if (d.agrees) {
      return {kWarnedStretchedRing, true,
              StretchOf(coarse.stretch_warning) + "; " + o.kind + ": " + o.detail + after +
                  unstretched + d.detail};
    }
    return {o.kind, false, o.detail + after + unstretched + d.detail};
  }
  return {o.kind, false, o.detail + after + unstretched};
}

Outcome Judge(const Scene& s) {
  t_shortened = t_stalled = t_held = t_rang = t_bounced = t_swung = t_alternated = false;
  Outcome o = JudgeRuns(s);
  o.shortened = t_shortened;
  o.stalled = t_stalled;
  o.held = t_held;
  o.rang = t_rang;
  o.bounced = t_bounced;
  o.swung = t_swung;
  o.alternated = t_alternated;
  return o;
}

// One scene per line: its seed, optionally "draw=1" (the draw it was found with; default the
// current one), then free text (class and cause).
std::set<SceneId> ReadSeeds(const std::string& path) {
  std::set<SceneId> seeds;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line)) {
    std::istringstream l(line);
    unsigned long long seed;
    if (line.empty() || line[0] == '#' || !(l >> seed)) continue;
    std::string word;
    int draw = kDraw;
    if (l >> word && word.rfind("draw=", 0) == 0) draw = std::stoi(word.substr(5));
    seeds.insert(Canonical(seed, draw));
  }
  return seeds;
}

// The seeds to run: MJTETHER_SCENE_FUZZ_FIRST.. (count of them) and the regression seeds, or
// MJTETHER_SCENE_FUZZ_SEEDS="4,136,141,372d1": exactly these seeds (to re-check a list); a
// suffix d1 means draw 1.
std::vector<SceneId> SeedList(long count, const std::set<SceneId>& regressions) {
  const long first = EnvLong("MJTETHER_SCENE_FUZZ_FIRST", 1);
  std::set<SceneId> seeds = regressions;
  for (long k = 0; k < count; ++k) seeds.insert(Canonical(first + k, kDraw));
  if (const char* only = std::getenv("MJTETHER_SCENE_FUZZ_SEEDS"); only && *only) {
    seeds.clear();
    std::istringstream l(only);
    for (std::string seed; std::getline(l, seed, ',');) {
      const size_t d = seed.find('d');
      seeds.insert(Canonical(std::stoull(seed.substr(0, d)),
                             d == std::string::npos ? kDraw : std::stoi(seed.substr(d + 1))));
    }
  }
  return std::vector<SceneId>(seeds.begin(), seeds.end());
}

// Judges every scene of the list (made by make) on MJTETHER_SCENE_FUZZ_THREADS threads, prints
// the counts per outcome and the known failures (listed in known_file), and fails the test on
// every other failure. prefix starts each scene's line ("seed", "world seed").
void RunScenes(const std::vector<SceneId>& list, const std::set<SceneId>& known,
               Scene (*make)(const SceneId&), const char* prefix, const char* title,
               const char* known_file) {
  const long threads = std::max(1L, EnvLong("MJTETHER_SCENE_FUZZ_THREADS", 2));
  const bool verbose = EnvLong("MJTETHER_SCENE_FUZZ_VERBOSE", 0) != 0;
  const testing::WarningHandler counting(CountWarning);
  std::mutex mutex;
  std::map<std::string, int> counts;
  std::vector<std::string> failures, known_failures, known_passing;
  std::atomic<size_t> next{0};
  auto worker = [&]() {
    for (size_t i; (i = next++) < list.size();) {
      const Scene s = make(list[i]);
      if (EnvLong("MJTETHER_SCENE_FUZZ_XML", 0) != 0) {
        std::lock_guard<std::mutex> lock(mutex);
        std::printf("%s %s:\n%s", prefix, Name(list[i]).c_str(), s.xml.c_str());
        continue;
      }
      const Outcome o = Judge(s);
      std::ostringstream line;
      line << prefix << " " << Name(list[i]) << " [" << s.integrator << ", N=" << s.segments
           << ", EA=" << s.EA << ", m=" << s.mass << " kg, omega*h=" << s.omega_h
           << ", seabed kind " << s.seabed_kind << ", thrust/holds=" << s.thrust / s.holds()
           << Describe(s) << "]: " << (o.pass ? "pass" : "FAIL") << ": " << o.kind << ": "
           << o.detail << (o.held ? " [warned at load: held end force]" : "")
           << (o.rang ? " [warned at run: a snap rang the segment mode]" : "")
           << (o.bounced ? " [warned at run: a snap rang the vehicle's bounce]" : "")
           << (o.swung ? " [warned at run: the vehicle's bounce swung]" : "")
           << (o.alternated ? " [warned at run: an end tension alternated]" : "");
      std::lock_guard<std::mutex> lock(mutex);
      ++counts[(o.pass ? "pass  " : "FAIL  ") + o.kind];
      if (o.shortened) ++counts["(of these, run shortened below 1 s by the cost budget)"];
      if (o.stalled) ++counts["(of these, with stalled implicit steps: warned)"];
      if (o.held) {
        ++counts[o.pass ? "(of these, passes warned of a held end force at omega h >= 0.1)"
                        : "(of these, failures warned of a held end force at omega h >= 0.1)"];
      }
      if (o.rang) {
        ++counts[o.pass ? "(of these, passes warned of a snap ringing the segment mode)"
                        : "(of these, failures warned of a snap ringing the segment mode)"];
      }
      if (o.bounced) {
        ++counts[o.pass ? "(of these, passes warned of a snap ringing the vehicle's bounce)"
                        : "(of these, failures warned of a snap ringing the vehicle's bounce)"];
      }
      if (o.swung) {
        ++counts[o.pass ? "(of these, passes warned of the vehicle's bounce swinging)"
                        : "(of these, failures warned of the vehicle's bounce swinging)"];
      }
      if (o.alternated) {
        ++counts[o.pass ? "(of these, passes warned of an end tension alternating)"
                        : "(of these, failures warned of an end tension alternating)"];
      }
      const bool is_known = known.count(list[i]) > 0;
      if (!o.pass && is_known) known_failures.push_back(line.str());
      if (!o.pass && !is_known) failures.push_back(line.str());
      if (o.pass && is_known) known_passing.push_back(line.str());
      if (verbose) std::printf("%s\n", line.str().c_str()), std::fflush(stdout);
    }
  };
  std::vector<std::thread> pool;
  for (long t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();

  std::printf("%s", title);
  for (const auto& [kind, n] : counts) std::printf("  %5d  %s\n", n, kind.c_str());
  std::printf("known failures (%s), run but not asserted: %zu\n", known_file,
              known_failures.size());
  for (const std::string& f : known_failures) std::printf("  known: %s\n", f.c_str());
  for (const std::string& f : known_passing)
    std::printf("  known but now passing: %s\n", f.c_str());
  for (const std::string& f : failures) ADD_FAILURE() << f;
  EXPECT_TRUE(failures.empty()) << failures.size() << " scenes failed";
}

TEST(SceneFuzz, EveryRandomSceneIsRefusedRunsCorrectlyOrDivergesWithACheckedCause) {
  const long count = EnvLong("MJTETHER_SCENE_FUZZ_COUNT", 200);
  const long first = EnvLong("MJTETHER_SCENE_FUZZ_FIRST", 1);
  const std::vector<SceneId> list =
      SeedList(count, ReadSeeds(MJTETHER_SCENE_FUZZ_REGRESSIONS));
  std::ostringstream title;
  title << "scene fuzzer: " << list.size() << " scenes (seeds " << first << ".."
        << first + count - 1 << " plus the regression seeds, or the list given)\n";
  RunScenes(list, ReadSeeds(MJTETHER_SCENE_FUZZ_KNOWN),
            [](const SceneId& id) {
              const Scene s = Make(id.seed, id.draw);
              const char* slack = std::getenv("MJTETHER_SCENE_FUZZ_SLACK");
              return slack && !s.xml.empty() ? Unstretched(s, std::atof(slack)) : s;
            }, "seed",
            title.str().c_str(), "tests/scene_fuzz_known.txt");
}

// The world draw (MakeWorld): tethers that touch a geom or that a winch pays out and hauls in,
// judged by the same oracle. MJTETHER_SCENE_FUZZ_WORLD_COUNT scenes (default 150: 15 s on
// the 2 cores this was written on) from MJTETHER_SCENE_FUZZ_FIRST, or the seeds of
// MJTETHER_SCENE_FUZZ_SEEDS; the other variables as above. Every seed is its draw-2 scene
// with the world's additions (a suffix d1 is ignored: the world draw is made on draw 2 only).
// Known failures: tests/scene_fuzz_world_known.txt.
TEST(SceneFuzz, TethersThatTouchGeomsOrWinchAreRefusedRunCorrectlyOrDivergeWithACheckedCause) {
  const long count = EnvLong("MJTETHER_SCENE_FUZZ_WORLD_COUNT", 150);
  const long first = EnvLong("MJTETHER_SCENE_FUZZ_FIRST", 1);
  const std::vector<SceneId> list =
      SeedList(count, ReadSeeds(MJTETHER_SCENE_FUZZ_WORLD_REGRESSIONS));
  std::ostringstream title;
  title << "scene fuzzer, world draw: " << list.size() << " scenes (seeds " << first << ".."
        << first + count - 1 << ", or the list given)\n";
  RunScenes(list, ReadSeeds(MJTETHER_SCENE_FUZZ_WORLD_KNOWN),
            [](const SceneId& id) { return MakeWorld(id.seed); }, "world seed",
            title.str().c_str(), "tests/scene_fuzz_world_known.txt");
}

// The warned outcome (JudgeRuns) needs both conditions: Attach's warning, captured at load,
// and the same scene started unstretched agreeing. Seed 644: rk4, 4 segments, 1374 kg, strain
// 0.91; its 2 ms run is 0.065 m off the 0.2 ms run (tolerance 0.059 m), and unstretched it
// agrees. Seed 9037: implicit2, 43 segments, 4.3 kg, stretched too, but 0.68 N against 25.8 N
// also unstretched, and 0.68 against 15.9 N (12.9 N at 0.02 ms) unstretched with
// damping_ratio=1: still a failure. (Seed 1910, the example in session 41, agrees damped since
// session 42, its stiff end damper on the held force: a warned outcome. Seed 7637, the example
// until session 40, is off unstretched too, but its
// unstretched twin rang and agrees damped: the two warnings' outcome of session 41, below.)
// (Seed 7185, rk4, the example from session 29 to 33, rings its undamped segment mode and
// agrees with damping_ratio=1 since explicit schemes are watched for it: a warned outcome of
// its own. Seed 582 of draw 1, the example until session 29, is refused at load since rk4's
// coupling limit is 0.5; seed 399, the one until session 13, agrees unstretched since
// explicit's stable step was halved.)
TEST(SceneFuzzOracle, AStretchedStartIsWarnedOnlyWhereItsUnstretchedTwinAgrees) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = Make(644, kDraw);
  const mjtether::Run run = Simulate(s, kStep);
  ASSERT_TRUE(run.stretched);
  EXPECT_TRUE(WarnsStepDependence(run.stretch_warning)) << run.stretch_warning;
  EXPECT_EQ(StretchOf(run.stretch_warning).rfind("warned: a strain of 0.91", 0), 0u)
      << StretchOf(run.stretch_warning);
  EXPECT_FALSE(Simulate(Unstretched(s), kStep, run.duration).stretched);
  const Outcome warned = Judge(s);
  EXPECT_TRUE(warned.pass) << warned.kind << ": " << warned.detail;
  EXPECT_EQ(warned.kind, kWarnedStretched);
  EXPECT_TRUE(Contains(warned.detail, "started unstretched: agrees")) << warned.detail;
  const Outcome failed = Judge(Make(9037, kDraw));
  EXPECT_FALSE(failed.pass) << failed.detail;
  EXPECT_EQ(failed.kind, "disagrees with 10x smaller step");
  EXPECT_TRUE(Contains(failed.detail, "started unstretched: disagrees")) << failed.detail;
  EXPECT_TRUE(Contains(failed.detail, "started unstretched, with damping_ratio=1: disagrees"))
      << failed.detail;
  // Seed 12100 (implicit2, strain 0.43, segment damping ratio 272): until session 29 its 0.2 ms
  // run diverged on the release's snap (strain beyond max_strain) while the 2 ms run went on,
  // and started unstretched it agreed: warned. That divergence was implicit2's own step on an
  // overdamped segment mode, which now steps as backward Euler
  // (kSecondOrderMaxDampingRatioImplicit2), and the 0.2 ms run goes on: the scene agrees with
  // its refinements. It was the only scene of seeds 1-15000 with that outcome, so the warned
  // outcome's fine-step-failed branch has no example left here (the branch stays: JudgeRuns).
  const Outcome fine_ran = Judge(Make(12100, kDraw));
  EXPECT_TRUE(fine_ran.pass) << fine_ran.kind << ": " << fine_ran.detail;
  EXPECT_FALSE(Contains(fine_ran.detail, "fine step failed")) << fine_ran.detail;
  // A warning without the step's caveat does not excuse a disagreement.
  EXPECT_FALSE(WarnsStepDependence("starts stretched, far from equilibrium"));
}

// A run warned of two causes, a stretched start and (at its end) a snap that rang the undamped
// segment mode, is a warned outcome where the twin with both taken away agrees, though the twin
// with only the stretch taken away does not (JudgeWithDampingToo; session 41). Seed 7637:
// explicit, 6 segments, a 2.6 t vehicle, strain 0.86; 468 N at 2 ms against 7.4 kN at 0.2 ms;
// started unstretched it still reads 918 N against 332 N, the undamped mode ringing after the
// line's first snap; unstretched with damping_ratio=1 it agrees (324 against 316 N). Seed 9037
// (above) is the same pair of warnings with a doubly cleared twin that still disagrees: a
// failure. Where the stretch alone explains the run, the outcome is the stretch's: seed 644
// rang too, but started unstretched it agrees, and no damped twin is judged.
TEST(SceneFuzzOracle, TwoWarnedCausesAreWarnedOnlyWhereTheTwinWithoutBothAgrees) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = Make(7637, kDraw);
  const mjtether::Run run = Simulate(s, kStep);
  EXPECT_TRUE(WarnsStepDependence(run.stretch_warning)) << run.stretch_warning;
  EXPECT_TRUE(Contains(run.ring_warning, "Declare damping_ratio=1")) << run.ring_warning;
  const Outcome warned = Judge(s);
  EXPECT_TRUE(warned.pass) << warned.kind << ": " << warned.detail;
  EXPECT_EQ(warned.kind, kWarnedStretchedRing);
  EXPECT_TRUE(Contains(warned.detail, "started unstretched: disagrees")) << warned.detail;
  EXPECT_TRUE(Contains(warned.detail, "started unstretched, with damping_ratio=1: agrees"))
      << warned.detail;
  const Outcome one_cause = Judge(Make(644, kDraw));
  EXPECT_EQ(one_cause.kind, kWarnedStretched) << one_cause.detail;
  EXPECT_FALSE(Contains(one_cause.detail, "with damping_ratio=1")) << one_cause.detail;
}

// The thrust-warned outcome (JudgeRuns, session 15) needs Attach's thrust warning and the same
// scene with the thrust at kThrottle x what the tether holds agreeing. Seed 9153: implicit2,
// 63 segments, thrust 1.88 x EA x max_strain; its 2 ms run goes to the end while the 0.2 ms run
// diverges on the thrust at 0.743 s, and at 0.45 x it agrees: warned. Seed 4842: rk4, 311
// segments, thrust 1.85 x; 315 N against 421 N at 0.2 ms, and at 0.45 x still 30 N against
// 44 N: the thrust is not the whole cause, a failure.
TEST(SceneFuzzOracle, AThrustBeyondWhatTheTetherHoldsIsWarnedOnlyWhereItsThrottledTwinAgrees) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = Make(9153, kDraw);
  const mjtether::Run run = Simulate(s, kStep);
  EXPECT_TRUE(WarnsThrustStepDependence(run.thrust_warning)) << run.thrust_warning;
  // The twin's thrust is below half of what the tether holds: Attach does not warn it.
  const Scene t = Throttled(s);
  EXPECT_NEAR(t.thrust, kThrottle * s.holds(), 1e-9 * s.holds());
  EXPECT_TRUE(Simulate(t, kStep, run.duration).thrust_warning.empty());
  const Outcome warned = Judge(s);
  EXPECT_TRUE(warned.pass) << warned.kind << ": " << warned.detail;
  EXPECT_EQ(warned.kind, kWarnedThrust);
  EXPECT_EQ(warned.detail.rfind("fine step failed: ", 0), 0u) << warned.detail;
  EXPECT_TRUE(Contains(warned.detail, "x what it holds: agrees")) << warned.detail;
  const Outcome failed = Judge(Make(4842, kDraw));
  EXPECT_FALSE(failed.pass) << failed.detail;
  EXPECT_EQ(failed.kind, "disagrees with 10x smaller step");
  EXPECT_TRUE(Contains(failed.detail, "x what it holds: disagrees")) << failed.detail;
  // A thrust warning without the step's caveat does not excuse a disagreement.
  EXPECT_FALSE(WarnsThrustStepDependence("the thrust: schedules push body 'rov' with 1 N"));
}

// World seed 116 (bdf2, 210 segments, a 702 kg vehicle, its skin 6.3 mm inside a capsule
// rock, no friction) is warned at load and disagrees with its fine step; with the rock moved
// clear (Cleared: its skin clear by kClearedBy d, no warning) it agrees, so the outcome is
// warned. World seed 563 (0.7 mm inside a box, a taut line ringing in a current) disagrees as
// much with the box clear (and with damping_ratio=1 as well): the start is not the cause, and
// it still fails. (Until session 24 the first was world seed 459, which now agrees outright
// from the chain-at-rest start.)
TEST(SceneFuzzOracle, AStartInsideARockIsWarnedOnlyWhereItsClearTwinAgrees) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = MakeWorld(116);
  ASSERT_LT(s.clearance, 0);
  const mjtether::Run run = Simulate(s, kStep);
  EXPECT_TRUE(WarnsContactStepDependence(run.contact_warning)) << run.contact_warning;
  const Scene c = Cleared(s);
  ASSERT_FALSE(c.xml.empty());
  EXPECT_GE(c.clearance, kClearedBy * s.diameter * (1 - 1e-9));
  EXPECT_LT(c.clearance, 2 * kClearedBy * s.diameter);
  EXPECT_TRUE(Simulate(c, kStep, run.duration).contact_warning.empty());
  const Outcome warned = Judge(s);
  EXPECT_TRUE(warned.pass) << warned.kind << ": " << warned.detail;
  EXPECT_EQ(warned.kind, kWarnedInside);
  EXPECT_TRUE(Contains(warned.detail, "geom moved clear: agrees")) << warned.detail;
  const Outcome failed = Judge(MakeWorld(563));
  EXPECT_FALSE(failed.pass) << failed.detail;
  EXPECT_EQ(failed.kind, "disagrees with 10x smaller step");
  EXPECT_TRUE(Contains(failed.detail, "geom moved clear: disagrees")) << failed.detail;
  EXPECT_TRUE(Contains(failed.detail, "geom moved clear, with damping_ratio=1: disagrees"))
      << failed.detail;
  // Two warned causes (session 41, JudgeWithDampingToo): world seed 943 (bdf2, 23 segments, its
  // skin 18 mm inside a capsule) rang too; with the capsule clear it still reads 47.5 N against
  // 81.2 N, and with the capsule clear and damping_ratio=1 it agrees (47.56 against 47.50 N).
  const Outcome both = Judge(MakeWorld(943));
  EXPECT_TRUE(both.pass) << both.kind << ": " << both.detail;
  EXPECT_EQ(both.kind, kWarnedInsideRing);
  EXPECT_TRUE(Contains(both.detail, "geom moved clear, with damping_ratio=1: agrees"))
      << both.detail;
  EXPECT_FALSE(WarnsContactStepDependence("starts inside a geom it touches"));
}

// Seed 5957 (bdf2, 72 segments of 4.8 m, EA 3.6e7 N, a 2.9 t vehicle under a heaving TMS):
// segments snap taut in the first 0.1 s, the segment axial mode (omega_n 3728 rad/s, omega_n h
// 7.5) is undamped, and the vehicle-end tension over the last 0.2 s reads 20.1 N at 2 ms against
// 30.6 N at 0.2 ms. The run warns at its end (RingWarnings) and advises damping_ratio=1, with
// which the scene agrees with its fine step (18.03 N at both): the outcome is warned. Seed 6946
// (bdf2, 270 segments, a 48 kg vehicle) rings and is warned too, but its damped twin still
// disagrees (334 against 512 N): the warning does not excuse it. (Seed 6727, implicit2, was that
// example until session 40, when implicit2's held force became its stages' mean and it agreed
// undamped.) The same warning is absent with the mode damped (the twin).
// An explicit tether's substeps keep the ringing instead of damping it, but the energy a snap
// leaves in it differs between steps as much (session 33): the same scene with explicit warns,
// in its own words, and seed 3244 (explicit, 4 segments of EA 2.7e8 N, undamped: 65.7 N at 2 ms
// against 15.8 N at 0.2 ms and 16.4 N at 0.02 ms) is warned, and with damping_ratio=1 agrees
// (15.71 against 15.76 N, as every implicit scheme reads it at 2 ms undamped).
TEST(SceneFuzzOracle, AnUndampedRingingSnapIsWarnedOnlyWhereItsDampedTwinAgrees) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = Make(5957, kDraw);
  const mjtether::Run run = Simulate(s, kStep);
  EXPECT_TRUE(Contains(run.ring_warning, "snapped taut")) << run.ring_warning;
  EXPECT_TRUE(Contains(run.ring_warning, "Declare damping_ratio=1")) << run.ring_warning;
  const Scene c = Damped(s);
  ASSERT_FALSE(c.xml.empty());
  EXPECT_TRUE(Contains(c.xml, " damping_ratio=1\"")) << c.xml;
  EXPECT_TRUE(Simulate(c, kStep, run.duration).ring_warning.empty());
  Scene e = s;
  const std::string bdf2 = "integrator=bdf2";
  e.xml.replace(e.xml.find(bdf2), bdf2.size(), "integrator=explicit");
  const std::string kept = Simulate(e, kStep, run.duration).ring_warning;
  EXPECT_TRUE(Contains(kept, "keeps the ringing after a snap undamped")) << kept;
  EXPECT_FALSE(Contains(kept, "damps the ringing")) << kept;
  const Outcome explicit_warned = Judge(Make(3244, kDraw));
  EXPECT_TRUE(explicit_warned.pass) << explicit_warned.kind << ": " << explicit_warned.detail;
  EXPECT_EQ(explicit_warned.kind, kWarnedRing);
  EXPECT_TRUE(Contains(explicit_warned.detail, "with damping_ratio=1: agrees"))
      << explicit_warned.detail;
  const Outcome warned = Judge(s);
  EXPECT_TRUE(warned.pass) << warned.kind << ": " << warned.detail;
  EXPECT_EQ(warned.kind, kWarnedRing);
  EXPECT_TRUE(Contains(warned.detail, "with damping_ratio=1: agrees")) << warned.detail;
  const Outcome failed = Judge(Make(6946, kDraw));
  EXPECT_FALSE(failed.pass) << failed.detail;
  EXPECT_EQ(failed.kind, "disagrees with 10x smaller step");
  EXPECT_TRUE(Contains(failed.detail, "with damping_ratio=1: disagrees")) << failed.detail;
}

// Seed 6260 (implicit, 203 segments of 1.6 m, EA 1.1e5 N, undamped, a 19 kg vehicle on a slack
// 331 m line through the seabed): its snaps are small, and backward Euler damps them further. The
// largest reads 0.83 N at 2 ms (bdf2 1.04 N), under kRingBigJump's 1 N, while the ends hold about
// 47 N (TMS) and 20 N (vehicle). Measured against the larger end tension (before session 42) it
// was under 2% (0.94 N), and the run exited 0 without a word, 5.19 N at 2 ms against 5.71 N at
// 0.2 ms. Against the smaller end's, which a jump moves most, it is 4%: the run warns, and with
// damping_ratio=1 it agrees (4.86 against 5.04 N). The jump in the warning is under 1 N, so the
// relative criterion is the one that counted.
TEST(SceneFuzzOracle, ASnapIsMeasuredAgainstTheSmallerEndTension) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = Make(6260, kDraw);
  EXPECT_EQ(s.integrator, "implicit");
  const mjtether::Run run = Simulate(s, kStep);
  const std::string key = "largest axial wave tension jump ";
  const size_t at = run.ring_warning.find(key);
  EXPECT_NE(at, std::string::npos) << run.ring_warning;
  if (at != std::string::npos) {
    EXPECT_LT(std::stod(run.ring_warning.substr(at + key.size())), 1.0) << run.ring_warning;
  }
  const Outcome warned = Judge(s);
  EXPECT_TRUE(warned.pass) << warned.kind << ": " << warned.detail;
  EXPECT_EQ(warned.kind, kWarnedRing);
  EXPECT_TRUE(Contains(warned.detail, "with damping_ratio=1: agrees")) << warned.detail;
}

// PhaseRange on a made-up history at the coarse step: 5 N with one snap of 1005 N at the third
// last step. The oracle's window (0.2 s, 100 steps) holds it: 5 + 1000 / 100 = 15 N; moved 3
// steps (6 ms) or more earlier (up to 20 ms, 10 steps) it does not: 5 N.
TEST(SceneFuzzOracle, TheWindowsRangeIsWhatASnapAtTheEdgeMovesTheMeanBy) {
  mjtether::Run r;
  r.duration = kDuration;
  r.tensions.assign(500, 5.0);
  r.tensions[500 - 3] = 1005;
  const Range range = PhaseRange(r, kStep);
  EXPECT_NEAR(range.lo, 5, 1e-9);
  EXPECT_NEAR(range.hi, 15, 1e-9);
  EXPECT_DOUBLE_EQ(Gap(range, Range{16, 20}), 1);
  EXPECT_DOUBLE_EQ(Gap(range, Range{10, 20}), 0);
}

// Seed 1460 (rk4, 2 segments, a 3.7 kg vehicle, no seabed): the vehicle-end tension over the
// last 0.2 s reads 19.19 N at 2 ms against 20.55 N at 0.2 ms (tolerance 1.03 N), and a window
// moved by up to a tenth of its length holds the same snaps: it agrees within the moved window.
// Seed 5069 (bdf2, 3 segments of EA 8.4e6 N, a 16 kg vehicle, the consistent coupling at omega
// h 1.03) reads 260.5 against 282.6 N (tolerance 14.1 N), and no window moved by up to a tenth
// brings it within (260.3-263.2 N against 280.9-296.8 N, and 286.8-303.4 N at 0.02 ms): a real
// difference is not excused by the window's phase. (Seed 1423, implicit2's held force at omega
// h 0.42, 15.17 against 16.56 N, was the wrong one in session 39; since session 40 implicit2's
// held force is its stages' mean and it agrees: Coupling.Implicit2sHeldForceIsTheForceItsNodesTook.
// Seed 6876, explicit at omega h 0.45, 631
// against 51.4 N, was the wrong one until session 39, when the coupling's work balance in the
// frame moving with the site saw its chatter and stopped it: Coupling.
// AChatterUnderADriftingVehicleIsStoppedAndBothCuresAgree. Seed 3244, explicit at 0.4998, 65.7
// against 15.8 N, was the wrong one from
// session 29 to 33; since explicit's snaps are watched for ringing, it is warned, and with
// damping_ratio=1 it agrees: AnUndampedRingingSnapIsWarnedOnlyWhereItsDampedTwinAgrees.
// Seed 913, rk4 at
// omega h 0.71, was the wrong one until session 29 made rk4 refuse from 0.5; until session
// 27 it was 4324, explicit at omega h 0.51, 157 against 170 N; with end node B on
// MuJoCo's Euler path it reads 158.5 N and a moved window brings it within. Until session 24 the pair
// was 3711, a snap train of a slack chain, and 539, whose snaps were shorter than the MuJoCo
// step; the chain-at-rest start took the slack start, and with it those snaps, from both.)
TEST(SceneFuzzOracle, ASnapTrainAgreesWithinAMovedWindowButAWrongImpulseDoesNot) {
  const testing::WarningHandler counting(CountWarning);
  const Outcome phase = Judge(Make(1460, kDraw));
  EXPECT_TRUE(phase.pass) << phase.kind << ": " << phase.detail;
  EXPECT_EQ(phase.kind, kSnapPhase);
  const Outcome wrong = Judge(Make(5069, kDraw));
  EXPECT_FALSE(wrong.pass) << wrong.detail;
  EXPECT_EQ(wrong.kind, "disagrees with 10x smaller step");
  EXPECT_TRUE(Contains(wrong.detail, "windows up to a tenth earlier")) << wrong.detail;
}


// The energy oracle's end work (Simulate, "Energy oracle"): the step's reaction along the end
// node's displacement is the work the scheme does on its ends, so the 2 ms run's end work is
// the converged one. Seed 9297 (bdf2, omega h 1.35, 5 segments held at 1.7e8 N by a thrust, no
// current): 1.634e9 J at 2 ms, 1.620e9 J at 0.2 ms (0.9% apart: the 2 ms run's force history
// is its own); the trapezoid of F . v sampled once per step, the oracle until session 14, read
// 1.05e9 J at 2 ms (35% short, the previous step's force weighed at omega h >= 1), so the
// tether seemed to gain 5.2e8 J. Tolerance 3%: the runs' own difference, the 2 ms run's force
// lagging the converged one's by up to a step, is ~1%; the trapezoid's error is 35%.
// The oracle still sees a real gain: with symplectic Euler's substep at 0.8 of its limit
// (kExplicitSafety, planted by hand in session 14) seed 1279 gains 2.39 J against its
// tolerance 0.22 J, as Energy.ExplicitSlackSwitchingGainsNoEnergyBeyondTheEndsWork asserts on
// the engine alone.
TEST(SceneFuzzOracle, EndWorkIsTheStepsForceAlongTheEndNodesDisplacement) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = Make(9297, kDraw);
  ASSERT_TRUE(s.current.norm() == 0) << "the balance is checked without a current";
  const mjtether::Run coarse = Simulate(s, kStep);
  const mjtether::Run fine = Simulate(s, kStep / 10, coarse.duration);
  ASSERT_TRUE(coarse.balanced && fine.balanced && !coarse.diverged && !fine.diverged);
  EXPECT_GT(coarse.work, 1e8) << "the thrust does work on the tether";
  EXPECT_NEAR(coarse.work, fine.work, 0.03 * std::abs(fine.work));
  EXPECT_LE(coarse.excess, EnergyTolerance(coarse));
  const Outcome o = Judge(s);
  EXPECT_TRUE(o.pass) << o.kind << ": " << o.detail;
}

// A coupling chatter stop below half the advisor's limit (session 27): accepted where Attach
// warned at load (the held end force, or explicit's consistent coupling, at omega h >= 0.1)
// and the 10x smaller step runs to the end, as the message advises. Held-out seed 10311
// (explicit, 35 segments, a 19 kg vehicle, the held force at omega h 0.42) stops at 0.39 s with
// the chatter named; at 0.2 ms it runs. The same scene with bdf2 gets no such warning nor stop.
TEST(SceneFuzzOracle, AChatterStopBelowHalfTheLimitPassesWhereItWasWarnedAndTheStepCuresIt) {
  const testing::WarningHandler counting(CountWarning);
  const Scene s = Make(10311, kDraw);
  const mjtether::Run coarse = Simulate(s, kStep);
  EXPECT_TRUE(coarse.held_warning);
  EXPECT_LT(s.omega_h, 0.5 * CouplingLimitOf(s));
  const Outcome o = Judge(s);
  EXPECT_TRUE(o.pass) << o.kind << ": " << o.detail;
  EXPECT_EQ(o.kind, "diverged: coupling chatter");
  EXPECT_TRUE(Contains(o.detail, "warned at load, and the 10x smaller step runs")) << o.detail;
}

}  // namespace
}  // namespace mjtether
