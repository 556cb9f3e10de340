// A child process (ffmpeg, gnuplot) reading what we write on its stdin: started with
// fork/exec (no shell, so any file name is passed as it is), closed with its exit status.
#ifndef MJTETHER_PLUGIN_CLI_PIPE_H_
#define MJTETHER_PLUGIN_CLI_PIPE_H_

#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace mjtether::cli {

class ChildPipe {
 public:
  // Starts args[0] (looked up on PATH) with the arguments args[1...]. A program that cannot be
  // started exits with status 127 (see Close).
  bool Open(std::vector<std::string> args, std::string* error) {
    int fds[2];
    if (pipe(fds) != 0) {
      *error = std::string("pipe: ") + std::strerror(errno);
      return false;
    }
    pid_ = fork();
    if (pid_ < 0) {
      *error = std::string("fork: ") + std::strerror(errno);
      close(fds[0]);
      close(fds[1]);
      return false;
    }
    if (pid_ == 0) {
      dup2(fds[0], 0);
      close(fds[0]);
      close(fds[1]);
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execvp(argv[0], argv.data());
      std::fprintf(stderr, "mjtether: cannot run %s: %s\n", argv[0], std::strerror(errno));
      _exit(127);
    }
    close(fds[0]);
    fd_ = fds[1];
    return true;
  }

  // Writes all n bytes; false if the child stopped reading (ignore SIGPIPE to see this).
  bool Write(const void* data, size_t n) {
    const char* p = static_cast<const char*>(data);
    while (n > 0) {
      const ssize_t w = write(fd_, p, n);
      if (w < 0) {
        if (errno == EINTR) continue;
        return false;
      }
      p += w;
      n -= static_cast<size_t>(w);
    }
    return true;
  }
  bool Write(const std::string& s) { return Write(s.data(), s.size()); }

  // Closes the pipe and waits; returns the child's exit status (127: not found), or -1.
  int Close() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
    if (pid_ <= 0) return -1;
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }

  ChildPipe() = default;
  ChildPipe(const ChildPipe&) = delete;
  ChildPipe& operator=(const ChildPipe&) = delete;
  ~ChildPipe() { Close(); }

 private:
  int fd_ = -1;
  pid_t pid_ = -1;
};

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_PIPE_H_
