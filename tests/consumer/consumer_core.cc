// The engine alone (mjtether::core: C++17 and Eigen, no MuJoCo) from the installed headers: a
// declaration parsed, a tether built from it. Its rest segment length must be length/segments
// (40 m in 20 segments: 2 m, exact in binary), and a bad value must be refused naming its key.
#include <mjtether/declaration.h>
#include <mjtether/tether.h>

#include <cstdio>
#include <string>

int main() {
  mjtether::Environment env;  // defaults: gravity, dry
  mjtether::DeclarationError error;
  auto decl = mjtether::ParseTether(
      "ends=a,b length=40 segments=20 diameter=0.02 mass_per_length=0.35 EA=2e5", env, &error);
  if (!decl) {
    std::fprintf(stderr, "consumer_core: %s\n", error.message.c_str());
    return 2;
  }
  std::string why;
  auto tether = mjtether::Tether::Create(decl->params, env, &why);
  if (!tether) {
    std::fprintf(stderr, "consumer_core: %s\n", why.c_str());
    return 2;
  }
  const bool bad_refused = !mjtether::ParseTether(
                               "ends=a,b length=-1 segments=20 diameter=0.02 "
                               "mass_per_length=0.35 EA=2e5",
                               env, &error) &&
                           error.key == "length";
  std::printf("%d segments of %g m; length=-1 refused: %s\n", tether->segments(),
              tether->rest_segment_length(), bad_refused ? "yes" : "no");
  return tether->segments() == 20 && tether->rest_segment_length() == 2.0 && bad_refused ? 0 : 1;
}
