#include "declaration.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include "text_check.h"

namespace mjtether {
namespace {

std::string Fmt(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

bool Fail(DeclarationError* error, const std::string& key, const std::string& message) {
  if (error) *error = {key, message};
  return false;
}

// Parses a finite decimal number that fills the whole string (no "1.5abc", "nan", "inf" or
// "0x10"; see ParseDecimal).
bool ParseNumber(const std::string& key, const std::string& text, double* value,
                 DeclarationError* error) {
  const NumberStatus status = ParseDecimal(text, value);
  if (status == NumberStatus::kOk) return true;
  return Fail(error, key,
              "key '" + Shown(key) + "': '" + Shown(text) + "' " + NumberProblem(status));
}

// A closed or half-open range [lo, hi] or (lo, hi]; NaN fails every comparison, so the checks
// are written to fail on it.
struct Range {
  double lo, hi;
  bool lo_open;
  std::string Describe() const {
    return std::string(lo_open ? "(" : "[") + Fmt(lo) + ", " + Fmt(hi) + "]";
  }
  bool Contains(double x) const { return (lo_open ? x > lo : x >= lo) && x <= hi; }
};

bool ParseInRange(const std::string& key, const std::string& text, const Range& range,
                  double* value, DeclarationError* error) {
  double x;
  if (ParseDecimal(text, &x) == NumberStatus::kUnderflow) {
    return Fail(error, key,
                "key '" + key + "' = " + Shown(text) +
                    " is out of range (below 2.2e-308 in magnitude; write 0 or a larger number); "
                    "allowed: " +
                    range.Describe());
  }
  if (!ParseNumber(key, text, &x, error)) return false;
  if (!range.Contains(x)) {
    return Fail(
        error, key,
        "key '" + key + "' = " + Shown(text) + " is out of range; allowed: " + range.Describe());
  }
  *value = x;
  return true;
}

bool ParseInteger(const std::string& key, const std::string& text, const Range& range,
                  int* value, DeclarationError* error) {
  double x;
  if (!ParseInRange(key, text, range, &x, error)) return false;
  if (x != std::floor(x)) {
    return Fail(
        error, key,
        "key '" + key + "' = " + Shown(text) + " must be a whole number in " + range.Describe());
  }
  *value = static_cast<int>(x);
  return true;
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::string item;
  std::istringstream s(text);
  while (std::getline(s, item, ',')) items.push_back(item);
  if (!text.empty() && text.back() == ',') items.push_back("");
  return items;
}

bool ParseVector(const std::string& key, const std::string& text, Vec3* v,
                 DeclarationError* error) {
  std::vector<std::string> items = SplitList(text);
  if (items.size() != 3) {
    return Fail(error, key, "key '" + key + "' = " + Shown(text) + " must be 3 numbers x,y,z");
  }
  for (int i = 0; i < 3; ++i) {
    if (!ParseNumber(key, items[i], &(*v)[i], error)) return false;
    if (!(std::abs((*v)[i]) <= 1e3)) {
      return Fail(error, key,
                  "key '" + key + "' = " + Shown(text) + ": each component in [-1000, 1000]");
    }
  }
  return true;
}

// "unknown key 'diamter'; did you mean 'diameter'? (allowed keys: ...)".
std::string UnknownKey(const std::string& key, const char* const* allowed, int n) {
  std::string list;
  std::vector<std::string> keys;
  for (int i = 0; i < n; ++i) {
    list += std::string(i ? ", " : "") + allowed[i];
    keys.emplace_back(allowed[i]);
  }
  return "unknown key '" + Shown(key) + "'" + DidYouMean(key, keys) + "; allowed keys: " + list;
}

}  // namespace

std::optional<KeyValues> SplitKeyValues(const std::string& text, DeclarationError* error) {
  KeyValues pairs;
  if (std::optional<std::string> odd = OddCharacter(text)) {
    Fail(error, "", *odd);
    return std::nullopt;
  }
  std::istringstream s(text);
  std::string token;
  while (s >> token) {
    size_t eq = token.find('=');
    if (eq == std::string::npos) {
      Fail(error, "", "'" + Shown(token) + "' is not of the form key=value");
      return std::nullopt;
    }
    std::string key = token.substr(0, eq), value = token.substr(eq + 1);
    if (key.empty() || value.empty()) {
      Fail(error, key,
           (key.empty() ? "" : "key '" + Shown(key) + "': ") + "'" + Shown(token) +
               "' needs both a key and a value (key=value, no spaces)");
      return std::nullopt;
    }
    for (const auto& kv : pairs) {
      if (kv.first == key) {
        Fail(error, key, "key '" + Shown(key) + "' is given twice");
        return std::nullopt;
      }
    }
    pairs.emplace_back(key, value);
  }
  return pairs;
}

// A word that can name a geom: a letter or '_' first, then letters, digits and _ - . : /
// (so "nan", "inf" and "0x10" stay numbers that are refused as such).
static bool IsGeomName(const std::string& v) {
  if (v.empty() || !(std::isalpha(static_cast<unsigned char>(v[0])) || v[0] == '_')) return false;
  for (char ch : v) {
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || std::strchr("_-.:/", ch))) return false;
  }
  const std::string low = [&] {
    std::string l;
    for (char ch : v) l += static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return l;
  }();
  return low != "nan" && low != "inf" && low != "infinity";
}

std::optional<Water> ParseWater(const std::string& text, DeclarationError* error) {
  static const char* const kKeys[] = {
      "density",          "current",         "seabed",
      "seabed_stiffness", "seabed_damping",  "seabed_friction",
      "seabed_friction_axial", "seabed_friction_speed", "current_profile"};
  std::optional<KeyValues> pairs = SplitKeyValues(text, error);
  if (!pairs) return std::nullopt;
  Water w;
  for (const auto& [key, value] : *pairs) {
    bool ok = true;
    if (key == "density") {
      ok = ParseInRange(key, value, {0, 1e4, true}, &w.density, error);
    } else if (key == "current") {
      ok = ParseVector(key, value, &w.current, error);
    } else if (key == "current_profile") {
      // Read by the MuJoCo glue, which knows the model's directory (ReadCurrentProfile).
      if (value.size() < 5 || value.compare(value.size() - 4, 4, ".csv") != 0) {
        ok = Fail(error, key,
                  "key 'current_profile' = " + Shown(value) + ": expected a file name FILE.csv");
      }
      w.current_profile = value;
    } else if (key == "seabed") {
      // A height [m], or the name of a plane or hfield geom (resolved by the MuJoCo glue).
      double z;
      if (ParseDecimal(value, &z) == NumberStatus::kNotNumber && IsGeomName(value)) {
        w.seabed_geom = value;
        w.has_seabed = true;
      } else {
        ok = ParseInRange(key, value, {-1.1e4, 1e4, false}, &w.seabed, error);
        w.has_seabed = ok;
      }
    } else if (key == "seabed_stiffness") {
      ok = ParseInRange(key, value, {0, 1e10, true}, &w.seabed_stiffness, error);
    } else if (key == "seabed_damping") {
      ok = ParseInRange(key, value, {0, 1e10, false}, &w.seabed_damping, error);
    } else if (key == "seabed_friction") {
      ok = ParseInRange(key, value, {0, 10, false}, &w.seabed_friction, error);
    } else if (key == "seabed_friction_axial") {
      ok = ParseInRange(key, value, {0, 10, false}, &w.seabed_friction_axial, error);
    } else if (key == "seabed_friction_speed") {
      ok = ParseInRange(key, value, {0, 10, true}, &w.seabed_friction_speed, error);
    } else {
      ok = Fail(error, key, UnknownKey(key, kKeys, std::size(kKeys)));
    }
    if (!ok) return std::nullopt;
  }
  bool seabed_key = false;
  for (const auto& kv : *pairs) {
    seabed_key |= kv.first.rfind("seabed_", 0) == 0;
  }
  if (seabed_key && !w.has_seabed) {
    Fail(error, "seabed", "seabed_* keys are given but no 'seabed' height: add seabed=Z [m]");
    return std::nullopt;
  }
  if (w.seabed_friction_axial < 0) w.seabed_friction_axial = w.seabed_friction;
  if (!w.current_profile.empty() && w.current.squaredNorm() > 0) {
    Fail(error, "current_profile",
         "keys 'current' and 'current_profile' exclude each other: give the uniform current as "
         "a one-row profile, or drop 'current'");
    return std::nullopt;
  }
  return w;
}

// A current is declared: uniform and non-zero, or a profile (read or only named: the effects
// are resolved before the glue reads the file in some callers).
static bool HasCurrent(const Water& w) { return w.has_current() || !w.current_profile.empty(); }

std::optional<unsigned> ResolveEffects(const TetherParams& p, const Environment& env,
                                       const std::string& effects_text, DeclarationError* error,
                                       bool has_contact) {
  const bool gravity = env.gravity.squaredNorm() > 0;
  const bool wet = env.wet;
  // What each effect needs, and whether its coefficient makes it active by default.
  struct Need {
    bool available;
    bool by_default;
    const char* missing;
  };
  const Need needs[kNumEffects] = {
      {true, true, ""},
      {p.damping > 0, p.damping > 0, "damping > 0"},
      {p.EI > 0, p.EI > 0, "EI > 0"},
      {gravity, gravity, "a non-zero <option gravity>"},
      {wet && gravity, wet && gravity, "a water declaration and gravity"},
      {wet && (p.Cdn > 0 || p.Cdt > 0), wet && (p.Cdn > 0 || p.Cdt > 0),
       "a water declaration and Cdn or Cdt > 0"},
      {wet && p.Can > 0, wet && p.Can > 0, "a water declaration and Can > 0"},
      {wet && HasCurrent(env.water) && (p.Cdn > 0 || p.Cdt > 0),
       wet && HasCurrent(env.water) && (p.Cdn > 0 || p.Cdt > 0),
       "a non-zero water current (or current_profile) and drag (Cdn or Cdt > 0)"},
      {wet && env.water.has_seabed, wet && env.water.has_seabed, "water seabed=Z"},
      {(p.clamp_a || p.clamp_b) && p.EI > 0, (p.clamp_a || p.clamp_b) && p.EI > 0,
       "clamp=A|B|both and EI > 0"},
      {p.EAc > 0, p.EAc > 0, "EAc > 0"},
      {has_contact, has_contact, "contact=all or contact=NAME,..."},
  };
  unsigned effects = 0;
  if (effects_text.empty()) {
    for (int i = 0; i < kNumEffects; ++i) {
      if (needs[i].by_default) effects |= 1u << i;
    }
    return effects;
  }
  for (const std::string& name : SplitList(effects_text)) {
    int found = -1;
    for (int i = 0; i < kNumEffects; ++i) {
      if (name == kEffectNames[i]) found = i;
    }
    if (found < 0) {
      Fail(error, "effects",
           "key 'effects': unknown effect '" + Shown(name) +
               "'; allowed: " + EffectsToString((1u << kNumEffects) - 1));
      return std::nullopt;
    }
    if (!needs[found].available) {
      Fail(error, "effects",
           "key 'effects': effect '" + Shown(name) + "' needs " + needs[found].missing);
      return std::nullopt;
    }
    effects |= 1u << found;
  }
  if (!(effects & kAxial)) {
    Fail(error, "effects", "key 'effects': 'axial' is required (a tether without axial "
                           "stiffness has no shape)");
    return std::nullopt;
  }
  if ((effects & kCurrent) && !(effects & kDrag)) {
    Fail(error, "effects", "key 'effects': 'current' acts through drag; list 'drag' too");
    return std::nullopt;
  }
  return effects;
}

std::string EffectsToString(unsigned effects) {
  std::string s;
  for (int i = 0; i < kNumEffects; ++i) {
    if (effects & (1u << i)) s += std::string(s.empty() ? "" : ",") + kEffectNames[i];
  }
  return s;
}

double SegmentModeDamping(const TetherParams& p, double zeta) {
  const double L0 = p.length / p.segments;  // [m]
  return zeta * L0 * std::sqrt(p.EA * p.mass_per_length);
}

std::optional<TetherDeclaration> ParseTether(const std::string& text, const Environment& env,
                                             DeclarationError* error) {
  static const char* const kKeys[] = {
      "ends",    "length", "segments",   "diameter", "mass_per_length", "EA",
      "EI",      "damping", "damping_ratio", "Cdn",  "Cdt",      "Can",  "integrator",
      "clamp",   "effects", "substeps",  "max_step", "max_strain", "bending",
      "EAc",     "contact", "contact_stiffness", "contact_damping", "contact_friction",
      "contact_friction_speed", "start"};
  static const char* const kRequired[] = {"ends",     "length",          "segments",
                                          "diameter", "mass_per_length", "EA"};
  std::optional<KeyValues> pairs = SplitKeyValues(text, error);
  if (!pairs) return std::nullopt;
  TetherDeclaration decl;
  TetherParams& p = decl.params;
  std::string clamp;
  for (const auto& [key, value] : *pairs) {
    bool ok = true;
    if (key == "ends") {
      std::vector<std::string> sites = SplitList(value);
      if (sites.size() != 2 || sites[0].empty() || sites[1].empty()) {
        ok = Fail(error, key,
                  "key 'ends' = " + Shown(value) +
                      " must be two site names A,B (B may be "
                      "'free')");
      } else if (sites[0] == "free") {
        ok = Fail(error, key, "key 'ends': end A must be a site; only end B may be 'free'");
      } else if (sites[0] == sites[1]) {
        ok = Fail(error, key, "key 'ends': both ends are on site '" + sites[0] + "'");
      } else {
        decl.site_a = sites[0];
        p.free_end = sites[1] == "free";
        decl.site_b = p.free_end ? "" : sites[1];
      }
    } else if (key == "length") {
      ok = ParseInRange(key, value, {0, 1e5, true}, &p.length, error);
    } else if (key == "segments") {
      ok = ParseInteger(key, value, {1, 1e5, false}, &p.segments, error);
    } else if (key == "diameter") {
      ok = ParseInRange(key, value, {0, 10, true}, &p.diameter, error);
    } else if (key == "mass_per_length") {
      ok = ParseInRange(key, value, {0, 1e5, true}, &p.mass_per_length, error);
    } else if (key == "EA") {
      ok = ParseInRange(key, value, {0, 1e13, true}, &p.EA, error);
    } else if (key == "EAc") {
      ok = ParseInRange(key, value, {0, 1e13, true}, &p.EAc, error);  // as EA: EAc = EA is usual
    } else if (key == "EI") {
      ok = ParseInRange(key, value, {0, 1e12, false}, &p.EI, error);
    } else if (key == "damping") {
      ok = ParseInRange(key, value, {0, 1e12, false}, &p.damping, error);
    } else if (key == "damping_ratio") {
      ok = ParseInRange(key, value, {0, 10, false}, &p.damping_ratio, error);
    } else if (key == "Cdn") {
      ok = ParseInRange(key, value, {0, 100, false}, &p.Cdn, error);
    } else if (key == "Cdt") {
      ok = ParseInRange(key, value, {0, 100, false}, &p.Cdt, error);
    } else if (key == "Can") {
      ok = ParseInRange(key, value, {0, 100, false}, &p.Can, error);
    } else if (key == "integrator") {
      if (value == "explicit") {
        p.integrator = Integrator::kExplicit;
      } else if (value == "implicit") {
        p.integrator = Integrator::kImplicit;
      } else if (value == "implicit2") {
        p.integrator = Integrator::kImplicit2;
      } else if (value == "rk4") {
        p.integrator = Integrator::kRK4;
      } else if (value == "bdf2") {
        p.integrator = Integrator::kBdf2;
      } else {
        ok = Fail(error, key,
                  "key 'integrator' = " + Shown(value) +
                      "; allowed: bdf2 (default), implicit, implicit2, explicit, rk4");
      }
    } else if (key == "start") {
      if (value == "catenary") {
        p.start = Start::kCatenary;
      } else if (value == "static") {
        p.start = Start::kStatic;
      } else {
        ok = Fail(error, key,
                  "key 'start' = " + Shown(value) + "; allowed: catenary (default), static");
      }
    } else if (key == "bending") {
      if (value == "galerkin") {
        p.bending = Bending::kGalerkin;
      } else if (value == "der") {
        p.bending = Bending::kDER;
      } else {
        ok = Fail(error, key, "key 'bending' = " + Shown(value) + "; allowed: galerkin, der");
      }
    } else if (key == "clamp") {
      clamp = value;
      p.clamp_a = value == "A" || value == "both";
      p.clamp_b = value == "B" || value == "both";
      if (!p.clamp_a && !p.clamp_b) {
        ok = Fail(error, key, "key 'clamp' = " + Shown(value) + "; allowed: A, B, both");
      }
    } else if (key == "effects") {
      decl.effects_text = value;
    } else if (key == "substeps") {
      ok = ParseInteger(key, value, {1, 1e5, false}, &p.substeps, error);
    } else if (key == "max_step") {
      ok = ParseInRange(key, value, {0, 1, true}, &p.max_step, error);
    } else if (key == "max_strain") {
      ok = ParseInRange(key, value, {0, 100, true}, &p.max_strain, error);
    } else if (key == "contact") {
      // Names are checked against the model by the glue; here only the list's form.
      for (const std::string& item : SplitList(value)) {
        if (item.empty()) ok = Fail(error, key, "key 'contact' = " + value + " has an empty name");
      }
      decl.contact = value;
    } else if (key == "contact_stiffness") {
      ok = ParseInRange(key, value, {0, 1e10, true}, &p.contact_stiffness, error);
    } else if (key == "contact_damping") {
      ok = ParseInRange(key, value, {0, 1e10, false}, &p.contact_damping, error);
    } else if (key == "contact_friction") {
      ok = ParseInRange(key, value, {0, 10, false}, &p.contact_friction, error);
    } else if (key == "contact_friction_speed") {
      ok = ParseInRange(key, value, {0, 10, true}, &p.contact_friction_speed, error);
    } else {
      ok = Fail(error, key, UnknownKey(key, kKeys, std::size(kKeys)));
    }
    if (!ok) return std::nullopt;
  }
  // Required keys after the unknown ones, so that 'diamter=' reads as a misspelling.
  for (const char* key : kRequired) {
    bool present = false;
    for (const auto& kv : *pairs) present |= kv.first == key;
    if (!present) {
      Fail(error, key, std::string("missing required key '") + key + "'");
      return std::nullopt;
    }
  }
  if (p.free_end && p.clamp_b) {
    Fail(error, "clamp", "key 'clamp' = " + clamp + ": end B is free and cannot be clamped");
    return std::nullopt;
  }
  if ((p.clamp_a || p.clamp_b) && !(p.EI > 0)) {
    Fail(error, "clamp", "key 'clamp' needs bending stiffness: EI > 0");
    return std::nullopt;
  }
  if (p.contact_friction > 0 && p.integrator == Integrator::kImplicit2) {
    // Its second stage extrapolates the first by 2.4 x, which the saturating friction law
    // does not survive: capstan ratios came out up to 2x low (docs/contact.md).
    Fail(error, "contact_friction",
         "key 'contact_friction' > 0 is not supported with integrator=implicit2 yet; use "
         "integrator=implicit, explicit or rk4, or contact_friction=0");
    return std::nullopt;
  }
  if (p.damping_ratio >= 0) {
    bool both = false;
    for (const auto& kv : *pairs) both |= kv.first == "damping";
    if (both) {
      Fail(error, "damping_ratio",
           "keys 'damping' [N s] and 'damping_ratio' [-] exclude each other; give one");
      return std::nullopt;
    }
    p.damping = SegmentModeDamping(p, p.damping_ratio);
  }
  if (p.substeps > 0 && p.max_step > 0) {
    Fail(error, "substeps", "keys 'substeps' and 'max_step' exclude each other; give one");
    return std::nullopt;
  }
  bool contact_key = false;
  for (const auto& kv : *pairs) contact_key |= kv.first.rfind("contact_", 0) == 0;
  if (contact_key && decl.contact.empty()) {
    Fail(error, "contact", "contact_* keys are given but no 'contact': add contact=all or "
                           "contact=NAME,... (geom or body names)");
    return std::nullopt;
  }
  std::optional<unsigned> effects =
      ResolveEffects(p, env, decl.effects_text, error, !decl.contact.empty());
  if (!effects) return std::nullopt;
  p.effects = *effects;
  return decl;
}

}  // namespace mjtether
