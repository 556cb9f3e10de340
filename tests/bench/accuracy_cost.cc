// What accuracy costs in time: runs reference scenes across integrators, segment counts and
// time steps, measures the error of end tension and node positions against a converged
// reference and the CPU (and wall) time per simulated second, and writes accuracy_cost.csv and
// accuracy_cost.md into DIR. tools/accuracy_cost.sh runs it and draws the charts.
//
//   accuracy_cost [--quick] [--scenes line,catenary,...] [--steps 0.05,0.01] [--out DIR]
//
// --quick: 10 and 20 segments against 40 (seconds); --steps: the implicit steps [s].
// Debugging aids: --rope-only (only the composite rope runs, with a summary), and the
// environment variable ACCURACY_COST_DUMP=DIR (tension series of every run, rope MJCF).
//
// Scenes (see Scenes() below):
//   line      the fixed comparison scene: 100 m line, anchor (0,0,-150), fairlead from
//             (80,0,-100) moving x = 80 + 2 sin(2 pi t/10), 60 s; error = RMS fairlead tension.
//             Run by the engine alone, through MuJoCo (fairlead on a mocap body), and as a
//             MuJoCo <composite type="rope"> chain.
//   catenary  static elastic catenary settling from the inextensible shape; reference: Irvine's
//             closed form (tests/catenary_reference.h).
//   swing     a dry chain released straight at 30 degrees from hanging (pendulum of a free
//             tether).
//   snap      a slack line jerked taut: end B moves 0.9 L -> 1.005 L in 0.5 s.
//   slack     slack ROV tether with bending and a current, end B circling.
//
// Reference: for each scene, the finest segment count (Nref) integrated with the explicit
// scheme at half its stable step; at each N of the sweep, the explicit scheme at a quarter and
// an eighth of its stable step, Richardson-extrapolated (order 1), separates the time error
// from the space error. Error columns: `err_T` RMS over the samples (after `error_from`) of the
// end tension against the finest reference, `err_T_time` against the same-N reference, `err_x`
// RMS over samples of the largest node distance to the reference's node at the same arc length.
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "../reference_scenes.h"
#include "declaration.h"
#include "mjtether.h"
#include "tether.h"

namespace mjtether {
namespace {

// fopen for writing, or exit 2 naming the path and the reason (a missing --out directory used
// to crash in fwrite on a null FILE*).
FILE* OpenForWriting(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "accuracy_cost: cannot write %s: %s\n", path.c_str(), std::strerror(errno));
    std::exit(2);
  }
  return f;
}

using namespace reference_scenes;

// ------------------------------------------------------------------------------------------
// The fixed scene through MuJoCo: the tether between a world site and a mocap body.

std::string LineMjcf(const Scene& s, int N, const std::string& integrator, double h,
                     double max_step) {
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco><option timestep=\"" << h << "\"/><custom>"
    << "<text name=\"water\" data=\"" << s.water << "\"/>"
    << "<text name=\"tether:line\" data=\"ends=anchor,fair "
    << Declaration(s, N, integrator, max_step, 0) << "\"/></custom><worldbody>"
    << "<site name=\"anchor\" pos=\"0 0 -150\"/>"
    << "<body name=\"fairlead\" mocap=\"true\" pos=\"80 0 -100\"><site name=\"fair\"/></body>"
    << "</worldbody></mujoco>";
  return x.str();
}

Run RunMujoco(const Scene& s, int N, const std::string& integrator, double h, double max_step) {
  Run r;
  r.scene = s.name;
  r.path = "mujoco";
  r.integrator = integrator;
  r.segments = N;
  r.outer = h;
  std::string error;
  mjModel* m = LoadModelFromString(LineMjcf(s, N, integrator, h, max_step), "line.xml", &error);
  if (!m) {
    std::fprintf(stderr, "%s\n", error.c_str());
    std::exit(2);
  }
  mjData* d = mj_makeData(m);
  r.step = h / GetTether(m, 0)->SubstepsFor(h);
  const long steps = std::lround(s.duration / h);
  const long every = std::max(1L, std::lround(s.sample / h));
  const Stamp start = Now();
  for (long k = 0; k <= steps; ++k) {
    const Vec3 p = s.b(k * h).pos;  // the fairlead at the time of this step
    for (int i = 0; i < 3; ++i) d->mocap_pos[i] = p[i];
    mj_step(m, d);  // the callback advances the tether to k h and applies the reactions
    if (CheckDivergence(m, d)) {
      r.ok = false;
      break;
    }
    if (k % every == 0) r.T.push_back(GetReactions(m, d, 0).tension_b);
  }
  const Stamp stop = Now();
  r.wall = stop.wall - start.wall;
  r.cpu = stop.cpu - start.cpu;
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
  return r;
}

// ------------------------------------------------------------------------------------------
// The fixed scene as a MuJoCo 2.2 user would build it without this project: a
// <composite type="rope"> chain of rigid capsules (two hinges per joint, no stretch), MuJoCo's
// inertia-box fluid drag from <option density>, buoyancy applied by the user through
// xfrc_applied, the fairlead held by an equality connect to the mocap body. The initial shape
// is the same inextensible catenary as the tether's (the joint angles are set from it).

std::string RopeMjcf(const Scene& s, int links, double h, const std::vector<Vec3>& shape) {
  const double L = 100, d = 0.025, mu = 1.0, sp = L / links;
  // The root element rB0 carries the ball joint at the anchor. MuJoCo builds the chain straight
  // along x and compiles the connect constraint from that pose: the fairlead body is declared
  // at the straight chain's end (the constraint's point is then its origin), and moved to the
  // real fairlead at run time; the joint angles (set below) bend the chain into the catenary.
  const Vec3 anchor = shape[0];
  const Vec3 c0 = anchor + Vec3(0.5 * sp, 0, 0);
  const Vec3 end0 = anchor + Vec3(L, 0, 0);
  (void)s;
  std::ostringstream x;
  x.precision(17);
  x << "<mujoco><option timestep=\"" << h << "\" density=\"1025\"/>"
    << "<size njmax=\"100\" nconmax=\"10\"/><worldbody>"
    << "<body name=\"fairlead\" mocap=\"true\" pos=\"" << end0.x() << " " << end0.y() << " "
    << end0.z() << "\"/>"
    << "<body name=\"rB0\" pos=\"" << c0.x() << " " << c0.y() << " " << c0.z() << "\">"
    << "<joint type=\"ball\" pos=\"" << -0.5 * sp << " 0 0\"/>"
    << "<composite type=\"rope\" count=\"" << links << " 1 1\" spacing=\"" << sp
    << "\" prefix=\"r\"><joint kind=\"main\" damping=\"0\"/>"
    << "<geom type=\"capsule\" size=\"" << d / 2 << " " << 0.5 * sp - d / 2 << "\" mass=\""
    << mu * sp << "\" contype=\"0\" conaffinity=\"0\"/></composite></body></worldbody>"
    << "<equality><connect body1=\"rB" << links - 1 << "\" body2=\"fairlead\" anchor=\"" << 0.5 * sp
    << " 0 0\"/></equality></mujoco>";
  return x.str();
}

Run RunRope(const Scene& s, int links, double h) {
  Run r;
  r.scene = s.name;
  r.path = "composite";
  r.integrator = "rope";
  r.segments = links;
  r.step = r.outer = h;
  // Inextensible catenary through the two ends, as the tether starts.
  std::string error;
  std::optional<Tether> t = MakeTether(s, links, "explicit", 0, 0, &error);
  std::vector<double> xs(3 * (links + 1)), vs(3 * (links + 1));
  t->InitialShape(EndsAt(s, 0), xs.data(), vs.data());
  std::vector<Vec3> shape(links + 1);
  for (int i = 0; i <= links; ++i) shape[i] = Vec3(&xs[3 * i]);

  char buf[1000] = "";
  const std::string xml = RopeMjcf(s, links, h, shape);
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  mj_makeEmptyFileVFS(vfs.get(), "rope.xml", static_cast<int>(xml.size()));
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), "rope.xml")], xml.data(), xml.size());
  mjModel* m = mj_loadXML("rope.xml", vfs.get(), buf, sizeof(buf));
  mj_deleteVFS(vfs.get());
  if (!m) {
    std::fprintf(stderr, "rope: %s\n", buf);
    std::exit(3);
  }
  if (const char* dump = std::getenv("ACCURACY_COST_DUMP")) {
    FILE* f = OpenForWriting(std::string(dump) + "/rope.xml");
    std::fputs(xml.c_str(), f);
    std::fclose(f);
  }
  mjData* d = mj_makeData(m);
  // Joint angles from the shape (all in the x-z plane): link k points along
  // (cos phi, 0, -sin phi), a rotation by phi about y; the hinges about y take the differences.
  std::vector<double> phi(links);
  for (int k = 0; k < links; ++k) {
    const Vec3 e = shape[k + 1] - shape[k];
    phi[k] = std::atan2(-e.z(), e.x());
  }
  d->qpos[0] = std::cos(phi[0] / 2);
  d->qpos[1] = 0;
  d->qpos[2] = std::sin(phi[0] / 2);
  d->qpos[3] = 0;
  for (int j = 0; j < m->njnt; ++j) {
    if (m->jnt_type[j] != mjJNT_HINGE) continue;
    const int body = m->jnt_bodyid[j];
    const int k = body - m->jnt_bodyid[0];  // link index
    const double* axis = m->jnt_axis + 3 * j;
    if (std::abs(axis[1]) > 0.5) d->qpos[m->jnt_qposadr[j]] = phi[k] - phi[k - 1];
  }
  const int fair = mj_name2id(m, mjOBJ_BODY, "fairlead");
  for (int i = 0; i < 3; ++i) d->mocap_pos[3 * m->body_mocapid[fair] + i] = s.b(0).pos[i];
  mj_forward(m, d);
  if (std::getenv("ACCURACY_COST_DUMP")) {
    const int last = m->nbody - 1;
    std::fprintf(stderr, "rope: last body %g %g %g, nefc %d, efc_pos %g %g %g\n", d->xpos[3 * last],
                 d->xpos[3 * last + 1], d->xpos[3 * last + 2], d->nefc,
                 d->nefc > 0 ? d->efc_pos[0] : 0.0, d->nefc > 1 ? d->efc_pos[1] : 0.0,
                 d->nefc > 2 ? d->efc_pos[2] : 0.0);
  }
  const int first = m->jnt_bodyid[0];
  // Buoyancy of each link, the user's own upward force at its centre.
  const double buoy = 1025 * kPi * 0.025 * 0.025 / 4 * (100.0 / links) * 9.81;
  const long steps = std::lround(s.duration / h);
  const long every = std::max(1L, std::lround(s.sample / h));
  const Stamp start = Now();
  for (long k = 0; k <= steps; ++k) {
    const Vec3 p = s.b(k * h).pos;
    for (int i = 0; i < 3; ++i) d->mocap_pos[3 * m->body_mocapid[fair] + i] = p[i];
    for (int b = first; b < first + links; ++b) d->xfrc_applied[6 * b + 2] = buoy;
    mj_step(m, d);
    bool finite = true;
    for (int i = 0; i < m->nq; ++i) finite = finite && std::isfinite(d->qpos[i]);
    if (!finite) {
      r.ok = false;
      break;
    }
    if (k % every == 0) {
      // Fairlead tension: the connect constraint's force (rows of equality 0), after the step's
      // solve (it belongs to the state at the start of this step).
      Vec3 f = Vec3::Zero();
      int row = 0;
      for (int i = 0; i < d->nefc; ++i) {
        if (d->efc_type[i] == mjCNSTR_EQUALITY && d->efc_id[i] == 0 && row < 3) {
          f[row++] = d->efc_force[i];
        }
      }
      r.T.push_back(f.norm());
    }
  }
  const Stamp stop = Now();
  r.wall = stop.wall - start.wall;
  r.cpu = stop.cpu - start.cpu;
  mj_deleteData(d);
  mj_deleteModel(m);
  return r;
}

// ------------------------------------------------------------------------------------------
// Errors

double RmsDiff(const std::vector<double>& a, const std::vector<double>& b, size_t from) {
  const size_t n = std::min(a.size(), b.size());
  if (n <= from || a.size() != b.size()) return NAN;
  double s = 0;
  for (size_t i = from; i < n; ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s / (n - from));
}

// RMS over samples of the largest distance between a run's node and the reference node at the
// same arc length (the reference has a multiple of the run's segments).
double NodeError(const Run& r, const Run& ref, size_t from) {
  if (r.x.size() <= from || r.x.size() != ref.x.size()) return NAN;
  const int N = r.segments, Nref = ref.segments;
  if (Nref % N != 0) return NAN;
  double s = 0;
  for (size_t k = from; k < r.x.size(); ++k) {
    double worst = 0;
    for (int i = 0; i <= N; ++i) {
      worst = std::max(worst, (r.x[k][i] - ref.x[k][i * (Nref / N)]).norm());
    }
    s += worst * worst;
  }
  return std::sqrt(s / (r.x.size() - from));
}

// Converged reference of one N: explicit at 0.2 and 0.1 of its stability limit, Richardson-
// extrapolated (symplectic Euler is first order). The finest N (whose time error is far below
// the space error it measures) is run once at 0.4 of its limit. (These were 1/4, 1/8 and 1/2
// of the stable step while symplectic Euler's safety factor was 0.8, before session 13.)
Run Reference(const Scene& s, int N, bool finest) {
  std::string error;
  const double h = 0.8 * MakeTether(s, N, "explicit", 0, 0, &error)->ExplicitStabilityLimit();
  const double outer = s.sample / std::ceil(s.sample / 0.002);
  if (finest) {
    Run r = RunEngine(s, N, "explicit", outer, h / 2, true);
    std::fprintf(stderr, "  reference %s N=%d: h=%.3g s (%.1f s)\n", s.name.c_str(), N, h / 2,
                 r.wall);
    return r;
  }
  Run a = RunEngine(s, N, "explicit", outer, h / 4, true);
  Run b = RunEngine(s, N, "explicit", outer, h / 8, true);
  Run r = b;
  for (size_t k = 0; k < r.T.size(); ++k) r.T[k] = 2 * b.T[k] - a.T[k];
  for (size_t k = 0; k < r.x.size(); ++k) {
    for (size_t i = 0; i < r.x[k].size(); ++i) r.x[k][i] = 2 * b.x[k][i] - a.x[k][i];
  }
  std::fprintf(stderr, "  reference %s N=%d: h=%.3g s, Richardson correction RMS %.3g N (%.1f s)\n",
               s.name.c_str(), N, h / 8, RmsDiff(a.T, b.T, 0), a.wall + b.wall);
  return r;
}

// ------------------------------------------------------------------------------------------

// Pareto fronts: a run is on the front of a set if no run of the set is both cheaper and more
// accurate (end tension against the finest reference).
void MarkPareto(std::vector<Run>* runs) {
  for (Run& r : *runs) {
    if (!r.ok || !std::isfinite(r.err_T)) continue;
    r.pareto = r.pareto_series = true;
    for (const Run& o : *runs) {
      if (&o == &r || o.scene != r.scene || !o.ok || !std::isfinite(o.err_T)) continue;
      const bool better =
          o.ms() <= r.ms() && o.err_T <= r.err_T && (o.ms() < r.ms() || o.err_T < r.err_T);
      if (better) {
        r.pareto = false;
        if (o.series() == r.series()) r.pareto_series = false;
      }
    }
  }
}

// accuracy_cost.csv (every run; tools/accuracy_cost.sh draws the charts from it) and
// accuracy_cost.md (a table per scene).
void Write(const std::string& dir, std::vector<Run>* runs) {
  MarkPareto(runs);
  FILE* csv = OpenForWriting(dir + "/accuracy_cost.csv");
  std::fprintf(csv,
               "scene,path,integrator,segments,step_s,outer_s,cpu_ms_per_s,wall_ms_per_s,"
               "err_T_N,err_T_time_N,err_x_m,mean_T_N,ok,pareto,pareto_series\n");
  for (const Run& r : *runs) {
    std::fprintf(csv, "%s,%s,%s,%d,%.6g,%.6g,%.4g,%.4g,%.4g,%.4g,%.4g,%.6g,%d,%d,%d\n",
                 r.scene.c_str(), r.path.c_str(), r.integrator.c_str(), r.segments, r.step, r.outer,
                 r.ms(), 1e3 * r.wall / r.duration, r.err_T, r.err_T_time, r.err_x, r.mean_T,
                 r.ok ? 1 : 0, r.pareto ? 1 : 0, r.pareto_series ? 1 : 0);
  }
  std::fclose(csv);

  FILE* md = OpenForWriting(dir + "/accuracy_cost.md");
  std::string scene;
  for (const Run& r : *runs) {
    if (r.scene != scene) {
      scene = r.scene;
      std::fprintf(md,
                   "\n**%s** (mean end tension %.4g N)\n\n| path | integrator | N | step [ms] | "
                   "CPU ms per s | err_T [N] | err_T [%%] | time-only err_T [N] | err_x [m] "
                   "| front |\n|---|---|---|---|---|---|---|---|---|---|\n",
                   scene.c_str(), r.mean_T);
    }
    if (!r.ok) {
      std::fprintf(md, "| %s | %s | %d | %.3g | %.3g | diverged | | | | |\n", r.path.c_str(),
                   r.integrator.c_str(), r.segments, 1e3 * r.step, r.ms());
      continue;
    }
    std::fprintf(md, "| %s | %s | %d | %.3g | %.3g | %.3g | %.3g | %.3g | %.3g | %s |\n",
                 r.path.c_str(), r.integrator.c_str(), r.segments, 1e3 * r.step, r.ms(), r.err_T,
                 100 * r.err_T / r.mean_T, r.err_T_time, r.err_x,
                 r.pareto ? "**yes**" : (r.pareto_series ? "own" : ""));
  }
  std::fclose(md);
}

struct Options {
  bool quick = false;
  std::string out = ".";
  std::vector<std::string> scenes = {"line", "catenary", "swing", "snap", "slack"};
  std::vector<int> rope_links = {10, 20, 40};
  bool rope_only = false;  // debugging: only the composite rope runs
  std::vector<double> steps = {0.05, 0.02, 0.01, 0.005, 0.002, 0.001};  // [s] implicit steps
  std::vector<int> segments;  // non-empty: only these N
  int reference = 0;          // > 0: the finest reference's N
};

}  // namespace
}  // namespace mjtether

int main(int argc, char** argv) {
  using namespace mjtether;
  Options o;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--quick") {
      o.quick = true;
    } else if (a == "--rope-only") {
      o.rope_only = true;
    } else if (a == "--out" && i + 1 < argc) {
      o.out = argv[++i];
    } else if (a == "--steps" && i + 1 < argc) {
      o.steps.clear();
      std::stringstream ss(argv[++i]);
      std::string item;
      while (std::getline(ss, item, ',')) o.steps.push_back(std::stod(item));
    } else if (a == "--segments" && i + 1 < argc) {
      // Debugging aid: only these segment counts (engine and MuJoCo), no composite rope.
      std::stringstream ss(argv[++i]);
      std::string item;
      while (std::getline(ss, item, ',')) o.segments.push_back(std::stoi(item));
    } else if (a == "--reference" && i + 1 < argc) {
      o.reference = std::stoi(argv[++i]);  // debugging aid: the finest reference's N
    } else if (a == "--scenes" && i + 1 < argc) {
      o.scenes.clear();
      std::stringstream ss(argv[++i]);
      std::string item;
      while (std::getline(ss, item, ',')) o.scenes.push_back(item);
    } else {
      std::fprintf(stderr,
                   "usage: accuracy_cost [--quick] [--scenes a,b] [--steps h1,h2] [--out DIR]\n");
      return 2;
    }
  }
  // The output directory is made before the runs, so that a bad one stops at once.
  if (std::error_code ec; !std::filesystem::create_directories(o.out, ec) && ec) {
    std::fprintf(stderr, "accuracy_cost: cannot create --out %s: %s\n", o.out.c_str(),
                 ec.message().c_str());
    return 2;
  }
  InstallErrorHandlers();
  std::map<std::string, Scene> all = {{"line", LineScene()},
                                      {"catenary", CatenaryScene()},
                                      {"swing", SwingScene()},
                                      {"snap", SnapScene()},
                                      {"slack", SlackScene()}};
  std::vector<Run> runs;
  for (const std::string& name : o.scenes) {
    if (!all.count(name)) {
      std::fprintf(stderr, "unknown scene %s\n", name.c_str());
      return 2;
    }
    Scene s = all[name];
    if (o.quick) {
      s.segments = {10, 20};
      s.reference_segments = 40;
    }
    if (!o.segments.empty()) s.segments = o.segments;
    if (o.reference > 0) s.reference_segments = o.reference;
    std::fprintf(stderr, "scene %s\n", name.c_str());
    if (o.rope_only) {
      for (int links : o.rope_links) {
        for (double h : {0.002, 0.001}) {
          Run r = RunRope(s, links, h);
          std::fprintf(stderr, "rope %d %g: ok %d, %zu samples, T0 %g, T end %g, %.3g ms/s\n",
                       links, h, r.ok, r.T.size(), r.T.empty() ? 0 : r.T[0],
                       r.T.empty() ? 0 : r.T.back(), 1e3 * r.wall / s.duration);
        }
      }
      continue;
    }
    Run finest = Reference(s, s.reference_segments, true);
    std::map<int, Run> ref_n;
    for (int N : s.segments) {
      ref_n[N] = Reference(s, N, false);
    }
    const std::vector<double>& steps = o.steps;
    double mean_T = 0;
    {
      const size_t from = std::lround(s.error_from / s.sample);
      for (size_t k = from; k < finest.T.size(); ++k) mean_T += finest.T[k];
      mean_T /= std::max<size_t>(1, finest.T.size() - from);
      if (s.static_reference) mean_T = s.static_tension;
    }
    auto finish = [&](Run r) {
      r.duration = s.duration;
      r.mean_T = mean_T;
      if (r.ok) {
        if (s.static_reference) {
          r.err_T = std::abs(r.T.back() - s.static_tension);
          r.err_T_time = std::abs(r.T.back() - ref_n[r.segments].T.back());
        } else {
          const size_t from = std::lround(s.error_from / s.sample);
          r.err_T = RmsDiff(r.T, finest.T, from);
          r.err_T_time = RmsDiff(r.T, ref_n[r.segments].T, from);
          r.err_x = NodeError(r, finest, from);
        }
      }
      std::fprintf(stderr,
                   "  %-9s %-9s N=%3d h=%.2g: %.3g ms/s CPU (%.3g wall), err_T %.3g N (time "
                   "%.3g)\n",
                   r.path.c_str(), r.integrator.c_str(), r.segments, r.step, r.ms(),
                   1e3 * r.wall / s.duration, r.err_T, r.err_T_time);
      if (const char* dump = std::getenv("ACCURACY_COST_DUMP")) {
        // Debugging aid: the tension series of every run, and of the references.
        std::ostringstream f;
        f << dump << "/" << r.scene << "_" << r.path << "_" << r.integrator << "_" << r.segments
          << "_" << r.step << ".txt";
        FILE* out = OpenForWriting(f.str());
        for (size_t k = 0; k < r.T.size() && k < finest.T.size(); ++k) {
          std::fprintf(out, "%g %.9g %.9g %.9g\n", k * s.sample, r.T[k], finest.T[k],
                       ref_n[r.segments].T[k]);
        }
        std::fclose(out);
      }
      r.x.clear();
      runs.push_back(std::move(r));
    };
    for (int N : s.segments) {
      // Explicit: substeps at the stability limit within a 2 ms coupling step.
      finish(RunEngine(s, N, "explicit", 0.002, 0, true));
      // RK4 at its stability limit: within the 2 ms coupling step (2 ms does not divide by the
      // limit, so the substeps are shorter than it), and with the limit itself as the step
      // (substeps of one sampling interval), which is what the engine alone allows.
      finish(RunEngine(s, N, "rk4", 0.002, 0, true));
      finish(RunEngine(s, N, "rk4", s.sample, 0, true));
      for (double h : steps) {
        if (h > s.sample + 1e-12) continue;
        finish(RunEngine(s, N, "implicit", h, 0, true));
        finish(RunEngine(s, N, "implicit2", h, 0, true));
        finish(RunEngine(s, N, "bdf2", h, 0, true));
      }
    }
    if (name == "line" && !o.quick) {
      // Through MuJoCo, the fairlead on a mocap body; the MuJoCo step is the tether step.
      for (int N : o.segments.empty() ? std::vector<int>{20, 80} : o.segments) {
        finish(RunMujoco(s, N, "explicit", 0.002, 0));
        finish(RunMujoco(s, N, "rk4", 0.002, 0));
        for (double h : {0.01, 0.002}) {
          finish(RunMujoco(s, N, "implicit", h, 0));
          finish(RunMujoco(s, N, "implicit2", h, 0));
          finish(RunMujoco(s, N, "bdf2", h, 0));
        }
      }
      for (int links : o.segments.empty() ? o.rope_links : std::vector<int>{}) {
        for (double h : {0.005, 0.002, 0.001}) {
          if (links >= 40 && h < 0.002) continue;  // 0.5 s of wall time per simulated second
          finish(RunRope(s, links, h));
        }
      }
    }
  }
  Write(o.out, &runs);
  return 0;
}
