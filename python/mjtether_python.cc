// Python bindings of mjtether (pybind11): a Simulation owning an mjModel and mjData with its
// tethers attached, numpy views on MuJoCo's arrays, stepping as `mjtether run` does, copies for
// rollouts and off-screen rendering. See docs/python.md.
//
// The module links Debian's libmujoco (the same one as the C++ libraries), so it cannot share a
// process with another MuJoCo Python package (mjcb_passive is one global pointer per libmujoco).
#include <dlfcn.h>
#include <mjtether/mjtether.h>
#include <mjtether/overrides.h>
#include <mjtether/render.h>
#include <mjtether/version.h>
#include <mujoco/mujoco.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "step_check.h"  // StepAndCheck: the checks `mjtether run` makes after each step

namespace py = pybind11;

namespace {

// Raised for every failure: load errors (the CLI's messages), divergence, MuJoCo errors.
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};
struct DivergenceError : Error {
  using Error::Error;
};

// MuJoCo's default error handler waits on stdin and exits; from Python an error must become an
// exception instead. libmujoco is C compiled with unwind tables (x86-64 default), so the
// exception crosses its frames; the Simulation whose call failed is reset (see Guarded).
void ThrowMujocoError(const char* message) { throw Error(std::string("MuJoCo error: ") + message); }
void PrintMujocoWarning(const char* message) {
  std::fprintf(stderr, "MuJoCo warning: %s\n", message);
}

// The model with its tethers attached; shared by a Simulation and its copies.
struct Model {
  mjModel* m = nullptr;
  std::string source;
  ~Model() {
    if (m) {
      mjtether::Detach(m);
      mj_deleteModel(m);
    }
  }
};

py::array View(double* data, std::vector<py::ssize_t> shape, py::handle owner, bool writable) {
  py::array a(py::dtype::of<double>(), shape, {}, data, owner);
  if (!writable) a.attr("flags").attr("writeable") = false;
  return a;
}

class Simulation {
 public:
  Simulation(std::shared_ptr<Model> model, mjData* d) : model_(std::move(model)), d_(d) {}
  ~Simulation() {
    renderer_.reset();
    if (d_) mj_deleteData(d_);
  }
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  static std::unique_ptr<Simulation> Load(mjModel* m, const std::string& source,
                                          const std::string& error) {
    if (!m) throw Error(error);
    auto model = std::make_shared<Model>();
    model->m = m;
    model->source = source;
    mjData* d = mj_makeData(m);
    if (!d) throw Error(source + ": could not allocate mjData");
    auto sim = std::make_unique<Simulation>(std::move(model), d);
    sim->Settle();
    return sim;
  }

  // `set`: overrides as `mjtether run --set` takes them, "TEXT.KEY=VALUE" or
  // "option.timestep=SECONDS" (overrides.h): e.g. the same scene at a smaller step.
  static std::unique_ptr<Simulation> FromFile(const std::string& path,
                                              const std::vector<std::string>& set) {
    std::vector<mjtether::Override> overrides;
    for (const std::string& spec : set) {
      std::string why;
      std::optional<mjtether::Override> o = mjtether::ParseOverride(spec, &why);
      if (!o) throw Error(path + ": set: " + why);
      overrides.push_back(*o);
    }
    std::string error;
    mjModel* m = nullptr;
    {
      py::gil_scoped_release release;
      m = mjtether::LoadModel(path, overrides, &error);
    }
    return Load(m, path, error);
  }

  static std::unique_ptr<Simulation> FromXml(const std::string& xml, const std::string& name) {
    if (xml.empty()) throw Error(name + ": the XML text is empty");
    std::string error;
    mjModel* m = mjtether::LoadModelFromString(xml, name, &error);
    return Load(m, name, error);
  }

  const mjModel* m() const { return model_->m; }
  mjModel* mutable_m() { return model_->m; }
  mjData* d() { return d_; }
  const std::string& source() const { return model_->source; }

  // Schedules at d->time, then kinematics, forces and the tethers at d->time: what
  // `mjtether run` does before each sample, so that every reading is current.
  void Settle() {
    mjtether::Prescribe(m(), d_);
    mj_forward(m(), d_);
  }

  // n steps as `mjtether run` takes them (mjtether::Step: schedules and motions, then mj_step;
  // the same checks), or plain mj_step calls; then Settle. Raises with the CLI's message.
  void Step(long long n, bool prescribe) {
    if (n < 0) throw py::value_error("step: n must be >= 0, got " + std::to_string(n));
    std::optional<std::string> stop;
    {
      py::gil_scoped_release release;
      std::lock_guard<std::mutex> lock(mutex_);
      Guarded([&] {
        for (long long i = 0; i < n && !stop; ++i) {
          if (prescribe) {
            stop = mjtether::cli::StepAndCheck(m(), d_, source());
          } else {
            mj_step(m(), d_);
            stop = mjtether::CheckDivergence(m(), d_);
          }
        }
        if (!stop) Settle();
      });
    }
    if (stop) throw DivergenceError(*stop);
  }

  void Forward() {
    std::lock_guard<std::mutex> lock(mutex_);
    Guarded([&] { mj_forward(m(), d_); });
  }

  void Reset() {
    std::lock_guard<std::mutex> lock(mutex_);
    mj_resetData(m(), d_);
    Guarded([&] { Settle(); });
  }

  std::unique_ptr<Simulation> Copy() {
    std::lock_guard<std::mutex> lock(mutex_);
    mjData* d = mj_makeData(m());
    if (!d) throw Error(source() + ": could not allocate mjData");
    mj_copyData(d, m(), d_);
    return std::make_unique<Simulation>(model_, d);
  }

  // H x W x 3 uint8, rows top-down. The renderer is kept while the size and camera stay.
  py::array_t<uint8_t> Render(int width, int height, const std::string& camera, int samples,
                              double tension_max, bool hud) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!renderer_ || width != options_.width || height != options_.height ||
        camera != options_.camera || samples != options_.samples ||
        tension_max != options_.tension_max || hud != options_.hud) {
      renderer_.reset();
      mjtether::render::RenderOptions o;
      o.width = width;
      o.height = height;
      o.camera = camera;
      o.samples = samples;
      o.tension_max = tension_max;
      o.hud = hud;
      std::string error;
      renderer_ = mjtether::render::Renderer::Create(mutable_m(), o, &error);
      if (!renderer_) throw Error(source() + ": " + error);
      options_ = o;
    }
    py::array_t<uint8_t> image({height, width, 3});
    std::vector<unsigned char> rgb(3 * static_cast<size_t>(width) * height);
    {
      py::gil_scoped_release release;
      Guarded([&] { renderer_->Render(m(), d_, rgb.data()); });
    }
    // OpenGL gives rows bottom-up; numpy images are top-down.
    uint8_t* out = image.mutable_data();
    const size_t row = 3 * static_cast<size_t>(width);
    for (int y = 0; y < height; ++y) {
      std::memcpy(out + row * y, rgb.data() + row * (height - 1 - y), row);
    }
    return image;
  }

 private:
  // Runs f; a MuJoCo error inside leaves mjData half-updated, so it is reset before raising.
  template <typename F>
  void Guarded(F&& f) {
    try {
      f();
    } catch (const Error&) {
      mj_resetData(m(), d_);
      throw;
    }
  }

  std::shared_ptr<Model> model_;
  mjData* d_ = nullptr;
  std::mutex mutex_;  // one call at a time per Simulation (the GIL is released inside)
  std::unique_ptr<mjtether::render::Renderer> renderer_;
  mjtether::render::RenderOptions options_;
};

int Id(const mjModel* m, mjtObj type, const std::string& name, const char* what,
       const std::string& source) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw py::key_error(source + ": no " + what + " named '" + name + "'");
  return id;
}

// A view of one tether of a Simulation (keeps the Simulation alive).
struct TetherView {
  py::object owner;
  Simulation* sim;
  int k;

  const mjtether::Tether* tether() const { return mjtether::GetTether(sim->m(), k); }
  py::array Nodes(bool velocities) const {
    const double* x = velocities ? mjtether::NodeVelocities(sim->m(), sim->d(), k)
                                 : mjtether::NodePositions(sim->m(), sim->d(), k);
    return View(const_cast<double*>(x), {tether()->nodes(), 3}, owner, false);
  }
  py::array_t<double> Tensions() const {
    py::array_t<double> T(tether()->segments());
    mjtether::GetTensions(sim->m(), sim->d(), k, T.mutable_data());
    return T;
  }
  double Length() const {
    const double* x = mjtether::NodePositions(sim->m(), sim->d(), k);
    double L = 0;
    for (int i = 0; i < tether()->segments(); ++i) {
      L += mju_dist3(x + 3 * i, x + 3 * i + 3);
    }
    return L;
  }
};

py::array_t<double> Vector(const mjtether::Vec3& v) {
  py::array_t<double> a(3);
  for (int i = 0; i < 3; ++i) a.mutable_data()[i] = v[i];
  return a;
}

// A view of one body's pose (keeps the Simulation alive).
struct BodyView {
  py::object owner;
  Simulation* sim;
  int id;
};

// The example models: share/mjtether/models of the prefix this module is installed in (it sits
// in <prefix>/lib/python3/dist-packages), else the configured install directory, else the
// source tree's (a module in the build tree).
std::string ModelsDir() {
  namespace fs = std::filesystem;
  Dl_info info;
  std::error_code ec;
  if (dladdr(reinterpret_cast<void*>(&ThrowMujocoError), &info) && info.dli_fname) {
    const fs::path here = fs::path(info.dli_fname).parent_path();
    const fs::path models = here / ".." / ".." / ".." / "share" / "mjtether" / "models";
    if (fs::is_directory(models, ec)) return fs::canonical(models, ec).string();
  }
  if (fs::is_directory(MJTETHER_MODELS_INSTALL_DIR, ec)) return MJTETHER_MODELS_INSTALL_DIR;
#ifdef MJTETHER_SOURCE_MODELS_DIR
  return MJTETHER_SOURCE_MODELS_DIR;
#else
  return MJTETHER_MODELS_INSTALL_DIR;
#endif
}

}  // namespace

PYBIND11_MODULE(mjtether, mod) {
  mod.doc() =
      "Lumped-mass ROV tethers in MuJoCo 2.2 (docs/python.md). Links Debian's libmujoco: do not "
      "import another MuJoCo Python package in the same process.";
  mod.attr("__version__") = MJTETHER_VERSION_STRING;
  mod.attr("mujoco_version") = mj_versionString();
  mod.attr("models_dir") = ModelsDir();

  static py::exception<Error> error(mod, "Error", PyExc_RuntimeError);
  static py::exception<DivergenceError> divergence(mod, "DivergenceError", error.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const DivergenceError& e) {
      divergence(e.what());
    } catch (const Error& e) {
      error(e.what());
    }
  });
  mju_user_error = ThrowMujocoError;
  mju_user_warning = PrintMujocoWarning;

  py::class_<TetherView>(mod, "Tether", "One tether of a Simulation (views into its mjData).")
      .def_property_readonly(
          "name", [](const TetherView& t) { return mjtether::TetherName(t.sim->m(), t.k); })
      .def_property_readonly("segments", [](const TetherView& t) { return t.tether()->segments(); })
      .def_property_readonly(
          "nodes", [](const TetherView& t) { return t.Nodes(false); },
          "(N+1) x 3 node positions, world frame [m] (read-only view)")
      .def_property_readonly(
          "velocities", [](const TetherView& t) { return t.Nodes(true); },
          "(N+1) x 3 node velocities [m/s] (read-only view)")
      .def_property_readonly("tensions", &TetherView::Tensions,
                             "N segment tensions [N] (a copy), 0 for a slack segment")
      .def_property_readonly(
          "reactions",
          [](const TetherView& t) {
            const mjtether::EndReactions r = mjtether::GetReactions(t.sim->m(), t.sim->d(), t.k);
            py::dict out;
            out["force_a"] = Vector(r.force_a);
            out["torque_a"] = Vector(r.torque_a);
            out["force_b"] = Vector(r.force_b);
            out["torque_b"] = Vector(r.torque_b);
            out["tension_a"] = r.tension_a;
            out["tension_b"] = r.tension_b;
            out["correction_b"] = Vector(r.correction_b);
            return out;
          },
          "end reactions as applied at the last evaluation: force_a, force_b [N] on the sites, "
          "torque_a, torque_b [N m], tension_a, tension_b [N], correction_b [N] (of force_b, "
          "the consistent coupling's slow-mode correction, its reaction in force_a)")
      .def_property_readonly("length", &TetherView::Length,
                             "current length along the nodes [m] (stretched)")
      .def_property_readonly(
          "rest_length",
          [](const TetherView& t) {
            return mjtether::GetWinch(t.sim->m(), t.sim->d(), t.k).length;
          },
          "unstretched length [m]: the declared one, or the deployed one with a winch")
      .def_property_readonly(
          "winch",
          [](const TetherView& t) -> py::object {
            const mjtether::WinchState w = mjtether::GetWinch(t.sim->m(), t.sim->d(), t.k);
            if (!w.present) return py::none();
            py::dict out;
            out["length"] = w.length;
            out["payout_speed"] = w.payout_speed;
            out["segments"] = w.segments;
            out["first_node"] = w.first_node;
            return out;
          },
          "None, or the winch's state (docs/winch.md): deployed length [m], payout_speed "
          "[m/s], deployed segments, first_node (nodes before it are on the drum)")
      .def_property_readonly(
          "time",
          [](const TetherView& t) { return mjtether::TetherTime(t.sim->m(), t.sim->d(), t.k); },
          "the tether's own time [s] (its last evaluation)");

  py::class_<BodyView>(mod, "Body", "One body of a Simulation (views into its mjData).")
      .def_property_readonly("id", [](const BodyView& b) { return b.id; })
      .def_property_readonly(
          "pos",
          [](const BodyView& b) { return View(b.sim->d()->xpos + 3 * b.id, {3}, b.owner, false); },
          "position of the body frame, world [m] (read-only view; write qpos or mocap_pos)")
      .def_property_readonly(
          "quat",
          [](const BodyView& b) { return View(b.sim->d()->xquat + 4 * b.id, {4}, b.owner, false); },
          "orientation quaternion w, x, y, z (read-only view)")
      .def_property_readonly(
          "xmat",
          [](const BodyView& b) {
            return View(b.sim->d()->xmat + 9 * b.id, {3, 3}, b.owner, false);
          },
          "rotation matrix, body to world (read-only view)")
      .def_property_readonly(
          "mocap_pos",
          [](const BodyView& b) -> py::object {
            const int i = b.sim->m()->body_mocapid[b.id];
            if (i < 0) return py::none();
            return View(b.sim->d()->mocap_pos + 3 * i, {3}, b.owner, true);
          },
          "writable mocap position of a mocap body, None otherwise")
      .def_property_readonly("mocap_quat", [](const BodyView& b) -> py::object {
        const int i = b.sim->m()->body_mocapid[b.id];
        if (i < 0) return py::none();
        return View(b.sim->d()->mocap_quat + 4 * i, {4}, b.owner, true);
      });

  py::class_<Simulation>(mod, "Simulation",
                         "An MJCF model with its tethers, vehicles and schedules, and its state.")
      .def(py::init(&Simulation::FromFile), py::arg("path"),
           py::arg("set") = std::vector<std::string>(),
           "Loads an MJCF file; raises mjtether.Error with the CLI's message on bad input. "
           "`set`: overrides as `mjtether run --set` takes them, e.g. "
           "['tether:umbilical.EA=4e5', 'option.timestep=0.0002'].")
      .def_static("from_xml", &Simulation::FromXml, py::arg("xml"), py::arg("name") = "<string>",
                  "Loads MJCF text; `name` stands for the file.")
      .def(
          "step", [](Simulation& s, long long n) { s.Step(n, true); }, py::arg("n") = 1,
          "n steps as `mjtether run` takes them: thrust: and motion: schedules, mj_step, the "
          "divergence checks (raises mjtether.DivergenceError); the GIL is released.")
      .def(
          "mj_step", [](Simulation& s, long long n) { s.Step(n, false); }, py::arg("n") = 1,
          "n plain mj_step calls: no schedules or motions (ctrl and mocap stay as written).")
      .def("forward", &Simulation::Forward, "mj_forward: derived quantities at the current state")
      .def("reset", &Simulation::Reset, "mj_resetData: the initial state, tethers included")
      .def("copy", &Simulation::Copy,
           "A full state copy (mj_copyData, tethers included) sharing the model.")
      .def("render", &Simulation::Render, py::arg("width") = 640, py::arg("height") = 480,
           py::arg("camera") = "follow", py::arg("samples") = 4, py::arg("tension_max") = 0,
           py::arg("hud") = true,
           "H x W x 3 uint8 image, rows top-down (OSMesa). camera: 'follow', 'track:BODY' or a "
           "model camera; tension_max [N]: top of the colour scale (<= 0: 1 N); hud: the text "
           "overlay and colour scale.")
      .def(
          "tether",
          [](py::object self, const std::string& name) {
            Simulation& s = self.cast<Simulation&>();
            const int k = mjtether::FindTether(s.m(), name);
            if (k < 0) throw py::key_error(s.source() + ": no tether named '" + name + "'");
            return TetherView{self, &s, k};
          },
          py::arg("name"))
      .def(
          "body",
          [](py::object self, const std::string& name) {
            Simulation& s = self.cast<Simulation&>();
            return BodyView{self, &s, Id(s.m(), mjOBJ_BODY, name, "body", s.source())};
          },
          py::arg("name"))
      .def("actuator_id",
           [](Simulation& s, const std::string& name) {
             return Id(s.m(), mjOBJ_ACTUATOR, name, "actuator", s.source());
           })
      .def_property_readonly("tethers",
                             [](Simulation& s) {
                               std::vector<std::string> names;
                               for (int k = 0; k < mjtether::TetherCount(s.m()); ++k) {
                                 names.push_back(mjtether::TetherName(s.m(), k));
                               }
                               return names;
                             })
      .def_property_readonly("warnings", [](Simulation& s) { return mjtether::Warnings(s.m()); },
                             "the time-step advisor's warnings, made at load")
      .def_property_readonly(
          "run_warnings",
          // What `mjtether run` prints at the end of a run, for the state so far (since load,
          // reset, or the copy's source was): read them before trusting a result.
          [](Simulation& s) { return mjtether::RunWarnings(s.m(), s.d()); },
          "warnings about the steps taken so far, as `mjtether run` prints at its end: implicit "
          "steps accepted unconverged (stalled) and snaps that rang the undamped segment mode "
          "(docs/python.md); empty when there is nothing to say")
      .def_property_readonly("source", &Simulation::source)
      .def_property_readonly("timestep", [](Simulation& s) { return s.m()->opt.timestep; })
      .def_property(
          "time", [](Simulation& s) { return s.d()->time; },
          [](Simulation& s, double t) {
            // A time that is not finite stops the tethers silently (they advance when it does).
            if (!std::isfinite(t)) {
              throw py::value_error(s.source() + ": time must be a finite number [s], got " +
                                    py::str(py::float_(t)).cast<std::string>());
            }
            s.d()->time = t;
          },
          "simulation time [s]")
      .def_property_readonly(
          "qpos",
          [](py::object self) {
            Simulation& s = self.cast<Simulation&>();
            return View(s.d()->qpos, {s.m()->nq}, self, true);
          },
          "generalized positions (writable view)")
      .def_property_readonly(
          "qvel",
          [](py::object self) {
            Simulation& s = self.cast<Simulation&>();
            return View(s.d()->qvel, {s.m()->nv}, self, true);
          },
          "generalized velocities (writable view)")
      .def_property_readonly(
          "ctrl",
          [](py::object self) {
            Simulation& s = self.cast<Simulation&>();
            return View(s.d()->ctrl, {s.m()->nu}, self, true);
          },
          "actuator controls (writable view; thrust: schedules overwrite theirs in step)")
      .def_property_readonly(
          "qfrc_applied",
          [](py::object self) {
            Simulation& s = self.cast<Simulation&>();
            return View(s.d()->qfrc_applied, {s.m()->nv}, self, true);
          },
          "applied generalized forces (writable view)")
      .def_property_readonly(
          "xfrc_applied",
          [](py::object self) {
            Simulation& s = self.cast<Simulation&>();
            return View(s.d()->xfrc_applied, {s.m()->nbody, 6}, self, true);
          },
          "applied Cartesian force and torque per body, world frame (writable view)")
      .def_property_readonly(
          "sensordata",
          [](py::object self) {
            Simulation& s = self.cast<Simulation&>();
            return View(s.d()->sensordata, {s.m()->nsensordata}, self, false);
          },
          "sensor readings (read-only view)");
}
