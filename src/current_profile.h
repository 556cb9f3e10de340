// A current that varies with depth: rows z,ux,uy,uz (metres, m/s, world frame) read from a CSV
// file declared by `current_profile=FILE.csv` in <text name="water"> (docs/environment.md).
// Linear between rows, constant beyond the first and the last row.
#ifndef MJTETHER_SRC_CURRENT_PROFILE_H_
#define MJTETHER_SRC_CURRENT_PROFILE_H_

#include <Eigen/Core>
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

namespace mjtether {

struct CurrentProfile {
  std::vector<double> z;           // [m] heights, strictly increasing (n >= 1)
  std::vector<Eigen::Vector3d> u;  // [m/s] current at each height (n)

  bool empty() const { return z.empty(); }

  // The current at height zq [m]: linear between rows, constant beyond. Allocates nothing.
  Eigen::Vector3d At(double zq) const {
    const int n = static_cast<int>(z.size());
    if (zq <= z[0]) return u[0];
    if (zq >= z[n - 1]) return u[n - 1];
    // Bisection for the row j with z[j] <= zq < z[j+1].
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) {
      const int mid = (lo + hi) / 2;
      (z[mid] <= zq ? lo : hi) = mid;
    }
    const double s = (zq - z[lo]) / (z[hi] - z[lo]);
    return u[lo] + s * (u[hi] - u[lo]);
  }

  // Largest |u| over the rows [m/s] (the largest anywhere, as the profile is piecewise linear).
  double MaxSpeed() const {
    double s = 0;
    for (const Eigen::Vector3d& ui : u) s = std::max(s, ui.norm());
    return s;
  }
};

// Reads `path`: one row z,ux,uy,uz per line, an optional header line, blank lines skipped.
// Refuses (nothing returned, *error naming the file and line) an unreadable or empty file,
// a row that is not 4 finite decimal numbers, z outside [-11000, 10000] m, a component outside
// [-1000, 1000] m/s, and z not strictly increasing.
std::optional<CurrentProfile> ReadCurrentProfile(const std::string& path, std::string* error);

}  // namespace mjtether

#endif  // MJTETHER_SRC_CURRENT_PROFILE_H_
