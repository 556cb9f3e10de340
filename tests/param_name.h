// Names for parameterised cases (INSTANTIATE_TEST_SUITE_P's 4th argument), so that gtest and
// ctest name a failing case by its parameters ("Contact/Capstan.X/mu0p3_theta0p5pi_implicit")
// instead of its index and a hex dump ("Contact/Capstan.X/3", "16-byte object <9A-99 ...>").
#ifndef MJTETHER_TESTS_PARAM_NAME_H_
#define MJTETHER_TESTS_PARAM_NAME_H_

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace mjtether::testing {

// Letters, digits and '_' only (gtest's rule for a parameter's name): anything else is '_'.
inline std::string ParamName(std::string s) {
  for (char& c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    if (!ok) c = '_';
  }
  return s;
}

// A number in a name: %g with '.' as 'p', '-' as 'm' and no '+' (0.45 -> 0p45, 1e+08 -> 1e08).
inline std::string NumberName(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%g", x);
  std::string s;
  for (const char* c = buf; *c; ++c) {
    if (*c == '.')
      s += 'p';
    else if (*c == '-')
      s += 'm';
    else if (*c != '+')
      s += *c;
  }
  return s;
}

// For suites whose parameter is a string (an integrator's or a geom's name).
struct StringParamName {
  template <class P>
  std::string operator()(const ::testing::TestParamInfo<P>& info) const {
    return ParamName(std::string(info.param));
  }
};

}  // namespace mjtether::testing

#endif  // MJTETHER_TESTS_PARAM_NAME_H_
