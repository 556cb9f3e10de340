// libFuzzer target over the declaration parser (src/declaration.cc): SplitKeyValues,
// ParseWater, ParseTether in a dry and a wet scene, and Tether::Create on what parses. Beyond
// "no crash, no hang, no leak" (libFuzzer with AddressSanitizer, LeakSanitizer and UBSan), it
// checks what the parser promises: every accepted value is finite and inside its documented
// range, and every rejection names a message.
//
//   tools/fuzz.sh [SECONDS]     (builds with clang-14 into build-fuzz/ and runs)
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "declaration.h"
#include "tether.h"

namespace {

using namespace mjtether;

void Check(bool condition) {
  if (!condition) __builtin_trap();
}

void CheckWater(const Water& w) {
  Check(w.density > 0 && w.density <= 1e4);
  for (int i = 0; i < 3; ++i) Check(std::abs(w.current[i]) <= 1e3);
  Check(!w.has_seabed || (w.seabed >= -1.1e4 && w.seabed <= 1e4));
  Check(w.seabed_stiffness > 0 && w.seabed_stiffness <= 1e10);
  Check(w.seabed_damping == -1 || (w.seabed_damping >= 0 && w.seabed_damping <= 1e10));
  Check(w.seabed_friction >= 0 && w.seabed_friction <= 10);
  Check(w.seabed_friction_axial >= 0 && w.seabed_friction_axial <= 10);
  Check(w.seabed_friction_speed > 0 && w.seabed_friction_speed <= 10);
}

void CheckTether(const TetherDeclaration& d, const Environment& env) {
  const TetherParams& p = d.params;
  Check(p.length > 0 && p.length <= 1e5);
  Check(p.segments >= 1 && p.segments <= 100000);
  Check(p.diameter > 0 && p.diameter <= 10);
  Check(p.mass_per_length > 0 && p.mass_per_length <= 1e5);
  Check(p.EA > 0 && p.EA <= 1e13);
  Check(p.EI >= 0 && p.EI <= 1e12);
  Check(p.EAc >= 0 && p.EAc <= 1e13);  // 0: not declared
  Check(((p.effects & kCompression) == 0) || p.EAc > 0);
  Check(p.damping >= 0 && p.damping <= 1e12);
  Check(p.Cdn >= 0 && p.Cdn <= 100 && p.Cdt >= 0 && p.Cdt <= 100 && p.Can >= 0 && p.Can <= 100);
  Check(p.substeps >= 0 && p.substeps <= 100000);
  Check(p.max_step >= 0 && p.max_step <= 1);
  Check(!(p.substeps > 0 && p.max_step > 0));
  Check(p.max_strain > 0 && p.max_strain <= 100);
  Check(!d.site_a.empty() && d.site_a != "free" && d.site_a != d.site_b);
  Check(p.free_end == d.site_b.empty());
  Check((p.effects & kAxial) != 0);
  // Small enough to build quickly: the engine must accept what the parser accepted, with a
  // finite, positive stability limit.
  if (p.segments <= 2000) {
    std::string error;
    std::optional<Tether> t = Tether::Create(p, env, &error);
    Check(t.has_value());
    Check(t->ExplicitStableStep() > 0);
    Check(t->SubstepsFor(0.002) >= 1);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  DeclarationError e;
  if (!SplitKeyValues(text, &e)) Check(!e.message.empty());

  e = {};
  std::optional<Water> water = ParseWater(text, &e);
  if (water) {
    CheckWater(*water);
  } else {
    Check(!e.message.empty());
  }

  Environment dry;
  Environment wet;
  wet.wet = true;
  wet.water.current = Vec3(0.3, 0, 0);
  wet.water.has_seabed = true;
  wet.water.seabed = -50;
  for (const Environment& env : {dry, wet}) {
    e = {};
    std::optional<TetherDeclaration> d = ParseTether(text, env, &e);
    if (d) {
      CheckTether(*d, env);
    } else {
      Check(!e.message.empty());
    }
  }
  return 0;
}
