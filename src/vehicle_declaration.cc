#include "vehicle_declaration.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "text_check.h"

namespace mjtether {
namespace {

bool Fail(DeclarationError* error, const std::string& key, const std::string& message) {
  if (error) *error = {key, message};
  return false;
}

std::string Fmt(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// A comma list of `count` finite numbers (count 0: any length >= 1), each in [lo, hi] (lo
// open when lo_open). NaN fails the comparisons.
bool ParseList(const std::string& key, const std::string& text, int count, double lo, bool lo_open,
               double hi, const char* what, std::vector<double>* out, DeclarationError* error) {
  const std::string range = std::string(lo_open ? "(" : "[") + Fmt(lo) + ", " + Fmt(hi) + "]";
  std::vector<std::string> items;
  std::string item;
  std::istringstream s(text);
  while (std::getline(s, item, ',')) items.push_back(item);
  if (!text.empty() && text.back() == ',') items.push_back("");
  if ((count > 0 && static_cast<int>(items.size()) != count) || items.empty()) {
    return Fail(error, key, "key '" + key + "' = " + Shown(text) + " must be " + what);
  }
  out->clear();
  for (const std::string& it : items) {
    double x = 0;
    const NumberStatus status = ParseDecimal(it, &x);
    if (status == NumberStatus::kUnderflow) {
      return Fail(error, key,
                  "key '" + key + "' = " + Shown(text) +
                      ": a value is out of range (below 2.2e-308 in magnitude; write 0 or a "
                      "larger number); each value in " +
                      range);
    }
    if (status != NumberStatus::kOk) {
      return Fail(error, key, "key '" + key + "': '" + Shown(it) + "' " + NumberProblem(status));
    }
    if (!((lo_open ? x > lo : x >= lo) && x <= hi)) {
      return Fail(
          error, key,
          "key '" + key + "' = " + Shown(text) + ": each value in " + range + " (" + what + ")");
    }
    out->push_back(x);
  }
  return true;
}

// "unknown key 'volme'; did you mean 'volume'? (allowed keys: ...)".
std::string UnknownKey(const std::string& key, const std::vector<const char*>& allowed) {
  std::string list;
  std::vector<std::string> keys;
  for (size_t i = 0; i < allowed.size(); ++i) {
    list += std::string(i ? ", " : "") + allowed[i];
    keys.emplace_back(allowed[i]);
  }
  return "unknown key '" + Shown(key) + "'" + DidYouMean(key, keys) + "; allowed keys: " + list;
}

}  // namespace

std::optional<VehicleParams> ParseVehicle(const std::string& text, DeclarationError* error) {
  static const std::vector<const char*> kKeys = {
      "volume", "cob", "added_mass", "linear_damping", "quadratic_damping", "coriolis"};
  std::optional<KeyValues> pairs = SplitKeyValues(text, error);
  if (!pairs) return std::nullopt;
  VehicleParams p;
  std::vector<double> x;
  for (const auto& [key, value] : *pairs) {
    bool ok = true;
    if (key == "volume") {
      ok = ParseList(key, value, 1, 0, false, 1e4, "one volume [m^3]", &x, error);
      if (ok) p.volume = x[0];
    } else if (key == "cob") {
      ok = ParseList(key, value, 3, -1e3, false, 1e3, "3 numbers x,y,z [m], body frame", &x, error);
      if (ok) p.cob = Vec3(x[0], x[1], x[2]);
    } else if (key == "added_mass" || key == "linear_damping" || key == "quadratic_damping") {
      ok = ParseList(key, value, 6, 0, false, 1e9,
                     "6 magnitudes: surge, sway, heave, roll, pitch, yaw", &x, error);
      Vec6& dst = key == "added_mass"       ? p.added_mass
                  : key == "linear_damping" ? p.linear_damping
                                            : p.quadratic_damping;
      if (ok) dst = Eigen::Map<const Vec6>(x.data());
    } else if (key == "coriolis") {
      p.coriolis = value == "1";
      if (value != "0" && value != "1") {
        ok = Fail(error, key, "key 'coriolis' = " + Shown(value) + "; allowed: 0, 1");
      }
    } else {
      ok = Fail(error, key, UnknownKey(key, kKeys));
    }
    if (!ok) return std::nullopt;
  }
  return p;
}

std::optional<MotionParams> ParseMotion(const std::string& text, DeclarationError* error) {
  static const std::vector<const char*> kKeys = {"x", "y", "z", "csv", "ramp"};
  std::optional<KeyValues> pairs = SplitKeyValues(text, error);
  if (!pairs) return std::nullopt;
  MotionParams p;
  std::vector<double> x;
  bool any = false;
  for (const auto& [key, value] : *pairs) {
    bool ok = true;
    const int axis = key == "x" ? 0 : key == "y" ? 1 : key == "z" ? 2 : -1;
    if (axis >= 0) {
      ok = ParseList(key, value, 3, -1e3, false, 1e6,
                     "amplitude [m] >= 0, period [s] > 0, phase [rad]", &x, error);
      if (ok && !(x[0] >= 0 && x[0] <= 1e4)) {
        ok = Fail(error, key, "key '" + key + "': amplitude " + Fmt(x[0]) + " outside [0, 10000]");
      } else if (ok && !(x[1] > 0)) {
        ok = Fail(error, key, "key '" + key + "': period " + Fmt(x[1]) + " outside (0, 1e6]");
      } else if (ok && !(std::abs(x[2]) <= 1e3)) {
        ok = Fail(error, key, "key '" + key + "': phase " + Fmt(x[2]) + " outside [-1000, 1000]");
      }
      if (ok) {
        p.harmonic[axis] = true;
        p.amplitude[axis] = x[0];
        p.period[axis] = x[1];
        p.phase[axis] = x[2];
        any = true;
      }
    } else if (key == "csv") {
      p.csv = value;
    } else if (key == "ramp") {
      ok = ParseList(key, value, 1, 0, false, 1e6, "one duration [s]", &x, error);
      if (ok) p.ramp = x[0];
    } else {
      ok = Fail(error, key, UnknownKey(key, kKeys));
    }
    if (!ok) return std::nullopt;
  }
  if (any && !p.csv.empty()) {
    Fail(error, "csv", "key 'csv' excludes the harmonic keys x, y, z; give one or the other");
    return std::nullopt;
  }
  if (!any && p.csv.empty()) {
    Fail(error, "x", "a motion needs x, y, z (amplitude,period,phase) or csv=FILE");
    return std::nullopt;
  }
  return p;
}

std::optional<Schedule> ParseSchedule(const std::string& text, DeclarationError* error) {
  static const std::vector<const char*> kKeys = {"t", "ctrl"};
  std::optional<KeyValues> pairs = SplitKeyValues(text, error);
  if (!pairs) return std::nullopt;
  Schedule s;
  bool has_t = false, has_ctrl = false;
  for (const auto& [key, value] : *pairs) {
    bool ok = true;
    if (key == "t") {
      ok = ParseList(key, value, 0, 0, false, 1e7, "times [s]", &s.t, error);
      has_t = ok;
      for (size_t i = 1; ok && i < s.t.size(); ++i) {
        if (s.t[i] < s.t[i - 1])
          ok = Fail(error, key,
                    "key 't' = " + Shown(value) +
                        ": times must not "
                        "decrease");
      }
    } else if (key == "ctrl") {
      ok = ParseList(key, value, 0, -1e9, false, 1e9, "ctrl values", &s.value, error);
      has_ctrl = ok;
    } else {
      ok = Fail(error, key, UnknownKey(key, kKeys));
    }
    if (!ok) return std::nullopt;
  }
  if (!has_t || !has_ctrl) {
    Fail(error, has_t ? "ctrl" : "t",
         std::string("missing required key '") + (has_t ? "ctrl" : "t") + "'");
    return std::nullopt;
  }
  if (s.t.size() != s.value.size()) {
    Fail(error, "ctrl",
         "keys 't' and 'ctrl' must have as many values (" + std::to_string(s.t.size()) + " and " +
             std::to_string(s.value.size()) + ")");
    return std::nullopt;
  }
  return s;
}

}  // namespace mjtether
