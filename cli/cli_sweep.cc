// `mjtether sweep`: many runs of overridden models from a CSV manifest, on every local core, or
// as a Slurm job array (docs/sweeps.md).
//
//   mjtether sweep MANIFEST.csv --out DIR [--jobs N] [--every S] [--rows A-B] [--retry-failed]
//   mjtether sweep MANIFEST.csv --out DIR --merge
//   mjtether sweep MANIFEST.csv --out DIR --slurm [--tasks T] [--cpus-per-task C]
//       [--sbatch-option OPT]...
//
// The manifest has a header; `model` and `duration` are required, `id` names a row's files
// (default: its row number), and every other column TEXT.KEY overrides one declaration key
// (overrides.h; an empty cell: no override in that row). Each row is one `mjtether run` of its
// model in a child process (so a crash or a MuJoCo error ends that row only), writing
// DIR/ID.log.csv, DIR/ID.stderr.txt and DIR/ID.result.csv; DIR/summary.csv gathers the results.
// A row whose result is there, for the same model, duration, overrides and --every, is skipped
// (resume).
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_command.h"
#include "cli_csv.h"
#include "cli_run_summary.h"
#include "mjtether.h"
#include "overrides.h"

namespace fs = std::filesystem;

namespace {

struct SweepOptions {
  std::string manifest;
  std::string out;
  int jobs = 0;  // 0: every core this process may use
  double every = 0.1;
  std::string rows;  // "A-B" or "A", 1-based, inclusive; empty: all
  bool retry_failed = false;
  bool merge = false;
  bool slurm = false;
  int tasks = 0;  // Slurm array tasks; 0: min(rows, 16)
  int cpus_per_task = 1;
  std::vector<std::string> sbatch_options;
};

struct Row {
  int number = 0;  // 1-based data row
  int line = 0;    // line in the manifest
  std::string id;
  std::string model_path;                     // resolved against the manifest's directory
  std::string duration;                       // as written (passed on verbatim)
  std::vector<std::string> cells;             // every manifest column but id, as written
  std::vector<mjtether::Override> overrides;  // the non-empty override cells
};

struct Manifest {
  std::vector<std::string> columns;  // every column but id, in manifest order
  std::vector<Row> rows;
};

std::string ReadFile(const std::string& path, bool* ok) {
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  *ok = static_cast<bool>(f);
  return s.str();
}

// Writes `text` to path through a temporary file and a rename (a reader never sees half).
bool WriteAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp" + std::to_string(getpid());
  {
    std::ofstream f(tmp, std::ios::binary);
    f << text;
    f.close();
    if (!f) return false;
  }
  return std::rename(tmp.c_str(), path.c_str()) == 0;
}

bool ValidId(const std::string& id) {
  if (id.empty() || id.size() > 200 || id[0] == '.') return false;
  for (char c : id) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) {
      return false;
    }
  }
  return true;
}

// Reads and checks the manifest (not the models). Returns false with *error naming the line,
// the row and the column.
bool ReadManifest(const std::string& path, Manifest* mf, std::string* error) {
  bool ok = false;
  const std::string text = ReadFile(path, &ok);
  if (!ok) {
    *error = path + ": cannot read the manifest";
    return false;
  }
  std::string message;
  std::optional<std::vector<mjtether::cli::CsvRecord>> records =
      mjtether::cli::ParseCsv(text, &message);
  if (!records) {
    *error = path + ": " + message;
    return false;
  }
  if (records->empty()) {
    *error = path + ": empty manifest (expected a header with columns model and duration)";
    return false;
  }
  const std::vector<std::string>& header = records->front().fields;
  int col_model = -1, col_duration = -1, col_id = -1;
  std::vector<int> override_cols;
  std::vector<mjtether::Override> override_names;
  for (size_t c = 0; c < header.size(); ++c) {
    const std::string& name = header[c];
    for (size_t e = 0; e < c; ++e) {
      if (header[e] == name) {
        *error = path + ": line 1: column '" + name + "' appears twice";
        return false;
      }
    }
    if (name == "model") {
      col_model = static_cast<int>(c);
    } else if (name == "duration") {
      col_duration = static_cast<int>(c);
    } else if (name == "id") {
      col_id = static_cast<int>(c);
      continue;
    } else {
      mjtether::Override o;
      if (!mjtether::SplitOverrideName(name, &o, &message)) {
        *error =
            path + ": line 1: column " + message + "; the other columns are model, duration and id";
        return false;
      }
      override_cols.push_back(static_cast<int>(c));
      override_names.push_back(o);
    }
    mf->columns.push_back(name);
  }
  if (col_model < 0 || col_duration < 0) {
    *error = path + ": line 1: the header needs columns 'model' and 'duration'";
    return false;
  }
  const fs::path dir = fs::path(path).parent_path();
  std::map<std::string, int> ids;
  for (size_t r = 1; r < records->size(); ++r) {
    const mjtether::cli::CsvRecord& rec = (*records)[r];
    Row row;
    row.number = static_cast<int>(r);
    row.line = rec.line;
    const std::string where =
        path + ": line " + std::to_string(rec.line) + " (row " + std::to_string(r) + ")";
    if (rec.fields.size() != header.size()) {
      *error = where + ": " + std::to_string(rec.fields.size()) + " fields, the header has " +
               std::to_string(header.size());
      return false;
    }
    row.id = col_id >= 0 ? rec.fields[col_id] : std::to_string(r);
    if (!ValidId(row.id)) {
      *error = where + ": column 'id': '" + row.id +
               "' is not a file name part (letters, digits, '_', '-', '.', not starting with "
               "'.')";
      return false;
    }
    if (ids.count(row.id)) {
      *error = where + ": column 'id': '" + row.id + "' is also the id of row " +
               std::to_string(ids[row.id]);
      return false;
    }
    ids[row.id] = row.number;
    const std::string& model = rec.fields[col_model];
    if (model.empty()) {
      *error = where + ": column 'model' is empty";
      return false;
    }
    row.model_path = fs::path(model).is_absolute() ? model : (dir / model).string();
    row.duration = rec.fields[col_duration];
    char* end = nullptr;
    const double duration = std::strtod(row.duration.c_str(), &end);
    if (row.duration.empty() || *end != '\0' || !std::isfinite(duration) || duration < 0 ||
        duration > 1e7) {
      *error = where + ": column 'duration': '" + row.duration +
               "' is not a number of seconds in [0, 1e7]";
      return false;
    }
    for (size_t c = 0; c < header.size(); ++c) {
      if (static_cast<int>(c) != col_id) row.cells.push_back(rec.fields[c]);
    }
    for (size_t k = 0; k < override_cols.size(); ++k) {
      const std::string& value = rec.fields[override_cols[k]];
      if (value.empty()) continue;  // no override in this row
      std::optional<mjtether::Override> o =
          mjtether::ParseOverride(header[override_cols[k]] + "=" + value, &message);
      if (!o) {
        *error = where + ": column '" + header[override_cols[k]] + "': " + message;
        return false;
      }
      row.overrides.push_back(*o);
    }
    mf->rows.push_back(row);
  }
  if (mf->rows.empty()) {
    *error = path + ": no rows after the header";
    return false;
  }
  return true;
}

// Loads each row's model with its overrides: the same parser and range checks as the MJCF.
bool CheckModels(const std::string& path, const std::vector<const Row*>& rows, std::string* error) {
  for (const Row* row : rows) {
    std::string message;
    if (!fs::is_regular_file(row->model_path)) {
      message = row->model_path + ": no such file (model paths are relative to the manifest)";
    } else if (mjModel* m = mjtether::LoadModel(row->model_path, row->overrides, &message)) {
      mjtether::Detach(m);
      mj_deleteModel(m);
      continue;
    }
    *error = path + ": line " + std::to_string(row->line) + " (row " + std::to_string(row->number) +
             ", id " + row->id + "): " + message;
    return false;
  }
  return true;
}

// summary.csv: the row, its id, the manifest's columns, then what happened.
std::vector<std::string> SummaryHeader(const Manifest& mf) {
  std::vector<std::string> h = {"row", "id"};
  h.insert(h.end(), mf.columns.begin(), mf.columns.end());
  for (const char* c : {"log_every", "status", "exit_code", "message", "wall_time"}) {
    h.push_back(c);
  }
  std::stringstream run(mjtether::cli::RunSummary::kHeader);
  std::string c;
  while (std::getline(run, c, ',')) h.push_back(c);
  h.push_back("log");
  return h;
}

std::string Num(double v) { return mjtether::cli::Shortest(v); }

// The first fields of a row's summary line: what defines the run (resume compares them).
std::vector<std::string> RowSpec(const Row& row, const SweepOptions& opt) {
  std::vector<std::string> f = {std::to_string(row.number), row.id};
  f.insert(f.end(), row.cells.begin(), row.cells.end());
  f.push_back(Num(opt.every));
  return f;
}

std::string ResultPath(const SweepOptions& opt, const Row& row) {
  return (fs::path(opt.out) / (row.id + ".result.csv")).string();
}

// The row's recorded result if it is there for the same header and spec, else nullopt.
std::optional<std::vector<std::string>> ReadResult(const SweepOptions& opt, const Manifest& mf,
                                                   const Row& row) {
  bool ok = false;
  const std::string text = ReadFile(ResultPath(opt, row), &ok);
  if (!ok) return std::nullopt;
  std::string error;
  auto records = mjtether::cli::ParseCsv(text, &error);
  if (!records || records->size() != 2 || (*records)[0].fields != SummaryHeader(mf)) {
    return std::nullopt;
  }
  const std::vector<std::string>& fields = (*records)[1].fields;
  const std::vector<std::string> spec = RowSpec(row, opt);
  // Field 0, the row number, may differ (rows inserted above): the id names the row.
  if (fields.size() != SummaryHeader(mf).size() ||
      !std::equal(spec.begin() + 1, spec.end(), fields.begin() + 1)) {
    return std::nullopt;
  }
  std::vector<std::string> current = fields;
  current[0] = spec[0];
  return current;
}

// Index of the `status` field in a summary line.
size_t StatusField(const Manifest& mf) { return 2 + mf.columns.size() + 1; }

// ---------------------------------------------------------------------------------------------
// Running rows in child processes

volatile std::sig_atomic_t g_signal = 0;
void OnSignal(int s) { g_signal = s; }

int UsableCores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1L, sysconf(_SC_NPROCESSORS_ONLN));
}

struct Child {
  const Row* row = nullptr;
  std::chrono::steady_clock::time_point start;
};

// Starts `mjtether run` for one row; its stdout and stderr go to DIR/ID.stderr.txt.
pid_t StartRow(const SweepOptions& opt, const Row& row) {
  const fs::path out(opt.out);
  std::vector<std::string> args = {"mjtether",
                                   "run",
                                   row.model_path,
                                   "--duration",
                                   row.duration,
                                   "--every",
                                   Num(opt.every),
                                   "--log",
                                   (out / (row.id + ".log.csv")).string(),
                                   "--summary",
                                   (out / (row.id + ".run.csv")).string()};
  for (const mjtether::Override& o : row.overrides) {
    args.push_back("--set");
    args.push_back(o.text + "." + o.key + "=" + o.value);
  }
  const std::string err = (out / (row.id + ".stderr.txt")).string();
  const pid_t pid = fork();
  if (pid != 0) return pid;
  // The child: default signals, no stdin, output to the row's file, then the run.
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  const int in = open("/dev/null", O_RDONLY);
  const int fd = open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (in < 0 || fd < 0) _exit(126);
  dup2(in, 0);
  dup2(fd, 1);
  dup2(fd, 2);
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  execv("/proc/self/exe", argv.data());
  std::fprintf(stderr, "mjtether: sweep: cannot run /proc/self/exe: %s\n", std::strerror(errno));
  _exit(127);
}

// The last non-empty line of the row's stderr, without the "mjtether: " prefix, cut to 500
// characters.
std::string LastMessage(const std::string& path) {
  bool ok = false;
  std::stringstream s(ReadFile(path, &ok));
  std::string line, last;
  while (std::getline(s, line)) {
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  }
  if (last.rfind("mjtether: ", 0) == 0) last = last.substr(10);
  if (last.size() > 500) last = last.substr(0, 500) + "...";
  return last;
}

// Records a finished row in DIR/ID.result.csv. Returns its status word.
std::string RecordRow(const SweepOptions& opt, const Manifest& mf, const Row& row, int wstatus,
                      double wall) {
  const fs::path out(opt.out);
  std::string status, message;
  int code = -1;
  if (WIFEXITED(wstatus)) {
    code = WEXITSTATUS(wstatus);
    status = code == 0   ? "ok"
             : code == 1 ? "diverged"
             : code == 2 ? "bad_input"
             : code == 3 ? "mujoco_error"
                         : "failed";
  } else if (WIFSIGNALED(wstatus)) {
    status = "killed";
    message = std::string("killed by signal ") + std::to_string(WTERMSIG(wstatus)) + " (" +
              strsignal(WTERMSIG(wstatus)) + ")";
  }
  if (code != 0 && message.empty())
    message = LastMessage((out / (row.id + ".stderr.txt")).string());
  std::vector<std::string> fields = RowSpec(row, opt);
  fields.push_back(status);
  fields.push_back(code >= 0 ? std::to_string(code) : "");
  fields.push_back(message);
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.3f", wall);
  fields.push_back(buf);
  // The run's own summary row (peak tension, final pose), if it wrote one.
  const std::string run_csv = (out / (row.id + ".run.csv")).string();
  bool ok = false;
  std::string error;
  auto run = mjtether::cli::ParseCsv(ReadFile(run_csv, &ok), &error);
  const size_t nrun = SummaryHeader(mf).size() - fields.size() - 1;
  if (ok && run && run->size() == 2 && (*run)[1].fields.size() == nrun) {
    fields.insert(fields.end(), (*run)[1].fields.begin(), (*run)[1].fields.end());
  } else {
    fields.resize(fields.size() + nrun);
  }
  std::remove(run_csv.c_str());
  fields.push_back(row.id + ".log.csv");
  WriteAtomically(ResultPath(opt, row),
                  mjtether::cli::CsvLine(SummaryHeader(mf)) + mjtether::cli::CsvLine(fields));
  return status;
}

// summary.csv from every row's result (rows without one: status "pending").
bool WriteSummary(const SweepOptions& opt, const Manifest& mf, int* not_ok) {
  std::string text = mjtether::cli::CsvLine(SummaryHeader(mf));
  *not_ok = 0;
  for (const Row& row : mf.rows) {
    std::optional<std::vector<std::string>> fields = ReadResult(opt, mf, row);
    if (!fields) {
      fields = RowSpec(row, opt);
      fields->push_back("pending");
      fields->resize(SummaryHeader(mf).size());
    }
    *not_ok += (*fields)[StatusField(mf)] != "ok";
    text += mjtether::cli::CsvLine(*fields);
  }
  return WriteAtomically((fs::path(opt.out) / "summary.csv").string(), text);
}

std::string Clock(double seconds) {
  const long s = std::lround(seconds);
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%02ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
  return buf;
}

// Progress on a terminal: one line redrawn in place; otherwise one plain line per row.
class Progress {
 public:
  explicit Progress(int total) : total_(total), tty_(isatty(2) != 0) {}
  void Done(const Row& row, const std::string& status, double wall) {
    ++done_;
    failed_ += status != "ok";
    const double elapsed = Elapsed();
    if (!tty_ || status != "ok") {
      if (tty_) std::cerr << "\r\033[K";
      char seconds[32];
      std::snprintf(seconds, sizeof(seconds), "%.2f", wall);
      std::cerr << "mjtether: sweep: row " << row.number << " (id " << row.id << ") " << status
                << " in " << seconds << " s [" << done_ << "/" << total_ << "]\n";
    }
    if (tty_) Draw(elapsed);
  }
  void Start() {
    if (tty_) Draw(0);
  }
  void Finish() {
    if (tty_) std::cerr << "\n";
  }
  double Elapsed() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  void Draw(double elapsed) {
    const int width = 30;
    const int filled = total_ ? done_ * width / total_ : width;
    std::string bar(filled, '#');
    bar += std::string(width - filled, '.');
    std::cerr << "\r\033[K[" << bar << "] " << done_ << "/" << total_ << " rows";
    if (failed_) std::cerr << ", " << failed_ << " not ok";
    std::cerr << ", " << Clock(elapsed);
    if (done_ > 0 && done_ < total_) {
      std::cerr << ", ~" << Clock(elapsed / done_ * (total_ - done_)) << " left";
    }
    std::cerr << std::flush;
  }
  int total_, done_ = 0, failed_ = 0;
  bool tty_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// Runs the rows with at most `jobs` children at a time. Returns 130/143 if interrupted.
int RunRows(const SweepOptions& opt, const Manifest& mf, const std::vector<const Row*>& todo,
            int jobs) {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;  // no SA_RESTART: waitpid returns on a signal
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  Progress progress(static_cast<int>(todo.size()));
  progress.Start();
  std::map<pid_t, Child> running;
  size_t next = 0;
  bool stopping = false;
  while (next < todo.size() || !running.empty()) {
    if (g_signal && !stopping) {
      for (auto& [child, c] : running) kill(child, SIGTERM);  // stop the rows too
      stopping = true;
    }
    while (!g_signal && next < todo.size() && static_cast<int>(running.size()) < jobs) {
      const Row& row = *todo[next++];
      std::remove(ResultPath(opt, row).c_str());  // not done until it finishes again
      const pid_t pid = StartRow(opt, row);
      if (pid < 0) {
        std::cerr << "mjtether: sweep: fork failed: " << std::strerror(errno) << "\n";
        g_signal = SIGTERM;
        break;
      }
      running[pid] = {&row, std::chrono::steady_clock::now()};
    }
    int wstatus = 0;
    const pid_t pid = waitpid(-1, &wstatus, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      break;  // no children left
    }
    auto it = running.find(pid);
    if (it == running.end()) continue;
    const Row& row = *it->second.row;
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - it->second.start).count();
    running.erase(it);
    // A row stopped by the interrupt is not done: a resume runs it again.
    const bool stopped =
        WIFSIGNALED(wstatus) ||
        (WIFEXITED(wstatus) && (WEXITSTATUS(wstatus) == 130 || WEXITSTATUS(wstatus) == 143));
    if (g_signal && stopped) continue;
    progress.Done(row, RecordRow(opt, mf, row, wstatus, wall), wall);
  }
  progress.Finish();
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  return g_signal == SIGINT ? 130 : g_signal ? 143 : 0;
}

// Selected rows: all, or --rows A-B.
bool SelectRows(const SweepOptions& opt, const Manifest& mf, std::vector<const Row*>* rows,
                std::string* error) {
  int first = 1, last = static_cast<int>(mf.rows.size());
  if (!opt.rows.empty()) {
    int a = 0, b = 0;
    char dash = 0, extra = 0;
    const int n = std::sscanf(opt.rows.c_str(), "%d%c%d%c", &a, &dash, &b, &extra);
    if (n == 1) b = a;
    if (!((n == 1) || (n == 3 && dash == '-')) || a < 1 || b < a ||
        b > static_cast<int>(mf.rows.size())) {
      *error = "--rows " + opt.rows +
               ": expected A-B (or A) with 1 <= A <= B <= " + std::to_string(mf.rows.size()) +
               " (the manifest's rows)";
      return false;
    }
    first = a;
    last = b;
  }
  for (int r = first; r <= last; ++r) rows->push_back(&mf.rows[r - 1]);
  return true;
}

// Single-quoted for bash.
std::string ShellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// The sbatch job-array script, the merge job and a submit script, in DIR.
int WriteSlurm(const SweepOptions& opt, const Manifest& mf) {
  const int nrows = static_cast<int>(mf.rows.size());
  const int tasks = std::min(nrows, opt.tasks > 0 ? opt.tasks : std::min(nrows, 16));
  char exe[4096] = "";
  const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
  if (n <= 0) {
    std::cerr << "mjtether: sweep: cannot find this program's path\n";
    return 2;
  }
  exe[n] = '\0';
  const std::string manifest = fs::absolute(opt.manifest).lexically_normal().string();
  const std::string out = fs::absolute(opt.out).lexically_normal().string();
  const std::string command = ShellQuote(exe) + " sweep " + ShellQuote(manifest) + " --out " +
                              ShellQuote(out) + " --every " + Num(opt.every);
  // Blocks of consecutive rows, as even as possible.
  std::ostringstream blocks;
  for (int t = 0; t < tasks; ++t) {
    const int first = 1 + static_cast<int>(static_cast<long long>(nrows) * t / tasks);
    const int last = static_cast<int>(static_cast<long long>(nrows) * (t + 1) / tasks);
    blocks << (t ? " " : "") << first << "-" << last;
  }
  std::ostringstream array;
  array << "#!/bin/bash\n"
        << "# Written by `mjtether sweep --slurm` for " << manifest << ":\n"
        << "# " << nrows << " rows in " << tasks
        << " array tasks, each running the same sweep command on its block of rows\n"
        << "# (rows already done are skipped). Submit with submit.sh, which also queues the\n"
        << "# merge of the rows' results into summary.csv.\n"
        << "#SBATCH --job-name=mjtether-sweep\n"
        << "#SBATCH --array=0-" << tasks - 1 << "\n"
        << "#SBATCH --cpus-per-task=" << opt.cpus_per_task << "\n";
  for (const std::string& o : opt.sbatch_options) array << "#SBATCH " << o << "\n";
  array << "set -euo pipefail\n"
        << "blocks=(" << blocks.str() << ")\n"
        << "exec " << command << " --rows \"${blocks[$SLURM_ARRAY_TASK_ID]}\""
        << " --jobs \"${SLURM_CPUS_PER_TASK:-1}\"\n";
  std::ostringstream merge;
  merge << "#!/bin/bash\n"
        << "# Written by `mjtether sweep --slurm`: gathers the rows' results into summary.csv\n"
        << "# (after the array, whatever its tasks' exit codes).\n"
        << "#SBATCH --job-name=mjtether-merge\n";
  for (const std::string& o : opt.sbatch_options) merge << "#SBATCH " << o << "\n";
  merge << "exec " << command << " --merge\n";
  std::ostringstream submit;
  submit << "#!/bin/bash\n"
         << "# Written by `mjtether sweep --slurm`: submits the job array, then the merge that\n"
         << "# waits for it. Prints the two job ids. Slurm's output files go to this folder.\n"
         << "set -euo pipefail\n"
         << "cd " << ShellQuote(out) << "\n"
         << "array=$(sbatch --parsable sweep.sbatch)\n"
         << "array=${array%%;*}\n"
         << "merge=$(sbatch --parsable --dependency=afterany:$array merge.sbatch)\n"
         << "echo \"$array ${merge%%;*}\"\n";
  const fs::path dir(out);
  if (!WriteAtomically((dir / "sweep.sbatch").string(), array.str()) ||
      !WriteAtomically((dir / "merge.sbatch").string(), merge.str()) ||
      !WriteAtomically((dir / "submit.sh").string(), submit.str())) {
    std::cerr << "mjtether: sweep: cannot write the Slurm scripts in " << out << "\n";
    return 2;
  }
  std::cerr << "mjtether: sweep: wrote " << (dir / "sweep.sbatch").string() << " (" << tasks
            << " array tasks of about " << (nrows + tasks - 1) / tasks << " rows), "
            << (dir / "merge.sbatch").string() << " and " << (dir / "submit.sh").string()
            << "; submit with: bash " << ShellQuote((dir / "submit.sh").string()) << "\n";
  return 0;
}

int Sweep(const SweepOptions& opt) {
  Manifest mf;
  std::string error;
  if (!ReadManifest(opt.manifest, &mf, &error)) {
    std::cerr << "mjtether: " << error << "\n";
    return 2;
  }
  std::vector<const Row*> rows;
  if (!SelectRows(opt, mf, &rows, &error)) {
    std::cerr << "mjtether: sweep: " << error << "\n";
    return 2;
  }
  std::error_code ec;
  fs::create_directories(opt.out, ec);
  if (!fs::is_directory(opt.out)) {
    std::cerr << "mjtether: sweep: --out " << opt.out << ": cannot create the folder\n";
    return 2;
  }
  int not_ok = 0;
  if (opt.merge) {
    if (!WriteSummary(opt, mf, &not_ok)) {
      std::cerr << "mjtether: sweep: cannot write " << opt.out << "/summary.csv\n";
      return 2;
    }
    std::cerr << "mjtether: sweep: merged " << mf.rows.size() << " rows into " << opt.out
              << "/summary.csv; " << not_ok << " not ok\n";
    return not_ok ? 1 : 0;
  }
  if (!CheckModels(opt.manifest, rows, &error)) {
    std::cerr << "mjtether: " << error << "\n";
    return 2;
  }
  if (opt.slurm) return WriteSlurm(opt, mf);

  // Resume: rows recorded for the same spec are skipped (failed ones too, unless
  // --retry-failed).
  std::vector<const Row*> todo;
  for (const Row* row : rows) {
    std::optional<std::vector<std::string>> done = ReadResult(opt, mf, *row);
    if (done && ((*done)[StatusField(mf)] == "ok" || !opt.retry_failed)) continue;
    todo.push_back(row);
  }
  const int jobs = opt.jobs > 0 ? opt.jobs : UsableCores();
  std::cerr << "mjtether: sweep: " << rows.size() << " rows, " << rows.size() - todo.size()
            << " already done, " << todo.size() << " to run on " << jobs << " core(s)\n";
  const auto start = std::chrono::steady_clock::now();
  const int interrupted = RunRows(opt, mf, todo, jobs);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // The rows of this invocation; with --rows (a Slurm task) only those, and no summary.csv
  // (the merge writes it).
  not_ok = 0;
  for (const Row* row : rows) {
    std::optional<std::vector<std::string>> done = ReadResult(opt, mf, *row);
    not_ok += !done || (*done)[StatusField(mf)] != "ok";
  }
  if (opt.rows.empty()) {
    int unused = 0;
    if (!WriteSummary(opt, mf, &unused)) {
      std::cerr << "mjtether: sweep: cannot write " << opt.out << "/summary.csv\n";
      return 2;
    }
  }
  std::cerr << "mjtether: sweep: " << (interrupted ? "interrupted; " : "") << rows.size()
            << " rows, " << rows.size() - not_ok << " ok, " << not_ok << " not ok; "
            << std::round(wall * 10) / 10 << " s wall"
            << (opt.rows.empty() ? "; summary: " + (fs::path(opt.out) / "summary.csv").string()
                                 : std::string("; merge with --merge"))
            << "\n";
  if (interrupted) return interrupted;
  return not_ok ? 1 : 0;
}

std::function<int()> SetupSweep(CLI::App* sub) {
  auto opt = std::make_shared<SweepOptions>();
  sub->add_option("manifest", opt->manifest,
                  "CSV: model, duration, [id], TEXT.KEY override columns")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--out", opt->out, "folder for the rows' logs and summary.csv")->required();
  sub->add_option("--jobs", opt->jobs, "rows run at once (default: every usable core)")
      ->check(CLI::Range(1, 4096));
  sub->add_option("--every", opt->every, "sampling interval of the rows' logs [s]")
      ->check(CLI::Range(1e-9, 1e7));
  sub->add_option("--rows", opt->rows, "only rows A-B (1-based, inclusive); no summary.csv");
  sub->add_flag("--retry-failed", opt->retry_failed, "run again the rows recorded as not ok");
  sub->add_flag("--merge", opt->merge, "only gather the rows' results into summary.csv");
  sub->add_flag("--slurm", opt->slurm, "write a Slurm job array (sweep.sbatch, submit.sh)");
  sub->add_option("--tasks", opt->tasks, "Slurm array tasks (default: min(rows, 16))")
      ->check(CLI::Range(1, 100000));
  sub->add_option("--cpus-per-task", opt->cpus_per_task, "cores per Slurm array task")
      ->check(CLI::Range(1, 4096));
  sub->add_option("--sbatch-option", opt->sbatch_options,
                  "extra #SBATCH line, e.g. --sbatch-option=--time=1:00:00 (repeatable)")
      ->expected(1)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  return [opt]() { return Sweep(*opt); };
}

const bool registered = mjtether::cli::Register(
    {"sweep", "run a CSV manifest of overridden models on every core, or on Slurm", SetupSweep});

}  // namespace
