// `mjtether run --check-step F` (cli/cli_step_check.h, docs/step_check.md): the run compared with
// the same scene at a step F times smaller. Each verdict is checked against the two runs made
// separately with the plain command line (`run --log`, and `run --set option.timestep=h/F`), so
// that what the check reports is what a user comparing the two logs by hand would find.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cli_shell.h"

namespace {

using mjtether::test_util::Shell;

const std::string kCli = MJTETHER_CLI;
const std::string kDir = MJTETHER_STEP_CHECK_DIR;  // tests/step_check
const std::string kModels = MJTETHER_MODELS_DIR;

// The check's tolerances (cli_step_check.h; the scene fuzzer's criterion).
constexpr double kPositionAbs = 0.05, kPositionRel = 0.02;  // [m], of the span
constexpr double kTensionAbs = 0.5, kTensionRel = 0.05;     // [N], of the larger
constexpr double kWindow = 0.2;                             // [s]

struct Output {
  int status = -1;
  std::string text;  // stdout and stderr
};

Output Cli(const std::string& args) {
  Output o;
  o.text = Shell(kCli + " " + args + " 2>&1", &o.status);
  return o;
}

// A CSV log: its header and rows of numbers.
struct Log {
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  int Column(const std::string& name) const {
    const auto it = std::find(columns.begin(), columns.end(), name);
    return it == columns.end() ? -1 : static_cast<int>(it - columns.begin());
  }
};

Log ReadLog(const std::string& path) {
  Log log;
  std::ifstream f(path);
  std::string line;
  if (!std::getline(f, line)) return log;
  std::stringstream head(line);
  for (std::string c; std::getline(head, c, ',');) log.columns.push_back(c);
  while (std::getline(f, line)) {
    std::stringstream s(line);
    std::vector<double> row;
    for (std::string c; std::getline(s, c, ',');) row.push_back(std::strtod(c.c_str(), nullptr));
    log.rows.push_back(row);
  }
  return log;
}

std::string TempDir() {
  char name[] = "/tmp/mjtether_step_check_XXXXXX";
  return mkdtemp(name) ? name : "/tmp";
}

// The number after `key` in `text` from position `from` on (NaN when absent).
double NumberAfter(const std::string& text, const std::string& key, size_t from = 0) {
  const size_t at = text.find(key, from);
  return at == std::string::npos ? NAN : std::strtod(text.c_str() + at + key.size(), nullptr);
}

double TensionTolerance(double a, double b) {
  return std::max(kTensionAbs, kTensionRel * std::max(std::abs(a), std::abs(b)));
}

// The printed numbers have 4 significant digits.
void ExpectPrinted(double printed, double exact, const std::string& what) {
  EXPECT_NEAR(printed, exact, 6e-4 * std::abs(exact) + 1e-12) << what;
}

// A vehicle surging into a snap (models/manoeuvre_surge_snap.xml, 3 s): the check's position
// difference, its windows' mean end tensions and the peak tension are those of the two runs'
// logs written at every step. The log row at t_n is the state the next step's callback sees, so
// a window [t_a, t_b) holds the log rows at t_a <= t < t_b.
TEST(StepCheck, ReportsWhatTheLogsOfTheTwoRunsShow) {
  const std::string dir = TempDir();
  const std::string model = kModels + "/manoeuvre_surge_snap.xml";
  const double duration = 3, h = 0.002;  // the model's <option timestep>, checked below
  const Output check = Cli("run " + model + " --duration 3 --check-step 10");
  ASSERT_NE(check.text.find("against the same scene at h/10 (0.0002 s)"), std::string::npos)
      << check.text;
  const Output coarse = Cli("run " + model + " --duration 3 --every 0.002 --digits 17 --log " +
                            dir + "/coarse.csv");
  const Output fine = Cli("run " + model + " --duration 3 --every 0.0002 --digits 17 --log " +
                          dir + "/fine.csv --set option.timestep=0.0002");
  ASSERT_EQ(coarse.status, 0) << coarse.text;
  ASSERT_EQ(fine.status, 0) << fine.text;
  const Log c = ReadLog(dir + "/coarse.csv"), f = ReadLog(dir + "/fine.csv");
  ASSERT_EQ(c.rows.size(), std::llround(duration / h) + 1u);
  ASSERT_EQ(f.rows.size(), 10 * (c.rows.size() - 1) + 1);
  ASSERT_NEAR(c.rows[1][0], h, 1e-12);

  // Positions at the windows' ends (every 100th coarse row, every 1000th fine row).
  const int x = c.Column("rov.x");
  ASSERT_GE(x, 0);
  double worst = 0;
  for (size_t k = 100; k < c.rows.size(); k += 100) {
    double s = 0;
    for (int a = 0; a < 3; ++a) s += std::pow(c.rows[k][x + a] - f.rows[10 * k][x + a], 2);
    worst = std::max(worst, std::sqrt(s));
  }
  ExpectPrinted(NumberAfter(check.text, "body 'rov': position off by "), worst, "position");

  // Window means of each end's tension; the window farthest off in units of its tolerance.
  for (const char* end : {"A", "B"}) {
    const int col = c.Column(std::string("umbilical.tension_") + end);
    ASSERT_GE(col, 0);
    double excess = -1, cm = 0, fm = 0;
    for (size_t w = 0; w < 15; ++w) {
      double sc = 0, sf = 0;
      for (size_t i = 100 * w; i < 100 * (w + 1); ++i) sc += c.rows[i][col];
      for (size_t i = 1000 * w; i < 1000 * (w + 1); ++i) sf += f.rows[i][col];
      sc /= 100, sf /= 1000;
      const double e = std::abs(sc - sf) / TensionTolerance(sc, sf);
      if (e > excess) excess = e, cm = sc, fm = sf;
    }
    const size_t at = check.text.find(std::string("tether 'umbilical' end ") + end);
    ASSERT_NE(at, std::string::npos) << check.text;
    ExpectPrinted(NumberAfter(check.text, "mean tension ", at), cm, std::string("mean ") + end);
    ExpectPrinted(NumberAfter(check.text, " N against ", at), fm, std::string("mean ") + end);
  }

  // The peak over every step: ends and segments (the log's tension_max), the last row aside
  // (the check reads a step's tensions at its start).
  auto peak = [](const Log& l) {
    double p = 0;
    for (size_t i = 0; i + 1 < l.rows.size(); ++i) {
      for (const char* col : {"umbilical.tension_A", "umbilical.tension_B",
                              "umbilical.tension_max"}) {
        p = std::max(p, l.rows[i][l.Column(col)]);
      }
    }
    return p;
  };
  const size_t at = check.text.find("tether 'umbilical': peak tension ");
  ExpectPrinted(NumberAfter(check.text, "peak tension ", at), peak(c), "coarse peak");
  ExpectPrinted(NumberAfter(check.text, ") against ", at), peak(f), "fine peak");

  // The verdict follows from the lines: exit 0 and "agrees" exactly when none is exceeded.
  const bool exceeded = check.text.find("EXCEEDED") != std::string::npos;
  EXPECT_EQ(check.status, exceeded ? 6 : 0) << check.text;
  EXPECT_EQ(check.text.find("agrees within every tolerance") != std::string::npos, !exceeded);
}

// A stretched start released by a snap (scene fuzzer seed 7637): at 2 ms the vehicle ends far
// from where it ends at 0.2 ms. The check exits 6 and names the body; the logs show the
// difference beyond max(5 cm, 2% of the span). The outputs of the run are kept.
TEST(StepCheck, AStepDependentRunExitsSixAndKeepsItsLog) {
  const std::string dir = TempDir();
  const std::string model = kDir + "/stretched_start.xml";
  const Output check =
      Cli("run " + model + " --duration 1 --check-step 10 --log " + dir + "/check.csv");
  const Output coarse = Cli("run " + model + " --duration 1 --log " + dir + "/coarse.csv");
  const Output fine = Cli("run " + model + " --duration 1 --log " + dir +
                          "/fine.csv --set option.timestep=0.0002");
  ASSERT_EQ(coarse.status, 0) << coarse.text;
  ASSERT_EQ(fine.status, 0) << fine.text;
  const Log c = ReadLog(dir + "/coarse.csv"), f = ReadLog(dir + "/fine.csv");
  const int x = c.Column("rov.x");
  ASSERT_GE(x, 0);
  ASSERT_EQ(c.rows.size(), f.rows.size());
  // The span: the TMS site is at the origin, the vehicle's site at its body's origin.
  const double span = std::hypot(c.rows[0][x], c.rows[0][x + 1], c.rows[0][x + 2]);
  const double tol = std::max(kPositionAbs, kPositionRel * span);
  double worst = 0;
  for (size_t k = 0; k < c.rows.size(); ++k) {
    worst = std::max(worst, std::hypot(c.rows[k][x] - f.rows[k][x],
                                       c.rows[k][x + 1] - f.rows[k][x + 1],
                                       c.rows[k][x + 2] - f.rows[k][x + 2]));
  }
  ASSERT_GT(worst, tol) << "the scene no longer depends on its step: choose another";
  // The stretched start is warned about at load ("compare with a smaller one"): the plain run
  // points to the check, the checked run does not.
  const std::string note = "note: --check-step 10 makes that comparison";
  EXPECT_NE(coarse.text.find(note), std::string::npos) << coarse.text;
  EXPECT_EQ(check.text.find(note), std::string::npos) << check.text;
  EXPECT_EQ(check.status, 6) << check.text;
  EXPECT_NE(check.text.find("DISAGREES: body 'rov': position off by"), std::string::npos)
      << check.text;
  EXPECT_NE(check.text.find("--set option.timestep=0.0002"), std::string::npos) << check.text;
  // The run's own log is complete and the same as without the check.
  const Log kept = ReadLog(dir + "/check.csv");
  ASSERT_EQ(kept.rows.size(), c.rows.size());
  for (size_t k = 0; k < c.rows.size(); ++k) EXPECT_EQ(kept.rows[k], c.rows[k]) << "row " << k;
}

// Mean of column `col` over the rows with t in [from, to) (the check's window; column 0 is time).
double WindowMean(const Log& log, int col, double from, double to) {
  double sum = 0;
  int n = 0;
  for (const std::vector<double>& row : log.rows) {
    if (row[0] >= from - 1e-9 && row[0] < to - 1e-9) sum += row[col], ++n;
  }
  return n ? sum / n : NAN;
}

// `model` run for 1 s at the step h (also its sampling), logged to `log`: the mean vehicle-end
// tension t.tension_B over the last kWindow (NaN without that column); the run's output in
// *text where given. The run must exit 0.
double MeanTensionBAt(const std::string& model, const std::string& h, const std::string& log,
                      std::string* text) {
  const Output run = Cli("run " + model + " --duration 1 --every " + h +
                         " --set option.timestep=" + h + " --log " + log);
  EXPECT_EQ(run.status, 0) << run.text;
  if (text) *text = run.text;
  const Log l = ReadLog(log);
  const int col = l.Column("t.tension_B");
  return col < 0 ? NAN : WindowMean(l, col, 1 - kWindow, 1 + 1e-9);
}

// A run warning that asks for the comparison (a snap that rang the undamped segment mode, at the
// run's end) is followed by the note that points to --check-step, once; a checked run has none.
// The scene is a line started as long as its span (scene fuzzer seed 491 at
// MJTETHER_SCENE_FUZZ_SLACK=0): it has no load warning, so the note can only come from the run's.
TEST(StepCheck, ARunWarningThatAsksForTheComparisonPointsToTheCheck) {
  const std::string model = kDir + "/near_taut_start.xml";
  const Output plain = Cli("run " + model + " --duration 1");
  ASSERT_EQ(plain.status, 0) << plain.text;
  const size_t warned = plain.text.find("a slack segment snapped taut at t = ");
  ASSERT_NE(warned, std::string::npos) << plain.text;
  const size_t asks = plain.text.find("compare with a smaller <option timestep>", warned);
  EXPECT_NE(asks, std::string::npos) << plain.text;
  const std::string note = "note: --check-step 10 makes that comparison";
  const size_t noted = plain.text.find(note);
  ASSERT_NE(noted, std::string::npos) << plain.text;
  EXPECT_GT(noted, warned) << "the note follows the run's warning\n" << plain.text;
  EXPECT_EQ(plain.text.find(note, noted + 1), std::string::npos) << "once\n" << plain.text;
  const Output checked = Cli("run " + model + " --duration 1 --check-step 10");
  EXPECT_EQ(checked.text.find(note), std::string::npos) << checked.text;
}

// What the ringing warning now says of a line started near taut, measured: with damping_ratio=1
// (the warning's cure for the segment mode, which then is not watched) the vehicle-end tension
// over 0.8-1 s still differs between 2 ms and 0.2 ms by more than the fuzzer's tolerance
// (10.7 against 23.3 N), while 0.5 ms agrees with 0.2 ms (23.2 N; 23.3 N at 0.02 ms): a smaller
// step, which the warning asks to compare with, is the cure. --check-step 10 finds it (exit 6).
// Since session 45 the damped 2 ms run warns too, of the vehicle's bounce (BounceMode).
// If a change makes 2 ms agree, the warning's sentence "damped or not the tensions after it
// depend on the step" is no longer true of this scene: revise it.
TEST(StepCheck, ALineStartedNearTautDependsOnTheStepDampedOrNot) {
  const std::string dir = TempDir();
  const std::string model = kDir + "/near_taut_start.xml";
  const std::string damped = " --set tether:t.damping_ratio=1 --duration 1 --every 0.002";
  double mean[3];
  const char* steps[3] = {"0.002", "0.0005", "0.0002"};
  for (int k = 0; k < 3; ++k) {
    const std::string log = dir + "/h" + steps[k] + ".csv";
    const Output run =
        Cli("run " + model + damped + " --set option.timestep=" + steps[k] + " --log " + log);
    ASSERT_EQ(run.status, 0) << run.text;
    // Damped, the segment mode is not watched; the vehicle's bounce on the line is (session
    // 45: damping ratio 0.008, omega h 0.23 at 2 ms), and only where its omega h reaches
    // kBounceOmegaH: at 2 ms, not at 0.5 or 0.2 ms, which agree.
    EXPECT_EQ(run.text.find("segment axial mode (omega_n"), std::string::npos) << run.text;
    EXPECT_EQ(run.text.find("bouncing on the whole line") != std::string::npos, k == 0)
        << steps[k] << "\n" << run.text;
    const Log l = ReadLog(log);
    const int col = l.Column("t.tension_B");
    ASSERT_GE(col, 0);
    mean[k] = WindowMean(l, col, 1 - kWindow, 1 + 1e-9);
    ASSERT_TRUE(std::isfinite(mean[k])) << steps[k];
  }
  EXPECT_GT(std::abs(mean[0] - mean[2]), TensionTolerance(mean[0], mean[2]))
      << mean[0] << " N at 2 ms, " << mean[2] << " N at 0.2 ms";
  EXPECT_LE(std::abs(mean[1] - mean[2]), TensionTolerance(mean[1], mean[2]))
      << mean[1] << " N at 0.5 ms, " << mean[2] << " N at 0.2 ms";
  const Output check = Cli("run " + model + damped + " --check-step 10");
  EXPECT_EQ(check.status, 6) << check.text;
  EXPECT_NE(check.text.find("DISAGREES"), std::string::npos) << check.text;
}

// A vehicle bouncing on a stiff, short line after a snap (scene fuzzer seed 10280; session 45):
// the line's damping damps its segment mode (damping ratio 0.38, above kRingDampingRatio, so the
// segment mode is not watched) but not the vehicle's bounce on the taut line (0.0002). Until
// session 45 the run exited 0 silent, 1490 N at 2 ms against 1892 N at 0.02 ms. The run now
// warns of the bounce, with the cure a smaller step, and the measurements below hold the
// warning's words: 2 ms is off the 0.02 ms reference beyond the fuzzer's tolerance, damped or
// not (damping_ratio=1: "more line damping does not reach the bounce"), and 0.2 ms, where the
// bounce's omega h is below kBounceOmegaH and the run is not warned, agrees within it.
TEST(StepCheck, AVehicleBouncingOnAStiffDampedLineIsWarnedAndTheStepIsTheCure) {
  const std::string dir = TempDir();
  const std::string model = kDir + "/vehicle_bounce.xml";
  const Output info = Cli("info " + model);
  ASSERT_EQ(info.status, 0) << info.text;
  EXPECT_NE(info.text.find("damping ratio 0.0002"), std::string::npos) << info.text;
  EXPECT_NE(info.text.find("(snaps and swings watched)"), std::string::npos) << info.text;
  const auto mean_at = [&](const std::string& h, std::string* text) {
    return MeanTensionBAt(model, h, dir + "/b" + h + ".csv", text);
  };
  std::string coarse_text, fine_text;
  const double coarse = mean_at("0.002", &coarse_text);
  const double fine = mean_at("0.0002", &fine_text);
  const double reference = mean_at("0.00002", nullptr);
  ASSERT_TRUE(std::isfinite(coarse) && std::isfinite(fine) && std::isfinite(reference));
  const size_t warned = coarse_text.find("bouncing on the whole line");
  ASSERT_NE(warned, std::string::npos) << coarse_text;
  EXPECT_NE(coarse_text.find("compare with a smaller <option timestep>", warned),
            std::string::npos)
      << coarse_text;
  EXPECT_NE(coarse_text.find("note: --check-step 10 makes that comparison"), std::string::npos)
      << coarse_text;
  EXPECT_EQ(fine_text.find("bouncing on the whole line"), std::string::npos) << fine_text;
  EXPECT_GT(std::abs(coarse - reference), TensionTolerance(coarse, reference))
      << coarse << " N at 2 ms, " << reference << " N at 0.02 ms";
  EXPECT_LE(std::abs(fine - reference), TensionTolerance(fine, reference))
      << fine << " N at 0.2 ms, " << reference << " N at 0.02 ms";
  // The line's damping made critical for its segments: the bounce stays (damping ratio 0.0006).
  const std::string damped = dir + "/damped.xml";
  {
    std::ifstream in(model);
    std::stringstream text;
    text << in.rdbuf();
    std::string xml = text.str();
    const std::string key = " damping=125.8816635";
    const size_t at = xml.find(key);
    ASSERT_NE(at, std::string::npos);
    xml.replace(at, key.size(), " damping_ratio=1");
    std::ofstream(damped) << xml;
  }
  const Output d2 = Cli("run " + damped + " --duration 1 --every 0.002 --log " + dir + "/d2.csv");
  const Output d0 = Cli("run " + damped +
                        " --duration 1 --every 0.00002 --set option.timestep=0.00002 --log " +
                        dir + "/d0.csv");
  ASSERT_EQ(d2.status, 0) << d2.text;
  ASSERT_EQ(d0.status, 0) << d0.text;
  EXPECT_NE(d2.text.find("bouncing on the whole line"), std::string::npos) << d2.text;
  const Log l2 = ReadLog(dir + "/d2.csv"), l0 = ReadLog(dir + "/d0.csv");
  const double m2 = WindowMean(l2, l2.Column("t.tension_B"), 1 - kWindow, 1 + 1e-9);
  const double m0 = WindowMean(l0, l0.Column("t.tension_B"), 1 - kWindow, 1 + 1e-9);
  EXPECT_GT(std::abs(m2 - m0), TensionTolerance(m2, m0))
      << "damping_ratio=1: " << m2 << " N at 2 ms, " << m0 << " N at 0.02 ms";
}

// A bounce that swings without a snap (scene fuzzer seed 1920 at its span; session 45): the
// run warns that the tension at the vehicle swung by more than its mean (kSwingRatio) while the
// step damps the bounce, and the 2 ms run is indeed off the 0.02 ms reference. The watch stops
// at kBounceOmegaH: at 0.2 ms (omega h 0.016) the run is not warned and is still off (21.7
// against 32.7 N; the bounce's numerical damping is first order in the step, and the slow-mode
// correction does not take it where end node B outweighs the body). That is a known silent
// failure, asserted here so that a change that cures it, or moves it, is seen.
TEST(StepCheck, AVehicleBounceThatSwingsWithoutASnapIsWarnedAtTheCoarseStep) {
  const std::string dir = TempDir();
  const std::string model = kDir + "/bounce_swing.xml";
  double mean[3];
  std::string text[3];
  const char* steps[3] = {"0.002", "0.0002", "0.00002"};
  for (int k = 0; k < 3; ++k) {
    const std::string log = dir + "/s" + steps[k] + ".csv";
    const Output run = Cli("run " + model + " --duration 1 --every " + steps[k] +
                           " --set option.timestep=" + steps[k] + " --log " + log);
    ASSERT_EQ(run.status, 0) << run.text;
    text[k] = run.text;
    const Log l = ReadLog(log);
    const int col = l.Column("t.tension_B");
    ASSERT_GE(col, 0);
    mean[k] = WindowMean(l, col, 1 - kWindow, 1 + 1e-9);
    ASSERT_TRUE(std::isfinite(mean[k])) << steps[k];
  }
  EXPECT_EQ(text[0].find("snapped taut"), std::string::npos) << text[0];
  const size_t warned = text[0].find("swung by");
  ASSERT_NE(warned, std::string::npos) << text[0];
  EXPECT_NE(text[0].find("compare with a smaller <option timestep>", warned), std::string::npos)
      << text[0];
  EXPECT_GT(std::abs(mean[0] - mean[2]), TensionTolerance(mean[0], mean[2]))
      << mean[0] << " N at 2 ms, " << mean[2] << " N at 0.02 ms";
  EXPECT_EQ(text[1].find("swung by"), std::string::npos) << text[1];
  EXPECT_GT(std::abs(mean[1] - mean[2]), TensionTolerance(mean[1], mean[2]))
      << mean[1] << " N at 0.2 ms, " << mean[2] << " N at 0.02 ms";
}

// A run that stops: the check says whether the smaller step cures it, and is right both ways
// (the same scene run alone at h/10 exits 0, or stops too).
TEST(StepCheck, AStopIsBlamedOnTheStepOnlyWhenTheSmallerStepRuns) {
  for (const std::string name : {"cured_by_the_step", "not_cured_by_the_step"}) {
    const std::string model = kDir + "/" + name + ".xml";
    const Output check = Cli("run " + model + " --duration 1 --check-step 10");
    const Output fine = Cli("run " + model + " --duration 1 --set option.timestep=0.0002");
    EXPECT_EQ(check.status, 1) << check.text;
    ASSERT_TRUE(fine.status == 0 || fine.status == 1) << fine.text;
    if (fine.status == 0) {
      EXPECT_NE(check.text.find("at h/10 the scene ran to t = 1 s: the step is the cause"),
                std::string::npos)
          << name << "\n" << check.text;
    } else {
      EXPECT_NE(check.text.find("at h/10 the scene stopped too"), std::string::npos)
          << name << "\n" << check.text;
    }
    // The two scenes are chosen to cover both answers.
    EXPECT_EQ(fine.status, name == "cured_by_the_step" ? 0 : 1) << name << "\n" << fine.text;
  }
}

// The run goes on where the same scene at h/10 stops (scene fuzzer seed 9828): nothing confirms
// the run, so it exits 6 with the other run's message.
TEST(StepCheck, ARunWhoseFineSelfStopsIsNotConfirmed) {
  const std::string model = kDir + "/fine_step_stops.xml";
  const Output coarse = Cli("run " + model + " --duration 1");
  const Output fine = Cli("run " + model + " --duration 1 --set option.timestep=0.0002");
  ASSERT_EQ(coarse.status, 0) << coarse.text;
  ASSERT_EQ(fine.status, 1) << fine.text;
  const Output check = Cli("run " + model + " --duration 1 --check-step 10");
  EXPECT_EQ(check.status, 6) << check.text;
  EXPECT_NE(check.text.find("the same scene at h/10 stopped at t = "), std::string::npos)
      << check.text;
  EXPECT_NE(check.text.find("this run is not confirmed"), std::string::npos) << check.text;
  // The fine run's own message, as the plain run at h/10 prints it.
  const std::string message = fine.text.substr(fine.text.find("tether 't' diverged"));
  EXPECT_NE(check.text.find(message.substr(0, message.find('\n'))), std::string::npos)
      << check.text;
}

// --check-from leaves a start-up transient out: the windows compared start there.
TEST(StepCheck, CheckFromLeavesTheStartOut) {
  const std::string model = kModels + "/manoeuvre_surge_snap.xml";
  const Output all = Cli("run " + model + " --duration 1 --check-step 10");
  const Output late = Cli("run " + model + " --duration 1 --check-step 10 --check-from 0.4");
  EXPECT_NE(all.text.find("over 5 window(s):"), std::string::npos) << all.text;
  EXPECT_NE(late.text.find("over 3 window(s) from t = 0.4 s:"), std::string::npos) << late.text;
  EXPECT_EQ(late.text.find(" over 0-0.2 s"), std::string::npos) << late.text;
  EXPECT_EQ(late.text.find(" over 0.2-0.4 s"), std::string::npos) << late.text;
}

// An end tension that alternates from step to step (session 46, found by the scene fuzzer run at
// a 1 ms step, MJTETHER_SCENE_FUZZ_STEP): two lines stepping as backward Euler on an overdamped
// segment mode, whose tension at the vehicle is off its fine-step self at 1 ms only. The run at
// 1 ms must warn (RingWarnings' alternation watch, kAlternationRatio) and be off the 0.1 ms
// reference beyond the fuzzer's tolerance; the runs at the steps that agree with it must not
// warn (the watch's false alarms on smooth tensions).
TEST(StepCheck, AnEndTensionThatAlternatesFromStepToStepIsWarned) {
  const std::string dir = TempDir();
  struct Case {
    const char* scene;
    std::vector<const char*> agree;  // steps that agree with 0.1 ms (measured, session 46)
  };
  // 3251: 4.0 N at 2, 0.5, 0.1 ms, 5.0 N at 1 ms (alternating 4.0/5.7 N); 11820: 0.45 N at
  // 2 ms, 0.44 N at 0.1 ms, 9.2 N at 1 ms (a three-step cycle 0/16/0.8 N).
  const Case cases[] = {{"alternating_end.xml", {"0.002", "0.0005"}},
                        {"alternating_cycle.xml", {"0.002"}}};
  for (const Case& c : cases) {
    const std::string model = kDir + "/" + c.scene;
    const auto run = [&](const std::string& h, std::string* text) {
      return MeanTensionBAt(model, h, dir + "/" + c.scene + h + ".csv", text);
    };
    std::string text;
    const double reference = run("0.0001", &text);
    ASSERT_TRUE(std::isfinite(reference)) << c.scene;
    EXPECT_EQ(text.find("alternated from step to step"), std::string::npos) << c.scene << text;
    const double off = run("0.001", &text);
    EXPECT_GT(std::abs(off - reference), TensionTolerance(off, reference))
        << c.scene << ": " << off << " N at 1 ms, " << reference << " N at 0.1 ms";
    const size_t warned = text.find("the tension at end B has alternated from step to step");
    ASSERT_NE(warned, std::string::npos) << c.scene << text;
    EXPECT_NE(text.find("steps as backward Euler", warned), std::string::npos) << text;
    EXPECT_NE(text.find("compare with a smaller <option timestep>", warned), std::string::npos)
        << text;
    EXPECT_NE(text.find("note: --check-step 10 makes that comparison"), std::string::npos)
        << text;
    for (const char* h : c.agree) {
      const double mean = run(h, &text);
      EXPECT_LE(std::abs(mean - reference), TensionTolerance(mean, reference))
          << c.scene << ": " << mean << " N at " << h << " s, " << reference << " N at 0.1 ms";
      EXPECT_EQ(text.find("alternated from step to step"), std::string::npos)
          << c.scene << " at " << h << " s: " << text;
    }
  }
}

}  // namespace
