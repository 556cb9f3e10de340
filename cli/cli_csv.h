// CSV as RFC 4180 writes it: fields separated by commas, a field holding a comma, a quote or a
// line break inside double quotes, a quote doubled. Used by `mjtether sweep` (manifest and
// summary) and `mjtether plot --x --y`.
#ifndef MJTETHER_PLUGIN_CLI_CSV_H_
#define MJTETHER_PLUGIN_CLI_CSV_H_

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

namespace mjtether::cli {

// The shortest decimal that reads back as exactly v (at most 17 significant digits).
inline std::string Shortest(double v) {
  char buf[64];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

// A field, quoted only when it needs to be.
inline std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

inline std::string CsvLine(const std::vector<std::string>& fields) {
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + CsvField(fields[i]);
  return line + "\n";
}

struct CsvRecord {
  int line = 0;  // line of the file where the record starts (1-based)
  std::vector<std::string> fields;
};

// Parses a whole file. Line ends LF or CRLF; empty lines are skipped; a quoted field may hold
// line breaks. Returns nullopt with *error ("line L: ...") on a quote that is not closed or
// text after a closing quote.
inline std::optional<std::vector<CsvRecord>> ParseCsv(const std::string& text, std::string* error) {
  std::vector<CsvRecord> records;
  CsvRecord record;
  std::string field;
  int line = 1;
  bool in_record = false;  // something (a field or a comma) was read on this record
  size_t i = 0;
  auto end_record = [&]() {
    if (in_record) {
      record.fields.push_back(field);
      records.push_back(record);
    }
    record = CsvRecord();
    field.clear();
    in_record = false;
  };
  while (i < text.size()) {
    const char c = text[i];
    if (!in_record) record.line = line;
    if (c == '"' && field.empty()) {
      // A quoted field.
      const int start = line;
      ++i;
      for (;;) {
        if (i >= text.size()) {
          *error = "line " + std::to_string(start) + ": a quote is not closed";
          return std::nullopt;
        }
        if (text[i] == '"') {
          if (i + 1 < text.size() && text[i + 1] == '"') {
            field += '"';
            i += 2;
            continue;
          }
          ++i;
          break;
        }
        if (text[i] == '\n') ++line;
        field += text[i++];
      }
      in_record = true;
      if (i < text.size() && text[i] != ',' && text[i] != '\n' && text[i] != '\r') {
        *error = "line " + std::to_string(line) + ": text after a closing quote";
        return std::nullopt;
      }
      continue;
    }
    if (c == ',') {
      record.fields.push_back(field);
      field.clear();
      in_record = true;
      ++i;
    } else if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') {
      ++i;
    } else if (c == '\n') {
      end_record();
      ++line;
      ++i;
    } else {
      field += c;
      in_record = true;
      ++i;
    }
  }
  end_record();
  return records;
}

}  // namespace mjtether::cli

#endif  // MJTETHER_PLUGIN_CLI_CSV_H_
