// Off-screen rendering: tether pixels where the nodes project, colours on the tension scale,
// the CLI's video (frame count and size through ffprobe), stills and plot.
#include "render.h"

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "cli_shell.h"
#include "mjtether.h"
#include "render_geometry.h"

namespace mjtether::render {
namespace {

namespace fs = std::filesystem;
using mjtether::test_util::kTwoTethers;
using mjtether::test_util::Shell;

constexpr double kTensionHot = 1000;  // [N] EA * (10/9.5 - 1)
constexpr double kTensionMid = 500;   // [N]

class RenderTest : public ::testing::Test {
 protected:
  void TearDown() override {
    if (d_) mj_deleteData(d_);
    if (m_) {
      Detach(m_);
      mj_deleteModel(m_);
    }
  }
  void Load(const char* xml) {
    std::string error;
    m_ = LoadModelFromString(xml, "render_test.xml", &error);
    ASSERT_NE(m_, nullptr) << error;
    d_ = mj_makeData(m_);
    mj_forward(m_, d_);  // sets the initial shape: straight, stretched
  }
  mjModel* m_ = nullptr;
  mjData* d_ = nullptr;
};

constexpr auto Project = test_util::ProjectScene;

TEST_F(RenderTest, TetherPixelsAppearWhereTheNodesProjectInTheirTensionColour) {
  Load(kTwoTethers);
  const int W = 640, H = 480;
  RenderOptions opt;
  opt.width = W;
  opt.height = H;
  opt.samples = 0;  // crisp edges: a pixel is the tether's or not
  opt.camera = "side";
  opt.tension_max = kTensionHot;
  opt.hud = false;
  std::string error;
  std::unique_ptr<Renderer> r = Renderer::Create(m_, opt, &error);
  ASSERT_NE(r, nullptr) << error;
  // The off-screen buffer is the requested size (a larger viewport would be cropped).
  EXPECT_EQ(m_->vis.global.offwidth, W);
  EXPECT_EQ(m_->vis.global.offheight, H);

  // The tensions are the ones the colours are chosen for (straight, uniform).
  for (int k = 0; k < 2; ++k) {
    std::vector<double> T(10);
    GetTensions(m_, d_, k, T.data());
    const double expected = TetherName(m_, k) == "hot" ? kTensionHot : kTensionMid;
    for (double t : T) EXPECT_NEAR(t, expected, 1e-6 * expected);
  }

  std::vector<unsigned char> with(3 * W * H), without(3 * W * H);
  r->Render(m_, d_, with.data());
  const mjvScene scn = r->scene();  // camera of the frame with tethers
  RenderOptions bare = opt;
  bare.draw_tethers = false;
  std::unique_ptr<Renderer> r0 = Renderer::Create(m_, bare, &error);
  ASSERT_NE(r0, nullptr) << error;
  r0->Render(m_, d_, without.data());

  // Not blank: the background alone has a vertical gradient (distinct rows), and the tethers
  // change pixels.
  int changed = 0;
  for (int i = 0; i < W * H; ++i) {
    changed += std::abs(with[3 * i] - without[3 * i]) +
                   std::abs(with[3 * i + 1] - without[3 * i + 1]) +
                   std::abs(with[3 * i + 2] - without[3 * i + 2]) >
               30;
  }
  EXPECT_NE(without[3 * (W / 2)], without[3 * ((H - 1) * W + W / 2) + 2]);
  EXPECT_GT(changed, 500);

  // At every interior node, a pixel within 1 px of the projection has the tether's colour:
  // red (R > 2G, R > 2B) for "hot", green (G > 2R, G > 2B) for "mid". Shading scales the
  // channels together, so ratios of 2 leave margin (the ramp's red is 0.95/0.10/0.05, its green
  // 0.15/0.85/0.15) while excluding the water (blue) and the other tether.
  int checked = 0;
  for (int k = 0; k < 2; ++k) {
    const bool hot = TetherName(m_, k) == "hot";
    const double* x = NodePositions(m_, d_, k);
    for (int i = 1; i < 10; ++i) {
      const std::array<double, 2> px = Project(scn, W, H, x + 3 * i);
      const int cx = static_cast<int>(std::lround(px[0])), cy = static_cast<int>(px[1]);
      ASSERT_TRUE(cx > 1 && cx < W - 2 && cy > 1 && cy < H - 2) << "node off screen";
      bool found = false;
      for (int dy = -1; dy <= 1 && !found; ++dy) {
        for (int dx = -1; dx <= 1 && !found; ++dx) {
          const unsigned char* p = with.data() + 3 * ((cy + dy) * W + cx + dx);
          const int R = p[0], G = p[1], B = p[2];
          found = hot ? (R > 2 * G && R > 2 * B) : (G > 2 * R && G > 2 * B);
        }
      }
      EXPECT_TRUE(found) << TetherName(m_, k) << " node " << i << " at pixel (" << cx << ", " << cy
                         << ")";
      ++checked;
    }
  }
  EXPECT_EQ(checked, 18);

  // Nothing changes away from the tethers: pixels farther than 6 px from both projected lines
  // (the capsules are about 4 px thick here) are identical with and without them.
  const double* a = NodePositions(m_, d_, 0);
  const double* b = NodePositions(m_, d_, 1);
  const std::array<double, 2> lines[2][2] = {{Project(scn, W, H, a), Project(scn, W, H, a + 30)},
                                             {Project(scn, W, H, b), Project(scn, W, H, b + 30)}};
  int far_changed = 0;
  for (int row = 0; row < H; ++row) {
    for (int col = 0; col < W; ++col) {
      bool near = false;
      for (const auto& l : lines) {
        const double x0 = l[0][0], y0 = l[0][1], x1 = l[1][0], y1 = l[1][1];
        const double t = std::clamp(((col - x0) * (x1 - x0) + (row - y0) * (y1 - y0)) /
                                        ((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0)),
                                    0.0, 1.0);
        near |= std::hypot(col - (x0 + t * (x1 - x0)), row - (y0 + t * (y1 - y0))) < 6;
      }
      const int i = row * W + col;
      if (!near && (with[3 * i] != without[3 * i] || with[3 * i + 1] != without[3 * i + 1] ||
                    with[3 * i + 2] != without[3 * i + 2])) {
        ++far_changed;
      }
    }
  }
  EXPECT_EQ(far_changed, 0);
}

// The follow camera keeps every node of the tether and the vehicle in the picture through the
// default scene's manoeuvre (snap included); the track camera puts its body at the centre.
TEST(RenderCamera, FollowKeepsTheWholeTetherInViewAndTrackCentresTheBody) {
  std::string error;
  mjModel* m = LoadModel(std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml", &error);
  ASSERT_NE(m, nullptr) << error;
  mjData* d = mj_makeData(m);
  const int W = 160, H = 90;
  RenderOptions opt;
  opt.width = W;
  opt.height = H;
  opt.samples = 0;
  opt.hud = false;
  std::unique_ptr<Renderer> follow = Renderer::Create(m, opt, &error);
  ASSERT_NE(follow, nullptr) << error;
  opt.camera = "track:rov";
  std::unique_ptr<Renderer> track = Renderer::Create(m, opt, &error);
  ASSERT_NE(track, nullptr) << error;
  const int rov = mj_name2id(m, mjOBJ_BODY, "rov");
  std::vector<unsigned char> rgb(3 * W * H);
  const int k = FindTether(m, "umbilical");
  for (int frame = 0; frame <= 10; ++frame) {
    while (d->time < 2.0 * frame - 1e-9) Step(m, d);
    mj_forward(m, d);
    follow->Render(m, d, rgb.data());
    const double* x = NodePositions(m, d, k);
    for (int i = 0; i < GetTether(m, k)->nodes(); ++i) {
      const std::array<double, 2> p = Project(follow->scene(), W, H, x + 3 * i);
      EXPECT_TRUE(p[0] >= 0 && p[0] <= W && p[1] >= 0 && p[1] <= H)
          << "t = " << d->time << " node " << i << " at (" << p[0] << ", " << p[1] << ")";
    }
    // The body's origin projects to the centre to within a thousandth of the width (the
    // camera's data are floats).
    track->Render(m, d, rgb.data());
    const std::array<double, 2> c = Project(track->scene(), W, H, d->xpos + 3 * rov);
    EXPECT_NEAR(c[0], W / 2.0, 1e-3 * W) << "t = " << d->time;
    EXPECT_NEAR(c[1], H / 2.0, 1e-3 * W) << "t = " << d->time;
  }
  follow.reset();
  track.reset();
  mj_deleteData(d);
  Detach(m);
  mj_deleteModel(m);
}

TEST_F(RenderTest, HudDrawsTextInTheTopLeftCorner) {
  Load(kTwoTethers);
  RenderOptions opt;
  opt.width = 320;
  opt.height = 240;
  opt.samples = 0;
  opt.camera = "side";
  opt.tension_max = kTensionHot;
  std::string error;
  std::unique_ptr<Renderer> r = Renderer::Create(m_, opt, &error);
  ASSERT_NE(r, nullptr) << error;
  opt.hud = false;
  std::unique_ptr<Renderer> r0 = Renderer::Create(m_, opt, &error);
  ASSERT_NE(r0, nullptr) << error;
  std::vector<unsigned char> with(3 * 320 * 240), without(3 * 320 * 240);
  r->Render(m_, d_, with.data());
  r0->Render(m_, d_, without.data());
  // The top-left 80x40 pixels (rows from the bottom: 200-239) hold the HUD's first lines.
  int changed = 0;
  for (int row = 200; row < 240; ++row) {
    for (int col = 0; col < 80; ++col) {
      const int i = 3 * (row * 320 + col);
      changed += with[i] != without[i] || with[i + 1] != without[i + 1];
    }
  }
  EXPECT_GT(changed, 200);
}

TEST_F(RenderTest, CreateRejectsBadOptionsWithAMessage) {
  Load(kTwoTethers);
  std::string error;
  RenderOptions opt;
  opt.width = 641;
  EXPECT_EQ(Renderer::Create(m_, opt, &error), nullptr);
  EXPECT_NE(error.find("even"), std::string::npos) << error;
  opt = RenderOptions();
  opt.camera = "nosuch";
  EXPECT_EQ(Renderer::Create(m_, opt, &error), nullptr);
  EXPECT_NE(error.find("nosuch"), std::string::npos) << error;
  opt = RenderOptions();
  opt.camera = "track:nobody";
  EXPECT_EQ(Renderer::Create(m_, opt, &error), nullptr);
  EXPECT_NE(error.find("nobody"), std::string::npos) << error;
  opt = RenderOptions();
  opt.samples = 17;
  EXPECT_EQ(Renderer::Create(m_, opt, &error), nullptr);
  EXPECT_NE(error.find("[0, 16]"), std::string::npos) << error;
}

TEST(TensionColor, SlackIsGreyAndTheRampRunsBlueToRed) {
  float c[4];
  for (double T : {0.0, -5.0}) {
    TensionColor(T, 100, c);
    EXPECT_EQ(c[0], c[1]);
    EXPECT_EQ(c[1], c[2]);
  }
  TensionColor(1e-9, 100, c);  // the smallest tension is blue, not grey
  EXPECT_GT(c[2], 2 * c[0]);
  TensionColor(50, 100, c);  // middle: green
  EXPECT_GT(c[1], 2 * c[0]);
  EXPECT_GT(c[1], 2 * c[2]);
  float top[4], above[4];
  TensionColor(100, 100, top);  // top and above the scale: red
  TensionColor(1e6, 100, above);
  EXPECT_GT(top[0], 5 * top[1]);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(top[i], above[i]);
}

TEST(NiceCeil, RoundsUpToOneToEightTimesAPowerOfTen) {
  EXPECT_DOUBLE_EQ(NiceCeil(0.3), 0.3);
  EXPECT_DOUBLE_EQ(NiceCeil(200), 200);
  EXPECT_DOUBLE_EQ(NiceCeil(245), 300);
  EXPECT_DOUBLE_EQ(NiceCeil(601), 800);
  EXPECT_DOUBLE_EQ(NiceCeil(801), 1000);
  EXPECT_DOUBLE_EQ(NiceCeil(0), 1);
}

// Frames scheduled by index never drift: over an hour at 30 fps with a 2 ms step (1/30 s is
// not a whole number of steps), frame k is within half a step of k/30.
TEST(FrameStep, FrameTimesStayWithinHalfAStepOfKOverFps) {
  const double h = 0.002, fps = 30;
  double worst = 0;
  for (long long k = 0; k < 3600 * 30; ++k) {
    worst = std::max(worst, std::abs(FrameStep(k, fps, h) * h - k / fps));
  }
  EXPECT_LE(worst, 0.5 * h * (1 + 1e-9));
}

// ---- the command line ----

bool Have(const std::string& tool) {
  int status = 0;
  Shell("command -v " + tool + " >/dev/null 2>&1", &status);
  return status == 0;
}

// Width and height from a PNG's IHDR chunk (bytes 16-23, big-endian).
std::array<int, 2> PngSize(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  unsigned char h[24] = {};
  f.read(reinterpret_cast<char*>(h), 24);
  if (!f || h[1] != 'P' || h[2] != 'N' || h[3] != 'G') return {0, 0};
  auto be = [&](int o) { return (h[o] << 24) | (h[o + 1] << 16) | (h[o + 2] << 8) | h[o + 3]; };
  return {be(16), be(20)};
}

class RenderCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("mjtether_render_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
  const std::string cli_ = MJTETHER_CLI;
  const std::string model_ = std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml";
};

TEST_F(RenderCli, VideoHasTheFrameCountAndSizeAsked) {
  if (!Have("ffmpeg") || !Have("ffprobe")) {
    GTEST_SKIP() << "ffmpeg or ffprobe is not installed: cannot write or inspect the video";
  }
  const std::string video = (dir_ / "out.mp4").string();
  int status = 0;
  Shell(cli_ + " render " + model_ +
            " --duration 1 --fps 10 --speedup 2 --size 160x120 --samples 0" + " --video " + video +
            " --png-every 0.5 " + (dir_ / "stills").string() + " 2>&1",
        &status);
  ASSERT_EQ(status, 0);
  // 1 s at 10 fps: frames at t = 0, 0.1, ..., 1.0 (the last instant is on the grid), played
  // at 10 x 2 = 20 frames per second.
  const std::string probe = Shell(
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
      "stream=width,height,nb_read_frames,codec_name,pix_fmt,r_frame_rate -of csv=p=0 " +
          video,
      &status);
  ASSERT_EQ(status, 0);
  EXPECT_EQ(probe, "h264,160,120,yuv420p,20/1,11\n");
  // Stills at t = 0, 0.5 and 1 s, the video's size.
  for (const char* name : {"t_00000.000.png", "t_00000.500.png", "t_00001.000.png"}) {
    const std::array<int, 2> size = PngSize((dir_ / "stills" / name).string());
    EXPECT_EQ(size[0], 160) << name;
    EXPECT_EQ(size[1], 120) << name;
  }
  int stills = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "stills")) stills += e.is_regular_file();
  EXPECT_EQ(stills, 3);
}

// Stills are taken on the nearest frame: an interval shorter than a frame gives one still per
// frame (0, 0.1, 0.2 s at 10 fps), not one still and then none.
TEST_F(RenderCli, StillsShorterThanAFrameFallOnEveryFrame) {
  int status = 0;
  const std::string out =
      Shell(cli_ + " render " + model_ + " --duration 0.3 --fps 10 --size 64x48 --samples 0" +
                " --png-every 0.01 " + (dir_ / "s").string() + " 2>&1",
            &status);
  ASSERT_EQ(status, 0) << out;
  for (const char* name : {"t_00000.000.png", "t_00000.100.png", "t_00000.200.png"}) {
    EXPECT_EQ(PngSize((dir_ / "s" / name).string()), (std::array<int, 2>{64, 48})) << name;
  }
}

// --set renders the scene that `run --set` runs: a still with the tether shortened from 20 to
// 12 m on the command line is, byte for byte, the still of the file edited by hand, and not the
// still of the file as it is (the shorter tether hangs another way from t = 0). A bad override
// is refused before anything is rendered (exit 2, naming the key).
TEST_F(RenderCli, SetOverridesRenderTheSceneEditedByHand) {
  std::ifstream in(model_);
  std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string from = "length=20 segments=40";
  ASSERT_NE(xml.find(from), std::string::npos) << "models/rov_tether.xml changed: fix the test";
  xml.replace(xml.find(from), from.size(), "length=12 segments=40");
  const std::string edited = (dir_ / "edited.xml").string();
  std::ofstream(edited) << xml;
  auto still = [&](const std::string& model, const std::string& extra, const std::string& dir) {
    int status = 0;
    const std::string out = Shell(cli_ + " render " + model + extra +
                                      " --duration 0.1 --fps 10 --size 64x48 --samples 0" +
                                      " --png-every 0.1 " + (dir_ / dir).string() + " 2>&1",
                                  &status);
    EXPECT_EQ(status, 0) << out;
    std::ifstream f(dir_ / dir / "t_00000.100.png", std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  };
  const std::string set = still(model_, " --set tether:umbilical.length=12", "set");
  const std::string hand = still(edited, "", "hand");
  const std::string as_is = still(model_, "", "as_is");
  ASSERT_FALSE(set.empty());
  EXPECT_TRUE(set == hand) << "the --set still differs from the hand-edited file's";
  EXPECT_FALSE(set == as_is) << "the override changed nothing in the picture";

  int status = 0;
  const std::string bad = Shell(cli_ + " render " + model_ +
                                    " --duration 0.1 --size 64x48 --samples 0 --png-every 0.1 " +
                                    (dir_ / "bad").string() +
                                    " --set tether:umbilical.lenght=12 2>&1",
                                &status);
  EXPECT_EQ(status, 2) << bad;
  EXPECT_NE(bad.find("lenght"), std::string::npos) << bad;
  EXPECT_FALSE(fs::exists(dir_ / "bad" / "t_00000.000.png")) << bad;
}

TEST_F(RenderCli, FfmpegFailureIsExitCode4AndBadSizeIs2) {
  int status = 0;
  const std::string out = Shell(cli_ + " render " + model_ +
                                    " --duration 0.1 --fps 10 --size 64x48 --samples 0 --video " +
                                    (dir_ / "out.nosuchformat").string() + " 2>&1",
                                &status);
  // (A missing directory is refused before the run, exit 2: see tests/hostile/cases.txt. An
  // extension ffmpeg knows no format for makes ffmpeg itself fail.)
  if (Have("ffmpeg")) {
    EXPECT_EQ(status, 4) << out;
    EXPECT_NE(out.find("ffmpeg"), std::string::npos) << out;
  }
  const std::string bad = Shell(
      cli_ + " render " + model_ + " --duration 0.1 --size 641x480 --video x.mp4 2>&1", &status);
  EXPECT_EQ(status, 2) << bad;
  EXPECT_NE(bad.find("even"), std::string::npos) << bad;
}

TEST_F(RenderCli, PlotFromARunLogAndFromTheModelWritesAPngOfTheAskedSize) {
  if (!Have("gnuplot")) GTEST_SKIP() << "gnuplot is not installed: cannot plot";
  const std::string log = (dir_ / "log.csv").string();
  int status = 0;
  Shell(cli_ + " run " + model_ + " --duration 1 --log " + log + " 2>&1", &status);
  ASSERT_EQ(status, 0);
  const std::string from_log = (dir_ / "from_log.png").string();
  const std::string out =
      Shell(cli_ + " plot " + log + " --out " + from_log + " --size 800x600 2>&1", &status);
  EXPECT_EQ(status, 0) << out;
  EXPECT_EQ(PngSize(from_log), (std::array<int, 2>{800, 600}));
  const std::string from_model = (dir_ / "from_model.png").string();
  Shell(cli_ + " plot " + model_ + " --duration 1 --out " + from_model + " 2>&1", &status);
  EXPECT_EQ(status, 0);
  EXPECT_EQ(PngSize(from_model), (std::array<int, 2>{1000, 700}));

  // A CSV without the tension columns is bad input, named in the message.
  const std::string bad = (dir_ / "bad.csv").string();
  std::ofstream(bad) << "time,x\n0,1\n";
  const std::string message =
      Shell(cli_ + " plot " + bad + " --out " + (dir_ / "bad.png").string() + " 2>&1", &status);
  EXPECT_EQ(status, 2);
  EXPECT_NE(message.find("bad.csv"), std::string::npos) << message;
  EXPECT_NE(message.find("tension_A"), std::string::npos) << message;
}

}  // namespace
}  // namespace mjtether::render
