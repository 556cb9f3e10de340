// Reference scenes shared by the accuracy/cost sweep (tests/bench/accuracy_cost.cc) and the
// tests that measure against them (tests/stable_step_test.cc): the fixed comparison line, a
// settling catenary, a swinging chain, a snap and a slack ROV tether, each with its end
// motions, and a run of one of them through the engine alone.
#ifndef MJTETHER_TESTS_REFERENCE_SCENES_H_
#define MJTETHER_TESTS_REFERENCE_SCENES_H_

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <functional>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "catenary_reference.h"
#include "declaration.h"
#include "tether.h"

namespace mjtether {
namespace reference_scenes {

constexpr double kPi = 3.14159265358979323846;
using Clock = std::chrono::steady_clock;

// Wall time and this thread's CPU time [s]. The machine is shared: CPU time is the cost on one
// core, wall time also counts what other processes took from it.
struct Stamp {
  double wall = 0, cpu = 0;
};
inline Stamp Now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return {std::chrono::duration<double>(Clock::now().time_since_epoch()).count(),
          ts.tv_sec + 1e-9 * ts.tv_nsec};
}

// ------------------------------------------------------------------------------------------
// Scenes

struct Scene {
  std::string name;
  std::string declaration;  // tether keys without ends, segments, integrator
  std::string water;        // water keys, empty: dry
  Vec3 gravity = Vec3(0, 0, -9.81);
  std::function<EndState(double)> a, b;  // end motions; b empty: free end
  double duration = 0;                   // [s]
  double sample = 0.1;                   // [s] sampling interval of the error
  double error_from = 0;                 // [s] samples before this are not in the error
  std::vector<int> segments;             // N of the sweep
  int reference_segments = 0;            // finest N (reference)
  double start_angle = -1;  // [rad] >= 0: free end starts straight, this far from hanging, at rest
  bool static_reference = false;  // error of the final tension against the closed form
  double static_tension = 0;      // [N] closed-form end tension at B
};


inline EndState Fixed(Vec3 p) {
  EndState e;
  e.pos = p;
  return e;
}

// Unstretched length from the declaration ("length=...").
inline double s_len(const Scene& s) {
  const size_t at = s.declaration.find("length=");
  return std::stod(s.declaration.substr(at + 7));
}

inline Scene LineScene() {
  Scene s;
  s.name = "line";
  s.declaration =
      "length=100 diameter=0.025 mass_per_length=1 EA=1e6 damping=1000 Cdn=1.2 Can=1 "
      "Cdt=0.008";
  s.water = "density=1025";
  s.a = [](double) { return Fixed(Vec3(0, 0, -150)); };
  s.b = [](double t) {
    EndState e;
    const double w = 2 * kPi / 10;
    e.pos = Vec3(80 + 2 * std::sin(w * t), 0, -100);
    e.vel = Vec3(2 * w * std::cos(w * t), 0, 0);
    return e;
  };
  s.duration = 60;
  // The first period is the start from the inextensible catenary (a snap as the line takes up
  // its stretch), not the periodic response the comparison is about.
  s.error_from = 10;
  // 160 and 320 segments reach the 0.1% and 0.01% levels of the recommendations (README).
  s.segments = {10, 20, 40, 80, 160, 320};
  s.reference_segments = 640;
  return s;
}

inline Scene CatenaryScene() {
  Scene s;
  s.name = "catenary";
  // Heavily damped so that it settles; the error is that of the settled end tension.
  s.declaration = "length=100 diameter=0.02 mass_per_length=1 EA=1e5 damping=2000 Cdn=1.2";
  s.water = "density=1025";
  s.a = [](double) { return Fixed(Vec3(0, 0, 0)); };
  s.b = [](double) { return Fixed(Vec3(80, 0, 20)); };
  s.duration = 40;
  s.sample = 40;
  s.segments = {10, 20, 40, 80};
  s.reference_segments = 80;
  s.static_reference = true;
  const double w = (1.0 - 1025 * kPi * 0.02 * 0.02 / 4) * 9.81;  // [N/m] wet weight
  s.static_tension = testing::SolveCatenary(80, 20, 100, w, 1e5).tension_b();
  return s;
}

inline Scene SwingScene() {
  Scene s;
  s.name = "swing";
  s.declaration = "length=10 diameter=0.01 mass_per_length=0.5 EA=1e5 damping=5";
  s.gravity = Vec3(0, 0, -9.81);
  s.a = [](double) {
    EndState e = Fixed(Vec3(0, 0, 0));
    e.axis = Vec3(1, 0, 0);
    return e;
  };
  s.start_angle = kPi / 6;
  s.duration = 5;
  s.sample = 0.02;
  s.segments = {10, 20, 40, 80};
  s.reference_segments = 160;
  return s;
}

inline Scene SnapScene() {
  Scene s;
  s.name = "snap";
  s.declaration =
      "length=20 diameter=0.02 mass_per_length=0.35 EA=2e5 damping=50 Cdn=1.2 Cdt=0.01 Can=1";
  s.water = "density=1025";
  s.gravity = Vec3(0, 0, -9.81);
  s.a = [](double) { return Fixed(Vec3(0, 0, 0)); };
  // End B moves along x from 0.9 L to 1.005 L in 0.5 s (smooth cubic ramp), then holds.
  s.b = [](double t) {
    const double T = 0.5, d0 = 18, d1 = 20.1;
    const double u = std::min(t / T, 1.0);
    EndState e;
    e.pos = Vec3(d0 + (d1 - d0) * (3 * u * u - 2 * u * u * u), 0, 0);
    e.vel = Vec3(t < T ? (d1 - d0) * (6 * u - 6 * u * u) / T : 0, 0, 0);
    return e;
  };
  s.duration = 3;
  s.sample = 0.01;
  s.segments = {10, 20, 40, 80};
  s.reference_segments = 160;
  return s;
}

inline Scene SlackScene() {
  Scene s;
  s.name = "slack";
  s.declaration =
      "length=40 diameter=0.02 mass_per_length=0.35 EA=2e5 EI=0.5 damping=50 Cdn=1.2 Cdt=0.01 "
      "Can=1";
  s.water = "density=1025 current=0.3,0,0";
  s.a = [](double) { return Fixed(Vec3(0, 0, 0)); };
  // End B circles (radius 3 m, period 20 s) around (20, 0, -15).
  s.b = [](double t) {
    const double w = 2 * kPi / 20;
    EndState e;
    e.pos = Vec3(20 + 3 * std::cos(w * t), 3 * std::sin(w * t), -15);
    e.vel = Vec3(-3 * w * std::sin(w * t), 3 * w * std::cos(w * t), 0);
    return e;
  };
  s.duration = 20;
  s.sample = 0.1;
  s.segments = {10, 20, 40, 80};
  s.reference_segments = 160;
  return s;
}

// ------------------------------------------------------------------------------------------
// One run through the engine alone.

struct Run {
  std::string scene, path, integrator;  // path: engine, mujoco, composite
  int segments = 0;
  double step = 0;   // [s] the integrator's step (tether step; the MuJoCo step for composite)
  double outer = 0;  // [s] the coupling step (Advance / mj_step)
  double wall = 0;   // [s] wall time of the whole run
  double cpu = 0;    // [s] CPU time of the whole run (this thread)
  bool ok = true;
  std::vector<double> T;             // end tension at each sample [N]
  std::vector<std::vector<Vec3>> x;  // nodes at each sample
  double err_T = NAN, err_T_time = NAN, err_x = NAN;
  double duration = 0;         // [s] simulated
  double mean_T = 0;           // [N] mean reference tension over the error window
  bool pareto = false;         // on the scene's front (no run cheaper and more accurate)
  bool pareto_series = false;  // on the front of its own path and integrator
  double ms() const { return 1e3 * cpu / duration; }  // CPU ms per simulated second
  std::string series() const { return path == "engine" ? integrator : path + "_" + integrator; }
};

inline std::string Declaration(const Scene& s, int N, const std::string& integrator, double max_step,
                        double substeps) {
  std::ostringstream d;
  d.precision(17);
  d << s.declaration << " segments=" << N << " integrator=" << integrator;
  if (max_step > 0) d << " max_step=" << max_step;
  if (substeps > 0) d << " substeps=" << static_cast<int>(substeps);
  return d.str();
}

// The fixed comparison line as an MJCF model at MuJoCo step h [s]: end A anchored at
// (0, 0, -150), end B on the mocap body `fairlead` (move it along s.b). Used by bench_callback
// and tools/line_steps.cc.
inline std::string LineModelXml(const Scene& s, int segments, const char* integrator, double h) {
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco><option timestep=\"" << h << "\"/><custom>"
    << "<text name=\"water\" data=\"" << s.water << "\"/>"
    << "<text name=\"tether:line\" data=\"ends=anchor,fair "
    << Declaration(s, segments, integrator, 0, 0) << "\"/></custom><worldbody>"
    << "<site name=\"anchor\" pos=\"0 0 -150\"/>"
    << "<body name=\"fairlead\" mocap=\"true\" pos=\"80 0 -100\"><site name=\"fair\"/></body>"
    << "</worldbody></mujoco>";
  return x.str();
}

// A tether from a declaration's text in an environment: nullopt with *error set where the
// declaration or the tether is refused.
inline std::optional<Tether> TetherFrom(const std::string& declaration, const Environment& env,
                                        std::string* error) {
  DeclarationError e;
  std::optional<TetherDeclaration> decl = ParseTether(declaration, env, &e);
  if (!decl) {
    *error = e.message;
    return std::nullopt;
  }
  return Tether::Create(decl->params, env, error);
}

inline std::optional<Tether> MakeTether(const Scene& s, int N, const std::string& integrator,
                                 double max_step, int substeps, std::string* error) {
  Environment env;
  env.gravity = s.gravity;
  if (!s.water.empty()) {
    DeclarationError e;
    std::optional<Water> w = ParseWater(s.water, &e);
    if (!w) {
      *error = e.message;
      return std::nullopt;
    }
    env.wet = true;
    env.water = *w;
  }
  const std::string ends = s.b ? "ends=a,b " : "ends=a,free ";
  return TetherFrom(ends + Declaration(s, N, integrator, max_step, substeps), env, error);
}

inline Ends EndsAt(const Scene& s, double t) {
  Ends e;
  e.a = s.a(t);
  if (s.b) e.b = s.b(t);
  return e;
}

// Runs the scene with outer step `outer` (tether steps per outer step from max_step).
inline Run RunEngine(const Scene& s, int N, const std::string& integrator, double outer, double max_step,
              bool keep_nodes) {
  Run r;
  r.scene = s.name;
  r.path = "engine";
  r.integrator = integrator;
  r.segments = N;
  r.outer = outer;
  std::string error;
  std::optional<Tether> t = MakeTether(s, N, integrator, max_step, 0, &error);
  if (!t) {
    std::fprintf(stderr, "%s: %s\n", s.name.c_str(), error.c_str());
    std::exit(2);
  }
  r.step = outer / t->SubstepsFor(outer);
  std::vector<double> x(3 * t->nodes()), v(3 * t->nodes()), work(t->WorkspaceSize());
  std::vector<double> history(t->HistorySize() + 1);  // bdf2's last step between calls
  const long steps = std::lround(s.duration / outer);
  const long every = std::max(1L, std::lround(s.sample / outer));
  auto record = [&](const Ends& ends) {
    EndReactions re = t->Reactions(x.data(), v.data(), ends, work.data());
    r.T.push_back(s.b ? re.tension_b : re.tension_a);
    if (keep_nodes) {
      std::vector<Vec3> nodes(t->nodes());
      for (int i = 0; i < t->nodes(); ++i) nodes[i] = Vec3(&x[3 * i]);
      r.x.push_back(std::move(nodes));
    }
  };
  // Timed: the stepping and the reaction at each outer step (as the MuJoCo callback does).
  const Stamp start = Now();
  Ends from = EndsAt(s, 0);
  t->InitialShape(from, x.data(), v.data());
  if (s.start_angle >= 0) {
    const Vec3 dir(std::sin(s.start_angle), 0, -std::cos(s.start_angle));
    for (int i = 0; i < t->nodes(); ++i) {
      const Vec3 p = from.a.pos + dir * (s_len(s) * i / N);
      for (int k = 0; k < 3; ++k) x[3 * i + k] = p[k];
    }
  }
  double sink = 0;
  for (long k = 0; k < steps; ++k) {
    if (k % every == 0) {
      const Stamp pause = Now();
      record(from);
      const Stamp resume = Now();
      r.wall -= resume.wall - pause.wall;
      r.cpu -= resume.cpu - pause.cpu;
    }
    const Ends to = EndsAt(s, (k + 1) * outer);
    StepStatus st = t->Advance(x.data(), v.data(), from, to, outer, work.data(), history.data());
    if (!st.ok) {
      r.ok = false;
      break;
    }
    sink += t->Reactions(x.data(), v.data(), to, work.data()).tension_a;
    from = to;
  }
  const Stamp stop = Now();
  r.wall += stop.wall - start.wall;
  r.cpu += stop.cpu - start.cpu;
  if (r.ok) record(from);
  if (!(sink >= 0)) r.ok = false;
  return r;
}


}  // namespace reference_scenes
}  // namespace mjtether

#endif  // MJTETHER_TESTS_REFERENCE_SCENES_H_
