// `mjtether run --summary FILE`: one CSV row about a whole run, which `mjtether sweep` collects
// into its summary.csv: the peak tension over every MuJoCo step (not only the logged samples)
// and the vehicle's final pose.
#ifndef MJTETHER_PLUGIN_CLI_RUN_SUMMARY_H_
#define MJTETHER_PLUGIN_CLI_RUN_SUMMARY_H_

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "cli_csv.h"
#include "mjtether.h"
#include "render.h"

namespace mjtether::cli {

class RunSummary {
 public:
  // Columns of the row, in order.
  static constexpr const char* kHeader =
      "sim_time,peak_tension,peak_tether,peak_time,vehicle,x,y,z,qw,qx,qy,qz";

  explicit RunSummary(const mjModel* m) : vehicle_(render::Vehicle(m)) {
    int n = 0;
    for (int k = 0; k < TetherCount(m); ++k) n = std::max(n, GetTether(m, k)->segments());
    tensions_.resize(n);  // once: Observe allocates nothing
  }

  // After each mj_step: the largest segment or end tension of every tether, at the tether's
  // own time [N] (the start of the step: the step's callback brought the tether there).
  void Observe(const mjModel* m, const mjData* d) {
    for (int k = 0; k < TetherCount(m); ++k) {
      GetTensions(m, d, k, tensions_.data());
      const EndReactions r = GetReactions(m, d, k);
      double peak = std::max(r.tension_a, r.tension_b);
      for (int j = 0; j < GetTether(m, k)->segments(); ++j) peak = std::max(peak, tensions_[j]);
      if (peak > peak_) {
        peak_ = peak;
        peak_tether_ = k;
        peak_time_ = TetherTime(m, d, k);
      }
    }
  }

  // The row for the state d ends in: time, peak, and the vehicle's position [m] and
  // orientation (unit quaternion w,x,y,z) from its free joint (empty without a vehicle).
  std::string Row(const mjModel* m, const mjData* d) const {
    auto num = [](double v) { return Shortest(v); };
    std::string row = num(d->time) + "," + num(peak_) + "," +
                      (peak_tether_ >= 0 ? CsvField(TetherName(m, peak_tether_)) : "") + "," +
                      num(peak_time_) + ",";
    if (vehicle_ < 0) return row + ",,,,,,,";
    const char* name = mj_id2name(m, mjOBJ_BODY, vehicle_);
    row += name ? CsvField(name) : "";
    const int adr = m->jnt_qposadr[m->body_jntadr[vehicle_]];
    for (int i = 0; i < 7; ++i) row += "," + num(d->qpos[adr + i]);
    return row;
  }

  // Observes the final state too (the tethers are at d->time when the run's last sample
  // brought them there), then writes the header and the row.
  bool Write(const std::string& path, const mjModel* m, const mjData* d) {
    Observe(m, d);
    std::ofstream f(path);
    f << kHeader << "\n" << Row(m, d) << "\n";
    f.close();
    return static_cast<bool>(f);
  }

 private:
  int vehicle_ = -1;
  std::vector<double> tensions_;
  double peak_ = 0, peak_time_ = 0;
  int peak_tether_ = -1;
};

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_RUN_SUMMARY_H_
