// Shared by the tests that run the command line or render the two-tether scene
// (render_test.cc, render_framing_test.cc, viewer_test.cc).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace mjtether::test_util {

// Runs `command` with /bin/sh, returns its standard output and sets *status to its exit code
// (-1 when it could not start or did not exit normally).
inline std::string Shell(const std::string& command, int* status) {
  std::string out;
  FILE* p = popen(command.c_str(), "r");
  if (!p) {
    *status = -1;
    return out;
  }
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof(buf), p)) > 0) out.append(buf, n);
  const int s = pclose(p);
  *status = WIFEXITED(s) ? WEXITSTATUS(s) : -1;
  return out;
}

// Two straight tethers between world sites, no gravity, dry: each carries the uniform tension
// EA * (span / length - 1) (no other force acts). "hot": 10 m span, 9.5 m long, EA 1.9e4 N:
// T = 1000 N; "mid": same span, EA 0.95e4 N: T = 500 N. On a 0-1000 N scale they are red and
// green. A fixed camera 15 m in front looks along +y.
inline constexpr char kTwoTethers[] = R"(
<mujoco>
  <option gravity="0 0 0"/>
  <custom>
    <text name="tether:hot" data="ends=h0,h1 length=9.5 segments=10 diameter=0.02
          mass_per_length=0.3 EA=1.9e4"/>
    <text name="tether:mid" data="ends=m0,m1 length=9.5 segments=10 diameter=0.02
          mass_per_length=0.3 EA=0.95e4"/>
  </custom>
  <worldbody>
    <site name="h0" pos="0 0 1"/>  <site name="h1" pos="10 0 1"/>
    <site name="m0" pos="0 0 -1"/> <site name="m1" pos="10 0 -1"/>
    <camera name="side" pos="5 -15 0" xyaxes="1 0 0 0 0 1"/>
  </worldbody>
</mujoco>)";

}  // namespace mjtether::test_util
