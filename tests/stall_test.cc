// `mjtether run` warns once per run, at its end, when an implicit tether accepted steps whose
// Newton iteration did not converge even at 1/256 of the step (StepStatus::stalled_steps),
// naming the file, the tether and what to change; a run without such steps says nothing.
// Stalled steps cost up to 256 normal ones (the fuzzer's seed 346: 130 s of wall per simulated
// second), so the run also says so once, as soon as it sees the first, with its time.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

namespace {

int RunCli(const std::string& args, std::string* output) {
  const std::string out = ::testing::TempDir() + "/stall_cli_" + std::to_string(getpid());
  const int status = std::system(
      (std::string(MJTETHER_CLI) + " " + args + " > " + out + " 2>&1 < /dev/null").c_str());
  std::ifstream f(out);
  std::stringstream s;
  s << f.rdbuf();
  *output = s.str();
  std::remove(out.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int Count(const std::string& text, const std::string& part) {
  int n = 0;
  for (size_t i = text.find(part); i != std::string::npos; i = text.find(part, i + 1)) ++n;
  return n;
}

// A very stiff (EA 1e9 N), damped line of 100 segments hanging from a heaving boat onto a
// seabed, at a 50 ms MuJoCo step: a heave of 1 m makes the implicit step stall (the segments
// snap between slack and taut within a step faster than Newton can follow, even in 1/256 of
// it); a heave of 0.2 m does not.
std::string Scene(const std::string& heave) {
  return R"(<mujoco><option timestep="0.05"/>
<custom><text name="water" data="density=1025 seabed=-5"/>
<text name="tether:umbilical" data="ends=a,b length=30 segments=100 diameter=0.02
  mass_per_length=0.5 EA=1e9 Cdn=1.2 Cdt=0.01 Can=1 integrator=implicit damping=200"/>
<text name="motion:boat" data="z=)" +
         heave + R"(,4,0"/></custom>
<worldbody><body name="boat" mocap="true"><site name="a"/></body>
<site name="b" pos="10 0 -4"/></worldbody></mujoco>)";
}

TEST(StallWarning, PrintedOnceAtTheEndOfARunWithStalledSteps) {
  const std::string path = ::testing::TempDir() + "/stall_scene.xml";
  std::ofstream(path) << Scene("1");
  std::string output;
  EXPECT_EQ(RunCli("run " + path + " --duration 1", &output), 0) << output;
  EXPECT_EQ(Count(output, "Newton iteration not converged"), 1) << output;
  EXPECT_NE(output.find("mjtether: warning: " + path + ": tether 'umbilical': "), std::string::npos)
      << output;
  EXPECT_NE(output.find("implicit step(s) were accepted"), std::string::npos) << output;
  // What to change: the time step, the segments, the integrator.
  EXPECT_NE(output.find("Reduce <option timestep> (now 0.05 s) or set max_step"), std::string::npos)
      << output;
  EXPECT_NE(output.find("use fewer segments (now 100)"), std::string::npos) << output;
  EXPECT_NE(output.find("or use integrator=implicit2"), std::string::npos) << output;
}

TEST(StallWarning, NoticedOnceAsSoonAsSeenBeforeTheFinalWarning) {
  const std::string path = ::testing::TempDir() + "/stall_notice.xml";
  std::ofstream(path) << Scene("1");
  std::string output;
  EXPECT_EQ(RunCli("run " + path + " --duration 1", &output), 0) << output;
  const std::string notice = "mjtether: note: " + path + ": tether 'umbilical': its implicit " +
                             "steps began to stall at t = ";
  EXPECT_EQ(Count(output, notice), 1) << output;
  // Before the end-of-run warning, and at the time that warning gives for the first stall.
  const size_t at_notice = output.find(notice), at_warning = output.find("mjtether: warning: ");
  ASSERT_NE(at_notice, std::string::npos) << output;
  ASSERT_NE(at_warning, std::string::npos) << output;
  EXPECT_LT(at_notice, at_warning) << output;
  const double t_notice = std::strtod(output.c_str() + at_notice + notice.size(), nullptr);
  const std::string first = "the first in the step to t = ";
  const size_t at_first = output.find(first);
  ASSERT_NE(at_first, std::string::npos) << output;
  EXPECT_EQ(t_notice, std::strtod(output.c_str() + at_first + first.size(), nullptr)) << output;
}

TEST(StallWarning, AbsentWhenNoStepStalled) {
  const std::string path = ::testing::TempDir() + "/stall_quiet.xml";
  std::ofstream(path) << Scene("0.2");
  std::string output;
  EXPECT_EQ(RunCli("run " + path + " --duration 1", &output), 0) << output;
  EXPECT_EQ(output.find("not converged"), std::string::npos) << output;
  EXPECT_EQ(output.find("began to stall"), std::string::npos) << output;
}

// Fuzzer seed 346: a 370 kg vehicle 7.4 m from its TMS on 9.8 m of a stiff line (111 segments,
// EA 2.5e8 N) that lies partly on a seabed 3.2 m down, implicit, at 2 ms. From t = 0.022 s every
// step stalls, even at 1/256 of it; before session 14 the run went on for its whole duration
// (130 s of CPU per simulated second) and ended with the vehicle-end tension frozen at 76 N
// against 0.195 N at 0.2 ms. Now 50 stalled MuJoCo steps in a row stop it (exit 1), with the
// time, the cause and what to change; at 0.2 ms no step stalls and the run goes to its end,
// so the step is the cause, as the message says.
std::string Seed346(const std::string& step) {
  return R"(<mujoco><option timestep=")" + step + R"("/><custom>
<text name="water" data="density=1025 seabed=-3.155209832"/>
<text name="vehicle:rov" data="volume=0.3681942212 cob=0,0,0.07175483495
  added_mass=165.60486,207.6434356,287.6279662,9.510992812,9.510992812,9.510992812
  linear_damping=651.3491577,651.3491577,651.3491577,31.70330937,31.70330937,31.70330937
  quadratic_damping=263.8737624,263.8737624,263.8737624,31.70330937,31.70330937,31.70330937
  coriolis=0"/>
<text name="tether:t" data="ends=tms_site,att length=9.829472374 segments=111
  diameter=0.006899390972 mass_per_length=0.07618550731 EA=249787896.3 Cdn=1.2 Cdt=0.01 Can=1
  integrator=implicit"/>
</custom><worldbody>
<body name="tms" mocap="true"><site name="tms_site"/></body>
<body name="rov" pos="7.224253317 1.522510027 -3.095680786"><freejoint/><inertial pos="0 0 0"
  mass="369.4481613" diaginertia="31.70330937 31.70330937 31.70330937"/><site name="att"/></body>
</worldbody></mujoco>)";
}

TEST(StallStop, FiftyStalledStepsInARowStopTheRunWithTheCauseAndTheFineStepRuns) {
  const std::string coarse = ::testing::TempDir() + "/stall_346.xml";
  std::ofstream(coarse) << Seed346("0.002");
  std::string output;
  EXPECT_EQ(RunCli("run " + coarse + " --duration 0.3", &output), 1) << output;
  const std::string stop = "mjtether: " + coarse + ": tether 't' stopped at t = ";
  const size_t at = output.find(stop);
  ASSERT_NE(at, std::string::npos) << output;
  // 50 steps after the first stall (0.022 s): at 0.12 s, not at the end of the run.
  const double t_stop = std::strtod(output.c_str() + at + stop.size(), nullptr);
  EXPECT_NEAR(t_stop, 0.022 + 49 * 0.002, 1e-9) << output;
  EXPECT_NE(output.find("its implicit steps did not converge in 50 MuJoCo steps in a row"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("Reduce <option timestep> (now 0.002 s) or set max_step"),
            std::string::npos)
      << output;
  EXPECT_NE(output.find("or use integrator=implicit2 or explicit"), std::string::npos) << output;
  // Said once: the end-of-run stall warning leaves out the tether the stop named.
  EXPECT_EQ(output.find("accepted with the Newton iteration not converged"), std::string::npos)
      << output;
  const std::string fine = ::testing::TempDir() + "/stall_346_fine.xml";
  std::ofstream(fine) << Seed346("0.0002");
  EXPECT_EQ(RunCli("run " + fine + " --duration 0.3", &output), 0) << output;
  EXPECT_EQ(output.find("began to stall"), std::string::npos) << output;
  EXPECT_EQ(output.find("not converged"), std::string::npos) << output;
}

}  // namespace
