// Wall time per 640x480 frame with 4x MSAA and the HUD, of the default scene (rov_tether.xml)
// simulated and rendered as `mjtether render` does (motion and thrust schedules, mj_step at
// 2 ms, the state observed on a copy, then rendered): the single-threaded path
// (--render-threads 1) and the pipelined one (render/pipeline.h, one worker per core, at least
// 2 and at most 4) side by side, then their ratio (target <= 0.5; docs/rendering.md) and what
// the automatic setting (--render-threads auto) picks on this machine.
//
// Each repetition is one run of 24 frames (0.8 s at 30 fps) in a fresh process (fork): llvmpipe
// reads LP_NUM_THREADS once per process, and each path gets the setting a `mjtether render`
// run would (the pipeline's LP_NUM_THREADS, or llvmpipe's default for the serial path). The
// time is the frame loop's alone (model loading and context creation excluded), divided by the
// frames. Repetitions of the two paths are interleaved, so that the machine's load affects
// both alike; the medians are compared.
//
//   ./build/tests/bench/bench_render                     # 9 repetitions of each path
//   ./build/tests/bench/bench_render --benchmark_repetitions=15
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "mjtether.h"
#include "pipeline.h"
#include "render.h"

namespace {

constexpr int kFrames = 24;           // frames per repetition
constexpr double kFps = 30;           // [frames/s]
constexpr int kWidth = 640;           // [pixel]
constexpr int kHeight = 480;          // [pixel]
constexpr int kSamples = 4;           // MSAA
constexpr double kTensionMax = 1000;  // [N] fixed colour scale (no pre-pass)

double LoadAverage() {
  std::ifstream f("/proc/loadavg");
  double load = -1;
  f >> load;
  return load;
}

// One run in this process: the frame loop's wall time [s] per frame, or a negative value with
// *error set. threads: 1 serial, >= 2 pipelined.
double RunFrames(int threads, int* used_threads, std::string* error) {
  mjModel* m = mjtether::LoadModel(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml", error);
  if (!m) return -1;
  mjData* d = mj_makeData(m);
  mjData* o = mj_makeData(m);
  mjtether::render::RenderOptions ropt;
  ropt.width = kWidth;
  ropt.height = kHeight;
  ropt.samples = kSamples;
  ropt.tension_max = kTensionMax;
  mjtether::render::PipelineOptions popt;
  popt.threads = threads;
  unsigned long long checksum = 0;
  auto sink = [&](const mjtether::render::Frame& f) {
    for (int i = 0; i < 3 * kWidth * kHeight; i += 997) checksum += f.rgb[i];
    return true;
  };
  double per_frame = -1;
  {
    std::unique_ptr<mjtether::render::FramePipeline> p =
        mjtether::render::FramePipeline::Create(m, ropt, popt, sink, error);
    if (p) {
      *used_threads = p->threads();
      const double h = m->opt.timestep;
      long long step = 0;
      const auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < kFrames; ++k) {
        for (; step < mjtether::render::FrameStep(k, kFps, h); ++step) mjtether::Step(m, d);
        mjtether::Prescribe(m, d);
        mj_copyData(o, m, d);  // the CLI's Observer
        mj_forward(m, o);
        p->Submit(o, k);
      }
      p->Flush();
      per_frame =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / kFrames;
    }
  }
  benchmark::DoNotOptimize(checksum);
  mj_deleteData(o);
  mj_deleteData(d);
  mjtether::Detach(m);
  mj_deleteModel(m);
  return per_frame;
}

// RunFrames in a child process; the result comes back through a pipe.
double RunInChild(int threads, int* used_threads, std::string* error) {
  int fds[2];
  if (pipe(fds) != 0) {
    *error = "pipe failed";
    return -1;
  }
  const pid_t pid = fork();
  if (pid < 0) {
    *error = "fork failed";
    return -1;
  }
  if (pid == 0) {
    close(fds[0]);
    char msg[512];
    std::string child_error;
    int used = 0;
    const double t = RunFrames(threads, &used, &child_error);
    std::snprintf(msg, sizeof(msg), "%.9g %d %s", t, used, child_error.c_str());
    (void)!write(fds[1], msg, std::strlen(msg));
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  std::string out;
  char buf[512];
  ssize_t n;
  while ((n = read(fds[0], buf, sizeof(buf))) > 0) out.append(buf, static_cast<size_t>(n));
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  double t = -1;
  char text[512] = {0};
  if (std::sscanf(out.c_str(), "%lf %d %511[^\n]", &t, used_threads, text) < 2 || t <= 0) {
    *error = out.empty() ? "the child process failed" : (text[0] ? text : out.c_str());
    return -1;
  }
  return t;
}

void RenderFrames(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  int used = 0;
  for (auto _ : state) {
    std::string error;
    const double t = RunInChild(threads, &used, &error);
    if (t < 0) {
      state.SkipWithError(error.c_str());
      return;
    }
    state.SetIterationTime(t);  // [s] per frame
  }
  state.counters["threads"] = used;
  state.counters["load1"] = LoadAverage();
}

// Workers of the pipelined path: one per core, at least 2 (a pipeline) and at most 4.
int PipelineWorkers() {
  return std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 2, 4);
}

// Prints the reports and keeps the medians, to print their ratio at the end.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name == "median") {
        medians_[r.run_name.args] = r.GetAdjustedRealTime();
      }
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    const int workers = PipelineWorkers();
    const auto serial = medians_.find("threads:1"),
               piped = medians_.find("threads:" + std::to_string(workers));
    if (serial == medians_.end() || piped == medians_.end()) return;
    std::printf(
        "median wall time per 640x480 4x MSAA frame: single-threaded %.1f ms, pipelined (%d "
        "workers) %.1f ms, ratio %.2f (target <= 0.5); --render-threads auto uses %d here\n",
        serial->second, workers, piped->second, piped->second / serial->second,
        mjtether::render::AutoRenderThreads());
  }

 private:
  std::map<std::string, double> medians_;
};

}  // namespace

int main(int argc, char** argv) {
  // Defaults: 9 interleaved repetitions of each path, medians reported. A flag given on the
  // command line comes later and wins.
  std::vector<char*> args(argv, argv + argc);
  char reps[] = "--benchmark_repetitions=9";
  char interleave[] = "--benchmark_enable_random_interleaving=true";
  char aggregates[] = "--benchmark_report_aggregates_only=true";
  args.insert(args.begin() + 1, {reps, interleave, aggregates});
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  // threads = 1: the single-threaded path; >= 2: the pipeline with that many workers.
  benchmark::RegisterBenchmark("RenderFrames", RenderFrames)
      ->ArgName("threads")
      ->Arg(1)
      ->Arg(PipelineWorkers())
      ->Iterations(1)
      ->UseManualTime()
      ->Unit(benchmark::kMillisecond);
  RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
