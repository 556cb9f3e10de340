// `mjtether view`: a model simulated live in a window (GLFW), drawn as `mjtether render` draws
// it (tethers coloured by tension, water, HUD) with the same stepping (motion: and thrust:
// schedules, then mj_step and the checks of `mjtether run`).
//
//   mjtether view MODEL.xml [--size 1280x720] [--camera follow|top|track:BODY|NAME] [--samples N]
//       [--tension-max N|auto] [--vehicle BODY] [--speed X] [--overlay] [--no-hud]
//       [--screenshot FILE.png --frames N] [--keys K1,K2,...] [--set TEXT.KEY=VALUE]...
//
// Keys: space pause/run, right arrow one step (pauses), backspace reset, + and - double or
// halve the speed, O the node and tension overlay, H the HUD, C back to the scene's camera,
// Esc or Q quit. Mouse (as MuJoCo's simulate): left drag rotates, right drag moves, middle
// drag or the wheel zooms; shift makes the drags horizontal. A mouse move frees the camera.
//
// --frames N renders N frames, each 1/60 s of simulated time times the speed (not wall-clock
// time, so that a run is reproducible), then writes the window's last frame to --screenshot
// and exits. --keys feeds key presses (names: space, right, backspace, plus, minus, o, h, c)
// before the first frame. docs/rendering.md.
#include <GLFW/glfw3.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_command.h"
#include "cli_common.h"
#include "mjtether.h"
#include "render.h"
#include "step_check.h"

namespace {

using namespace mjtether::cli;

struct ViewCliOptions {
  std::string model;
  std::string size = "1280x720";
  std::string camera = "follow";
  int samples = 4;
  double tension_max = 0;  // [N] 0: automatic
  std::string vehicle;
  double speed = 1;
  bool overlay = false;
  bool no_hud = false;
  std::string screenshot;
  int frames = 0;
  std::string keys;
  std::vector<std::string> set;  // TEXT.KEY=VALUE overrides, as for run (overrides.h)
};

constexpr double kFrameDt = 1.0 / 60;  // [s] simulated per frame with --frames (times speed)
constexpr double kMinSpeed = 1.0 / 64, kMaxSpeed = 64;

// The viewer's state, shared by the GLFW callbacks (through the window's user pointer).
struct Viewer {
  const mjModel* m = nullptr;
  mjData* d = nullptr;
  mjtether::render::Renderer* renderer = nullptr;
  std::string model;
  bool paused = false;
  int pending_steps = 0;  // right-arrow steps to make
  double speed = 1;       // simulated seconds per wall-clock (or frame) second
  double target = 0;      // [s] simulated time to reach
  bool diverged = false;
  bool quit = false;
  // Mouse.
  bool left = false, right = false, middle = false;
  double last_x = 0, last_y = 0;

  void Reset() {
    mj_resetData(m, d);
    target = 0;
    diverged = false;
    pending_steps = 0;
  }

  // A key, from GLFW or from --keys. Returns false for a key without a binding.
  bool Key(int key) {
    switch (key) {
      case GLFW_KEY_SPACE:
        paused = !paused;
        target = d->time;
        return true;
      case GLFW_KEY_RIGHT:
        paused = true;
        ++pending_steps;
        return true;
      case GLFW_KEY_BACKSPACE:
        Reset();
        return true;
      case GLFW_KEY_EQUAL:  // "+" without shift on a US keyboard
      case GLFW_KEY_KP_ADD:
        speed = std::min(kMaxSpeed, 2 * speed);
        return true;
      case GLFW_KEY_MINUS:
      case GLFW_KEY_KP_SUBTRACT:
        speed = std::max(kMinSpeed, 0.5 * speed);
        return true;
      case GLFW_KEY_O:
        renderer->set_overlay(!renderer->overlay());
        return true;
      case GLFW_KEY_H:
        renderer->set_hud(!renderer->hud());
        return true;
      case GLFW_KEY_C:
        renderer->SetFreeCamera(m, false);
        return true;
      case GLFW_KEY_ESCAPE:
      case GLFW_KEY_Q:
        quit = true;
        return true;
      default:
        return false;
    }
  }

  // Steps towards `target` (or the pending single steps), spending at most `budget_ms` of
  // wall-clock time; the rest is left for the next frame. Returns the step's error, if any.
  std::optional<std::string> Advance(double budget_ms) {
    if (diverged) return std::nullopt;
    const auto t0 = std::chrono::steady_clock::now();
    const double h = m->opt.timestep;
    auto step = [&]() -> std::optional<std::string> {
      std::optional<std::string> e = StepAndCheck(m, d, model);
      if (e) diverged = paused = true;
      return e;
    };
    for (; pending_steps > 0; --pending_steps) {
      if (std::optional<std::string> e = step()) return e;
    }
    if (paused) return std::nullopt;
    // Step while the next step ends nearer the target than this one (|t - target| <= h/2).
    while (d->time + 0.5 * h < target) {
      if (std::optional<std::string> e = step()) return e;
      if (budget_ms > 0 &&
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() >
              budget_ms) {
        target = d->time;  // slower than real time: drop the backlog
        break;
      }
    }
    return std::nullopt;
  }
};

Viewer* Of(GLFWwindow* w) { return static_cast<Viewer*>(glfwGetWindowUserPointer(w)); }

void OnKey(GLFWwindow* w, int key, int /*scancode*/, int action, int /*mods*/) {
  if (action == GLFW_PRESS || action == GLFW_REPEAT) Of(w)->Key(key);
}

void OnMouseButton(GLFWwindow* w, int /*button*/, int /*action*/, int /*mods*/) {
  Viewer* v = Of(w);
  v->left = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  v->right = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  v->middle = glfwGetMouseButton(w, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
  glfwGetCursorPos(w, &v->last_x, &v->last_y);
}

// As MuJoCo's simulate: drags move the camera by the fraction of the window's height.
void OnCursor(GLFWwindow* w, double x, double y) {
  Viewer* v = Of(w);
  const double dx = x - v->last_x, dy = y - v->last_y;
  v->last_x = x;
  v->last_y = y;
  if (!v->left && !v->right && !v->middle) return;
  int width = 0, height = 0;
  glfwGetWindowSize(w, &width, &height);
  if (height <= 0) return;
  const bool shift = glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                     glfwGetKey(w, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
  const int action = v->right  ? (shift ? mjMOUSE_MOVE_H : mjMOUSE_MOVE_V)
                     : v->left ? (shift ? mjMOUSE_ROTATE_H : mjMOUSE_ROTATE_V)
                               : mjMOUSE_ZOOM;
  v->renderer->SetFreeCamera(v->m, true);
  mjv_moveCamera(v->m, action, dx / height, dy / height, &v->renderer->scene(),
                 v->renderer->camera());
}

void OnScroll(GLFWwindow* w, double /*xoffset*/, double yoffset) {
  Viewer* v = Of(w);
  v->renderer->SetFreeCamera(v->m, true);
  mjv_moveCamera(v->m, mjMOUSE_ZOOM, 0, -0.05 * yoffset, &v->renderer->scene(),
                 v->renderer->camera());
}

void* GlProc(const char* name) { return reinterpret_cast<void*>(glfwGetProcAddress(name)); }

// --keys: names to GLFW keys.
std::optional<std::vector<int>> ParseKeys(const std::string& list) {
  std::vector<int> keys;
  std::stringstream s(list);
  std::string name;
  while (std::getline(s, name, ',')) {
    if (name.empty()) continue;
    static const std::pair<const char*, int> kNames[] = {
        {"space", GLFW_KEY_SPACE}, {"right", GLFW_KEY_RIGHT}, {"backspace", GLFW_KEY_BACKSPACE},
        {"plus", GLFW_KEY_EQUAL},  {"minus", GLFW_KEY_MINUS}, {"o", GLFW_KEY_O},
        {"h", GLFW_KEY_H},         {"c", GLFW_KEY_C}};
    int key = -1;
    for (const auto& [n, k] : kNames) {
      if (name == n) key = k;
    }
    if (key < 0) return std::nullopt;
    keys.push_back(key);
  }
  return keys;
}

// Largest tension of any segment or end in d [N].
double LargestTension(const mjModel* m, const mjData* d) {
  std::vector<double> T;
  double tmax = 0;
  for (int k = 0; k < mjtether::TetherCount(m); ++k) {
    T.resize(mjtether::GetTether(m, k)->segments());
    mjtether::GetTensions(m, d, k, T.data());
    for (double x : T) tmax = std::max(tmax, x);
    const mjtether::EndReactions r = mjtether::GetReactions(m, d, k);
    tmax = std::max({tmax, r.tension_a, r.tension_b});
  }
  return tmax;
}

struct GlfwSession {
  bool ok = false;
  GlfwSession() { ok = glfwInit() == GLFW_TRUE; }
  ~GlfwSession() {
    if (ok) glfwTerminate();
  }
};

int View(const ViewCliOptions& opt) {
  mjtether::render::RenderOptions ropt;
  {
    char x = 0, extra = 0;
    if (std::sscanf(opt.size.c_str(), "%d%c%d%c", &ropt.width, &x, &ropt.height, &extra) != 3 ||
        (x != 'x' && x != 'X')) {
      std::cerr << "mjtether: --size " << mjtether::Shown(opt.size)
                << ": expected WIDTHxHEIGHT, e.g. 1280x720\n";
      return kExitBadInput;
    }
  }
  std::optional<std::vector<int>> keys = ParseKeys(opt.keys);
  if (!keys) {
    std::cerr << "mjtether: --keys " << mjtether::Shown(opt.keys)
              << ": expected a comma-separated list of space, right, backspace, plus, minus, o, "
                 "h, c\n";
    return kExitBadInput;
  }
  if (opt.screenshot.empty() != (opt.frames == 0)) {
    std::cerr << "mjtether: --screenshot FILE and --frames N go together\n";
    return kExitBadInput;
  }
  ropt.samples = opt.samples;
  ropt.camera = opt.camera;
  ropt.vehicle = opt.vehicle;
  ropt.hud = !opt.no_hud;
  ropt.overlay = opt.overlay;

  std::vector<mjtether::Override> overrides;
  if (!ParseSets(opt.set, &overrides)) return kExitBadInput;
  ModelPtr owner = LoadChecked(opt.model, overrides);
  if (!owner) return kExitBadInput;
  mjModel* m = owner.get();
  OutputGuard guard;
  guard.AddModel(opt.model, m);
  ToolOutput shot;
  std::string error;
  if (!opt.screenshot.empty() && !shot.Open(opt.screenshot, "--screenshot", &guard, &error)) {
    std::cerr << "mjtether: " << error << "\n";
    return kExitBadInput;
  }
  DataPtr data = MakeData(m);
  mjData* d = data.get();
  Observer observer(m);

  // Colour scale: given, or the largest tension so far rounded up (it only grows).
  const bool auto_scale = !(opt.tension_max > 0);
  ropt.tension_max = auto_scale ? mjtether::render::NiceCeil(LargestTension(m, observer.Observe(d)))
                                : opt.tension_max;

  GlfwSession glfw;
  if (!glfw.ok) {
    const char* why = nullptr;
    glfwGetError(&why);
    std::cerr << "mjtether: view: cannot open a window (GLFW: " << (why ? why : "no reason given")
              << "); on a machine without a display, run it under xvfb-run\n";
    return kExitTool;
  }
  glfwWindowHint(GLFW_SAMPLES, opt.samples);
  GLFWwindow* window = glfwCreateWindow(ropt.width, ropt.height,
                                        ("mjtether view " + opt.model).c_str(), nullptr, nullptr);
  if (!window && opt.samples > 0) {  // no multisampled visual: without
    glfwWindowHint(GLFW_SAMPLES, 0);
    window = glfwCreateWindow(ropt.width, ropt.height, ("mjtether view " + opt.model).c_str(),
                              nullptr, nullptr);
  }
  if (!window) {
    const char* why = nullptr;
    glfwGetError(&why);
    std::cerr << "mjtether: view: cannot create a " << ropt.width << "x" << ropt.height
              << " OpenGL window (GLFW: " << (why ? why : "no reason given") << ")\n";
    return kExitTool;
  }
  glfwMakeContextCurrent(window);
  glfwSwapInterval(opt.frames > 0 ? 0 : 1);
  glfwGetFramebufferSize(window, &ropt.width, &ropt.height);

  std::unique_ptr<mjtether::render::Renderer> renderer =
      mjtether::render::Renderer::CreateForWindow(m, ropt, GlProc, &error);
  if (!renderer) {
    std::cerr << "mjtether: " << opt.model << ": " << error << "\n";
    glfwDestroyWindow(window);
    return error.rfind("OpenGL", 0) == 0 || error.rfind("MuJoCo", 0) == 0 ? kExitTool
                                                                          : kExitBadInput;
  }

  Viewer v;
  v.m = m;
  v.d = d;
  v.renderer = renderer.get();
  v.model = opt.model;
  v.speed = opt.speed;
  glfwSetWindowUserPointer(window, &v);
  glfwSetKeyCallback(window, OnKey);
  glfwSetMouseButtonCallback(window, OnMouseButton);
  glfwSetCursorPosCallback(window, OnCursor);
  glfwSetScrollCallback(window, OnScroll);
  for (int key : *keys) v.Key(key);

  int status = 0;
  std::vector<unsigned char> rgb;
  auto last = std::chrono::steady_clock::now();
  for (int frame = 0; !v.quit && !glfwWindowShouldClose(window); ++frame) {
    // Simulated time of this frame: 1/60 s per frame with --frames, else the wall-clock time
    // since the last frame (at most 0.1 s), times the speed.
    const auto now = std::chrono::steady_clock::now();
    const double wall = std::min(0.1, std::chrono::duration<double>(now - last).count());
    last = now;
    if (!v.paused) v.target += v.speed * (opt.frames > 0 ? kFrameDt : wall);
    if (std::optional<std::string> e = v.Advance(opt.frames > 0 ? 0 : 50)) {
      std::cerr << "mjtether: " << *e << "\n";  // paused; backspace resets
      if (opt.frames > 0) {
        status = kExitDiverged;
        break;
      }
    }

    mjtether::Prescribe(m, d);
    mjData* o = observer.Observe(d);  // the tether at d->time, on a copy
    if (auto_scale) {
      const double tmax = LargestTension(m, o);
      if (tmax > renderer->tension_max()) {
        renderer->set_tension_max(mjtether::render::NiceCeil(tmax));
      }
    }
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window, &fw, &fh);
    if (fw < 16 || fh < 16) {  // minimised
      glfwWaitEventsTimeout(0.1);
      continue;
    }
    renderer->Resize(fw, fh);
    renderer->Render(m, o, nullptr);
    char speed[64];
    std::snprintf(speed, sizeof(speed), "x%g%s", v.speed,
                  v.diverged ? "  diverged (backspace resets)"
                  : v.paused ? "  paused"
                             : "");
    renderer->Caption("speed", speed);
    if (opt.frames > 0 && frame + 1 >= opt.frames) {
      rgb.resize(static_cast<size_t>(3) * fw * fh);
      renderer->ReadPixels(rgb.data());
      if (!mjtether::render::WritePng(shot.path(), rgb.data(), fw, fh, &error) ||
          !shot.Commit(&error)) {
        std::cerr << "mjtether: output error: " << error << "\n";
        status = kExitOutput;
      } else {
        std::printf("mjtether: view: t = %.9g s after %d frame(s); screenshot %s (%dx%d)\n",
                    d->time, frame + 1, opt.screenshot.c_str(), fw, fh);
      }
      break;
    }
    glfwSwapBuffers(window);
    glfwPollEvents();
  }
  renderer.reset();  // with the window's context current
  glfwDestroyWindow(window);
  return status;
}

std::function<int()> SetupView(CLI::App* sub) {
  auto opt = std::make_shared<ViewCliOptions>();
  sub->add_option("model", opt->model, "MJCF file declaring the tethers")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--size", opt->size, "window size WIDTHxHEIGHT in pixels (default 1280x720)");
  sub->add_option("--camera", opt->camera,
                  "follow (default: keeps the tethers and vehicles in view, zooming smoothly), "
                  "top (the same from above), track:BODY, or the name of a <camera> in the model");
  sub->add_option("--samples", opt->samples, "multisampling samples, 0 to 16 (default 4)")
      ->check(CLI::Range(0, 16));
  sub->add_option("--tension-max", opt->tension_max,
                  "top of the tension colour scale [N], or auto (default; 0 is a synonym): the "
                  "largest tension so far rounded up to 1, 2, 3, 4, 5, 6 or 8 x 10^k (it grows "
                  "during the run)")
      ->check(mjtether::cli::Number(0, 1e12, false, "N"))
      ->transform(CLI::Validator(
          [](std::string& text) -> std::string {
            if (text == "auto") text = "0";  // the value that means automatic
            return "";
          },
          "auto", ""));
  sub->add_option("--vehicle", opt->vehicle, "body whose depth the HUD shows");
  AddSetOption(sub, &opt->set);
  sub->add_option("--speed", opt->speed,
                  "simulated seconds per second at the start (+ and - double and halve it)")
      ->check(mjtether::cli::Number(kMinSpeed, kMaxSpeed, false, ""));
  sub->add_flag("--overlay", opt->overlay, "start with the node and tension overlay (key O)");
  sub->add_flag("--no-hud", opt->no_hud, "start without the HUD (key H)");
  sub->add_option("--screenshot", opt->screenshot,
                  "PNG file: after --frames frames, write the window's last frame there and exit");
  sub->add_option("--frames", opt->frames,
                  "frames to render before the screenshot, each 1/60 s of simulated time x speed")
      ->check(CLI::Range(1, 1000000));
  sub->add_option("--keys", opt->keys,
                  "key presses before the first frame, comma-separated: space, right, "
                  "backspace, plus, minus, o, h, c");
  return [opt]() { return View(*opt); };
}

const bool registered = mjtether::cli::Register(
    {"view", "simulate a model live in a window (GLFW): mouse camera, pause, step, speed keys",
     SetupView});

}  // namespace
