// `mjtether render`: a video (H.264 through ffmpeg) and/or PNG stills of a model, rendered
// off-screen (plugin/render.h).
//
//   mjtether render MODEL.xml --duration S --video out.mp4 [--fps 30] [--size 1280x720]
//       [--camera follow|top|track:BODY|NAME] [--png-every S DIR] [--samples N]
//       [--tension-max N|auto] [--distance M|auto] [--speedup X] [--vehicle BODY] [--no-hud]
//       [--render-threads N|auto] [--set TEXT.KEY=VALUE]...
//
// Frame k shows the state at step round(k / (fps h)), h the model's timestep: frames are
// scheduled by index, so they never drift from t = k/fps by more than h/2 however long the
// video. The video has floor(duration * fps) + 1 frames, t = 0 to the last instant of the grid
// k/fps <= duration (so the end of the run is rendered when it falls on the grid).
// The simulation thread computes each frame's camera in order (Renderer::NextPose: the follow
// camera is a filter over frames); with several render threads the frames are rendered in
// parallel while the simulation goes on and written to ffmpeg in order (render/pipeline.h);
// --render-threads 1 renders each in turn.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli_command.h"
#include "cli_common.h"
#include "cli_pipe.h"
#include "step_check.h"
#include "mjtether.h"
#include "pipeline.h"
#include "render.h"

namespace {

struct RenderCliOptions {
  std::string model;
  double duration = 0;
  std::string video;
  double fps = 30;
  std::string size = "1280x720";
  std::string camera = "follow";
  std::vector<std::string> png_every;  // {interval, directory}
  int samples = 4;
  double tension_max = 0;
  double distance = 0;
  double speedup = 1;
  std::string vehicle;
  bool no_hud = false;
  int render_threads = 0;  // 0: automatic, 1: serial
  std::vector<std::string> set;  // TEXT.KEY=VALUE overrides, as for run (overrides.h)
};

// "auto" for --tension-max and --distance: stored as 0, the value that means automatic.
CLI::Validator Auto() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text == "auto") text = "0";
        return "";
      },
      "auto", "");
}

constexpr int kStill = 1;  // a frame's flag: write it as a PNG still too

bool ParseSize(const std::string& s, int* w, int* h) {
  char x = 0, extra = 0;
  return std::sscanf(s.c_str(), "%d%c%d%c", w, &x, h, &extra) == 3 && (x == 'x' || x == 'X');
}

// Largest tension of any segment or end over the frames' instants, to fix the colour scale
// before rendering. Returns nullopt if the simulation diverges (the message is printed).
std::optional<double> TensionPrepass(const mjModel* m, const std::string& model, long long nframes,
                                     double fps) {
  mjtether::cli::DataPtr data = mjtether::cli::MakeData(m);
  mjData* d = data.get();
  mjtether::cli::Observer observer(m);
  const double h = m->opt.timestep;
  std::vector<double> T;
  double tmax = 0;
  bool ok = true;
  long long step = 0;
  for (long long k = 0; k < nframes && ok; ++k) {
    const long long target = mjtether::render::FrameStep(k, fps, h);
    for (; step < target && !mjtether::cli::StopSignal(); ++step) {
      if (std::optional<std::string> diverged = mjtether::cli::StepAndCheck(m, d, model)) {
        std::cerr << "mjtether: " << *diverged << "\n";
        ok = false;
        break;
      }
    }
    if (!ok || mjtether::cli::StopSignal()) break;
    mjtether::Prescribe(m, d);
    const mjData* o = observer.Observe(d);
    for (int t = 0; t < mjtether::TetherCount(m); ++t) {
      T.resize(mjtether::GetTether(m, t)->segments());
      mjtether::GetTensions(m, o, t, T.data());
      for (double x : T) tmax = std::max(tmax, x);
      const mjtether::EndReactions r = mjtether::GetReactions(m, o, t);
      tmax = std::max({tmax, r.tension_a, r.tension_b});
    }
  }
  if (!ok) return std::nullopt;
  return tmax;
}

void Progress(long long done, long long total, double t, double elapsed) {
  const int width = 30;
  const int filled = static_cast<int>(width * done / std::max(1LL, total));
  const double eta = done > 0 ? elapsed * (total - done) / done : 0;
  std::fprintf(stderr, "\r[%s%s] %3d%% frame %lld/%lld t=%.2f s, %.0f s left ",
               std::string(filled, '#').c_str(), std::string(width - filled, ' ').c_str(),
               static_cast<int>(100 * done / std::max(1LL, total)), done, total, t, eta);
  std::fflush(stderr);
}

int Render(const RenderCliOptions& opt) {
  namespace fs = std::filesystem;
  using namespace mjtether::cli;
  InstallStopHandlers();
  mjtether::render::RenderOptions ropt;
  if (!ParseSize(opt.size, &ropt.width, &ropt.height)) {
    std::cerr << "mjtether: --size " << mjtether::Shown(opt.size)
              << ": expected WIDTHxHEIGHT, e.g. 1280x720\n";
    return kExitBadInput;
  }
  if (opt.video.empty() && opt.png_every.empty()) {
    std::cerr << "mjtether: render: nothing to write; give --video FILE.mp4 and/or --png-every "
                 "S DIR\n";
    return kExitBadInput;
  }
  double png_every = 0;
  std::string png_dir;
  if (!opt.png_every.empty()) {
    const mjtether::NumberStatus number = mjtether::ParseDecimal(opt.png_every[0], &png_every);
    if (number != mjtether::NumberStatus::kOk || !(png_every > 0) || png_every > 1e7) {
      std::cerr << "mjtether: --png-every " << mjtether::Shown(opt.png_every[0]) << ": "
                << (number == mjtether::NumberStatus::kOk ? "out of range"
                                                          : mjtether::NumberProblem(number))
                << "; the interval must be a number of seconds in (0, 1e7]\n";
      return kExitBadInput;
    }
    png_dir = opt.png_every[1];
  }
  ropt.samples = opt.samples;
  ropt.camera = opt.camera;
  ropt.vehicle = opt.vehicle;
  ropt.distance = opt.distance;
  ropt.hud = !opt.no_hud;

  std::string error;
  std::vector<mjtether::Override> overrides;
  if (!ParseSets(opt.set, &overrides)) return kExitBadInput;
  ModelPtr owner = LoadChecked(opt.model, overrides);
  if (!owner) return kExitBadInput;
  mjModel* m = owner.get();

  // Outputs: the video goes to a temporary file beside its target (renamed when ffmpeg is
  // done); each still is checked against the inputs as it is written.
  OutputGuard guard;
  guard.AddModel(opt.model, m);
  ToolOutput video;
  if (!opt.video.empty() && !video.Open(opt.video, "--video", &guard, &error)) {
    std::cerr << "mjtether: " << error << "\n";
    return kExitBadInput;
  }
  if (!png_dir.empty()) {
    std::error_code ec;
    fs::create_directories(png_dir, ec);
    if (ec || !fs::is_directory(png_dir)) {
      std::cerr << "mjtether: --png-every: cannot create directory " << png_dir << "\n";
      return kExitBadInput;
    }
  }

  const double h = m->opt.timestep;
  const double frame_dt = 1.0 / opt.fps;
  // Frames k = 0 .. floor(duration fps): the last instant is rendered when it is on the grid.
  const long long nframes = static_cast<long long>(std::floor(opt.duration * opt.fps + 1e-9)) + 1;

  // Colour scale: given, or the largest tension of the run rounded up (a pre-pass without
  // rendering costs a small fraction of the rendering).
  if (opt.tension_max > 0) {
    ropt.tension_max = opt.tension_max;
  } else {
    std::optional<double> tmax = TensionPrepass(m, opt.model, nframes, opt.fps);
    if (!tmax) return kExitDiverged;
    if (const int signal = StopSignal()) {
      std::cerr << "mjtether: " << opt.model << ": interrupted by "
                << (signal == SIGINT ? "SIGINT" : "SIGTERM")
                << " during the tension pre-pass; nothing was written\n";
      return 128 + signal;
    }
    ropt.tension_max = mjtether::render::NiceCeil(*tmax);
  }

  const int W = ropt.width, H = ropt.height;

  ChildPipe ffmpeg;  // started once the renderers exist
  DataPtr data = MakeData(m);
  mjData* d = data.get();
  Observer observer(m);
  const bool progress = isatty(2);
  std::vector<double> frame_ms;
  long long step = 0, next_png = 0, npng = 0;
  int status = 0;       // set by this thread
  int sink_status = 0;  // set by the sink, read after Flush
  std::string interrupted;  // why the run stopped early, printed once the frames are written
  auto start = std::chrono::steady_clock::now();  // of the frame loop

  // Each rendered frame, in order: to ffmpeg, and to a PNG if it is a still. Runs in the
  // pipeline's writer thread (or in this one with --render-threads 1).
  auto sink = [&](const mjtether::render::Frame& f) {
    frame_ms.push_back(f.render_ms);
    if (!opt.video.empty() && !ffmpeg.Write(f.rgb, static_cast<size_t>(3) * W * H)) {
      sink_status = kExitTool;  // ffmpeg stopped reading: its exit status is reported below
      return false;
    }
    if (f.flags & kStill) {
      char name[64];
      std::snprintf(name, sizeof(name), "t_%09.3f.png", f.tag * frame_dt);
      const std::string path = (fs::path(png_dir) / name).string();
      ToolOutput png;
      std::string png_error;
      if (!png.Open(path, "--png-every", &guard, &png_error)) {
        std::cerr << (progress ? "\n" : "") << "mjtether: " << png_error << "\n";
        sink_status = kExitBadInput;
        return false;
      }
      if (!mjtether::render::WritePng(png.path(), f.rgb, W, H, &png_error) ||
          !png.Commit(&png_error)) {
        std::cerr << (progress ? "\n" : "") << "mjtether: output error: " << png_error << "\n";
        sink_status = kExitOutput;
        return false;
      }
      ++npng;
    }
    if (progress) {
      Progress(f.tag + 1, nframes, f.time,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return true;
  };
  mjtether::render::PipelineOptions popt;
  popt.threads = opt.render_threads;
  std::unique_ptr<mjtether::render::FramePipeline> pipeline =
      mjtether::render::FramePipeline::Create(m, ropt, popt, sink, &error);
  if (!pipeline) {
    std::cerr << "mjtether: " << opt.model << ": " << error << "\n";
    return error.rfind("OSMesa", 0) == 0 || error.rfind("MuJoCo", 0) == 0 ? kExitTool
                                                                          : kExitBadInput;
  }

  std::signal(SIGPIPE, SIG_IGN);  // a dead ffmpeg shows up as a failed write, not a signal
  const std::string size = std::to_string(W) + "x" + std::to_string(H);
  char rate[32];
  std::snprintf(rate, sizeof(rate), "%.9g", opt.fps * opt.speedup);  // playback frame rate
  if (!opt.video.empty() &&
      !ffmpeg.Open({"ffmpeg",   "-hide_banner", "-loglevel", "error", "-y",    "-f",
                    "rawvideo", "-pix_fmt",     "rgb24",     "-s",    size,    "-r",
                    rate,       "-i",           "-",         "-vf",   "vflip", "-c:v",
                    "libx264",  "-pix_fmt",     "yuv420p",   "-r",    rate,    video.path()},
                   &error)) {
    std::cerr << "mjtether: cannot start ffmpeg: " << error << "\n";
    return kExitTool;
  }

  start = std::chrono::steady_clock::now();
  for (long long k = 0; k < nframes; ++k) {
    // Frame k at step round(k / (fps h)).
    const long long target = mjtether::render::FrameStep(k, opt.fps, h);
    for (; step < target; ++step) {
      if (const int signal = StopSignal()) {
        interrupted = Interrupted(signal, d->time, step,
                                  mjtether::render::FrameStep(nframes - 1, opt.fps, h));
        status = 128 + signal;
        break;
      }
      if (std::optional<std::string> diverged = StepAndCheck(m, d, opt.model)) {
        std::cerr << (progress ? "\n" : "") << "mjtether: " << *diverged << "\n";
        status = kExitDiverged;
        break;
      }
    }
    if (status) break;
    // Still j at frame round(j * png_every * fps).
    const bool still = png_every > 0 && k >= std::llround(next_png * png_every * opt.fps);
    if (opt.video.empty() && !still) continue;
    // Next still: the first one due after this frame (several may fall on one frame when the
    // interval is shorter than a frame).
    while (still && std::llround(next_png * png_every * opt.fps) <= k) ++next_png;

    mjtether::Prescribe(m, d);
    mjData* o = observer.Observe(d);  // the tether at d->time, on a copy
    if (!pipeline->Submit(o, k, still ? kStill : 0)) break;  // the sink set the status
  }
  // The frames in flight are written (the sink sets the status if that fails).
  pipeline->Flush();
  if (sink_status && !status) status = sink_status;
  const int threads = pipeline->threads(), samples = pipeline->samples();
  pipeline.reset();
  if (!interrupted.empty()) {
    std::cerr << (progress ? "\n" : "") << "mjtether: " << opt.model << ": " << interrupted
              << "; the video keeps " << frame_ms.size() << " frame(s)\n";
  }
  if (progress) std::fprintf(stderr, "\n");

  if (!opt.video.empty()) {
    const int rc = ffmpeg.Close();
    if (rc != 0 && (status == 0 || status == kExitTool || status >= 128)) {
      std::cerr << "mjtether: ffmpeg failed (exit status " << rc
                << (rc == 127 ? ": ffmpeg not found on PATH" : "") << ") writing " << opt.video
                << "\n";
      if (status < 128) status = kExitTool;
    } else if (status == kExitTool) {
      std::cerr << "mjtether: ffmpeg stopped reading frames for " << opt.video << "\n";
    } else if (rc == 0 && !frame_ms.empty() && !video.Commit(&error)) {
      std::cerr << "mjtether: " << error << "\n";
      if (status == 0) status = kExitOutput;
    }
  }
  if (status == 0) {
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::vector<double> sorted = frame_ms;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted.empty() ? 0 : sorted[sorted.size() / 2];
    std::cerr << "mjtether: rendered " << frame_ms.size() << " frame(s) " << W << "x" << H << ", "
              << samples << " MSAA samples, tension scale 0-" << ropt.tension_max << " N, in "
              << wall << " s (" << 1000 * wall / std::max<size_t>(1, frame_ms.size())
              << " ms/frame on " << threads << " render thread(s); median render " << median
              << " ms)";
    if (!opt.video.empty()) std::cerr << "; video: " << opt.video;
    if (npng > 0) std::cerr << "; " << npng << " still(s) in " << png_dir;
    std::cerr << "\n";
  }
  return status;
}

std::function<int()> SetupRender(CLI::App* sub) {
  auto opt = std::make_shared<RenderCliOptions>();
  sub->add_option("model", opt->model, "MJCF file declaring the tethers")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--duration", opt->duration, "simulated time [s]")
      ->required()
      ->check(mjtether::cli::Number(0, 1e5, false, "s"));
  sub->add_option("--video", opt->video, "MP4 file (H.264, yuv420p) written by ffmpeg");
  sub->add_option("--fps", opt->fps, "frames per second of simulated time (default 30)")
      ->check(mjtether::cli::Number(0.01, 1000, false, "frames/s"));
  sub->add_option("--size", opt->size, "WIDTHxHEIGHT in pixels, even numbers (default 1280x720)");
  sub->add_option("--camera", opt->camera,
                  "follow (default: keeps the tethers and vehicles in view, zooming smoothly), "
                  "top (the same from above), track:BODY, or the name of a <camera> in the model");
  sub->add_option("--png-every", opt->png_every, "S DIR: a PNG still every S seconds into DIR")
      ->expected(2);
  sub->add_option("--samples", opt->samples,
                  "multisampling samples, 0 to 16 (default 4; 0 is about twice as fast)")
      ->check(CLI::Range(0, 16));
  sub->add_option("--tension-max", opt->tension_max,
                  "top of the tension colour scale [N], or auto (default; 0 is a synonym): the "
                  "run's largest tension rounded up to 1, 2, 3, 4, 5, 6 or 8 x 10^k")
      ->check(mjtether::cli::Number(0, 1e12, false, "N"))
      ->transform(Auto());
  sub->add_option("--distance", opt->distance,
                  "camera distance for follow, top and track:BODY [m], fixed; or auto (default; "
                  "0 is a synonym): follow and top zoom to keep the tethers and vehicles in view, "
                  "track uses 8 x the body's radius, at least 1 m")
      ->check(mjtether::cli::Number(0, 1e6, false, "m"))
      ->transform(Auto());
  sub->add_option("--speedup", opt->speedup,
                  "the video plays this many times faster than real time (its frame rate is "
                  "fps x speedup; default 1)")
      ->check(mjtether::cli::Number(0.01, 1000, false, ""));
  sub->add_option("--vehicle", opt->vehicle, "body whose depth the HUD shows");
  mjtether::cli::AddSetOption(sub, &opt->set);
  sub->add_flag("--no-hud", opt->no_hud, "no text overlay or colour scale");
  sub->add_option("--render-threads", opt->render_threads,
                  "frames rendered in parallel, each with its own OSMesa context: 1 renders "
                  "each frame in turn; auto (default; 0 is a synonym): 1 on up to 2 cores, where "
                  "the pipeline does not pay, else one per core up to 4")
      ->check(CLI::Range(0, 16))
      ->transform(Auto());
  return [opt]() { return Render(*opt); };
}

const bool registered =
    mjtether::cli::Register({"render", "render a video and/or PNG stills off-screen", SetupRender});

}  // namespace
