// `mjtether plot TABLE.csv --x COL --y COL [--by COL]`: one column of a CSV table against
// another (e.g. a sweep's summary.csv), one line per value of --by. See cli_plot.cc.
#ifndef MJTETHER_PLUGIN_CLI_PLOT_COLUMNS_H_
#define MJTETHER_PLUGIN_CLI_PLOT_COLUMNS_H_

#include <string>

namespace mjtether::cli {

struct ColumnPlot {
  std::string input;  // the CSV file (RFC 4180, header line)
  std::string x, y;   // column names; NAME[i] takes item i (0-based) of a comma list
  std::string by;     // optional: one series per distinct value of this column
  std::string out;    // PNG
  int width = 1000, height = 700;
};

// Returns the exit code: 0, 2 bad input (file, column, no numbers), 4 gnuplot failed. Rows
// whose `status` column (if any) is not "ok", or whose x or y is not a number, are left out
// and counted on stderr.
int PlotColumns(const ColumnPlot& p);

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_PLOT_COLUMNS_H_
