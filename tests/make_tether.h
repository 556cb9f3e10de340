// Builds a Tether for engine tests the way the parser would: effects resolved from the
// coefficients and the environment (or from an explicit `effects=` list). Fails the test on
// a parameter error.
#ifndef MJTETHER_TESTS_MAKE_TETHER_H_
#define MJTETHER_TESTS_MAKE_TETHER_H_

#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "declaration.h"
#include "tether.h"

namespace mjtether {

inline Tether Make(const TetherParams& p, const Environment& env,
                   const std::string& effects = "") {
  TetherParams q = p;
  DeclarationError e;
  std::optional<unsigned> fx = ResolveEffects(q, env, effects, &e);
  EXPECT_TRUE(fx.has_value()) << e.message;
  q.effects = fx.value_or(kAxial);
  std::string error;
  std::optional<Tether> t = Tether::Create(q, env, &error);
  EXPECT_TRUE(t.has_value()) << error;
  return *t;
}

}  // namespace mjtether

#endif  // MJTETHER_TESTS_MAKE_TETHER_H_
