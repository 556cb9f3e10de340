// The hostile-input suite (issue 14, docs/bad_input.md): every case of tests/hostile/cases.txt
// runs the real mjtether binary in a fresh directory holding a copy of tests/hostile/, and must
// end with its expected exit code (never a crash, a hang or a silent success), print the
// expected fragment, and pass its checks (inputs unchanged, complete rows, no temporary file
// left, short messages).
//
// With MJTETHER_HOSTILE_VALGRIND=1 only the cases tagged `leak` run, each under valgrind
// (.ci/run): a definite leak or a memory error fails the case.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "run_binary.h"
#include "text_check.h"

namespace {

namespace fs = std::filesystem;

struct Case {
  std::string name;
  int exit = 0;
  std::string fragment, model, setup, signal, command, checks;
};

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t"), b = s.find_last_not_of(" \t");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

std::vector<std::string> Split(const std::string& s, const std::string& sep) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t at = s.find(sep, start);
    out.push_back(Trim(s.substr(start, at == std::string::npos ? std::string::npos : at - start)));
    if (at == std::string::npos) break;
    start = at + sep.size();
  }
  return out;
}

std::vector<Case> LoadCases() {
  std::vector<Case> cases;
  std::ifstream f(std::string(MJTETHER_HOSTILE_DIR) + "/cases.txt");
  std::string line;
  while (std::getline(f, line)) {
    if (Trim(line).empty() || Trim(line)[0] == '#') continue;
    const std::vector<std::string> c = Split(line, " | ");
    if (c.size() != 8) {
      cases.push_back({"malformed_line", -1, line, "", "", "", "", ""});
      continue;
    }
    cases.push_back({c[0], std::atoi(c[1].c_str()), c[2], c[3], c[4], c[5], c[6], c[7]});
  }
  return cases;
}

// \xHH bytes and {rep:TEXT:N}.
std::string Expand(const std::string& s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s.compare(i, 2, "\\x") == 0 && i + 3 < s.size()) {
      out += static_cast<char>(std::stoi(s.substr(i + 2, 2), nullptr, 16));
      i += 3;
    } else if (s.compare(i, 5, "{rep:") == 0) {
      const size_t close = s.find('}', i);
      const std::string spec = s.substr(i + 5, close - i - 5);
      const size_t colon = spec.rfind(':');
      const std::string text = spec.substr(0, colon);
      const long n = std::stol(spec.substr(colon + 1));
      for (long k = 0; k < n; ++k) out += text;
      i = close;
    } else {
      out += s[i];
    }
  }
  return out;
}

using mjtether::test_util::ReadFileBytes;

// Writes the edited models: 'SRC[>DST]: OLD => NEW ;; OLD => NEW', several groups allowed
// ('SRC ;; SRC2>DST2: ...' copies SRC to m.xml first).
void ApplyModel(const std::string& spec, const std::string& dir) {
  if (spec == "-") return;
  std::string current_dst;
  std::string text;
  auto flush = [&]() {
    if (!current_dst.empty()) std::ofstream(dir + "/" + current_dst, std::ios::binary) << text;
  };
  for (const std::string& part : Split(spec, ";;")) {
    const size_t arrow = part.find("=>");
    const size_t colon = part.find(": ");
    if (arrow == std::string::npos || (colon != std::string::npos && colon < arrow)) {
      // A new source: 'SRC[>DST][: OLD => NEW]'.
      flush();
      const std::string head = colon == std::string::npos ? part : part.substr(0, colon);
      const size_t gt = head.find('>');
      const std::string src = Trim(head.substr(0, gt));
      current_dst = gt == std::string::npos ? "m.xml" : Trim(head.substr(gt + 1));
      text = ReadFileBytes(dir + "/" + src);
      if (colon == std::string::npos) continue;
      const std::string edit = part.substr(colon + 2);
      const size_t a = edit.find("=>");
      const std::string from = Expand(Trim(edit.substr(0, a))),
                        to = Expand(Trim(edit.substr(a + 2)));
      if (!from.empty()) {
        const size_t at = text.find(from);
        ASSERT_NE(at, std::string::npos) << "'" << from << "' not in " << src;
        text.replace(at, from.size(), to);
      }
    } else {
      const std::string from = Expand(Trim(part.substr(0, arrow))),
                        to = Expand(Trim(part.substr(arrow + 2)));
      const size_t at = text.find(from);
      ASSERT_NE(at, std::string::npos) << "'" << from << "' not in the model";
      text.replace(at, from.size(), to);
    }
  }
  flush();
}

// A CSV whose every row ends with a newline and has the header's number of fields.
void ExpectCompleteRows(const std::string& path) {
  const std::string text = ReadFileBytes(path);
  ASSERT_FALSE(text.empty()) << path << " is empty or missing";
  EXPECT_EQ(text.back(), '\n') << path << ": the last row is cut";
  std::istringstream s(text);
  std::string line;
  size_t columns = 0;
  int row = 0;
  while (std::getline(s, line)) {
    ++row;
    const size_t n = mjtether::SplitCsvLine(line).size();
    if (row == 1) columns = n;
    ASSERT_EQ(n, columns) << path << " row " << row << ": " << line;
  }
  EXPECT_GE(row, 2) << path << ": no data row";
}

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class Hostile : public ::testing::TestWithParam<Case> {};

TEST_P(Hostile, ExitCodeMessageAndChecks) {
  const Case& c = GetParam();
  ASSERT_NE(c.exit, -1) << "malformed line in cases.txt: " << c.fragment;
  const bool valgrind = std::getenv("MJTETHER_HOSTILE_VALGRIND") != nullptr;
  const std::vector<std::string> checks = Split(c.checks, " ");
  const bool leak = std::find(checks.begin(), checks.end(), "leak") != checks.end();
  if (valgrind && !leak) GTEST_SKIP() << "not a leak case";

  // A fresh directory with a copy of tests/hostile/.
  const std::string dir =
      ::testing::TempDir() + "/hostile_" + c.name + "_" + std::to_string(getpid());
  fs::remove_all(dir);
  fs::create_directories(dir);
  for (const auto& entry : fs::directory_iterator(MJTETHER_HOSTILE_DIR)) {
    fs::copy(entry.path(), dir + "/" + entry.path().filename().string());
  }
  ApplyModel(c.model, dir);
  if (c.setup != "-") {
    ASSERT_EQ(std::system(("cd '" + dir + "' && " + c.setup).c_str()), 0) << c.setup;
  }
  std::map<std::string, std::string> before;
  for (const std::string& check : checks) {
    if (check.rfind("unchanged:", 0) == 0) {
      const std::string file = check.substr(10);
      before[file] = ReadFileBytes(dir + "/" + file);
      ASSERT_FALSE(before[file].empty()) << file;
    }
  }

  // Run the binary (under valgrind when asked), with a timeout: a hang fails the case.
  const std::string command =
      std::string(valgrind ? "valgrind -q --leak-check=full --errors-for-leak-kinds=definite "
                             "--error-exitcode=99 "
                           : "") +
      MJTETHER_CLI + " " + Expand(c.command);
  const double timeout = valgrind ? 300 : 120;  // [s]
  int signal = 0;
  double signal_at = -1;
  if (c.signal != "-") {
    signal = c.signal.rfind("INT@", 0) == 0 ? SIGINT : SIGTERM;
    signal_at = std::stod(c.signal.substr(c.signal.find('@') + 1));
  }
  const mjtether::test_util::BinaryRun run =
      mjtether::test_util::RunBinary(dir, command, timeout, signal, signal_at);
  ASSERT_TRUE(run.started) << "fork failed";
  const std::string& output = run.output;
  ASSERT_FALSE(run.hung) << "no exit within " << timeout << " s: " << output.substr(0, 2000);
  ASSERT_TRUE(run.exited) << "killed by signal " << run.signal << ": " << output.substr(0, 2000);
  const int code = run.code;
  ASSERT_NE(code, 99) << "valgrind found a leak or a memory error:\n" << output.substr(0, 4000);
  EXPECT_EQ(code, c.exit) << output.substr(0, 2000);
  EXPECT_NE(output.find(c.fragment), std::string::npos) << "expected '" << c.fragment << "' in:\n"
                                                        << output.substr(0, 2000);

  for (const std::string& check : checks) {
    if (check == "-" || check == "leak") continue;
    if (check.rfind("unchanged:", 0) == 0) {
      const std::string file = check.substr(10);
      EXPECT_EQ(ReadFileBytes(dir + "/" + file), before[file]) << file << " was changed";
    } else if (check.rfind("absent:", 0) == 0) {
      EXPECT_FALSE(fs::exists(dir + "/" + check.substr(7))) << check;
    } else if (check.rfind("rows:", 0) == 0) {
      ExpectCompleteRows(dir + "/" + check.substr(5));
    } else if (check == "notemp") {
      for (const auto& entry : fs::recursive_directory_iterator(dir)) {
        EXPECT_EQ(entry.path().filename().string().find(".tmp-"), std::string::npos)
            << "temporary file left: " << entry.path();
      }
    } else if (check.rfind("maxlen:", 0) == 0) {
      EXPECT_LE(output.size(), std::stoul(check.substr(7))) << output.substr(0, 3000);
    } else if (check.rfind("has:", 0) == 0) {
      std::string text = check.substr(4);
      std::replace(text.begin(), text.end(), '_', ' ');
      EXPECT_NE(output.find(text), std::string::npos) << "expected '" << text << "' in:\n"
                                                      << output.substr(0, 2000);
    } else {
      ADD_FAILURE() << "unknown check " << check;
    }
  }
  if (!HasFailure()) fs::remove_all(dir);
}

std::string CaseName(const ::testing::TestParamInfo<Case>& info) {
  std::string name = info.param.name;
  for (char& ch : name) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Cases, Hostile, ::testing::ValuesIn(LoadCases()), CaseName);

// The table covers every class of the issue with enough cases.
TEST(HostileTable, HasAtLeast80CasesOverEveryClass) {
  const std::vector<Case> cases = LoadCases();
  EXPECT_GE(cases.size(), 80u);
  for (const char* prefix : {"decl_", "key_", "char_", "name_", "include_", "csv_", "topo_",
                             "model_", "cli_", "out_", "sig_"}) {
    int n = 0;
    for (const Case& c : cases) n += c.name.rfind(prefix, 0) == 0;
    EXPECT_GE(n, 2) << prefix;
  }
  int leaks = 0;
  for (const Case& c : cases) leaks += c.checks.find("leak") != std::string::npos;
  EXPECT_GE(leaks, 8);
}

}  // namespace
