// Parsing of the `key=value` declarations that an MJCF file carries in <custom><text>.
//
//   <text name="water" data="density=1025 current=0.3,0,0 seabed=-60"/>
//   <text name="tether:umbilical" data="ends=tms,rov length=40 segments=40 ..."/>
//
// Pairs are separated by white space, list items inside a value by commas. Every key has a
// documented range; a value outside it, an unknown key, a duplicate key or a value that is not
// a finite number is an error whose message names the key and the allowed range. The caller
// (the MuJoCo glue or a test) prefixes the file and the element.
#ifndef MJTETHER_SRC_DECLARATION_H_
#define MJTETHER_SRC_DECLARATION_H_

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "params.h"

namespace mjtether {

// A declaration error: the key it concerns (may be empty) and a full sentence.
struct DeclarationError {
  std::string key;
  std::string message;
};

using KeyValues = std::vector<std::pair<std::string, std::string>>;

// Splits "a=1 b=2,3" into pairs. Fails on a token without '=', an empty key or value, or a key
// given twice.
std::optional<KeyValues> SplitKeyValues(const std::string& text, DeclarationError* error);

// A parsed tether declaration: the parameters plus the names of its end sites.
struct TetherDeclaration {
  TetherParams params;
  std::string site_a;
  std::string site_b;  // empty when end B is free
  std::string effects_text;  // `effects=` as written; empty: defaults
  // `contact=` as written: "all" or a comma list of geom or body names (resolved by the
  // MuJoCo glue); empty: no contact.
  std::string contact;
};

// [N s] The internal damping that gives the tether's segment axial mode the damping ratio
// zeta: adjacent nodes moving in opposite directions along the line, each segment's midpoint at
// rest. Each node of mass m = mass_per_length L0 sits between two half segments, so
//   m u'' + (4 damping / L0) u' + (4 EA / L0) u = 0,  omega_n = (2 / L0) sqrt(EA / mass_per_length),
// and zeta = damping / (L0 sqrt(EA mass_per_length)) (the relation of MoorDyn's BA/-zeta input,
// docs/reference.md "Internal damping"). The mode is the discretisation's own, at the highest
// axial frequency of the line; a lower mode of frequency s omega_n (s < 1) gets s zeta.
double SegmentModeDamping(const TetherParams& p, double zeta);

// Parses the water declaration.
std::optional<Water> ParseWater(const std::string& text, DeclarationError* error);

// Parses a tether declaration. The effects are resolved against the environment (see
// ResolveEffects), so `env` must be complete (gravity, wet, water).
std::optional<TetherDeclaration> ParseTether(const std::string& text, const Environment& env,
                                             DeclarationError* error);

// The effects a tether simulates. Defaults: axial always; damping if damping > 0; bending if
// EI > 0; weight if gravity != 0; in water buoyancy (gravity != 0), drag if Cdn or Cdt > 0,
// added mass if Can > 0, current if the current is non-zero, seabed if declared; clamp if a
// clamp is declared; compression if EAc > 0; contact if `contact=` is given. `effects=` (comma list of kEffectNames)
// replaces the defaults; naming an effect whose coefficient or declaration is missing is an
// error.
std::optional<unsigned> ResolveEffects(const TetherParams& p, const Environment& env,
                                       const std::string& effects_text, DeclarationError* error,
                                       bool has_contact = false);

// "axial,weight,..." for a bit set.
std::string EffectsToString(unsigned effects);

}  // namespace mjtether

#endif  // MJTETHER_SRC_DECLARATION_H_
