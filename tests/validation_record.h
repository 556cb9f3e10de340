// Rows of the README's validation table, recorded by the validation tests as GoogleTest
// properties so that tools/validation_table.py can build the table from the tests' own
// output (`--gtest_output=json`). Row k of a test is the properties "rowK.case",
// "rowK.reference", "rowK.ours", "rowK.error", "rowK.tolerance", "rowK.orders",
// "rowK.segments".
#ifndef MJTETHER_TESTS_VALIDATION_RECORD_H_
#define MJTETHER_TESTS_VALIDATION_RECORD_H_

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace mjtether::testing {

inline std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

// Observed orders of convergence between successive resolutions, from the errors at each
// (segments, error): p = log(e_i / e_i+1) / log(N_i+1 / N_i).
inline std::string Orders(const std::vector<std::pair<int, double>>& errors) {
  std::string s;
  for (size_t i = 0; i + 1 < errors.size(); ++i) {
    const double p = std::log(std::abs(errors[i].second) / std::abs(errors[i + 1].second)) /
                     std::log(double(errors[i + 1].first) / errors[i].first);
    s += (s.empty() ? "" : ", ") + Format("%.1f", p);
  }
  if (!errors.empty()) {
    std::string ns;
    for (const auto& e : errors) ns += (ns.empty() ? "" : "/") + std::to_string(e.first);
    s += " (N = " + ns + ")";
  }
  return s;
}

// Order between the last two resolutions (for assertions).
inline double LastOrder(const std::vector<std::pair<int, double>>& errors) {
  const size_t n = errors.size();
  return std::log(std::abs(errors[n - 2].second) / std::abs(errors[n - 1].second)) /
         std::log(double(errors[n - 1].first) / errors[n - 2].first);
}

struct Row {
  std::string what;       // the case and the quantity compared
  std::string reference;  // the reference: formula or source, and its value
  std::string ours;       // our value at the default resolution, with unit
  std::string error;      // signed error, relative (%) or absolute (with unit)
  std::string tolerance;  // what the test asserts
  std::string orders;     // observed convergence orders, or "–"
  int segments = 0;       // default resolution
};

// Records row k of the current test.
inline void Record(int k, const Row& r) {
  const std::string p = "row" + std::to_string(k) + ".";
  ::testing::Test::RecordProperty(p + "case", r.what);
  ::testing::Test::RecordProperty(p + "reference", r.reference);
  ::testing::Test::RecordProperty(p + "ours", r.ours);
  ::testing::Test::RecordProperty(p + "error", r.error);
  ::testing::Test::RecordProperty(p + "tolerance", r.tolerance);
  ::testing::Test::RecordProperty(p + "orders", r.orders.empty() ? "–" : r.orders);
  ::testing::Test::RecordProperty(p + "segments", std::to_string(r.segments));
}

// "−0.012%" style relative error.
inline std::string Percent(double relative) { return Format("%+.3g%%", 100 * relative); }

}  // namespace mjtether::testing

#endif  // MJTETHER_TESTS_VALIDATION_RECORD_H_
