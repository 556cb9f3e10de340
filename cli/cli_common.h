// What every sub-command of the mjtether tool shares: exit codes, owners of mjModel/mjData,
// checked numbers, safe outputs, SIGINT/SIGTERM and observation without side effects. See
// docs/bad_input.md.
#ifndef MJTETHER_PLUGIN_CLI_COMMON_H_
#define MJTETHER_PLUGIN_CLI_COMMON_H_

#include <fcntl.h>
#include <mujoco/mjxmacro.h>
#include <mujoco/mujoco.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "mjtether.h"
#include "model_files.h"
#include "overrides.h"
#include "text_check.h"
#include "vehicle_declaration.h"

namespace mjtether::cli {

// Exit codes (README, Command line).
enum Exit : int {
  kExitOk = 0,
  kExitDiverged = 1,
  kExitBadInput = 2,
  kExitMuJoCo = 3,
  kExitTool = 4,
  kExitOutput = 5,  // a write or close of an output failed
  kExitCheck = 6,   // run --check-step: the run disagrees with the scene at the smaller step,
                    // or that run stopped where this one did not (cli_step_check.h)
  // 128 + signal number after SIGINT (130) or SIGTERM (143)
};

// ---------------------------------------------------------------------------------------------
// Owners: the model is detached from mjtether before MuJoCo frees it.
struct ModelDeleter {
  void operator()(mjModel* m) const {
    mjtether::Detach(m);
    mj_deleteModel(m);
  }
};
struct DataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;
using DataPtr = std::unique_ptr<mjData, DataDeleter>;

inline DataPtr MakeData(const mjModel* m) { return DataPtr(mj_makeData(m)); }

// Every floating-point number of a loaded model is finite, and the time step is in (0, 1] s:
// MuJoCo accepts timestep="0" (a run never ends), a negative one (time runs backwards) and
// "nan". Returns the problem, naming the file and the <option> or array.
inline std::optional<std::string> CheckModelNumbers(const mjModel* m, const std::string& path) {
  std::ostringstream s;
  const double h = m->opt.timestep;
  if (!(h > 0 && h <= mjtether::kMaxTimestep)) {
    s << path << ": <option timestep=\"" << h << "\">: the time step must be in (0, "
      << mjtether::kMaxTimestep << "] s";
    return s.str();
  }
#define X(type, name)                                                                   \
  if (!std::isfinite(m->opt.name)) {                                                    \
    s << path << ": <option " #name "=\"" << m->opt.name << "\">: not a finite number"; \
    return s.str();                                                                     \
  }
  MJOPTION_FLOATS
#undef X
#define X(name, n)                                                                       \
  for (int i = 0; i < n; ++i) {                                                          \
    if (!std::isfinite(m->opt.name[i])) {                                                \
      s << path << ": <option " #name ">: component " << i << " is not a finite number"; \
      return s.str();                                                                    \
    }                                                                                    \
  }
  MJOPTION_VECTORS
#undef X
  if (m->opt.density < 0 || m->opt.viscosity < 0) {
    s << path << ": <option density/viscosity>: must be >= 0";
    return s.str();
  }
  MJMODEL_POINTERS_PREAMBLE(m)
#define X(type, name, nr, nc)                                                      \
  if constexpr (std::is_same_v<type, mjtNum> || std::is_same_v<type, float>) {     \
    const long long count = static_cast<long long>(m->nr) * (nc);                  \
    for (long long i = 0; i < count; ++i) {                                        \
      if (!std::isfinite(m->name[i])) {                                            \
        s << path << ": a non-finite number in the model (" #name "[" << i / (nc)  \
          << "]): check the attributes of element " << i / (nc) << " of its kind"; \
        return s.str();                                                            \
      }                                                                            \
    }                                                                              \
  }
  MJMODEL_POINTERS
#undef X
      (void)
      nuser_body,
      (void)nuser_jnt, (void)nuser_geom, (void)nuser_site, (void)nuser_cam;
  (void)nuser_tendon, (void)nuser_actuator, (void)nuser_sensor, (void)nq, (void)nv, (void)na;
  (void)nu, (void)nmocap;
  return std::nullopt;
}

// The --set options as overrides (overrides.h); false after naming the first bad one. Every
// sub-command that loads a model (run, info, render, view) takes them, so that what is rendered
// or viewed is the scene that was run.
inline bool ParseSets(const std::vector<std::string>& set, std::vector<mjtether::Override>* out) {
  for (const std::string& spec : set) {
    std::string why;
    std::optional<mjtether::Override> o = mjtether::ParseOverride(spec, &why);
    if (!o) {
      std::cerr << "mjtether: --set " << why << "\n";
      return false;
    }
    out->push_back(*o);
  }
  return true;
}

inline constexpr char kSetHelp[] =
    "override one declaration key, TEXT.KEY=VALUE (e.g. water.current=0.5,0,0), or the step, "
    "option.timestep=SECONDS; repeatable";

// Adds --set to a sub-command (kSetHelp; each occurrence one override).
inline void AddSetOption(CLI::App* sub, std::vector<std::string>* set) {
  sub->add_option("--set", *set, kSetHelp)
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
}

// Loads and attaches a model and checks its numbers; prints the error and the advisor's
// warnings. Null on failure (exit 2).
inline ModelPtr LoadChecked(const std::string& path,
                            const std::vector<mjtether::Override>& overrides = {}) {
  std::string error;
  ModelPtr m(mjtether::LoadModel(path, overrides, &error));
  if (!m) {
    std::cerr << "mjtether: " << error << "\n";
    return nullptr;
  }
  if (std::optional<std::string> bad = CheckModelNumbers(m.get(), path)) {
    std::cerr << "mjtether: " << *bad << "\n";
    return nullptr;
  }
  for (const std::string& w : mjtether::Warnings(m.get())) {
    std::cerr << "mjtether: warning: " << w << "\n";
  }
  return m;
}

// A count on the command line: decimal digits only, in [lo, hi] ("2.5", "1e3" and "-1" are
// named as what they are, not "out of range").
inline CLI::Validator Count(long long lo, long long hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const bool digits =
            !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
        if (!digits) return "'" + Shown(text) + "' is not a whole number; allowed: " + range;
        const long long x = text.size() <= 18 ? std::stoll(text) : hi + 1;  // no overflow
        if (x < lo || x > hi) return "'" + Shown(text) + "' is out of range; allowed: " + range;
        return "";
      },
      range, "INT");
}

// ---------------------------------------------------------------------------------------------
// Numbers on the command line: plain decimals (no nan, inf or hexadecimal) in a range.
inline CLI::Validator Number(double lo, double hi, bool lo_open, const std::string& unit) {
  std::ostringstream r;
  r << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
  const std::string range = r.str();
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double x = 0;
        const NumberStatus status = ParseDecimal(text, &x);
        if (status != NumberStatus::kOk && status != NumberStatus::kUnderflow) {
          return "'" + Shown(text) + "' " + NumberProblem(status) + "; allowed: " + range +
                 (unit.empty() ? "" : " " + unit);
        }
        if (status == NumberStatus::kUnderflow || !((lo_open ? x > lo : x >= lo) && x <= hi)) {
          return "'" + Shown(text) + "' is out of range; allowed: " + range +
                 (unit.empty() ? "" : " " + unit);
        }
        return "";
      },
      range, "NUMBER");
}

// ---------------------------------------------------------------------------------------------
// SIGINT and SIGTERM: the loops stop at the next step boundary (a second signal kills).
inline volatile std::sig_atomic_t g_stop_signal = 0;

inline void OnStopSignal(int signal) { g_stop_signal = signal; }

inline void InstallStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART | SA_RESETHAND;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

inline int StopSignal() { return g_stop_signal; }

// "interrupted by SIGINT at t = 1.25 s (step 625 of 5000)", printed when a run stops early.
inline std::string Interrupted(int signal, double time, long long step, long long steps) {
  std::ostringstream s;
  s << "interrupted by "
    << (signal == SIGINT    ? "SIGINT"
        : signal == SIGTERM ? "SIGTERM"
                            : "signal")
    << " at t = " << time << " s (step " << step << " of " << steps << ")";
  return s.str();
}

// ---------------------------------------------------------------------------------------------
// Files: identity by device and inode; an output that does not exist yet is identified by its
// directory's device and inode and its name.
struct FileId {
  dev_t dev = 0;
  ino_t ino = 0;
  std::string leaf;  // empty when the file exists
  bool operator==(const FileId& o) const { return dev == o.dev && ino == o.ino && leaf == o.leaf; }
};

inline std::string DirOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}
inline std::string LeafOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

inline std::optional<FileId> IdOf(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) == 0) return FileId{st.st_dev, st.st_ino, ""};
  if (stat(DirOf(path).c_str(), &st) == 0) return FileId{st.st_dev, st.st_ino, LeafOf(path)};
  return std::nullopt;
}

// The inputs of a run (model, included and asset files, motion csv tables) and the outputs
// already claimed; an output may be none of them.
class OutputGuard {
 public:
  void AddInput(const std::string& path, const std::string& what) {
    if (std::optional<FileId> id = IdOf(path); id && id->leaf.empty()) {
      files_.push_back({*id, what + " " + path});
    }
  }
  // The model's files and the csv tables of its motion: declarations.
  void AddModel(const std::string& path, const mjModel* m) {
    const std::vector<std::string> files = ModelFiles(path);
    for (size_t i = 0; i < files.size(); ++i)
      AddInput(files[i], i ? "the model's file" : "the model");
    const std::string dir = path.find('/') == std::string::npos ? "" : DirOf(path) + "/";
    for (int i = 0; m && i < m->ntext; ++i) {
      const std::string name = m->names + m->name_textadr[i];
      if (name.rfind("motion:", 0) != 0) continue;
      std::optional<MotionParams> p = ParseMotion(m->text_data + m->text_adr[i], nullptr);
      if (p && !p->csv.empty()) {
        AddInput(p->csv[0] == '/' ? p->csv : dir + p->csv, "the motion table");
      }
    }
  }
  // Claims `path` for `option`; false with *error if it is an input or another output.
  bool Claim(const std::string& path, const std::string& option, std::string* error) {
    std::optional<FileId> id = IdOf(path);
    if (!id) {
      *error = option + " " + path + ": its directory does not exist";
      return false;
    }
    for (const Entry& e : files_) {
      if (e.id == *id) {
        *error = option + " " + path + " is the same file as " + e.what +
                 ": refusing to overwrite it (choose another output name)";
        return false;
      }
    }
    files_.push_back({*id, option + " " + path});
    return true;
  }

 private:
  struct Entry {
    FileId id;
    std::string what;
  };
  std::vector<Entry> files_;
};

// The checks every output makes before it is opened: not a directory, and claimed in the
// guard (not an input, not another output).
inline bool ClaimTarget(const std::string& target, const std::string& option, OutputGuard* guard,
                        std::string* error) {
  struct stat st {};
  if (stat(target.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    *error = option + " " + target + " is a directory";
    return false;
  }
  return guard->Claim(target, option, error);
}

// A CSV (or any text) output: written to a temporary file beside its target and renamed into
// place by Commit. Rows are buffered whole and written whole; after a failed write the file is
// cut back to the last complete row. A target that is not a regular file (/dev/null, /dev/full,
// a pipe) is written directly.
class OutputFile {
 public:
  OutputFile() = default;
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile() { Discard(); }

  // Opens the temporary file (exit 2 on failure: a bad option, nothing was touched).
  bool Open(const std::string& target, const std::string& option, OutputGuard* guard,
            std::string* error) {
    target_ = target;
    option_ = option;
    if (!ClaimTarget(target, option, guard, error)) return false;
    struct stat st {};
    if (stat(target.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
      fd_ = open(target.c_str(), O_WRONLY | O_CLOEXEC);
      direct_ = true;
    } else {
      std::string pattern = DirOf(target) + "/." + LeafOf(target) + ".tmp-XXXXXX";
      std::vector<char> buf(pattern.begin(), pattern.end());
      buf.push_back('\0');
      fd_ = mkostemp(buf.data(), O_CLOEXEC);
      if (fd_ >= 0) temp_ = buf.data();
      if (fd_ >= 0) fchmod(fd_, 0666 & ~CurrentUmask());
    }
    if (fd_ < 0) {
      *error = "cannot write " + option + " " + target + ": " + std::strerror(errno);
      return false;
    }
    return true;
  }
  bool is_open() const { return fd_ >= 0; }
  bool failed() const { return failed_; }

  // Appends complete rows (each ending with '\n').
  void Write(const std::string& rows) {
    if (fd_ < 0 || failed_) return;
    buffer_ += rows;
    if (buffer_.size() >= (1u << 16)) Flush();
  }

  // Writes the buffer; false (and the file cut back to its last complete row) on failure.
  bool Flush() {
    if (fd_ < 0 || failed_) return !failed_;
    size_t done = 0;
    while (done < buffer_.size()) {
      const ssize_t w = write(fd_, buffer_.data() + done, buffer_.size() - done);
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) {
        errno_ = w < 0 ? errno : ENOSPC;
        failed_ = true;
        if (!direct_ && ftruncate(fd_, good_) != 0) {
        }
        buffer_.clear();
        return false;
      }
      done += static_cast<size_t>(w);
    }
    good_ += static_cast<off_t>(buffer_.size());
    buffer_.clear();
    return true;
  }

  // Flushes, closes and renames into place (also after a failure or a signal: the complete
  // rows are kept). False with *error on any failed write, close or rename (exit 5).
  bool Commit(std::string* error) {
    if (fd_ < 0) return true;
    Flush();
    if (!direct_ && !failed_ && fsync(fd_) != 0 && errno != EINVAL) {
      failed_ = true;
      errno_ = errno;
    }
    if (close(fd_) != 0 && !failed_) {
      failed_ = true;
      errno_ = errno;
    }
    fd_ = -1;
    if (!temp_.empty()) {
      if (rename(temp_.c_str(), target_.c_str()) != 0) {
        if (!failed_) errno_ = errno;
        failed_ = true;
        unlink(temp_.c_str());
      }
      temp_.clear();
    }
    if (failed_) {
      *error = "output error: " + option_ + " " + target_ + ": " + std::strerror(errno_) +
               " (complete rows up to the failure were kept)";
      return false;
    }
    return true;
  }

  // Removes the temporary file (the target is untouched).
  void Discard() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
    if (!temp_.empty()) unlink(temp_.c_str());
    temp_.clear();
  }

  static mode_t CurrentUmask() {
    const mode_t mask = umask(0);
    umask(mask);
    return mask;
  }

 private:
  std::string target_, option_, temp_, buffer_;
  int fd_ = -1;
  bool direct_ = false, failed_ = false;
  int errno_ = 0;
  off_t good_ = 0;  // bytes of complete rows on disk
};

// An output written by another program (ffmpeg, gnuplot, libpng): a temporary path beside the
// target with the same extension, renamed into place by Commit.
class ToolOutput {
 public:
  ToolOutput() = default;
  ToolOutput(const ToolOutput&) = delete;
  ToolOutput& operator=(const ToolOutput&) = delete;
  ~ToolOutput() { Discard(); }

  bool Open(const std::string& target, const std::string& option, OutputGuard* guard,
            std::string* error) {
    target_ = target;
    option_ = option;
    if (!ClaimTarget(target, option, guard, error)) return false;
    const std::string leaf = LeafOf(target);
    const size_t dot = leaf.find_last_of('.');
    const std::string ext = dot == std::string::npos || dot == 0 ? "" : leaf.substr(dot);
    std::string pattern = DirOf(target) + "/." + leaf + ".tmp-XXXXXX" + ext;
    std::vector<char> buf(pattern.begin(), pattern.end());
    buf.push_back('\0');
    const int fd = mkostemps(buf.data(), static_cast<int>(ext.size()), O_CLOEXEC);
    if (fd < 0) {
      *error = "cannot write " + option + " " + target + ": " + std::strerror(errno);
      return false;
    }
    fchmod(fd, 0666 & ~OutputFile::CurrentUmask());
    close(fd);
    temp_ = buf.data();
    return true;
  }
  const std::string& path() const { return temp_; }  // where the tool writes

  // Renames the tool's file into place when it is not empty.
  bool Commit(std::string* error) {
    if (temp_.empty()) return true;
    struct stat st {};
    if (stat(temp_.c_str(), &st) != 0 || st.st_size == 0) {
      *error = "output error: " + option_ + " " + target_ + ": nothing was written";
      Discard();
      return false;
    }
    if (rename(temp_.c_str(), target_.c_str()) != 0) {
      *error = "output error: " + option_ + " " + target_ + ": " + std::strerror(errno);
      Discard();
      return false;
    }
    temp_.clear();
    return true;
  }
  void Discard() {
    if (!temp_.empty()) unlink(temp_.c_str());
    temp_.clear();
  }

 private:
  std::string target_, option_, temp_;
};

// ---------------------------------------------------------------------------------------------
// Observation without side effects: the state at d->time (every tether brought to d->time, the
// reactions and kinematics of that instant) is computed by mj_forward on a copy, so that
// logging, plotting or rendering at any interval leaves the run bit for bit as it was.
class Observer {
 public:
  explicit Observer(const mjModel* m) : m_(m), scratch_(mj_makeData(m)) {}
  mjData* Observe(const mjData* d) {
    mj_copyData(scratch_.get(), m_, d);
    mj_forward(m_, scratch_.get());
    return scratch_.get();
  }

 private:
  const mjModel* m_;
  DataPtr scratch_;
};

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_COMMON_H_
