// Declaration overrides (plugin/overrides.h), `mjtether run --set/--summary`, `mjtether sweep`
// (local, resume, failures, bad input, the Slurm scripts run by hand) and `mjtether plot --x
// --y`. The CLI is run as a child process on the default scene.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cli_csv.h"
#include "mjtether.h"
#include "overrides.h"

namespace mjtether {
namespace {

std::string Read(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void Write(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
}

bool Contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// A fresh folder for one test.
std::string TempFolder(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/sweep_" + name + "_" + std::to_string(getpid());
  std::system(("rm -rf '" + dir + "' && mkdir -p '" + dir + "'").c_str());
  return dir;
}

// Runs a shell command; returns its exit status and its stdout + stderr.
int RunShell(const std::string& command, std::string* output) {
  const std::string out = ::testing::TempDir() + "/sweep_cli_" + std::to_string(getpid());
  const int status = std::system(("(" + command + ") > '" + out + "' 2>&1 < /dev/null").c_str());
  *output = Read(out);
  std::remove(out.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int RunCli(const std::string& args, std::string* output) {
  return RunShell(std::string(MJTETHER_CLI) + " " + args, output);
}

const std::string kScene = std::string(MJTETHER_MODELS_DIR) + "/rov_tether.xml";

// The default scene with text replaced, as a user would edit the file by hand.
std::string HandEdited(std::vector<std::pair<std::string, std::string>> edits) {
  std::string xml = Read(kScene);
  for (const auto& [from, to] : edits) {
    const size_t at = xml.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) xml.replace(at, from.size(), to);
  }
  return xml;
}

// summary.csv as a list of column -> value maps.
std::vector<std::map<std::string, std::string>> Summary(const std::string& path) {
  std::string error;
  auto records = cli::ParseCsv(Read(path), &error);
  std::vector<std::map<std::string, std::string>> rows;
  if (!records || records->empty()) {
    ADD_FAILURE() << path << ": " << error;
    return rows;
  }
  for (size_t r = 1; r < records->size(); ++r) {
    std::map<std::string, std::string> row;
    for (size_t c = 0; c < (*records)[0].fields.size(); ++c) {
      row[(*records)[0].fields[c]] = (*records)[r].fields.at(c);
    }
    rows.push_back(row);
  }
  return rows;
}

// ---------------------------------------------------------------------------------------------
// CSV and overrides

// Fields with commas, quotes and line breaks survive CsvLine then ParseCsv unchanged (RFC 4180),
// and a quote that is never closed is an error naming its line.
TEST(Csv, QuotedFieldsRoundTrip) {
  const std::vector<std::string> a = {"plain", "0.5,0,0", "say \"hi\"", "two\nlines", ""};
  const std::vector<std::string> b = {"x", "", "y", "z", "w"};
  std::string error;
  auto records = cli::ParseCsv(cli::CsvLine(a) + cli::CsvLine(b), &error);
  ASSERT_TRUE(records) << error;
  ASSERT_EQ(records->size(), 2u);
  EXPECT_EQ((*records)[0].fields, a);
  EXPECT_EQ((*records)[1].fields, b);
  EXPECT_EQ((*records)[1].line, 3);  // the quoted line break moved it down one line
  EXPECT_FALSE(cli::ParseCsv("a,b\n1,\"2\n", &error));
  EXPECT_TRUE(Contains(error, "line 2")) << error;
}

// An override replaces the key in the named <text> only: not in a comment that quotes the
// element, not in a <texture>; an absent key is appended; entities in the data are kept.
TEST(Overrides, RewriteOnlyTheNamedText) {
  const std::string xml = R"(<mujoco>
  <!-- <text name="water" data="density=1"/> -->
  <asset><texture name="water" type="2d" builtin="checker" width="8" height="8"/></asset>
  <custom><text data='density=1025   current=0.3,0,0' name="water"/>
    <text name="note" data="a=&quot;b&quot;"/></custom>
</mujoco>)";
  std::string error;
  std::optional<std::string> out =
      ApplyOverrides(xml, {{"water", "current", "0.6,0,0"}, {"water", "seabed", "-40"}}, &error);
  ASSERT_TRUE(out) << error;
  EXPECT_TRUE(Contains(*out, R"(<!-- <text name="water" data="density=1"/> -->)")) << *out;
  EXPECT_TRUE(Contains(*out, R"(data='density=1025 current=0.6,0,0 seabed=-40')")) << *out;
  EXPECT_TRUE(Contains(*out, R"(data="a=&quot;b&quot;")")) << *out;
  EXPECT_FALSE(ApplyOverrides(xml, {{"tether:x", "EA", "1"}}, &error));
  EXPECT_TRUE(Contains(error, "no <text name=\"tether:x\">")) << error;
}

// An out-of-range override gets the message the same value written in the file gets (the same
// parser and range checks), followed by the override that put it there, since the file on disk
// does not hold it.
TEST(Overrides, SameRangeCheckAsTheFile) {
  const std::string dir = TempFolder("range");
  const std::string hand = dir + "/rov_tether.xml";
  Write(hand, HandEdited({{"EA=2e5", "EA=-3"}}));
  std::string from_file, from_override;
  EXPECT_EQ(LoadModel(hand, &from_file), nullptr);
  EXPECT_EQ(LoadModel(kScene, {{"tether:umbilical", "EA", "-3"}}, &from_override), nullptr);
  ASSERT_TRUE(Contains(from_file, "'EA'")) << from_file;
  EXPECT_EQ(from_file.substr(from_file.find(": <text")) +
                " (the file as edited by the override(s) tether:umbilical.EA=-3)",
            from_override.substr(from_override.find(": <text")));
}

// A light vehicle (2.15 kg) on 6 stiff segments (EA 8.6e6 N), bdf2, in the file at a 2 ms step:
// coupling omega h 1.33 there, so the consistent coupling is on (from 1, docs/coupling.md);
// at 1 ms, 0.66, the held force. Scene fuzzer seed 5003's, without its current and damping,
// and with a lighter, thinner line (0.3 kg/m, 1 cm; 2.45 kg/m and 3.8 cm there), so that end
// node B (1.2 kg with its added mass) stays lighter than the body's m_eff (3.0 kg): a heavier
// node takes the consistent coupling at every step (session 23).
std::string LightVehicleScene(const std::string& step) {
  return R"(<mujoco><option timestep=")" + step + R"("/><custom>
<text name="water" data="density=1025"/>
<text name="vehicle:rov" data="volume=0.0021469 added_mass=2.1249,1.8775,0.85815,0.0017860,0.0017860,0.0017860 linear_damping=0.58203,0.58203,0.58203,0.0059532,0.0059532,0.0059532"/>
<text name="tether:t" data="ends=tms_site,att length=39.127 segments=6 diameter=0.01 mass_per_length=0.3 EA=8606710 Cdn=1.2 Cdt=0.01 Can=1 integrator=bdf2"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="21.382 13.161 -24.684"><freejoint/><inertial pos="0 0 0" mass="2.1466" diaginertia="0.0059532 0.0059532 0.0059532"/><site name="att"/></body>
</worldbody></mujoco>
)";
}

// option.timestep sets MuJoCo's step before the tethers are attached: the load-time advice sees
// it (the coupling changes from consistent to held with the step), and `run --set
// option.timestep=0.001` writes the same log, byte for byte, as the file edited by hand to
// 0.001 (set after the attachment, the run would keep the consistent coupling of 2 ms and
// differ); `info --set` prints the advice at that step; a sweep column of that name does the
// same as run.
TEST(Overrides, TimestepIsSetBeforeTheTethersAreAttached) {
  const std::string dir = TempFolder("timestep");
  Write(dir + "/light.xml", LightVehicleScene("0.002"));
  Write(dir + "/hand.xml", LightVehicleScene("0.001"));
  std::string error;
  mjModel* file = LoadModel(dir + "/light.xml", &error);
  ASSERT_NE(file, nullptr) << error;
  EXPECT_TRUE(GetCouplingLimit(file, 0, 1).consistent);
  EXPECT_NEAR(GetCouplingLimit(file, 0, 1).omega_h, 1.33, 0.01);
  Detach(file);
  mj_deleteModel(file);
  mjModel* set = LoadModel(dir + "/light.xml", {{"option", "timestep", "0.001"}}, &error);
  ASSERT_NE(set, nullptr) << error;
  EXPECT_EQ(set->opt.timestep, 0.001);
  EXPECT_FALSE(GetCouplingLimit(set, 0, 1).consistent);
  EXPECT_NEAR(GetCouplingLimit(set, 0, 1).omega_h, 0.66, 0.01);
  Detach(set);
  mj_deleteModel(set);

  std::string output;
  ASSERT_EQ(RunCli("run " + dir + "/light.xml --duration 0.5 --every 0.01 --log " + dir +
                       "/set.csv --set option.timestep=0.001",
                   &output),
            0)
      << output;
  ASSERT_EQ(RunCli("run " + dir + "/hand.xml --duration 0.5 --every 0.01 --log " + dir +
                       "/hand.csv",
                   &output),
            0)
      << output;
  ASSERT_EQ(RunCli("run " + dir + "/light.xml --duration 0.5 --every 0.01 --log " + dir +
                       "/file.csv",
                   &output),
            0)
      << output;
  const std::string by_set = Read(dir + "/set.csv");
  EXPECT_GT(by_set.size(), 1000u);
  EXPECT_EQ(by_set, Read(dir + "/hand.csv"));
  EXPECT_NE(by_set, Read(dir + "/file.csv"));  // the step matters here

  // `info --set` prints the advice at that step.
  ASSERT_EQ(RunCli("info " + dir + "/light.xml --set option.timestep=0.001", &output), 0) << output;
  EXPECT_TRUE(Contains(output, "timestep 0.001 s")) << output;
  EXPECT_TRUE(Contains(output, "held end force")) << output;
  ASSERT_EQ(RunCli("info " + dir + "/light.xml", &output), 0) << output;
  EXPECT_TRUE(Contains(output, "consistent coupling")) << output;

  Write(dir + "/manifest.csv", "id,model,duration,option.timestep\nfine,light.xml,0.5,0.001\n");
  ASSERT_EQ(RunCli("sweep " + dir + "/manifest.csv --out " + dir + "/out --every 0.01", &output),
            0)
      << output;
  EXPECT_EQ(Read(dir + "/out/fine.log.csv"), by_set);
}

// `run --set option.KEY=...`: only the step, in (0, 1] s; anything else exit 2, named.
TEST(RunSet, AStepOutOfRangeOrAnotherOptionIsBadInput) {
  std::string output;
  EXPECT_EQ(RunCli("run " + kScene + " --duration 0.1 --set option.timestep=0", &output), 2);
  EXPECT_TRUE(Contains(output, "'option.timestep=0'")) << output;
  EXPECT_TRUE(Contains(output, "allowed: (0, 1] s")) << output;
  EXPECT_EQ(RunCli("run " + kScene + " --duration 0.1 --set option.timestep=1e-3x", &output), 2);
  EXPECT_TRUE(Contains(output, "is not a number")) << output;
  EXPECT_EQ(RunCli("run " + kScene + " --duration 0.1 --set option.gravity=0,0,0", &output), 2);
  EXPECT_TRUE(Contains(output, "only timestep can be overridden")) << output;
}

// `run --set` with a misspelt key: exit 2, the key named.
TEST(RunSet, UnknownKeyIsBadInput) {
  std::string output;
  EXPECT_EQ(RunCli("run " + kScene + " --duration 0.1 --set tether:umbilical.EAX=1", &output), 2);
  EXPECT_TRUE(Contains(output, "'EAX'")) << output;
  EXPECT_EQ(RunCli("run " + kScene + " --duration 0.1 --set water.current", &output), 2);
  EXPECT_TRUE(Contains(output, "TEXT.KEY=VALUE")) << output;
}

// ---------------------------------------------------------------------------------------------
// Sweeps

const double kDuration = 2;  // [s] simulated per row: past the thrust ramp, cheap

// The manifest of most tests: the model relative to the manifest (in a sub-folder), a quoted
// list, an empty cell (no override), and an id column.
std::string MakeManifest(const std::string& dir) {
  std::system(
      ("mkdir -p '" + dir + "/models' && cp '" + kScene + "' '" + dir + "/models/'").c_str());
  std::ostringstream m;
  m << "id,model,duration,water.current,tether:umbilical.EA,tether:umbilical.EAc\n"
    << "stiff,models/rov_tether.xml," << kDuration << ",\"0.6,0,0\",4e5,4e5\n"
    << "plain,models/rov_tether.xml," << kDuration << ",,,\n"
    << "soft,models/rov_tether.xml," << kDuration << ",\"0,0.3,0\",1e5,1e5\n";
  Write(dir + "/manifest.csv", m.str());
  return dir + "/manifest.csv";
}

// A row run by the sweep writes the same log, byte for byte, as `mjtether run` of the model
// edited by hand with the row's values; the rows really differ; the summary has a status,
// exit code, peak tension (at least the largest logged tension) and the final pose (the log's
// last position).
TEST(Sweep, RowMatchesRunOfTheHandEditedModel) {
  const std::string dir = TempFolder("identity");
  const std::string manifest = MakeManifest(dir);
  std::string output;
  ASSERT_EQ(RunCli("sweep " + manifest + " --out " + dir + "/out --jobs 2", &output), 0) << output;
  Write(dir + "/hand.xml",
        HandEdited({{"current=0.3,0,0", "current=0.6,0,0"}, {"EA=2e5 EAc=2e5", "EA=4e5 EAc=4e5"}}));
  ASSERT_EQ(RunCli("run " + dir + "/hand.xml --duration 2 --log " + dir + "/hand.csv", &output), 0)
      << output;
  const std::string stiff = Read(dir + "/out/stiff.log.csv");
  EXPECT_GT(stiff.size(), 1000u);
  EXPECT_EQ(stiff, Read(dir + "/hand.csv"));
  ASSERT_EQ(RunCli("run " + kScene + " --duration 2 --log " + dir + "/plain.csv", &output), 0);
  EXPECT_EQ(Read(dir + "/out/plain.log.csv"), Read(dir + "/plain.csv"));
  EXPECT_NE(stiff, Read(dir + "/out/plain.log.csv"));

  const auto rows = Summary(dir + "/out/summary.csv");
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("status"), "ok");
    EXPECT_EQ(row.at("exit_code"), "0");
    EXPECT_EQ(row.at("vehicle"), "rov");
    EXPECT_EQ(row.at("peak_tether"), "umbilical");
    EXPECT_GT(std::stod(row.at("wall_time")), 0);
    EXPECT_DOUBLE_EQ(std::stod(row.at("sim_time")), kDuration);
    // The log: largest of tension_A, tension_B, tension_max over the samples; last position.
    std::string error;
    auto log = cli::ParseCsv(Read(dir + "/out/" + row.at("log")), &error);
    ASSERT_TRUE(log && log->size() > 2);
    double logged = 0;
    for (size_t r = 1; r < log->size(); ++r) {
      for (int c : {4, 5, 6}) logged = std::max(logged, std::stod((*log)[r].fields[c]));
    }
    const std::vector<std::string>& last = log->back().fields;
    EXPECT_GE(std::stod(row.at("peak_tension")), logged * (1 - 1e-8)) << row.at("id");
    // The log prints 9 significant digits.
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(std::stod(row.at(std::string(1, "xyz"[i]))), std::stod(last[1 + i]), 1e-7)
          << row.at("id");
    }
    const double qn = std::hypot(std::hypot(std::stod(row.at("qw")), std::stod(row.at("qx"))),
                                 std::hypot(std::stod(row.at("qy")), std::stod(row.at("qz"))));
    EXPECT_NEAR(qn, 1, 1e-9);
  }
  EXPECT_EQ(rows[0].at("water.current"), "0.6,0,0");
  EXPECT_EQ(rows[1].at("id"), "plain");
}

// Resume: rows recorded for the same values are not run again (their log is left as it is);
// a row without a result, or whose values changed, is.
TEST(Sweep, ResumeSkipsRowsAlreadyDone) {
  const std::string dir = TempFolder("resume");
  const std::string manifest = MakeManifest(dir);
  const std::string out = dir + "/out";
  std::string output;
  ASSERT_EQ(RunCli("sweep " + manifest + " --out " + out, &output), 0) << output;
  const std::string soft = Read(out + "/soft.log.csv");
  Write(out + "/stiff.log.csv", "left alone\n");
  Write(out + "/plain.log.csv", "left alone\n");
  std::remove((out + "/plain.result.csv").c_str());
  // Row "soft" changes: its current.
  std::string m = Read(manifest);
  m.replace(m.find("\"0,0.3,0\""), 9, "\"0,0.2,0\"");
  Write(manifest, m);
  ASSERT_EQ(RunCli("sweep " + manifest + " --out " + out, &output), 0) << output;
  EXPECT_TRUE(Contains(output, "3 rows, 1 already done, 2 to run")) << output;
  EXPECT_EQ(Read(out + "/stiff.log.csv"), "left alone\n");
  EXPECT_NE(Read(out + "/plain.log.csv"), "left alone\n");
  EXPECT_NE(Read(out + "/soft.log.csv"), soft);
  EXPECT_EQ(Summary(out + "/summary.csv")[2].at("water.current"), "0,0.2,0");
}

// A row that diverges is recorded with its exit code and message, the other rows still run,
// and the sweep exits 1.
TEST(Sweep, FailingRowIsRecordedAndTheOthersRun) {
  const std::string dir = TempFolder("failing");
  MakeManifest(dir);
  Write(dir + "/manifest.csv",
        "model,duration,tether:umbilical.integrator,tether:umbilical.substeps\n"
        "models/rov_tether.xml,1,,\n"
        "models/rov_tether.xml,1,explicit,1\n"
        "models/rov_tether.xml,1,,\n");
  std::string output;
  EXPECT_EQ(RunCli("sweep " + dir + "/manifest.csv --out " + dir + "/out", &output), 1) << output;
  const auto rows = Summary(dir + "/out/summary.csv");
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0].at("status"), "ok");
  EXPECT_EQ(rows[1].at("status"), "diverged");
  EXPECT_EQ(rows[1].at("exit_code"), "1");
  EXPECT_TRUE(Contains(rows[1].at("message"), "tether 'umbilical' diverged"))
      << rows[1].at("message");
  EXPECT_EQ(rows[2].at("status"), "ok");
  EXPECT_TRUE(Contains(Read(dir + "/out/2.stderr.txt"), "diverged"));
}

// Bad input in the manifest stops the sweep before any row runs, with exit 2 and a message
// naming the line, the row and the column or key.
TEST(Sweep, BadInputExitsTwoNamingRowAndKey) {
  const std::string dir = TempFolder("bad");
  MakeManifest(dir);
  struct Case {
    std::string manifest;
    std::vector<std::string> expected;
  };
  const std::vector<Case> cases = {
      {"model,duration,tether:umbilical.EA\nmodels/rov_tether.xml,1,1e5\n"
       "models/rov_tether.xml,1,-5\n",
       {"line 3 (row 2", "'EA'", "out of range"}},
      {"model,duration,tether:umbilical.EA\nmodels/rov_tether.xml,1,2e99\n",
       {"line 2 (row 1", "'EA'"}},
      {"model,duration,tether:nope.EA\nmodels/rov_tether.xml,1,1e5\n", {"row 1", "tether:nope"}},
      {"model,duration,water.current\nmodels/rov_tether.xml,1,0.5 0 0\n",
       {"row 1", "water.current", "white space"}},
      {"model,duration,EA\nmodels/rov_tether.xml,1,1e5\n", {"line 1", "'EA'", "TEXT.KEY"}},
      {"model,duration\nmissing.xml,1\n", {"row 1", "missing.xml", "no such file"}},
      {"model,duration\nmodels/rov_tether.xml,-1\n", {"row 1", "'duration'"}},
      {"model,id\nmodels/rov_tether.xml,a\n", {"'model' and 'duration'"}},
      {"model,duration,id\nmodels/rov_tether.xml,1,a\nmodels/rov_tether.xml,1,a\n",
       {"row 2", "'a' is also the id of row 1"}},
  };
  for (const Case& c : cases) {
    Write(dir + "/manifest.csv", c.manifest);
    std::string output;
    EXPECT_EQ(RunCli("sweep " + dir + "/manifest.csv --out " + dir + "/out", &output), 2)
        << c.manifest << output;
    for (const std::string& e : c.expected) EXPECT_TRUE(Contains(output, e)) << e << ": " << output;
    EXPECT_FALSE(std::ifstream(dir + "/out/summary.csv")) << "no row ran: " << c.manifest;
  }
}

// The progress bar goes to a terminal only (drawn in place); to a file, one plain line per row.
// The default number of rows at once is the cores this process may use (taskset: 1).
TEST(Sweep, ProgressBarOnlyOnATerminal) {
  const std::string dir = TempFolder("progress");
  const std::string manifest = MakeManifest(dir);
  std::string output;
  ASSERT_EQ(RunShell("taskset -c 0 " + std::string(MJTETHER_CLI) + " sweep " + manifest +
                         " --out " + dir + "/file",
                     &output),
            0)
      << output;
  EXPECT_TRUE(Contains(output, "to run on 1 core(s)")) << output;
  EXPECT_TRUE(Contains(output, "row 2 (id plain) ok in ")) << output;
  EXPECT_FALSE(Contains(output, "\r")) << output;
  // script(1) gives the sweep a terminal.
  ASSERT_EQ(RunShell("script -qec '" + std::string(MJTETHER_CLI) + " sweep " + manifest +
                         " --out " + dir + "/tty' /dev/null",
                     &output),
            0)
      << output;
  EXPECT_TRUE(Contains(output, "\r\033[K[##############################] 3/3 rows")) << output;
  EXPECT_FALSE(Contains(output, "ok in ")) << output;
}

// SIGTERM stops the sweep and its running rows: exit 143, the rows stopped are not recorded
// as done (summary: pending), so that a resume runs them again. The signal is sent once both
// rows have started (their stderr files exist: the sweep handles signals from before the first
// row starts), not after a fixed second: under ASan on a loaded machine (session 40's CI, with
// two builds beside it) a second was not enough to reach the rows, and the default action of
// SIGTERM ended the sweep before it had a summary to write.
TEST(Sweep, InterruptedRowsAreNotDone) {
  const std::string dir = TempFolder("interrupt");
  MakeManifest(dir);
  Write(dir + "/manifest.csv",
        "model,duration\nmodels/rov_tether.xml,600\nmodels/rov_tether.xml,600\n");
  std::string output;
  const std::string started = "[ -e " + dir + "/out/1.stderr.txt ] && [ -e " + dir +
                              "/out/2.stderr.txt ]";
  const int status =
      RunShell(std::string(MJTETHER_CLI) + " sweep " + dir + "/manifest.csv --out " + dir +
                   "/out --jobs 2 --every 10 & i=0; while [ $i -lt 1200 ] && ! { " + started +
                   "; }; do sleep 0.05; i=$((i+1)); done; sleep 0.2; kill -TERM $!; wait $!",
               &output);
  EXPECT_EQ(status, 143) << output;
  EXPECT_TRUE(Contains(output, "interrupted; 2 rows, 0 ok, 2 not ok")) << output;
  EXPECT_FALSE(std::ifstream(dir + "/out/1.result.csv"));
  const auto rows = Summary(dir + "/out/summary.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].at("status"), "pending");
  EXPECT_EQ(rows[1].at("status"), "pending");
}

// The Slurm scripts, run by hand as the array's tasks would be (SLURM_ARRAY_TASK_ID 0..2),
// then the merge: blocks of rows as written in the script, and a summary and logs identical
// to the local sweep's but for the wall times.
TEST(Sweep, SlurmScriptTasksGiveTheLocalSweep) {
  const std::string dir = TempFolder("slurm");
  const std::string manifest = MakeManifest(dir);
  std::string m = Read(manifest);
  for (int r = 0; r < 4; ++r) {
    m += "r" + std::to_string(r) + ",models/rov_tether.xml,1,\"0." + std::to_string(r + 1) +
         ",0,0\",,\n";
  }
  Write(manifest, m);  // 7 rows
  std::string output;
  ASSERT_EQ(RunCli("sweep " + manifest + " --out " + dir + "/local", &output), 0) << output;
  ASSERT_EQ(RunCli("sweep " + manifest + " --out " + dir + "/array --slurm --tasks 3", &output), 0)
      << output;
  const std::string script = Read(dir + "/array/sweep.sbatch");
  EXPECT_TRUE(Contains(script, "#SBATCH --array=0-2\n")) << script;
  EXPECT_TRUE(Contains(script, "blocks=(1-2 3-4 5-7)")) << script;
  for (int task = 0; task < 3; ++task) {
    EXPECT_EQ(RunShell("cd '" + dir + "/array' && SLURM_ARRAY_TASK_ID=" + std::to_string(task) +
                           " SLURM_CPUS_PER_TASK=1 bash sweep.sbatch",
                       &output),
              0)
        << output;
  }
  EXPECT_FALSE(std::ifstream(dir + "/array/summary.csv")) << "tasks write no summary";
  ASSERT_EQ(RunShell("cd '" + dir + "/array' && bash merge.sbatch", &output), 0) << output;
  auto local = Summary(dir + "/local/summary.csv");
  auto array = Summary(dir + "/array/summary.csv");
  ASSERT_EQ(local.size(), 7u);
  ASSERT_EQ(array.size(), 7u);
  for (size_t r = 0; r < local.size(); ++r) {
    EXPECT_EQ(array[r].at("status"), "ok");
    local[r].erase("wall_time");
    array[r].erase("wall_time");
    EXPECT_EQ(local[r], array[r]) << "row " << r + 1;
    const std::string log = "/" + local[r].at("log");
    EXPECT_EQ(Read(dir + "/local" + log), Read(dir + "/array" + log)) << log;
  }
}

// `plot TABLE.csv --x --y --by`: one series per value, rows not ok left out and counted; an
// unknown column is bad input naming it and the columns there are.
TEST(Plot, SummaryColumns) {
  const std::string dir = TempFolder("plot");
  Write(dir + "/summary.csv",
        "id,water.current,tether:umbilical.EA,status,peak_tension\n"
        "a,\"0.1,0,0\",1e5,ok,10\n"
        "b,\"0.2,0,0\",1e5,ok,12\n"
        "c,\"0.1,0,0\",2e5,ok,11\n"
        "d,\"0.2,0,0\",2e5,diverged,\n"
        "e,\"0.3,0,0\",2e5,ok,15\n");
  std::string output;
  ASSERT_EQ(RunCli("plot " + dir +
                       "/summary.csv --x 'water.current[0]' --y peak_tension --by "
                       "tether:umbilical.EA --out " +
                       dir + "/p.png",
                   &output),
            0)
      << output;
  EXPECT_TRUE(Contains(output, "left out 1 rows whose status is not ok")) << output;
  EXPECT_TRUE(Contains(output, "plotted 4 points in 2 series")) << output;
  EXPECT_EQ(Read(dir + "/p.png").substr(1, 3), "PNG");
  EXPECT_EQ(
      RunCli("plot " + dir + "/summary.csv --x current --y peak_tension --out " + dir + "/q.png",
             &output),
      2);
  EXPECT_TRUE(Contains(output, "no column 'current' (columns: id, water.current")) << output;
}

}  // namespace
}  // namespace mjtether
