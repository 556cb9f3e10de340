#include "winch_declaration.h"

#include <algorithm>
#include <cmath>
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

// A finite number in (lo, hi] (lo closed when !lo_open); NaN fails the comparisons.
bool Number(const std::string& key, const std::string& text, double lo, bool lo_open, double hi,
            const char* unit, double* out, DeclarationError* error) {
  const std::string range = std::string(lo_open ? "(" : "[") + Fmt(lo) + ", " + Fmt(hi) + "]";
  double x = 0;
  const NumberStatus status = ParseDecimal(text, &x);
  if (status == NumberStatus::kUnderflow) {
    return Fail(error, key,
                "key '" + key + "' = " + Shown(text) +
                    " is out of range (below 2.2e-308 in magnitude; write 0 or a larger "
                    "number); allowed: " + range + " " + unit);
  }
  if (status != NumberStatus::kOk) {
    return Fail(error, key, "key '" + key + "': '" + Shown(text) + "' " + NumberProblem(status));
  }
  if (!((lo_open ? x > lo : x >= lo) && x <= hi)) {
    return Fail(error, key,
                "key '" + key + "' = " + Shown(text) + " is out of range; allowed: " + range +
                    " " + unit);
  }
  *out = x;
  return true;
}

}  // namespace

std::optional<WinchParams> ParseWinch(const std::string& text, DeclarationError* error) {
  static const std::vector<const char*> kKeys = {"end",        "mode",      "actuator",
                                                 "min_length", "max_length", "max_speed",
                                                 "max_accel",  "tau",        "band"};
  std::optional<KeyValues> pairs = SplitKeyValues(text, error);
  if (!pairs) return std::nullopt;
  WinchParams w;
  std::vector<bool> has(kKeys.size(), false);  // which keys were given
  for (const auto& [key, value] : *pairs) {
    bool ok = true;
    for (size_t k = 0; k < kKeys.size(); ++k) has[k] = has[k] || key == kKeys[k];
    if (key == "end") {
      if (value == "A" || value == "B") {
        w.end = value == "A" ? 0 : 1;
      } else {
        ok = Fail(error, key, "key 'end' = " + Shown(value) + "; allowed: A, B");
      }
    } else if (key == "mode") {
      if (value == "speed" || value == "tension") {
        w.mode = value == "speed" ? WinchMode::kSpeed : WinchMode::kTension;
      } else {
        ok = Fail(error, key, "key 'mode' = " + Shown(value) + "; allowed: speed, tension");
      }
    } else if (key == "actuator") {
      w.actuator = value;
    } else if (key == "min_length") {
      ok = Number(key, value, 0, true, 1e5, "m", &w.min_length, error);
    } else if (key == "max_length") {
      ok = Number(key, value, 0, true, 1e5, "m", &w.max_length, error);
    } else if (key == "max_speed") {
      ok = Number(key, value, 0, true, 100, "m/s", &w.max_speed, error);
    } else if (key == "max_accel") {
      ok = Number(key, value, 0, true, 1e4, "m/s^2", &w.max_accel, error);
    } else if (key == "tau") {
      ok = Number(key, value, 0, false, 100, "s", &w.tau, error);
    } else if (key == "band") {
      ok = Number(key, value, 0, true, 10, "(fraction of the set tension)", &w.band, error);
    } else {
      std::string list;
      std::vector<std::string> keys;
      for (size_t i = 0; i < kKeys.size(); ++i) {
        list += std::string(i ? ", " : "") + kKeys[i];
        keys.emplace_back(kKeys[i]);
      }
      ok = Fail(error, key,
                "unknown key '" + Shown(key) + "'" + DidYouMean(key, keys) +
                    "; allowed keys: " + list);
    }
    if (!ok) return std::nullopt;
  }
  // actuator, min_length, max_length, max_speed, max_accel are required.
  for (size_t k : {size_t(2), size_t(3), size_t(4), size_t(5), size_t(6)}) {
    if (!has[k]) {
      Fail(error, kKeys[k],
           std::string("key '") + kKeys[k] + "' is missing; a winch needs actuator, "
           "min_length [m], max_length [m], max_speed [m/s] and max_accel [m/s^2]");
      return std::nullopt;
    }
  }
  if (!(w.min_length <= w.max_length)) {
    Fail(error, "min_length",
         "key 'min_length' = " + Fmt(w.min_length) + " m is greater than max_length = " +
             Fmt(w.max_length) + " m; allowed: min_length <= max_length");
    return std::nullopt;
  }
  return w;
}

double WinchSpeed(const WinchParams& w, const DrumState& s, double ctrl, double tension,
                  double dt, double impedance) {
  double target = 0;
  if (w.mode == WinchMode::kSpeed) {
    target = std::isfinite(ctrl) ? ctrl : 0;
  } else {
    const double set = std::isfinite(ctrl) ? std::max(ctrl, 0.0) : 0;
    const double b = dt / (w.tau + dt), M = w.max_speed;
    if (!(set > 0)) {
      target = s.speed + (M - s.speed) * b;
    } else {
      // Backward Euler of tau s' = clamp(gain (T - set)) - s with T at the step's end,
      // T(v) = tension - Z (v - s.speed): a speed that pays out lowers the tension it is
      // judged by within the same step. Taken at the step's start (Z = 0) the loop's pole,
      // (1 + gain Z)/tau, is stepped explicitly, and at gain Z b > 2 the drum and the tension
      // ring from step to step (a 14 MN/m end segment at 2 ms: 3 to 37 N about a set 30 N;
      // docs/winch.md). g(v) = v - s - b (clamp(e(v)) - s) increases with v: a saturated root
      // first, else the linear one.
      const double gain = M / (w.band * set);  // [m/s per N]
      const double Z = std::isfinite(impedance) ? std::max(impedance, 0.0) : 0;
      auto e = [&](double v) { return gain * (tension - set - Z * (v - s.speed)); };
      const double up = s.speed + (M - s.speed) * b, down = s.speed + (-M - s.speed) * b;
      if (e(up) >= M) {
        target = up;
      } else if (e(down) <= -M) {
        target = down;
      } else {
        target = s.speed + b * (gain * (tension - set) - s.speed) / (1 + b * gain * Z);
      }
    }
  }
  double v = std::clamp(target, -w.max_speed, w.max_speed);
  v = std::clamp(v, s.speed - w.max_accel * dt, s.speed + w.max_accel * dt);
  // Slow down ahead of a limit, no faster than max_accel: the largest speed v from which
  // steps of dt, each slower by max_accel dt, stop within the distance d left,
  // v dt + (v - a dt) dt + ... <= d, i.e. v^2 + a dt v - 2 a d <= 0.
  auto stoppable = [&](double d) {
    const double a = w.max_accel;
    return 0.5 * (-a * dt + std::sqrt(a * a * dt * dt + 8 * a * std::max(d, 0.0)));
  };
  v = std::min(v, std::max(stoppable(w.max_length - s.length), s.speed - w.max_accel * dt));
  v = std::max(v, std::min(-stoppable(s.length - w.min_length), s.speed + w.max_accel * dt));
  // Brake: stop exactly at a limit; hold there while the command pushes outward.
  if (s.length + v * dt > w.max_length) v = std::max(0.0, (w.max_length - s.length) / dt);
  if (s.length + v * dt < w.min_length) v = std::min(0.0, (w.min_length - s.length) / dt);
  return v;
}

}  // namespace mjtether
