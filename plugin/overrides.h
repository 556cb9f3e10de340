// Declaration overrides: change one key of one <custom><text> declaration of an MJCF file
// without editing the file, as `mjtether run --set` and `mjtether sweep` do.
//
//   std::vector<mjtether::Override> o;
//   o.push_back(*mjtether::ParseOverride("tether:umbilical.EA=4e5", &error));
//   mjModel* m = mjtether::LoadModel("models/rov_tether.xml", o, &error);
//
// The override replaces the key's value in the element's `data` (or appends `KEY=VALUE` when
// the key is absent), and the model is then loaded and attached as usual: the value goes
// through the same parser and range checks as one written in the file, and an error names
// the file, the element and the key. The edited text is loaded from memory under the file's
// own path, so <include>, meshes and motion csv files resolve relative to the model as before.
// Only <text> elements of the top-level file can be overridden (not of an <include>d file).
//
// One name is not a <text>: `option.timestep=SECONDS` sets MuJoCo's <option timestep> (in
// (0, 1] s) on the compiled model before the tethers are attached, so that the load-time
// checks and advice see the new step. It is how a run is compared with itself at a smaller
// step, as the advisor's messages suggest, without editing the file (a <text name="option">
// cannot be overridden). No other <option> attribute can.
#ifndef MJTETHER_PLUGIN_OVERRIDES_H_
#define MJTETHER_PLUGIN_OVERRIDES_H_

#include <mujoco/mujoco.h>

#include <optional>
#include <string>
#include <vector>

namespace mjtether {

struct Override {
  std::string text;   // the <text> element's name, e.g. "tether:umbilical" or "water"
  std::string key;    // e.g. "EA"
  std::string value;  // as written in the MJCF, e.g. "0.5,0,0"
};

// Splits a column or option name "TEXT.KEY" at its last '.' (keys contain no '.').
// Returns false with *error set when either part is empty or the value is unusable.
bool SplitOverrideName(const std::string& name, Override* o, std::string* error);

// Parses "TEXT.KEY=VALUE". The value may not be empty nor contain white space (list items
// are separated by commas, as in the MJCF).
std::optional<Override> ParseOverride(const std::string& spec, std::string* error);

// The MJCF text `xml` with each override applied to the data of the <text> it names. Fails
// (with *error naming the element) when the file has no such <text>, or has it twice.
std::optional<std::string> ApplyOverrides(const std::string& xml,
                                          const std::vector<Override>& overrides,
                                          std::string* error);

// LoadModel (mjtether.h) with overrides. Without overrides it is exactly LoadModel(path).
mjModel* LoadModel(const std::string& path, const std::vector<Override>& overrides,
                   std::string* error);

}  // namespace mjtether

#endif  // MJTETHER_PLUGIN_OVERRIDES_H_
