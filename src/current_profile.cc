#include "current_profile.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "text_check.h"

namespace mjtether {
namespace {

// Ranges: heights as the seabed's [m], current components as the uniform current's [m/s].
constexpr double kMinZ = -1.1e4, kMaxZ = 1e4, kMaxU = 1e3;

}  // namespace

std::optional<CurrentProfile> ReadCurrentProfile(const std::string& path, std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = "key 'current_profile': " + message;
    return std::nullopt;
  };
  std::ifstream in(path);
  if (!in) return fail("cannot read '" + path + "'");
  CurrentProfile p;
  std::string line;
  int row = 0;
  while (std::getline(in, line)) {
    ++row;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = path + " line " + std::to_string(row) + ": ";
    double v[4];
    if (!ParseCsvRow(line, 4, v)) {
      if (row == 1) continue;  // a header
      return fail(where + "expected 4 finite decimal numbers z,ux,uy,uz");
    }
    if (!(v[0] >= kMinZ && v[0] <= kMaxZ)) {
      std::ostringstream o;
      o << where << "z = " << v[0] << " m outside [-11000, 10000]";
      return fail(o.str());
    }
    for (int i = 1; i < 4; ++i) {
      if (!(std::abs(v[i]) <= kMaxU)) {
        std::ostringstream o;
        o << where << "u"
          << "xyz"[i - 1] << " = " << v[i] << " m/s outside [-1000, 1000]";
        return fail(o.str());
      }
    }
    if (!p.z.empty() && !(v[0] > p.z.back())) {
      return fail(where + "z must increase strictly from row to row");
    }
    p.z.push_back(v[0]);
    p.u.emplace_back(v[1], v[2], v[3]);
  }
  if (p.z.empty()) return fail(path + " has no rows z,ux,uy,uz");
  return p;
}

}  // namespace mjtether
