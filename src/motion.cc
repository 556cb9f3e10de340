#include "motion.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "text_check.h"

namespace mjtether {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Ranges of a table row: times [s] and offsets [m] (as a harmonic motion's amplitude).
constexpr double kMaxTableTime = 1e7;
constexpr double kMaxTableOffset = 1e4;

}  // namespace

std::optional<Motion> Motion::Create(const MotionParams& params, const std::string& csv_path,
                                     std::string* error) {
  auto fail = [&](const std::string& message) {
    if (error) *error = message;
    return std::nullopt;
  };
  Motion mo;
  mo.p_ = params;
  if (!params.csv.empty()) {
    std::ifstream in(csv_path);
    if (!in) return fail("key 'csv': cannot read '" + csv_path + "'");
    std::string line;
    int row = 0;
    while (std::getline(in, line)) {
      ++row;
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      double v[4];
      if (!ParseCsvRow(line, 4, v)) {
        if (row == 1) continue;  // a header
        return fail("key 'csv': " + csv_path + " line " + std::to_string(row) +
                    ": expected 4 decimal numbers time,x,y,z");
      }
      if (!(std::abs(v[0]) <= kMaxTableTime)) {
        std::ostringstream o;
        o << "key 'csv': " << csv_path << " line " << row << ": time " << v[0]
          << " s outside [-1e7, 1e7]";
        return fail(o.str());
      }
      for (int i = 1; i < 4; ++i) {
        if (!(std::abs(v[i]) <= kMaxTableOffset)) {
          std::ostringstream o;
          o << "key 'csv': " << csv_path << " line " << row << ": offset "
            << "xyz"[i - 1] << " = " << v[i] << " m outside [-10000, 10000]";
          return fail(o.str());
        }
      }
      if (!mo.time_.empty() && !(v[0] > mo.time_.back())) {
        return fail("key 'csv': " + csv_path + " line " + std::to_string(row) +
                    ": times must increase strictly");
      }
      mo.time_.push_back(v[0]);
      mo.table_.emplace_back(v[1], v[2], v[3]);
    }
    if (mo.time_.empty()) return fail("key 'csv': " + csv_path + " has no rows time,x,y,z");
  }
  if (params.ramp >= 0) {
    mo.ramp_ = params.ramp;
  } else if (params.csv.empty()) {
    for (int i = 0; i < 3; ++i) {
      if (params.harmonic[i]) mo.ramp_ = std::max(mo.ramp_, params.period[i]);
    }
  }
  return mo;
}

Vec3 Motion::Raw(double t, Vec3* rate) const {
  Vec3 s = Vec3::Zero();
  *rate = Vec3::Zero();
  if (!time_.empty()) {
    if (t <= time_.front()) return table_.front();
    if (t >= time_.back()) return table_.back();
    const size_t j = std::upper_bound(time_.begin(), time_.end(), t) - time_.begin() - 1;
    const double h = time_[j + 1] - time_[j];
    *rate = (table_[j + 1] - table_[j]) / h;
    return table_[j] + (t - time_[j]) * *rate;
  }
  for (int i = 0; i < 3; ++i) {
    if (!p_.harmonic[i]) continue;
    const double w = 2 * kPi / p_.period[i];  // [rad/s]
    s[i] = p_.amplitude[i] * std::sin(w * t + p_.phase[i]);
    (*rate)[i] = p_.amplitude[i] * w * std::cos(w * t + p_.phase[i]);
  }
  return s;
}

Vec3 Motion::Offset(double t) const {
  Vec3 rate;
  const Vec3 s = Raw(t, &rate);
  if (t >= ramp_) return s;
  if (t <= 0) return Vec3::Zero();
  return 0.5 * (1 - std::cos(kPi * t / ramp_)) * s;
}

Vec3 Motion::Velocity(double t) const {
  Vec3 rate;
  const Vec3 s = Raw(t, &rate);
  if (t >= ramp_) return rate;
  if (t <= 0) return Vec3::Zero();
  const double r = 0.5 * (1 - std::cos(kPi * t / ramp_));
  const double dr = 0.5 * kPi / ramp_ * std::sin(kPi * t / ramp_);  // [1/s]
  return r * rate + dr * s;
}

double Schedule::At(double time) const {
  if (t.empty()) return 0;
  if (time <= t.front()) return value.front();
  if (time >= t.back()) return value.back();
  const size_t j = std::upper_bound(t.begin(), t.end(), time) - t.begin() - 1;
  const double h = t[j + 1] - t[j];
  if (h <= 0) return value[j + 1];
  return value[j] + (time - t[j]) / h * (value[j + 1] - value[j]);
}

}  // namespace mjtether
