// Runs a command line (the real mjtether binary) in a directory with a timeout, as a user's
// shell would: stdin from /dev/null, stdout and stderr together. Shared by the hostile-input
// suite (tests/hostile_test.cc) and its generator (tests/hostile_gen_test.cc).
#ifndef MJTETHER_TESTS_RUN_BINARY_H_
#define MJTETHER_TESTS_RUN_BINARY_H_

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

namespace mjtether::test_util {

struct BinaryRun {
  bool started = false;  // fork succeeded
  bool hung = false;     // killed after the timeout
  bool exited = false;   // ended by exit() (not by a signal)
  int code = -1;         // exit code when exited
  int signal = 0;        // the signal that ended it otherwise
  double seconds = 0;    // wall-clock time
  std::string output;    // stdout and stderr
};

inline std::string ReadFileBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// `command` runs under /bin/sh in `dir`, its output to dir/.output. `send` (SIGINT or SIGTERM,
// 0 for none) is sent `send_at` seconds after the start; after `timeout` seconds the process is
// killed and the run reported as hung.
inline BinaryRun RunBinary(const std::string& dir, const std::string& command, double timeout,
                           int send = 0, double send_at = -1) {
  BinaryRun run;
  const std::string out = dir + "/.output";
  const std::string line = "exec " + command;
  const pid_t pid = fork();
  if (pid < 0) return run;
  if (pid == 0) {
    if (chdir(dir.c_str()) != 0) _exit(126);
    if (!freopen("/dev/null", "r", stdin) || !freopen(out.c_str(), "w", stdout)) _exit(126);
    dup2(fileno(stdout), 2);
    execl("/bin/sh", "sh", "-c", line.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  run.started = true;
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  while (true) {
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    const double t =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (send && t >= send_at) {
      kill(pid, send);
      send = 0;
    }
    if (t > timeout) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      run.hung = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.output = ReadFileBytes(out);
  std::remove(out.c_str());
  if (!run.hung) {
    run.exited = WIFEXITED(status);
    if (run.exited) {
      run.code = WEXITSTATUS(status);
    } else if (WIFSIGNALED(status)) {
      run.signal = WTERMSIG(status);
    }
  }
  return run;
}

}  // namespace mjtether::test_util

#endif  // MJTETHER_TESTS_RUN_BINARY_H_
