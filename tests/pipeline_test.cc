// The render pipeline (render/pipeline.h): frames rendered by parallel workers, each with its
// own OSMesa context, are the single-threaded path's frames byte for byte and reach the sink in
// order; a failing sink stops it. Through the CLI too: stills of `--render-threads 1` and of a
// pipelined run (another process, so another LP_NUM_THREADS) are the same files.
#include "pipeline.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "mjtether.h"
#include "render.h"

namespace mjtether::render {
namespace {

namespace fs = std::filesystem;

constexpr int kW = 320, kH = 240;  // [pixel]
constexpr double kFps = 10;        // [frames/s]
constexpr int kFrames = 12;        // 1.2 s of the default scene: the tether moves

struct Recorded {
  std::vector<std::vector<unsigned char>> rgb;
  std::vector<long long> index, tag;
  std::vector<double> time;
};

// A scene's first kFrames frames at kFps through a pipeline of `threads`, as the CLI renders
// them (schedules, step, observe on a copy, submit).
Recorded RenderScene(int threads, int slots, const std::string& file = "rov_tether.xml",
                     const std::string& camera = "follow") {
  Recorded out;
  std::string error;
  mjModel* m = LoadModel(std::string(MJTETHER_MODELS_DIR) + "/" + file, &error);
  EXPECT_NE(m, nullptr) << error;
  if (!m) return out;
  mjData* d = mj_makeData(m);
  mjData* o = mj_makeData(m);
  RenderOptions ropt;
  ropt.width = kW;
  ropt.height = kH;
  ropt.samples = 4;
  ropt.tension_max = 1000;
  ropt.camera = camera;
  PipelineOptions popt;
  popt.threads = threads;
  popt.slots = slots;
  auto sink = [&](const Frame& f) {
    out.rgb.emplace_back(f.rgb, f.rgb + 3 * kW * kH);
    out.index.push_back(f.index);
    out.tag.push_back(f.tag);
    out.time.push_back(f.time);
    return true;
  };
  {
    std::unique_ptr<FramePipeline> p = FramePipeline::Create(m, ropt, popt, sink, &error);
    EXPECT_NE(p, nullptr) << error;
    if (p) {
      EXPECT_EQ(p->threads(), threads);
      long long step = 0;
      for (int k = 0; k < kFrames; ++k) {
        for (; step < FrameStep(k, kFps, m->opt.timestep); ++step) Step(m, d);
        Prescribe(m, d);
        mj_copyData(o, m, d);
        mj_forward(m, o);
        EXPECT_TRUE(p->Submit(o, 100 + k));
      }
      EXPECT_TRUE(p->Flush());
    }
  }
  mj_deleteData(o);
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
  return out;
}

TEST(FramePipeline, ParallelFramesAreTheSerialFramesByteForByteAndInOrder) {
  const Recorded serial = RenderScene(1, 0);
  // Three workers (more than the cores here, so frames finish out of order) and four slots (so
  // that Submit waits for free ones).
  const Recorded parallel = RenderScene(3, 4);
  ASSERT_EQ(serial.rgb.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(parallel.rgb.size(), static_cast<size_t>(kFrames));
  for (int k = 0; k < kFrames; ++k) {
    EXPECT_EQ(parallel.index[k], k);
    EXPECT_EQ(parallel.tag[k], 100 + k);
    EXPECT_EQ(parallel.time[k], serial.time[k]) << "frame " << k;
    EXPECT_TRUE(parallel.rgb[k] == serial.rgb[k]) << "frame " << k << " differs";
  }
  // The frames show a moving scene (so that a frame handed over twice, or out of order, would
  // be seen): the first and last differ.
  EXPECT_FALSE(serial.rgb.front() == serial.rgb.back());
}

// The follow and top cameras are a filter over frames, and the close-up appears below 40 px:
// the pipeline computes each frame's camera in order on the submitting thread
// (Renderer::NextPose) and the workers render through it, so a scene whose camera zooms and
// whose vehicle starts in the close-up (the surge manoeuvre, 30 m of tether, seen from above)
// gives the serial path's bytes too. (Were each worker to run its own filter over the frames it
// happens to get, its cameras would differ from the serial ones.)
TEST(FramePipeline, StatefulTopCameraAndCloseUpAreTheSerialFramesByteForByte) {
  const Recorded serial = RenderScene(1, 0, "manoeuvre_surge_snap.xml", "top");
  const Recorded parallel = RenderScene(3, 4, "manoeuvre_surge_snap.xml", "top");
  ASSERT_EQ(serial.rgb.size(), static_cast<size_t>(kFrames));
  ASSERT_EQ(parallel.rgb.size(), static_cast<size_t>(kFrames));
  for (int k = 0; k < kFrames; ++k) {
    EXPECT_TRUE(parallel.rgb[k] == serial.rgb[k]) << "frame " << k << " differs";
  }
  EXPECT_FALSE(serial.rgb.front() == serial.rgb.back());
}

TEST(FramePipeline, ASinkThatFailsStopsThePipeline) {
  std::string error;
  mjModel* m = LoadModel(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml", &error);
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  mj_forward(m, d);
  RenderOptions ropt;
  ropt.width = 64;
  ropt.height = 48;
  ropt.samples = 0;
  std::vector<long long> seen;
  auto sink = [&](const Frame& f) {
    seen.push_back(f.index);
    return f.index < 3;  // the fourth frame fails
  };
  for (int threads : {1, 2}) {
    seen.clear();
    PipelineOptions popt;
    popt.threads = threads;
    std::unique_ptr<FramePipeline> p = FramePipeline::Create(m, ropt, popt, sink, &error);
    ASSERT_NE(p, nullptr) << error;
    bool accepted = true;
    int submitted = 0;
    for (; submitted < 50 && accepted; ++submitted) accepted = p->Submit(d, submitted);
    EXPECT_FALSE(p->Flush()) << threads << " threads";
    // Submit refuses frames once the failure is known: with the serial path at once, with
    // the pipeline within the frames in flight (at most the slots, 2 x 2 + 2).
    EXPECT_FALSE(accepted) << threads << " threads";
    EXPECT_LE(submitted, threads == 1 ? 4 : 4 + 6 + 1) << threads << " threads";
    // The sink saw frames 0-3 in order and none after the failure.
    EXPECT_EQ(seen, (std::vector<long long>{0, 1, 2, 3})) << threads << " threads";
  }
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
}

TEST(FramePipeline, ThreadsOutOfRangeAreRefusedWithTheRange) {
  std::string error;
  mjModel* m = LoadModel(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml", &error);
  ASSERT_NE(m, nullptr) << error;
  PipelineOptions popt;
  popt.threads = 17;
  EXPECT_EQ(FramePipeline::Create(m, RenderOptions(), popt, nullptr, &error), nullptr);
  EXPECT_NE(error.find("1 (serial) to 16"), std::string::npos) << error;
  // A renderer error (a bad camera) comes back from the workers.
  popt.threads = 2;
  RenderOptions ropt;
  ropt.camera = "nosuch";
  EXPECT_EQ(FramePipeline::Create(m, ropt, popt, nullptr, &error), nullptr);
  EXPECT_NE(error.find("nosuch"), std::string::npos) << error;
  Detach(m);
  mj_deleteModel(m);
}

// ---- the command line ----

int RunShell(const std::string& command) {
  const int s = std::system(command.c_str());
  return WIFEXITED(s) ? WEXITSTATUS(s) : -1;
}

std::string Slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

TEST(FramePipelineCli, StillsOfTheSerialAndParallelRunsAreTheSameFiles) {
  const fs::path dir =
      fs::temp_directory_path() / ("mjtether_pipeline_test_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const std::string cli = MJTETHER_CLI;
  const std::string model = std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml";
  const std::string common = cli + " render " + model +
                             " --duration 0.8 --fps 10 --size 320x240 --samples 4 "
                             "--tension-max 1000 --png-every 0.1 ";
  // What each run printed is kept and shown on failure. Under the sanitizers (session 21's CI)
  // the serial run rendered its 9 stills and then exited with 1: LeakSanitizer's own tracer
  // crashed at exit ("Tracer caught signal 11 ... LeakSanitizer has encountered a fatal
  // error"), among llvmpipe's threads. This test is about the pictures, so its runs go without
  // leak checking (ASAN_OPTIONS is ignored by a build without the sanitizers); the command
  // line's leaks are checked by valgrind over the hostile inputs and by the other CLI tests.
  for (const char* run : {"serial", "parallel"}) {
    const fs::path log = dir.string() + "_" + run + ".log";
    const std::string threads = std::string(run) == "serial" ? "1" : "3";
    const int status = RunShell("ASAN_OPTIONS=detect_leaks=0 " + common + (dir / run).string() +
                                " --render-threads " + threads + " > " + log.string() + " 2>&1");
    ASSERT_EQ(status, 0) << run << " run printed:\n" << Slurp(log);
    fs::remove(log);
  }
  int compared = 0;
  for (const auto& e : fs::directory_iterator(dir / "serial")) {
    const fs::path other = dir / "parallel" / e.path().filename();
    ASSERT_TRUE(fs::exists(other)) << other;
    EXPECT_TRUE(Slurp(e.path()) == Slurp(other)) << e.path().filename() << " differs";
    ++compared;
  }
  EXPECT_EQ(compared, 9);  // t = 0, 0.1, ..., 0.8 s (the last instant is on the grid)
  fs::remove_all(dir);
}

}  // namespace
}  // namespace mjtether::render
