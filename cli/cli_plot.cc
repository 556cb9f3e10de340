// `mjtether plot`: a PNG (gnuplot) of the tension at both ends of a tether and the vehicle's
// depth over time, from a `mjtether run --log` CSV or by running the model.
//
//   mjtether plot INPUT --out FILE.png [--duration S] [--every S] [--tether NAME] [--body NAME]
//       [--size 1000x700]
//   mjtether plot TABLE.csv --x COL --y COL [--by COL] --out FILE.png   (cli_plot_columns.h)
//
// INPUT ending in .csv is read as a run log (columns time, NAME.tension_A, NAME.tension_B,
// BODY.z, and NAME.length, NAME.payout_speed with a winch: two more panels); otherwise it is a model, run for --duration seconds and sampled every --every
// seconds (scheduled by step index, as `mjtether run` does).
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "cli_command.h"
#include "cli_common.h"
#include "cli_pipe.h"
#include "cli_plot_columns.h"
#include "step_check.h"
#include "mjtether.h"
#include "render.h"

namespace {

struct PlotOptions {
  std::string input;
  std::string out;
  double duration = 0;
  double every = 0.05;
  std::string tether;
  std::string body;
  std::string size = "1000x700";
  std::string x, y, by;  // a column against another (cli_plot_columns.h)
  // The options given on the command line (each mode refuses the ones it would ignore).
  std::vector<CLI::Option*> given;
  bool Given(const std::string& name) const {
    for (const CLI::Option* o : given) {
      if (o->get_name() == name) return o->count() > 0;
    }
    return false;
  }
};

// Exit 2 naming the first of `names` given on the command line, which the mode `why` ignores.
bool RefuseIgnored(const PlotOptions& opt, std::initializer_list<const char*> names,
                   const std::string& why) {
  for (const char* name : names) {
    if (opt.Given(name)) {
      std::cerr << "mjtether: plot " << opt.input << ": " << name << " is not used " << why
                << "; remove it\n";
      return true;
    }
  }
  return false;
}

// The series to plot: time [s], tension at ends A and B [N], vehicle height z [m]; with a
// winch (docs/winch.md), the deployed length [m] and the payout speed [m/s].
struct Series {
  std::string title;
  std::string label_a = "end A", label_b = "end B", vehicle;
  bool winch = false;
  std::vector<double> t, ta, tb, z, length, speed;
};

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::vector<std::string> SplitCsv(const std::string& line) {
  return mjtether::SplitCsvLine(line);  // RFC 4180: quoted names may hold commas
}

// Reads a run log. Returns false with *error naming the file and the missing column.
bool ReadLog(const PlotOptions& opt, Series* s, std::string* error) {
  std::ifstream f(opt.input);
  std::string line;
  if (!f || !std::getline(f, line)) {
    *error = opt.input + ": cannot read the header line";
    return false;
  }
  const std::vector<std::string> head = SplitCsv(line);
  auto find = [&](const std::string& name) {
    return static_cast<int>(std::find(head.begin(), head.end(), name) - head.begin());
  };
  auto find_suffix = [&](const std::string& suffix) -> std::string {
    for (const std::string& h : head) {
      if (EndsWith(h, suffix)) return h.substr(0, h.size() - suffix.size());
    }
    return "";
  };
  const std::string tether = opt.tether.empty() ? find_suffix(".tension_A") : opt.tether;
  const std::string body = opt.body.empty() ? find_suffix(".z") : opt.body;
  const int ct = find("time"), ca = find(tether + ".tension_A"), cb = find(tether + ".tension_B");
  const int cz = body.empty() ? -1 : find(body + ".z");
  const int n = static_cast<int>(head.size());
  const int cl = find(tether + ".length"), cv = find(tether + ".payout_speed");
  s->winch = cl < n && cv < n;
  if (ct >= n || ca >= n || cb >= n || tether.empty()) {
    *error = opt.input + ": no columns time, " + (tether.empty() ? "NAME" : tether) +
             ".tension_A and .tension_B (write the log with mjtether run --log)";
    return false;
  }
  if (!opt.body.empty() && cz >= n) {
    *error = opt.input + ": --body " + opt.body + ": no column " + opt.body + ".z";
    return false;
  }
  s->title = tether + " (" + opt.input + ")";
  s->label_a = tether + ": tension at end A";
  s->label_b = tether + ": tension at end B";
  s->vehicle = cz < n ? body : "";
  int row = 1;
  while (std::getline(f, line)) {
    ++row;
    if (line.empty()) continue;
    const std::vector<std::string> v = SplitCsv(line);
    double value[6] = {0, 0, 0, 0, 0, 0};
    const int columns[6] = {ct, ca, cb, cz < n ? cz : -1, s->winch ? cl : -1, s->winch ? cv : -1};
    for (int c = 0; c < 6; ++c) {
      if (columns[c] < 0) continue;
      const std::string field =
          columns[c] < static_cast<int>(v.size()) ? v[columns[c]] : std::string("(missing)");
      const mjtether::NumberStatus status = mjtether::ParseDecimal(field, &value[c]);
      if (status != mjtether::NumberStatus::kOk || !(std::abs(value[c]) <= 1e15)) {
        *error = opt.input + ": line " + std::to_string(row) + ", column '" +
                 mjtether::Shown(head[columns[c]]) + "': '" + mjtether::Shown(field) + "' " +
                 (status == mjtether::NumberStatus::kOk ? "is out of range [-1e15, 1e15]"
                                                        : mjtether::NumberProblem(status));
        return false;
      }
    }
    s->t.push_back(value[0]);
    s->ta.push_back(value[1]);
    s->tb.push_back(value[2]);
    s->z.push_back(value[3]);
    s->length.push_back(value[4]);
    s->speed.push_back(value[5]);
  }
  return true;
}

std::string BodyName(const mjModel* m, int b) {
  if (b < 0) return "free end";
  const char* name = mj_id2name(m, mjOBJ_BODY, b);
  return name && *name ? name : "body " + std::to_string(b);
}

// Runs the model and samples it. Returns 0, or the exit code (1 diverged, 2 bad input).
// Runs the model and samples it. Returns 0, or the exit code (1 diverged, 2 bad input,
// 128 + signal when interrupted: the samples so far are plotted).
int RunModel(const PlotOptions& opt, const mjModel* m, Series* s) {
  using namespace mjtether::cli;
  int status = 0;
  const int k = opt.tether.empty() ? 0 : mjtether::FindTether(m, opt.tether);
  int vehicle =
      opt.body.empty() ? mjtether::render::Vehicle(m) : mj_name2id(m, mjOBJ_BODY, opt.body.c_str());
  if (mjtether::TetherCount(m) == 0 || k < 0) {
    std::cerr << "mjtether: " << opt.input << ": "
              << (k < 0 ? "no tether named '" + mjtether::Shown(opt.tether) + "'"
                        : "no tether declared")
              << "\n";
    return kExitBadInput;
  } else if (!opt.body.empty() && vehicle < 0) {
    std::cerr << "mjtether: " << opt.input << ": --body " << mjtether::Shown(opt.body)
              << ": no such body\n";
    return kExitBadInput;
  } else if (!(opt.duration > 0)) {
    std::cerr << "mjtether: plot " << opt.input << ": give --duration S to run the model\n";
    return kExitBadInput;
  }
  const std::string name = mjtether::TetherName(m, k);
  s->title = name + " (" + opt.input + ")";
  s->label_a = name + ": tension at " + BodyName(m, mjtether::EndBody(m, k, 0));
  s->label_b = name + ": tension at " + BodyName(m, mjtether::EndBody(m, k, 1));
  s->vehicle = vehicle >= 0 ? BodyName(m, vehicle) : "";

  DataPtr data = MakeData(m);
  mjData* d = data.get();
  s->winch = mjtether::GetWinch(m, d, k).present;
  Observer observer(m);
  const double h = m->opt.timestep;
  const long long steps = std::llround(opt.duration / h);
  if (opt.every < h) {
    std::cerr << "mjtether: warning: --every " << opt.every << " s is below the time step " << h
              << " s: sampling every step\n";
  }
  const double every = std::max(opt.every, h);
  long long next = 0, index = 0;
  for (long long i = 0;; ++i) {
    if (i == next) {
      mjtether::Prescribe(m, d);
      const mjData* o = observer.Observe(d);
      const mjtether::EndReactions r = mjtether::GetReactions(m, o, k);
      s->t.push_back(o->time);
      s->ta.push_back(r.tension_a);
      s->tb.push_back(r.tension_b);
      s->z.push_back(vehicle >= 0 ? o->xpos[3 * vehicle + 2] : 0.0);
      const mjtether::WinchState w = mjtether::GetWinch(m, o, k);
      s->length.push_back(w.length);
      s->speed.push_back(w.payout_speed);
      next = std::llround(++index * every / h);
    }
    if (i == steps) break;
    if (const int signal = StopSignal()) {
      std::cerr << "mjtether: " << opt.input << ": " << Interrupted(signal, d->time, i, steps)
                << "; plotting the " << s->t.size() << " sample(s) so far\n";
      status = 128 + signal;
      break;
    }
    if (std::optional<std::string> diverged = StepAndCheck(m, d, opt.input)) {
      std::cerr << "mjtether: " << *diverged << "\n";
      status = kExitDiverged;
      break;
    }
  }
  return status;
}

// A string in gnuplot's single quotes (a quote is doubled).
std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
  return q + "'";
}

int Plot(const PlotOptions& opt) {
  int W = 0, H = 0;
  char x = 0, extra = 0;
  if (std::sscanf(opt.size.c_str(), "%d%c%d%c", &W, &x, &H, &extra) != 3 || x != 'x' || W < 200 ||
      H < 200 || W > 8000 || H > 8000) {
    std::cerr << "mjtether: --size " << opt.size
              << ": expected WIDTHxHEIGHT, each in [200, 8000]\n";
    return 2;
  }
  if (!opt.x.empty() || !opt.y.empty()) {
    if (RefuseIgnored(opt, {"--duration", "--every", "--tether", "--body"},
                      "when plotting a column against another (--x, --y)")) {
      return mjtether::cli::kExitBadInput;
    }
    return mjtether::cli::PlotColumns({opt.input, opt.x, opt.y, opt.by, opt.out, W, H});
  }
  using namespace mjtether::cli;
  InstallStopHandlers();
  // The input (and a model's own files) may not be overwritten by --out.
  OutputGuard guard;
  Series s;
  ModelPtr model;
  int run_status = 0;
  if (EndsWith(opt.input, ".csv")) {
    if (RefuseIgnored(opt, {"--duration", "--every"},
                      "when the input is a run log (.csv): the log fixes the times")) {
      return kExitBadInput;
    }
    guard.AddInput(opt.input, "the input");
    std::string error;
    if (!ReadLog(opt, &s, &error)) {
      std::cerr << "mjtether: " << error << "\n";
      return kExitBadInput;
    }
  } else {
    model = LoadChecked(opt.input);
    if (!model) return kExitBadInput;
    guard.AddModel(opt.input, model.get());
  }
  ToolOutput out;
  std::string out_error;
  if (!out.Open(opt.out, "--out", &guard, &out_error)) {
    std::cerr << "mjtether: " << out_error << "\n";
    return kExitBadInput;
  }
  if (model) {
    run_status = RunModel(opt, model.get(), &s);
    if (run_status != 0 && run_status < 128) return run_status;
  }
  if (s.t.empty()) {
    std::cerr << "mjtether: " << opt.input << ": no samples to plot\n";
    return kExitBadInput;
  }

  // Panels sharing the time axis: end tensions; with a winch, the deployed length and the
  // payout speed; then the vehicle's depth (-z, downwards).
  std::ostringstream g;
  g.precision(9);
  g << "$data << EOD\n";
  for (size_t i = 0; i < s.t.size(); ++i) {
    g << s.t[i] << " " << s.ta[i] << " " << s.tb[i] << " " << -s.z[i] << " " << s.length[i]
      << " " << s.speed[i] << "\n";
  }
  g << "EOD\n"
    << "set terminal pngcairo size " << W << "," << H << " font 'sans,11'\n"
    << "set output " << Quote(out.path()) << "\n"
    << "set multiplot layout " << (s.vehicle.empty() ? 1 : 2) + (s.winch ? 2 : 0)
    << ",1 title " << Quote(s.title)
    << " noenhanced\n"
    << "set grid\nset key outside below center horizontal noenhanced\nset lmargin 12\n"
    << "set ylabel 'tension [N]'\n"
    << (s.vehicle.empty() && !s.winch ? "set xlabel 'time [s]'\n" : "")
    << "plot $data using 1:2 with lines lw 2 lc rgb '#1f77b4' title " << Quote(s.label_a)
    << ", $data using 1:3 with lines lw 2 lc rgb '#d62728' title " << Quote(s.label_b) << "\n";
  if (s.winch) {
    g << "set ylabel 'length [m]'\nplot $data using 1:5 with lines lw 2 lc rgb '#9467bd' "
         "title 'deployed length (winch)'\n"
      << (s.vehicle.empty() ? "set xlabel 'time [s]'\n" : "")
      << "set ylabel 'speed [m/s]'\nplot $data using 1:6 with lines lw 2 lc rgb '#8c564b' "
         "title 'payout speed (> 0 paying out)'\n";
  }
  if (!s.vehicle.empty()) {
    g << "set xlabel 'time [s]'\nset ylabel 'depth [m]'\nset yrange [*:*] reverse\n"
      << "plot $data using 1:4 with lines lw 2 lc rgb '#2ca02c' title "
      << Quote("depth of " + s.vehicle) << "\n";
  }
  g << "unset multiplot\nset output\n";

  std::signal(SIGPIPE, SIG_IGN);
  mjtether::cli::ChildPipe gnuplot;
  std::string error;
  if (!gnuplot.Open({"gnuplot"}, &error)) {
    std::cerr << "mjtether: cannot start gnuplot: " << error << "\n";
    return 4;
  }
  const bool written = gnuplot.Write(g.str());
  const int rc = gnuplot.Close();
  std::ifstream png(out.path(), std::ios::binary | std::ios::ate);
  if (!written || rc != 0 || !png || png.tellg() <= 0) {
    std::cerr << "mjtether: gnuplot failed (exit status " << rc
              << (rc == 127 ? ": gnuplot not found on PATH" : "") << ") writing " << opt.out
              << "\n";
    return kExitTool;
  }
  if (!out.Commit(&out_error)) {
    std::cerr << "mjtether: " << out_error << "\n";
    return kExitOutput;
  }
  std::cerr << "mjtether: plotted " << s.t.size() << " samples to " << opt.out << "\n";
  return run_status;
}

std::function<int()> SetupPlot(CLI::App* sub) {
  auto opt = std::make_shared<PlotOptions>();
  sub->add_option("input", opt->input, "run log (.csv from mjtether run --log) or MJCF model")
      ->required()
      ->check(CLI::ExistingFile);
  sub->add_option("--out", opt->out, "PNG file to write")->required();
  opt->given = {
      sub->add_option("--duration", opt->duration, "simulated time when INPUT is a model [s]")
          ->check(mjtether::cli::Number(0, 1e7, false, "s")),
      sub->add_option("--every", opt->every, "sampling interval when INPUT is a model [s]")
          ->check(mjtether::cli::Number(0, 1e7, true, "s")),
      sub->add_option("--tether", opt->tether, "tether to plot (default: the first)"),
      sub->add_option("--body", opt->body, "body whose depth is plotted (default: the vehicle)")};
  sub->add_option("--size", opt->size, "WIDTHxHEIGHT in pixels (default 1000x700)");
  sub->add_option("--x", opt->x, "CSV table: column for the x axis (NAME or NAME[i])");
  sub->add_option("--y", opt->y, "CSV table: column for the y axis");
  sub->add_option("--by", opt->by, "CSV table: one line per value of this column");
  return [opt]() { return Plot(*opt); };
}

const bool registered = mjtether::cli::Register(
    {"plot", "plot end tensions and vehicle depth over time (PNG, gnuplot)", SetupPlot});

}  // namespace
