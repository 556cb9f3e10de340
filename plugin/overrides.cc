// Declaration overrides (overrides.h): the `data` of a <text> element rewritten in the MJCF
// text, which is then loaded from memory under the file's own path.
#include "overrides.h"

#include <cctype>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>

#include "mjtether.h"
#include "text_check.h"

namespace mjtether {
namespace {

// The name that stands for MuJoCo's <option> in an override ("option.timestep=0.0005").
constexpr char kOptionText[] = "option";

bool StartsWith(const std::string& s, size_t at, const char* prefix) {
  return s.compare(at, std::strlen(prefix), prefix) == 0;
}

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

int LineOf(const std::string& s, size_t pos) {
  int line = 1;
  for (size_t i = 0; i < pos && i < s.size(); ++i) line += s[i] == '\n';
  return line;
}

// Appends code point c as UTF-8.
void AppendUtf8(unsigned long c, std::string* out) {
  if (c < 0x80) {
    *out += static_cast<char>(c);
  } else if (c < 0x800) {
    *out += static_cast<char>(0xC0 | (c >> 6));
    *out += static_cast<char>(0x80 | (c & 0x3F));
  } else if (c < 0x10000) {
    *out += static_cast<char>(0xE0 | (c >> 12));
    *out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    *out += static_cast<char>(0x80 | (c & 0x3F));
  } else {
    *out += static_cast<char>(0xF0 | (c >> 18));
    *out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
    *out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
    *out += static_cast<char>(0x80 | (c & 0x3F));
  }
}

// An XML attribute value with its entity and character references replaced.
std::string Unescape(const std::string& v) {
  std::string out;
  for (size_t i = 0; i < v.size(); ++i) {
    if (v[i] != '&') {
      out += v[i];
      continue;
    }
    const size_t semi = v.find(';', i);
    if (semi == std::string::npos) {
      out += v[i];
      continue;
    }
    const std::string ref = v.substr(i + 1, semi - i - 1);
    if (ref == "lt")
      out += '<';
    else if (ref == "gt")
      out += '>';
    else if (ref == "amp")
      out += '&';
    else if (ref == "quot")
      out += '"';
    else if (ref == "apos")
      out += '\'';
    else if (ref.size() > 1 && ref[0] == '#') {
      const bool hex = ref[1] == 'x' || ref[1] == 'X';
      AppendUtf8(std::strtoul(ref.c_str() + (hex ? 2 : 1), nullptr, hex ? 16 : 10), &out);
    } else {
      out += v.substr(i, semi - i + 1);  // unknown entity: left as written
    }
    i = semi;
  }
  return out;
}

std::string Escape(const std::string& v) {
  std::string out;
  for (char c : v) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// One <text> start tag of the file: its name and where its data value is.
struct TextTag {
  std::string name;
  bool has_data = false;
  size_t data_begin = 0, data_end = 0;  // the raw value between the quotes
  size_t insert_at = 0;                 // where to add a data attribute if there is none
};

// Finds every <text> start tag outside comments, CDATA and processing instructions.
bool FindTextTags(const std::string& xml, std::vector<TextTag>* tags, std::string* error) {
  size_t i = 0;
  auto skip_to = [&](const char* end) {
    const size_t j = xml.find(end, i);
    if (j == std::string::npos) {
      *error = "line " + std::to_string(LineOf(xml, i)) + ": unterminated markup";
      return false;
    }
    i = j + std::strlen(end);
    return true;
  };
  while ((i = xml.find('<', i)) != std::string::npos) {
    if (StartsWith(xml, i, "<!--")) {
      if (!skip_to("-->")) return false;
    } else if (StartsWith(xml, i, "<![CDATA[")) {
      if (!skip_to("]]>")) return false;
    } else if (StartsWith(xml, i, "<?")) {
      if (!skip_to("?>")) return false;
    } else if (StartsWith(xml, i, "<!")) {
      if (!skip_to(">")) return false;
    } else if (StartsWith(xml, i, "<text") && i + 5 < xml.size() &&
               (IsSpace(xml[i + 5]) || xml[i + 5] == '/' || xml[i + 5] == '>')) {
      TextTag tag;
      tag.insert_at = i + 5;
      size_t p = i + 5;
      const int line = LineOf(xml, i);
      auto bad = [&](const std::string& what) {
        *error = "line " + std::to_string(line) + ": cannot read a <text> tag (" + what + ")";
        return false;
      };
      for (;;) {
        while (p < xml.size() && IsSpace(xml[p])) ++p;
        if (p >= xml.size()) return bad("no closing '>'");
        if (xml[p] == '>' || xml[p] == '/') break;
        const size_t name_begin = p;
        while (p < xml.size() && !IsSpace(xml[p]) && xml[p] != '=') ++p;
        const std::string attr = xml.substr(name_begin, p - name_begin);
        while (p < xml.size() && IsSpace(xml[p])) ++p;
        if (p >= xml.size() || xml[p] != '=') return bad("attribute '" + attr + "' has no value");
        ++p;
        while (p < xml.size() && IsSpace(xml[p])) ++p;
        if (p >= xml.size() || (xml[p] != '"' && xml[p] != '\'')) {
          return bad("attribute '" + attr + "' is not quoted");
        }
        const char quote = xml[p++];
        const size_t end = xml.find(quote, p);
        if (end == std::string::npos) return bad("attribute '" + attr + "' is not closed");
        if (attr == "name") tag.name = Unescape(xml.substr(p, end - p));
        if (attr == "data") {
          tag.has_data = true;
          tag.data_begin = p;
          tag.data_end = end;
        }
        p = end + 1;
      }
      tags->push_back(tag);
      i = p;
    } else {
      ++i;
    }
  }
  return true;
}

// `data` with KEY's value replaced, or KEY=VALUE appended. Pairs are re-joined by one space
// (the declaration parser splits on any white space, so the meaning is unchanged).
std::string SetKey(const std::string& data, const std::string& key, const std::string& value) {
  std::istringstream in(data);
  std::string token, out;
  bool done = false;
  while (in >> token) {
    if (!done && token.compare(0, key.size() + 1, key + "=") == 0) {
      token = key + "=" + value;
      done = true;
    }
    out += (out.empty() ? "" : " ") + token;
  }
  if (!done) out += (out.empty() ? "" : " ") + key + "=" + value;
  return out;
}

}  // namespace

bool SplitOverrideName(const std::string& name, Override* o, std::string* error) {
  const size_t dot = name.rfind('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == name.size()) {
    *error = "'" + name +
             "' is not TEXT.KEY (the <text> element's name, a dot, one of its keys; e.g. "
             "tether:umbilical.EA or water.current)";
    return false;
  }
  o->text = name.substr(0, dot);
  o->key = name.substr(dot + 1);
  for (char c : o->key) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) {
      *error = "'" + name + "': key '" + o->key + "' is not a declaration key";
      return false;
    }
  }
  return true;
}

std::optional<Override> ParseOverride(const std::string& spec, std::string* error) {
  const size_t eq = spec.find('=');
  if (eq == std::string::npos) {
    *error = "'" + spec + "' is not TEXT.KEY=VALUE (e.g. water.current=0.5,0,0)";
    return std::nullopt;
  }
  Override o;
  if (!SplitOverrideName(spec.substr(0, eq), &o, error)) return std::nullopt;
  o.value = spec.substr(eq + 1);
  if (o.value.empty()) {
    *error = "'" + spec + "': empty value";
    return std::nullopt;
  }
  for (char c : o.value) {
    if (IsSpace(c) || c == '\0') {
      *error = "'" + spec +
               "': the value contains white space (list items are separated by "
               "commas, without spaces: 0.5,0,0)";
      return std::nullopt;
    }
  }
  return o;
}

std::optional<std::string> ApplyOverrides(const std::string& xml,
                                          const std::vector<Override>& overrides,
                                          std::string* error) {
  std::vector<TextTag> tags;
  if (!FindTextTags(xml, &tags, error)) return std::nullopt;
  // New data per tag, in file order.
  std::vector<std::optional<std::string>> data(tags.size());
  for (const Override& o : overrides) {
    int found = -1;
    for (size_t t = 0; t < tags.size(); ++t) {
      if (tags[t].name != o.text) continue;
      if (found >= 0) {
        *error = "<text name=\"" + o.text + "\"> appears twice";
        return std::nullopt;
      }
      found = static_cast<int>(t);
    }
    if (found < 0) {
      *error = "no <text name=\"" + o.text + "\"> in this file (to override key '" + o.key +
               "'; texts of <include>d files cannot be overridden)";
      return std::nullopt;
    }
    const TextTag& tag = tags[found];
    if (!data[found]) {
      data[found] = tag.has_data
                        ? Unescape(xml.substr(tag.data_begin, tag.data_end - tag.data_begin))
                        : std::string();
    }
    *data[found] = SetKey(*data[found], o.key, o.value);
  }
  // Rewrite from the end so that earlier offsets stay valid.
  std::string out = xml;
  for (size_t t = tags.size(); t-- > 0;) {
    if (!data[t]) continue;
    const std::string escaped = Escape(*data[t]);
    if (tags[t].has_data) {
      out.replace(tags[t].data_begin, tags[t].data_end - tags[t].data_begin, escaped);
    } else {
      out.insert(tags[t].insert_at, " data=\"" + escaped + "\"");
    }
  }
  return out;
}

// For a refusal of the edited file: the overrides of the <text> elements it names, so that a
// value the file does not hold is not looked for there (" (from the override tether:u.EA=-5)").
std::string OverridesNamed(const std::string& error, const std::vector<Override>& overrides) {
  std::string named;
  for (const Override& o : overrides) {
    if (o.text == kOptionText) continue;
    if (error.find("<text name=\"" + o.text + "\">") == std::string::npos) continue;
    named += (named.empty() ? "" : ", ") + Shown(o.text + "." + o.key + "=" + o.value);
  }
  return named.empty() ? "" : " (the file as edited by the override(s) " + named + ")";
}

mjModel* LoadModel(const std::string& path, const std::vector<Override>& overrides,
                   std::string* error) {
  if (overrides.empty()) return LoadModel(path, error);
  // option.timestep: MuJoCo's <option timestep>, set on the compiled model before Attach, so
  // that the load-time checks and advice (coupling omega h, stable steps, warnings) see it.
  std::vector<Override> texts;
  double timestep = 0;  // [s] 0: not overridden
  for (const Override& o : overrides) {
    if (o.text != kOptionText) {
      texts.push_back(o);
      continue;
    }
    const std::string spec = o.text + "." + o.key + "=" + o.value;
    if (o.key != "timestep") {
      *error = path + ": '" + Shown(spec) + "': of <option>, only timestep can be overridden " +
               "(option.timestep=SECONDS)";
      return nullptr;
    }
    const NumberStatus status = ParseDecimal(o.value, &timestep);
    if (status != NumberStatus::kOk || !(timestep > 0 && timestep <= kMaxTimestep)) {
      std::ostringstream allowed;
      allowed << "; allowed: (0, " << kMaxTimestep << "] s (MuJoCo's <option timestep>)";
      *error = path + ": '" + Shown(spec) + "': " +
               (status == NumberStatus::kOk ? "is out of range" : NumberProblem(status)) +
               allowed.str();
      return nullptr;
    }
  }
  std::ifstream f(path, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  if (!f) {
    *error = path + ": cannot read the file";
    return nullptr;
  }
  std::string message;
  std::optional<std::string> xml = ApplyOverrides(s.str(), texts, &message);
  if (!xml) {
    *error = path + ": " + message;
    return nullptr;
  }
  if (!mju_user_error) {
    auto warning = mju_user_warning;
    InstallErrorHandlers();
    mju_user_warning = warning;
  }
  // The edited file in a VFS under the file's own path: MuJoCo finds the top-level file there
  // (by its name without directories) and everything else (includes, meshes) on disk, relative
  // to the path's directory.
  auto vfs = std::make_unique<mjVFS>();  // about 2 MB: not on the stack
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), path.c_str(), static_cast<int>(xml->size())) != 0) {
    *error = path + ": cannot create an in-memory copy";
    return nullptr;
  }
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), path.c_str())], xml->data(), xml->size());
  char buffer[1000] = "";
  mjModel* m = mj_loadXML(path.c_str(), vfs.get(), buffer, sizeof(buffer));
  mj_deleteVFS(vfs.get());
  if (!m) {
    *error = path + ": " + buffer;
    return nullptr;
  }
  if (timestep > 0) m->opt.timestep = timestep;
  if (!Attach(m, path, error)) {
    mj_deleteModel(m);
    *error += OverridesNamed(*error, overrides);
    return nullptr;
  }
  return m;
}

}  // namespace mjtether
