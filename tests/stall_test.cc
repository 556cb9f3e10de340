// `mjtether run` warns once per run, at its end, when an implicit tether accepted steps whose
// Newton iteration did not converge even at 1/256 of the step (StepStatus::stalled_steps),
// naming the file, the tether and what to change; a run without such steps says nothing.
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

TEST(StallWarning, AbsentWhenNoStepStalled) {
  const std::string path = ::testing::TempDir() + "/stall_quiet.xml";
  std::ofstream(path) << Scene("0.2");
  std::string output;
  EXPECT_EQ(RunCli("run " + path + " --duration 1", &output), 0) << output;
  EXPECT_EQ(output.find("not converged"), std::string::npos) << output;
}

}  // namespace
