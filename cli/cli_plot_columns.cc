// `mjtether plot TABLE.csv --x COL --y COL [--by COL]` (cli_plot_columns.h).
#include "cli_plot_columns.h"

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include "cli_csv.h"
#include "cli_pipe.h"

namespace mjtether::cli {
namespace {

// A column named NAME or NAME[i].
struct Column {
  int index = -1;
  int item = -1;  // -1: the whole field
};

std::optional<Column> FindColumn(const std::vector<std::string>& header, const std::string& spec,
                                 std::string* error) {
  Column c;
  std::string name = spec;
  if (!spec.empty() && spec.back() == ']') {
    const size_t open = spec.rfind('[');
    char* end = nullptr;
    const long item =
        open == std::string::npos ? -1 : std::strtol(spec.c_str() + open + 1, &end, 10);
    if (open == std::string::npos || end != spec.c_str() + spec.size() - 1 || item < 0) {
      *error = "column '" + spec + "': expected NAME or NAME[i] with i >= 0";
      return std::nullopt;
    }
    name = spec.substr(0, open);
    c.item = static_cast<int>(item);
  }
  const auto it = std::find(header.begin(), header.end(), name);
  if (it == header.end()) {
    std::string names;
    for (const std::string& h : header) names += (names.empty() ? "" : ", ") + h;
    *error = "no column '" + name + "' (columns: " + names + ")";
    return std::nullopt;
  }
  c.index = static_cast<int>(it - header.begin());
  return c;
}

// The number in a field (or in item i of its comma list); nullopt if there is none.
std::optional<double> Value(const std::string& field, int item) {
  std::string s = field;
  if (item >= 0) {
    std::stringstream ss(field);
    for (int i = 0; i <= item; ++i) {
      if (!std::getline(ss, s, ',')) return std::nullopt;
    }
  }
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || *end != '\0' || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("''") : std::string(1, c);
  return q + "'";
}

}  // namespace

int PlotColumns(const ColumnPlot& p) {
  std::ifstream f(p.input, std::ios::binary);
  std::stringstream text;
  text << f.rdbuf();
  std::string error;
  auto records = ParseCsv(text.str(), &error);
  if (!f || !records || records->empty()) {
    std::cerr << "mjtether: " << p.input << ": " << (records ? "no header line" : error) << "\n";
    return 2;
  }
  if (p.x.empty() || p.y.empty()) {
    std::cerr << "mjtether: plot " << p.input << ": give both --x and --y\n";
    return 2;
  }
  const std::vector<std::string>& header = records->front().fields;
  std::optional<Column> cx = FindColumn(header, p.x, &error), cy, cby;
  if (cx) cy = FindColumn(header, p.y, &error);
  if (cx && cy && !p.by.empty()) cby = FindColumn(header, p.by, &error);
  if (!cx || !cy || (!p.by.empty() && !cby)) {
    std::cerr << "mjtether: " << p.input << ": " << error << "\n";
    return 2;
  }
  const auto status = std::find(header.begin(), header.end(), "status");
  const int cstatus = status == header.end() ? -1 : static_cast<int>(status - header.begin());
  // Series in order of first appearance; points sorted by x.
  std::vector<std::string> order;
  std::map<std::string, std::vector<std::pair<double, double>>> series;
  int skipped_status = 0, skipped_number = 0;
  for (size_t r = 1; r < records->size(); ++r) {
    const std::vector<std::string>& v = (*records)[r].fields;
    if (v.size() != header.size()) {
      std::cerr << "mjtether: " << p.input << ": line " << (*records)[r].line << ": " << v.size()
                << " fields, the header has " << header.size() << "\n";
      return 2;
    }
    if (cstatus >= 0 && v[cstatus] != "ok") {
      ++skipped_status;
      continue;
    }
    const std::optional<double> x = Value(v[cx->index], cx->item);
    const std::optional<double> y = Value(v[cy->index], cy->item);
    if (!x || !y) {
      ++skipped_number;
      continue;
    }
    std::string key;
    if (cby) {
      std::optional<double> b = Value(v[cby->index], cby->item);
      key = cby->item >= 0 && b ? std::to_string(*b) : v[cby->index];
    }
    if (!series.count(key)) order.push_back(key);
    series[key].push_back({*x, *y});
  }
  if (skipped_status) {
    std::cerr << "mjtether: plot: left out " << skipped_status << " rows whose status is not ok\n";
  }
  if (skipped_number) {
    std::cerr << "mjtether: plot: left out " << skipped_number << " rows without a number in "
              << p.x << " or " << p.y << "\n";
  }
  if (series.empty()) {
    std::cerr << "mjtether: " << p.input << ": no rows with numbers in " << p.x << " and " << p.y
              << "\n";
    return 2;
  }
  // Numeric --by values in increasing order.
  std::stable_sort(order.begin(), order.end(), [](const std::string& a, const std::string& b) {
    const std::optional<double> va = Value(a, -1), vb = Value(b, -1);
    return va && vb ? *va < *vb : false;
  });
  std::ostringstream g;
  g.precision(17);
  for (size_t s = 0; s < order.size(); ++s) {
    std::vector<std::pair<double, double>>& pts = series[order[s]];
    std::sort(pts.begin(), pts.end());
    g << "$s" << s << " << EOD\n";
    for (const auto& [x, y] : pts) g << x << " " << y << "\n";
    g << "EOD\n";
  }
  g << "set terminal pngcairo size " << p.width << "," << p.height << " font 'sans,11'\n"
    << "set output " << Quote(p.out) << "\n"
    << "set title " << Quote(p.input) << " noenhanced\n"
    << "set grid\nset key outside right top vertical noenhanced\n"  // legend off the data
    << "set xlabel " << Quote(p.x) << " noenhanced\n"
    << "set ylabel " << Quote(p.y) << " noenhanced\n"
    << "plot ";
  for (size_t s = 0; s < order.size(); ++s) {
    g << (s ? ", " : "") << "$s" << s << " using 1:2 with linespoints lw 2 pt 7 ps 0.6 title "
      << (cby ? Quote(p.by + " = " + order[s]) : std::string("notitle"));
  }
  g << "\nset output\n";
  std::signal(SIGPIPE, SIG_IGN);
  ChildPipe gnuplot;
  if (!gnuplot.Open({"gnuplot"}, &error)) {
    std::cerr << "mjtether: cannot start gnuplot: " << error << "\n";
    return 4;
  }
  const bool written = gnuplot.Write(g.str());
  const int rc = gnuplot.Close();
  std::ifstream png(p.out, std::ios::binary | std::ios::ate);
  if (!written || rc != 0 || !png || png.tellg() <= 0) {
    std::cerr << "mjtether: gnuplot failed (exit status " << rc
              << (rc == 127 ? ": gnuplot not found on PATH" : "") << ") writing " << p.out << "\n";
    return 4;
  }
  size_t n = 0;
  for (const auto& [k, pts] : series) n += pts.size();
  std::cerr << "mjtether: plotted " << n << " points in " << order.size() << " series to " << p.out
            << "\n";
  return 0;
}

}  // namespace mjtether::cli
