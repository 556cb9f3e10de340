#include "text_check.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace mjtether {
namespace {

char Lower(char c) { return c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c; }

std::string LowerString(std::string s) {
  for (char& c : s) c = Lower(c);
  return s;
}

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

NumberStatus ParseDecimal(const std::string& text, double* value) {
  const std::string lower = LowerString(text);
  size_t i = 0;
  if (i < lower.size() && (lower[i] == '+' || lower[i] == '-')) ++i;
  const std::string body = lower.substr(i);
  if (body == "nan" || body == "inf" || body == "infinity" || body.rfind("nan(", 0) == 0) {
    return NumberStatus::kNotFinite;
  }
  if (body.rfind("0x", 0) == 0) return NumberStatus::kHex;
  // [digits][.digits] with at least one digit, then an optional exponent.
  int digits = 0;
  while (i < lower.size() && IsDigit(lower[i])) ++i, ++digits;
  if (i < lower.size() && lower[i] == '.') {
    ++i;
    while (i < lower.size() && IsDigit(lower[i])) ++i, ++digits;
  }
  if (digits == 0) return NumberStatus::kNotNumber;
  if (i < lower.size() && lower[i] == 'e') {
    ++i;
    if (i < lower.size() && (lower[i] == '+' || lower[i] == '-')) ++i;
    int exponent_digits = 0;
    while (i < lower.size() && IsDigit(lower[i])) ++i, ++exponent_digits;
    if (exponent_digits == 0) return NumberStatus::kNotNumber;
  }
  if (i != lower.size()) return NumberStatus::kNotNumber;
  errno = 0;
  const double x = std::strtod(text.c_str(), nullptr);
  if (!std::isfinite(x)) return NumberStatus::kOverflow;
  if (x != 0 && std::abs(x) < DBL_MIN) return NumberStatus::kUnderflow;
  if (x == 0 && errno == ERANGE) return NumberStatus::kUnderflow;  // 1e-400 reads as 0
  *value = x;
  return NumberStatus::kOk;
}

std::string NumberProblem(NumberStatus status) {
  switch (status) {
    case NumberStatus::kOk:
      return "is a number";
    case NumberStatus::kNotNumber:
      return "is not a number";
    case NumberStatus::kNotFinite:
      return "is not a finite number";
    case NumberStatus::kHex:
      return "is hexadecimal, which is not accepted; write it in decimal";
    case NumberStatus::kUnderflow:
      return "is out of range: its magnitude is below 2.2e-308 (the smallest normal double); "
             "write 0 or a larger number";
    case NumberStatus::kOverflow:
      return "is not a finite number (out of range: beyond 1.8e308)";
  }
  return "is not a number";
}

std::string Shown(const std::string& text) {
  if (text.size() <= 60) return text;
  return text.substr(0, 40) + "... (" + std::to_string(text.size()) + " characters)";
}

int EditDistance(const std::string& a, const std::string& b) {
  const size_t n = a.size(), m = b.size();
  if (n > 64 || m > 64) return static_cast<int>(std::max(n, m));  // names are short
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1));
  for (size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (size_t i = 1; i <= n; ++i) {
    for (size_t j = 1; j <= m; ++j) {
      const int cost = Lower(a[i - 1]) == Lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && Lower(a[i - 1]) == Lower(b[j - 2]) &&
          Lower(a[i - 2]) == Lower(b[j - 1])) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates) {
  int best = 3;
  std::string found;
  for (const std::string& c : candidates) {
    const int dist = EditDistance(word, c);
    if (dist < best) best = dist, found = c;
  }
  return found.empty() ? "" : "; did you mean '" + found + "'?";
}

const std::vector<std::string>& DeclarationKinds() {
  static const std::vector<std::string> kinds = {"tether", "water",  "vehicle",
                                                 "motion", "thrust", "winch"};
  return kinds;
}

std::optional<std::string> NearMissDeclaration(const std::string& text_name) {
  // Ours: "water", or "KIND:" followed by anything.
  if (text_name == "water") return std::nullopt;
  for (const std::string& kind : DeclarationKinds()) {
    if (kind != "water" && text_name.rfind(kind + ":", 0) == 0) return std::nullopt;
  }
  // The leading run of letters, and what follows it.
  size_t n = 0;
  while (n < text_name.size() && std::isalpha(static_cast<unsigned char>(text_name[n]))) ++n;
  const std::string word = text_name.substr(0, n), rest = text_name.substr(n);
  if (word.size() < 4) return std::nullopt;
  // After the word: nothing, or a separator (':', '_', '.', '-', ' ', ...), not more letters or
  // digits ("waterline", "motion2" are someone else's names).
  const bool separated = rest.empty() || !std::isalnum(static_cast<unsigned char>(rest[0]));
  if (!separated) return std::nullopt;
  const bool colon = !rest.empty() && rest[0] == ':';
  for (const std::string& kind : DeclarationKinds()) {
    const int dist = EditDistance(word, kind);
    // The kind in another case or with another separator; or misspelt by one edit (two with
    // a colon after it, which only a declaration would have).
    if (dist > (colon ? 2 : 1)) continue;
    const std::string intent =
        kind == "water" ? "water" : kind + ":" + (rest.empty() ? "NAME" : rest.substr(1));
    return std::string("this name looks like a misspelt mjtether declaration; ") +
           "did you mean <text name=\"" + Shown(intent) +
           "\">? (Declaration names are case-sensitive: 'water', 'tether:NAME', 'vehicle:BODY', " +
           "'motion:BODY', 'thrust:ACTUATOR', 'winch:NAME'. Rename the text if it is not one.)";
  }
  return std::nullopt;
}

std::optional<std::string> OddCharacter(const std::string& text) {
  size_t position = 0;  // 1-based character count
  for (size_t i = 0; i < text.size();) {
    ++position;
    const unsigned char c = static_cast<unsigned char>(text[i]);
    unsigned code = c;
    size_t len = 1;
    if (c >= 0x80) {
      // UTF-8 sequence (a malformed one is named by its first byte).
      len = c >= 0xF8 ? 1 : c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 ? 2 : 1;
      bool valid = len > 1 && i + len <= text.size();
      for (size_t k = 1; valid && k < len; ++k) valid = (text[i + k] & 0xC0) == 0x80;
      if (!valid) {
        char buf[96];
        std::snprintf(buf, sizeof(buf), "byte 0x%02X (not valid UTF-8) at character %zu", c,
                      position);
        return std::string(buf) + " of the declaration: use plain ASCII";
      }
      code = c & (0xFF >> (len + 1));
      for (size_t k = 1; k < len; ++k) code = (code << 6) | (text[i + k] & 0x3F);
    }
    const char* name = nullptr;
    if (code < 0x20 && code != '\t' && code != '\n' && code != '\r') name = "control character";
    if (code == 0x7F) name = "delete character";
    if (code == 0xA0) name = "no-break space";
    if (code == 0x1680 || (code >= 0x2000 && code <= 0x200A)) name = "Unicode space";
    if (code >= 0x200B && code <= 0x200D) name = "zero-width space or joiner";
    if (code == 0x2028 || code == 0x2029) name = "Unicode line or paragraph separator";
    if (code == 0x202F) name = "narrow no-break space";
    if (code == 0x205F || code == 0x3000) name = "Unicode space";
    if (code == 0x2060 || code == 0xFEFF) name = "word joiner or byte-order mark";
    if (name) {
      char buf[160];
      std::snprintf(buf, sizeof(buf), "character U+%04X (%s) at character %zu of the declaration",
                    code, name, position);
      const std::string before = text.substr(i >= 20 ? i - 20 : 0, i >= 20 ? 20 : i);
      return std::string(buf) + (before.empty() ? "" : ", after '" + before + "'") +
             ": use a plain space between pairs and plain ASCII in values";
    }
    i += len;
  }
  return std::nullopt;
}

std::string CsvField(const std::string& field) {
  if (field.find_first_of(",\"\r\n") == std::string::npos) return field;
  std::string q = "\"";
  for (char c : field) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::vector<std::string> SplitCsvLine(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  bool quoted = false, was_quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"' && field.empty() && !was_quoted) {
      quoted = was_quoted = true;
    } else if (c == ',') {
      out.push_back(field);
      field.clear();
      was_quoted = false;
    } else if (c != '\r' || i + 1 != line.size()) {
      field += c;
    }
  }
  out.push_back(field);
  return out;
}

bool ParseCsvRow(const std::string& line, int count, double* out) {
  std::istringstream s(line);
  std::string item;
  int n = 0;
  while (std::getline(s, item, ',')) {
    if (n == count) return false;
    const size_t first = item.find_first_not_of(" \t\r"), last = item.find_last_not_of(" \t\r");
    if (first == std::string::npos) return false;
    if (ParseDecimal(item.substr(first, last - first + 1), &out[n]) != NumberStatus::kOk) {
      return false;
    }
    ++n;
  }
  return n == count;
}

}  // namespace mjtether
