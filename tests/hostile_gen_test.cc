// The hostile-input generator (docs/bad_input.md, "Generated hostile inputs"): the shipped
// models, changed the way users get them wrong, through the real mjtether binary. The
// hand-written suite (tests/hostile/cases.txt) covers the classes someone thought of; this one
// draws 1 to 3 edits per scene at random from a catalogue of mistakes (a misspelt key, a value
// off by powers of ten or not a number, a dropped or doubled key, a deleted declaration, a
// moved or renamed site, a body's mass or the time step scaled, a file cut short, a key added
// with a random value, another integrator or segment count), runs `mjtether run` (or `info`)
// on it and judges the outcome:
//
//   - never a crash (a signal), a hang (no exit within the timeout), or an exit code other
//     than 0, 1 and 2;
//   - exit 0: the log's rows are complete and every number in it is finite;
//   - exit 1 (stopped): one message naming the model and the simulated time, and never after
//     benign edits only (another tether or MuJoCo integrator, a smaller step), since every
//     shipped model runs: a metamorphic oracle, which found MuJoCo's RK4 breaking the
//     vehicles' added mass;
//   - exit 2 (refused): a message naming the model file and the element (a <text>, or the line
//     of MuJoCo's XML error), and no output file left behind;
//   - at most 16 kB printed (no flood of warnings).
//
// Every failure it found is fixed and kept as a hand-written case in tests/hostile/cases.txt.
//
//   MJTETHER_HOSTILE_GEN_COUNT=N    scenes (default 300, the CI set: seeds 1..N)
//   MJTETHER_HOSTILE_GEN_FIRST=K    first seed (default 1)
//   MJTETHER_HOSTILE_GEN_SEEDS=a,b  only these seeds
//   MJTETHER_HOSTILE_GEN_VERBOSE=1  one line per scene: the edits and the outcome
//   MJTETHER_HOSTILE_GEN_KEEP=DIR   keep each failing scene's model and output under DIR/seedN
//                                   (every scene's with MJTETHER_HOSTILE_GEN_SEEDS)
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "run_binary.h"
#include "text_check.h"

namespace {

namespace fs = std::filesystem;
using mjtether::test_util::BinaryRun;
using mjtether::test_util::ReadFileBytes;
using mjtether::test_util::RunBinary;

constexpr double kDuration = 0.3;  // [s] simulated per run: enough for a start-up to go wrong
constexpr double kTimeout = 90;    // [s] wall clock before a run counts as hung
constexpr size_t kMaxOutput = 16384;

long EnvLong(const char* name, long fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atol(v) : fallback;
}

// The models the generator starts from: every shipped scene.
std::vector<std::string> Models() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(MJTETHER_MODELS_DIR)) {
    if (e.path().extension() == ".xml") names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// A span [begin, end) of the file.
struct Span {
  size_t begin = 0, end = 0;
};

std::vector<Span> FindAll(const std::string& text, const std::regex& re, int group = 0) {
  std::vector<Span> out;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator();
       ++it) {
    const size_t b = static_cast<size_t>(it->position(group));
    out.push_back({b, b + static_cast<size_t>(it->length(group))});
  }
  return out;
}

class Mutator {
 public:
  Mutator(std::string text, unsigned long seed) : text_(std::move(text)), rng_(seed) {}

  // Applies one random edit; returns what it did ("" when the kind had nothing to edit).
  std::string Apply() {
    std::string r;
    bool benign = false;  // an edit after which a scene that runs must still run
    switch (Pick(19)) {
      case 0: r = KeyTypo(); break;
      case 1: r = ValueScale(); break;
      case 2: r = ValueSpecial(); break;
      case 3: r = TokenDrop(); break;
      case 4: r = TokenDouble(); break;
      case 5: r = Integrator(); benign = true; break;
      case 6: r = Segments(); break;
      case 7: r = TextDrop(); break;
      case 8: r = AttributeScale(); break;
      case 9: r = SiteMove(); break;
      case 10: r = SiteRename(); break;
      case 11: r = Truncate(); break;
      case 12: r = Timestep(&benign); break;
      case 13: r = Joint(); break;
      case 14: r = MujocoIntegrator(); benign = true; break;
      case 15: r = EndsSwap(); break;
      case 16: r = TetherTwice(); break;
      case 17: r = BodyMove(); break;
      default: r = KeyAdd();
    }
    if (!r.empty() && !benign) benign_ = false;
    return r;
  }
  // Every edit so far was benign: another tether or MuJoCo integrator, or a smaller step.
  bool benign() const { return benign_; }
  // The benign edits by name (the systematic sweep below).
  std::string SetTetherIntegrator(const std::string& name) {
    if (std::string r = SetKey("integrator", name); !r.empty()) return r;
    static const std::regex tether(R"re(<text\s+name="tether:[^"]*"[^>]*?data=")re");
    const std::vector<Span> all = FindAll(text_, tether);
    if (all.empty()) return "";
    text_.insert(all[0].end, "integrator=" + name + " ");
    return "integrator=" + name + " added";
  }
  std::string SetMujocoIntegrator(const std::string& name) { return MujocoIntegrator(name); }
  const std::string& text() const { return text_; }

 private:
  int Pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }
  template <class T>
  const T& PickOf(const std::vector<T>& v) {
    return v[static_cast<size_t>(Pick(static_cast<int>(v.size())))];
  }
  void Replace(const Span& s, const std::string& with) {
    text_.replace(s.begin, s.end - s.begin, with);
  }

  // key=value tokens inside the data="..." of <text> elements (group 1: key, 2: value).
  struct Token {
    Span all, key, value;
  };
  std::vector<Token> Tokens() {
    std::vector<Token> out;
    static const std::regex data(R"re(<text\s[^>]*?data="([^"]*)")re");
    static const std::regex token(R"re(([A-Za-z_]+)=([^\s"]*))re");
    for (auto it = std::sregex_iterator(text_.begin(), text_.end(), data);
         it != std::sregex_iterator(); ++it) {
      const size_t base = static_cast<size_t>(it->position(1));
      const std::string body = (*it)[1].str();
      for (auto t = std::sregex_iterator(body.begin(), body.end(), token);
           t != std::sregex_iterator(); ++t) {
        const size_t b = base + static_cast<size_t>(t->position(0));
        const size_t kb = base + static_cast<size_t>(t->position(1));
        const size_t vb = base + static_cast<size_t>(t->position(2));
        out.push_back({{b, b + static_cast<size_t>(t->length(0))},
                       {kb, kb + static_cast<size_t>(t->length(1))},
                       {vb, vb + static_cast<size_t>(t->length(2))}});
      }
    }
    return out;
  }
  std::vector<Token> NumericTokens() {
    std::vector<Token> out;
    for (const Token& t : Tokens()) {
      const std::string v = text_.substr(t.value.begin, t.value.end - t.value.begin);
      if (!v.empty() && (std::isdigit(static_cast<unsigned char>(v[0])) || v[0] == '-')) {
        out.push_back(t);
      }
    }
    return out;
  }
  std::string Show(const Span& s) { return text_.substr(s.begin, s.end - s.begin); }

  std::string KeyTypo() {
    const std::vector<Token> tokens = Tokens();
    if (tokens.empty()) return "";
    const Token t = PickOf(tokens);
    std::string key = Show(t.key);
    const std::string was = key;
    switch (Pick(4)) {
      case 0:
        key.erase(static_cast<size_t>(Pick(static_cast<int>(key.size()))), 1);
        break;
      case 1:
        if (key.size() > 1) {
          const size_t i = static_cast<size_t>(Pick(static_cast<int>(key.size()) - 1));
          std::swap(key[i], key[i + 1]);
        }
        break;
      case 2:
        key[0] = static_cast<char>(std::isupper(static_cast<unsigned char>(key[0]))
                                       ? std::tolower(key[0])
                                       : std::toupper(key[0]));
        break;
      default:
        key.insert(static_cast<size_t>(Pick(static_cast<int>(key.size()) + 1)), 1, 'e');
    }
    Replace(t.key, key);
    return "key " + was + " -> " + key;
  }
  std::string ValueScale() {
    const std::vector<Token> tokens = NumericTokens();
    if (tokens.empty()) return "";
    const Token t = PickOf(tokens);
    const std::string value = Show(t.value);
    const size_t comma = value.find(',');
    const double x = std::atof(value.substr(0, comma).c_str());
    static const std::vector<int> powers = {-12, -6, -3, -1, 1, 3, 6, 12};
    const int p = PickOf(powers);
    std::ostringstream s;
    s.precision(6);
    s << x * std::pow(10.0, p) << (comma == std::string::npos ? "" : value.substr(comma));
    const std::string was = Show(t.all);
    Replace(t.value, s.str());
    return was + " x 1e" + std::to_string(p);
  }
  std::string ValueSpecial() {
    const std::vector<Token> tokens = Tokens();
    if (tokens.empty()) return "";
    const Token t = PickOf(tokens);
    static const std::vector<std::string> values = {
        "0", "-1", "nan", "inf", "-inf", "1e999", "", "abc", "1,2", "0x10", "1e-320", "1,,2",
        "1e308", "-0", "2.5.1", ","};
    const std::string v = PickOf(values);
    const std::string was = Show(t.all);
    Replace(t.value, v);
    return was + " -> '" + v + "'";
  }
  std::string TokenDrop() {
    const std::vector<Token> tokens = Tokens();
    if (tokens.empty()) return "";
    const Token t = PickOf(tokens);
    const std::string was = Show(t.all);
    Replace(t.all, "");
    return "drop " + was;
  }
  std::string TokenDouble() {
    const std::vector<Token> tokens = Tokens();
    if (tokens.empty()) return "";
    const Token t = PickOf(tokens);
    const std::string was = Show(t.all);
    Replace(t.all, was + " " + was);
    return "double " + was;
  }
  std::string SetKey(const std::string& key, const std::string& value) {
    for (const Token& t : Tokens()) {
      if (Show(t.key) == key) {
        const std::string was = Show(t.all);
        Replace(t.value, value);
        return was + " -> " + value;
      }
    }
    return "";
  }
  std::string Integrator() {
    static const std::vector<std::string> names = {"explicit", "rk4", "implicit", "implicit2",
                                                   "bdf2"};
    return SetKey("integrator", PickOf(names));
  }
  std::string Segments() {
    static const std::vector<std::string> counts = {"1", "2", "3", "7", "400", "3000"};
    return SetKey("segments", PickOf(counts));
  }
  std::string TextDrop() {
    static const std::regex element(R"re(<text\s[^>]*?/>)re");
    const std::vector<Span> all = FindAll(text_, element);
    if (all.empty()) return "";
    const Span s = PickOf(all);
    std::string was = Show(s);
    was = was.substr(0, was.find("data"));
    Replace(s, "");
    return "delete " + was;
  }
  // A number of an attribute outside <text>: masses, positions, sizes, gravity, gear, ranges.
  std::string AttributeScale() {
    static const std::regex attr(
        R"re(\s(mass|pos|size|gravity|gear|ctrlrange|density|diaginertia|fromto)="([^"]*)")re");
    const std::vector<Span> all = FindAll(text_, attr, 2);
    if (all.empty()) return "";
    const Span s = PickOf(all);
    std::istringstream in(Show(s));
    std::vector<double> v;
    for (double x; in >> x;) v.push_back(x);
    if (v.empty()) return "";
    static const std::vector<double> factors = {0, -1, 1e-6, 1e-3, 0.1, 10, 1e3, 1e6};
    const double f = PickOf(factors);
    const size_t i = static_cast<size_t>(Pick(static_cast<int>(v.size())));
    v[i] *= f;
    std::ostringstream out;
    out.precision(6);
    for (size_t k = 0; k < v.size(); ++k) out << (k ? " " : "") << v[k];
    const std::string was = Show(s);
    Replace(s, out.str());
    return "attribute '" + was + "' -> '" + out.str() + "'";
  }
  // The pos="x y z" of an element matching `element` (group 1) moved by up to `reach` [m] on
  // each axis.
  std::string MovePos(const std::regex& element, double reach, const std::string& label) {
    const std::vector<Span> all = FindAll(text_, element, 1);
    if (all.empty()) return "";
    const Span s = PickOf(all);
    std::istringstream in(Show(s));
    double p[3] = {0, 0, 0};
    in >> p[0] >> p[1] >> p[2];
    std::uniform_real_distribution<double> offset(-reach, reach);
    std::ostringstream out;
    out.precision(6);
    out << p[0] + offset(rng_) << " " << p[1] + offset(rng_) << " " << p[2] + offset(rng_);
    const std::string was = Show(s);
    Replace(s, out.str());
    return label + " pos '" + was + "' -> '" + out.str() + "'";
  }
  std::string SiteMove() {
    static const std::regex site(R"re(<site\s[^>]*?pos="([^"]*)")re");
    return MovePos(site, 60, "site");
  }
  std::string SiteRename() {
    static const std::regex site(R"re(<site\s+name="([^"]*)")re");
    const std::vector<Span> all = FindAll(text_, site, 1);
    if (all.empty()) return "";
    const Span s = PickOf(all);
    const std::string was = Show(s);
    Replace(s, was + "_x");
    return "rename site " + was;
  }
  std::string Truncate() {
    const size_t at = static_cast<size_t>(Pick(static_cast<int>(text_.size())));
    text_.resize(at);
    return "cut at byte " + std::to_string(at);
  }
  std::string Timestep(bool* benign) {
    static const std::regex step(R"re(timestep="([^"]*)")re");
    const std::vector<Span> all = FindAll(text_, step, 1);
    static const std::vector<double> factors = {0.1, 0.5, 5, 25, 250, 1e6};
    const double f = PickOf(factors);
    if (all.empty()) return "";
    *benign = f < 1;
    const double h = std::atof(Show(all[0]).c_str()) * f;
    std::ostringstream out;
    out << h;
    Replace(all[0], out.str());
    return "timestep x " + std::to_string(f);
  }
  // The vehicle's free joint made a hinge, a slide or a ball, or removed (welded to its parent).
  std::string Joint() {
    const size_t at = text_.find("<freejoint/>");
    if (at == std::string::npos) return "";
    static const std::vector<std::string> joints = {
        "<joint type=\"hinge\" axis=\"0 0 1\"/>", "<joint type=\"slide\" axis=\"1 0 0\"/>",
        "<joint type=\"ball\"/>", ""};
    const std::string j = PickOf(joints);
    text_.replace(at, 12, j);
    return "freejoint -> '" + j + "'";
  }
  std::string MujocoIntegrator() {
    static const std::vector<std::string> names = {"RK4", "implicit", "Euler"};
    return MujocoIntegrator(PickOf(names));
  }
  std::string MujocoIntegrator(const std::string& name) {
    const size_t at = text_.find("<option");
    if (at == std::string::npos) return "";
    const size_t close = text_.find('>', at);
    const size_t attr = text_.find("integrator=\"", at);
    if (attr != std::string::npos && attr < close) {
      const size_t end = text_.find('"', attr + 12);
      text_.replace(attr + 12, end - attr - 12, name);
    } else {
      text_.insert(at + 7, " integrator=\"" + name + "\"");
    }
    return "<option integrator=" + name + ">";
  }
  std::string EndsSwap() {
    for (const Token& t : Tokens()) {
      if (Show(t.key) != "ends") continue;
      const std::string v = Show(t.value);
      const size_t comma = v.find(',');
      if (comma == std::string::npos) return "";
      Replace(t.value, v.substr(comma + 1) + "," + v.substr(0, comma));
      return "ends swapped";
    }
    return "";
  }
  // The first tether declared again under another name: two tethers between the same sites.
  std::string TetherTwice() {
    static const std::regex tether(R"re(<text\s+name="tether:[^"]*"[^>]*?/>)re");
    const std::vector<Span> all = FindAll(text_, tether);
    if (all.empty()) return "";
    std::string copy = Show(all[0]);
    copy.replace(copy.find("tether:"), 7, "tether:twin_");
    text_.insert(all[0].end, "\n" + copy);
    return "tether twice";
  }
  std::string BodyMove() {
    static const std::regex body(R"re(<body\s[^>]*?pos="([^"]*)")re");
    return MovePos(body, 300, "body");
  }
  std::string KeyAdd() {
    static const std::regex data(R"re(<text\s+name="(tether|water|vehicle|thrust|motion|winch)[^"]*"[^>]*?data=")re");
    const std::vector<Span> all = FindAll(text_, data);
    if (all.empty()) return "";
    static const std::vector<std::string> adds = {
        "start=static",      "EAc=1e5",        "EI=50",           "clamp=A",
        "clamp=B",           "effects=axial",  "substeps=3",      "max_step=1e-5",
        "bending=der",       "max_strain=0.01", "contact=floor",  "contact=all",
        "damping=1e6",       "Can=50",         "seabed=0",        "seabed=-1e4",
        "current=3,0,0",     "seabed_friction=5", "volume=10",    "cob=0,0,-5",
        "ends=a,b",          "length=0.01",    "diameter=2",      "mass_per_length=1e4"};
    const Span s = PickOf(all);
    const std::string add = PickOf(adds);
    text_.insert(s.end, add + " ");
    return "add " + add;
  }

  std::string text_;
  std::mt19937_64 rng_;
  bool benign_ = true;
};

struct Outcome {
  bool ok = true;
  std::string what;  // the outcome, or why it fails
};

// The log's NAME.x columns (each body's x; its y and z follow), as `mjtether run` writes them.
std::vector<size_t> XColumns(const std::vector<std::string>& head) {
  std::vector<size_t> x;
  for (size_t c = 0; c + 2 < head.size(); ++c) {
    const std::string& h = head[c];
    if (h.size() > 2 && h.compare(h.size() - 2, 2, ".x") == 0) x.push_back(c);
  }
  return x;
}

constexpr double kMaxSpeed = 340;  // [m/s] no ROV scene moves a body faster: a runaway

// Bodies (the log's NAME.x, .y, .z columns) that move faster than kMaxSpeed between samples.
std::string CheckSpeeds(const std::string& text) {
  std::istringstream s(text);
  std::string line;
  std::getline(s, line);
  const std::vector<std::string> head = mjtether::SplitCsvLine(line);
  const std::vector<size_t> x = XColumns(head);
  std::vector<double> last;
  double t_last = 0;
  while (std::getline(s, line)) {
    const std::vector<std::string> f = mjtether::SplitCsvLine(line);
    const double t = std::atof(f[0].c_str());
    std::vector<double> now;
    for (size_t c : x) {
      for (int k = 0; k < 3; ++k) now.push_back(std::atof(f[c + k].c_str()));
    }
    if (!last.empty() && t > t_last) {
      for (size_t b = 0; b < x.size(); ++b) {
        const double dx = now[3 * b] - last[3 * b], dy = now[3 * b + 1] - last[3 * b + 1],
                     dz = now[3 * b + 2] - last[3 * b + 2];
        const double v = std::sqrt(dx * dx + dy * dy + dz * dz) / (t - t_last);
        if (v > kMaxSpeed) {
          std::ostringstream m;
          m << head[x[b]].substr(0, head[x[b]].size() - 2) << " moves at " << v
            << " m/s between t = " << t_last << " and " << t << " s, and the run goes on";
          return m.str();
        }
      }
    }
    last = now;
    t_last = t;
  }
  return "";
}

// Every field of every data row a finite number (the header aside), every row complete.
std::string CheckLog(const std::string& path) {
  const std::string text = ReadFileBytes(path);
  if (text.empty()) return "the log is empty or missing";
  if (text.back() != '\n') return "the log's last row is cut";
  std::istringstream s(text);
  std::string line;
  size_t columns = 0;
  int row = 0;
  while (std::getline(s, line)) {
    const std::vector<std::string> fields = mjtether::SplitCsvLine(line);
    if (++row == 1) {
      columns = fields.size();
      continue;
    }
    if (fields.size() != columns) return "log row " + std::to_string(row) + " is incomplete";
    for (const std::string& f : fields) {
      char* end = nullptr;
      const double x = std::strtod(f.c_str(), &end);
      if (f.empty() || *end != '\0' || !std::isfinite(x)) {
        return "log row " + std::to_string(row) + " has '" + f + "'";
      }
    }
  }
  if (row < 2) return "the log has no data row";
  return CheckSpeeds(text);
}

// The first line that is not a warning, cut to 300 characters (for the verbose log).
std::string FirstLine(const std::string& out) {
  std::istringstream s(out);
  for (std::string line; std::getline(s, line);) {
    if (line.rfind("mjtether: warning", 0) == 0 || line.rfind("mjtether: note", 0) == 0) continue;
    return line.substr(0, 300);
  }
  return "";
}

// benign: the scene differs from a shipped model (each of which runs) only by benign edits, so
// it must run too, or be refused at load by the time-step advisor (an integrator that cannot
// hold the scene's coupling): a stop there is a wrong answer, whatever it blames.
Outcome Judge(const BinaryRun& run, const std::string& dir, bool info, bool benign) {
  const std::string& out = run.output;
  const std::string head = out.substr(0, 600);
  if (!run.started) return {false, "fork failed"};
  if (run.hung) return {false, "no exit within the timeout: " + head};
  if (!run.exited) return {false, "killed by signal " + std::to_string(run.signal) + ": " + head};
  if (out.size() > kMaxOutput) {
    return {false, "printed " + std::to_string(out.size()) + " bytes: " + head};
  }
  if (out.find("nan") != std::string::npos && out.find("'nan'") == std::string::npos &&
      out.find("= nan") == std::string::npos && out.find("=nan") == std::string::npos) {
    return {false, "prints a nan it was not given: " + head};
  }
  const bool log = fs::exists(dir + "/log.csv");
  switch (run.code) {
    case 0:
      if (info) return {true, "info"};
      if (std::string bad = CheckLog(dir + "/log.csv"); !bad.empty()) {
        return {false, "exit 0 but " + bad + ": " + head};
      }
      return {true, "ran"};
    case 1:
      if (benign) {
        return {false, "stopped after benign edits only (another integrator or a smaller "
                       "step) of a model that runs: " + head};
      }
      if (out.find("m.xml") == std::string::npos || out.find("t = ") == std::string::npos) {
        return {false, "exit 1 without the model and the time: " + head};
      }
      if (log) {
        if (std::string bad = CheckLog(dir + "/log.csv"); !bad.empty()) {
          return {false, "stopped, and " + bad + ": " + head};
        }
      }
      return {true, "stopped: " + FirstLine(out)};
    case 2: {
      if (out.find("m.xml") == std::string::npos) {
        return {false, "refused without naming the file: " + head};
      }
      const bool element = out.find("<text name=\"") != std::string::npos ||
                           out.find("line ") != std::string::npos ||
                           out.find("Line ") != std::string::npos ||
                           out.find("Element") != std::string::npos ||
                           out.find("<option") != std::string::npos;
      if (!element) return {false, "refused without naming the element: " + head};
      if (log) return {false, "refused but left log.csv: " + head};
      return {true, "refused: " + FirstLine(out)};
    }
    default:
      return {false, "exit code " + std::to_string(run.code) + ": " + head};
  }
}

struct Scene {
  unsigned long seed = 0;
  std::string model, edits;
  bool info = false;
  bool benign = false;  // only benign edits (Mutator::benign)
};

Scene Make(unsigned long seed, const std::vector<std::string>& models, std::string* text) {
  Scene s;
  s.seed = seed;
  s.model = models[seed % models.size()];
  Mutator m(ReadFileBytes(std::string(MJTETHER_MODELS_DIR) + "/" + s.model), seed * 7919 + 17);
  std::mt19937_64 rng(seed);
  // One edit in six scenes of ten, two in three, three in one: most scenes keep one mistake,
  // as a user's do, and some pile them up.
  const int draw = std::uniform_int_distribution<int>(0, 9)(rng);
  const int edits = draw < 6 ? 1 : draw < 9 ? 2 : 3;
  for (int k = 0, tries = 0; k < edits && tries < 20; ++tries) {
    const std::string e = m.Apply();
    if (e.empty()) continue;
    s.edits += (s.edits.empty() ? "" : "; ") + e;
    ++k;
  }
  s.info = std::uniform_int_distribution<int>(0, 9)(rng) == 0;  // a tenth through `info`
  s.benign = m.benign() && !s.edits.empty();
  *text = m.text();
  return s;
}

std::vector<unsigned long> Seeds() {
  std::vector<unsigned long> seeds;
  if (const char* only = std::getenv("MJTETHER_HOSTILE_GEN_SEEDS"); only && *only) {
    std::stringstream s(only);
    for (std::string item; std::getline(s, item, ',');) seeds.push_back(std::stoul(item));
    return seeds;
  }
  const long first = EnvLong("MJTETHER_HOSTILE_GEN_FIRST", 1);
  const long count = EnvLong("MJTETHER_HOSTILE_GEN_COUNT", 300);
  for (long k = 0; k < count; ++k) seeds.push_back(static_cast<unsigned long>(first + k));
  return seeds;
}

TEST(HostileGen, EveryEditedModelRunsOrStopsOrIsRefusedWithItsCause) {
  const std::vector<std::string> models = Models();
  ASSERT_GE(models.size(), 5u);
  const std::vector<unsigned long> seeds = Seeds();
  const bool verbose = EnvLong("MJTETHER_HOSTILE_GEN_VERBOSE", 0) != 0;
  const char* keep = std::getenv("MJTETHER_HOSTILE_GEN_KEEP");
  const bool listed = std::getenv("MJTETHER_HOSTILE_GEN_SEEDS") != nullptr;
  const std::string root = ::testing::TempDir() + "/hostile_gen_" + std::to_string(getpid());
  int counts[3] = {0, 0, 0};  // ran, stopped, refused

  // Two at a time: the runs are separate processes.
  const unsigned workers = std::max(1u, std::min(2u, std::thread::hardware_concurrency()));
  std::vector<std::string> lines(seeds.size());
  std::vector<char> failed(seeds.size(), 0);
  std::vector<std::string> kinds(seeds.size());
  std::vector<std::thread> pool;
  std::atomic<size_t> next{0};
  for (unsigned w = 0; w < workers; ++w) {
    pool.emplace_back([&]() {
      for (size_t i; (i = next++) < seeds.size();) {
        std::string text;
        const Scene s = Make(seeds[i], models, &text);
        const std::string dir = root + "/seed" + std::to_string(s.seed);
        fs::remove_all(dir);
        fs::create_directories(dir);
        for (const auto& e : fs::directory_iterator(MJTETHER_MODELS_DIR)) {
          fs::copy(e.path(), dir + "/" + e.path().filename().string());
        }
        std::ofstream(dir + "/m.xml", std::ios::binary) << text;
        std::ostringstream cmd;
        cmd << MJTETHER_CLI << (s.info ? " info m.xml" : " run m.xml --duration ")
            << (s.info ? "" : std::to_string(kDuration) + " --every 0.05 --log log.csv");
        const BinaryRun run = RunBinary(dir, cmd.str(), kTimeout);
        const Outcome o = Judge(run, dir, s.info, s.benign);
        std::ostringstream line;
        line << "seed " << s.seed << " [" << s.model << (s.info ? ", info" : "")
             << (s.benign ? ", benign" : "") << "; " << s.edits
             << "]: " << (o.ok ? "pass: " : "FAIL: ") << o.what << " (" << run.seconds << " s)";
        lines[i] = line.str();
        failed[i] = !o.ok;
        kinds[i] = o.what;
        if ((!o.ok || listed) && keep && *keep) {
          const std::string kept = std::string(keep) + "/seed" + std::to_string(s.seed);
          fs::remove_all(kept);
          fs::create_directories(kept);
          fs::copy(dir + "/m.xml", kept + "/m.xml");
          std::ofstream(kept + "/output.txt") << cmd.str() << "\n" << run.output;
        }
        fs::remove_all(dir);
      }
    });
  }
  for (std::thread& t : pool) t.join();
  fs::remove_all(root);
  int failures = 0;
  for (size_t i = 0; i < seeds.size(); ++i) {
    if (verbose) std::cout << lines[i] << "\n";
    if (failed[i]) {
      ++failures;
      ADD_FAILURE() << lines[i];
    } else {
      counts[kinds[i] == "ran" || kinds[i] == "info" ? 0 : kinds[i].rfind("stopped", 0) == 0 ? 1 : 2]++;
    }
  }
  std::cout << seeds.size() << " edited scenes: " << counts[0] << " ran, " << counts[1]
            << " stopped with a cause, " << counts[2] << " refused with a cause, " << failures
            << " failed\n";
  // The catalogue must reach all three outcomes on the CI set, or it tests too little.
  if (seeds.size() >= 100) {
    EXPECT_GT(counts[0], 0);
    EXPECT_GT(counts[2], 0);
  }
}

// The bodies' positions in the last row of a run log (the NAME.x, .y, .z columns).
std::vector<double> LastPositions(const std::string& path) {
  std::istringstream s(ReadFileBytes(path));
  std::string line, last;
  std::getline(s, line);
  const std::vector<std::string> head = mjtether::SplitCsvLine(line);
  while (std::getline(s, line)) last = line;
  const std::vector<std::string> f = mjtether::SplitCsvLine(last);
  std::vector<double> out;
  for (size_t c : XColumns(head)) {
    for (size_t k = c; k < c + 3 && k < f.size(); ++k) out.push_back(std::atof(f[k].c_str()));
  }
  return out;
}

// [m] MuJoCo's integrators differ by O(h) on the bodies: at 2 ms over 0.3 s a BlueROV2 moving at
// up to 1 m/s under its tether and thrust; measured 0.11 mm at most (session 21). 5 mm keeps a
// margin and still fails a vehicle that sinks at any speed worth the name (the RK4 bug: 14 m in
// 0.24 s).
constexpr double kAgree = 5e-3;

// The metamorphic oracle, swept instead of drawn: every shipped model with each of MuJoCo's
// integrators, and with each tether integrator, runs (or is refused at load by the advisor,
// exit 2 with its cause). The draw above found MuJoCo's RK4 sinking the BlueROV2 of
// models/minimal_rov.xml; this sweep has that case every time.
TEST(HostileGen, EveryShippedModelRunsWithEveryIntegrator) {
  const std::vector<std::string> models = Models();
  const std::string root = ::testing::TempDir() + "/hostile_sweep_" + std::to_string(getpid());
  int runs = 0, refused = 0;
  double worst = 0;  // [m] largest difference from Euler's positions
  for (const std::string& model : models) {
    const std::string original = ReadFileBytes(std::string(MJTETHER_MODELS_DIR) + "/" + model);
    std::vector<double> euler;  // the bodies' last logged positions with MuJoCo's Euler
    std::vector<std::pair<std::string, std::string>> edits;  // (kind, name)
    for (const char* mj : {"Euler", "implicit", "RK4"}) edits.emplace_back("mujoco", mj);
    for (const char* t : {"explicit", "rk4", "implicit", "implicit2", "bdf2"}) {
      edits.emplace_back("tether", t);
    }
    for (const auto& [kind, name] : edits) {
      Mutator m(original, 0);
      const std::string what =
          kind == "mujoco" ? m.SetMujocoIntegrator(name) : m.SetTetherIntegrator(name);
      if (what.empty()) continue;  // no <option>, or no integrator key to change
      const std::string dir = root + "/" + model + "_" + name;
      fs::remove_all(dir);
      fs::create_directories(dir);
      for (const auto& e : fs::directory_iterator(MJTETHER_MODELS_DIR)) {
        fs::copy(e.path(), dir + "/" + e.path().filename().string());
      }
      std::ofstream(dir + "/m.xml", std::ios::binary) << m.text();
      const BinaryRun run = RunBinary(dir, std::string(MJTETHER_CLI) + " run m.xml --duration " +
                                               std::to_string(kDuration) +
                                               " --every 0.05 --log log.csv",
                                      kTimeout);
      const Outcome o = Judge(run, dir, false, /*benign=*/true);
      EXPECT_TRUE(o.ok) << model << " with " << what << ": " << o.what;
      ++runs;
      refused += o.what.rfind("refused", 0) == 0;
      // MuJoCo's integrators move the bodies alike: at 0.3 s within kAgree of Euler's run.
      if (kind == "mujoco" && o.ok && o.what == "ran") {
        const std::vector<double> last = LastPositions(dir + "/log.csv");
        if (name == "Euler") {
          euler = last;
        } else if (!euler.empty() && euler.size() == last.size()) {
          for (size_t i = 0; i < last.size(); ++i) {
            worst = std::max(worst, std::abs(last[i] - euler[i]));
            EXPECT_LE(std::abs(last[i] - euler[i]), kAgree)
                << model << " with " << what << ": body coordinate " << i << " at "
                << kDuration << " s is " << last[i] << " m against Euler's " << euler[i];
          }
        }
      }
      fs::remove_all(dir);
    }
  }
  fs::remove_all(root);
  std::cout << runs << " runs of the shipped models with another integrator, " << refused
            << " refused at load by the advisor; MuJoCo's integrators move the bodies within "
            << worst << " m of Euler's in " << kDuration << " s\n";
  EXPECT_GE(runs, 3 * static_cast<int>(models.size()));
}

}  // namespace
