// Checks on text that users write: numbers (declarations, CSV files, the command line), key
// and declaration names (near misses, "did you mean"), odd characters, and long values cut
// down for messages. See docs/bad_input.md.
#ifndef MJTETHER_SRC_TEXT_CHECK_H_
#define MJTETHER_SRC_TEXT_CHECK_H_

#include <optional>
#include <string>
#include <vector>

namespace mjtether {

// How a number reads. Only plain decimals are numbers: [+-]digits[.digits][(e|E)[+-]digits]
// (a leading or trailing '.' is allowed: ".5", "5."). Hexadecimal ("0x10", "0x1.8p3"), "nan",
// "inf", white space and trailing characters are refused.
enum class NumberStatus {
  kOk,
  kNotNumber,  // not of the form above
  kNotFinite,  // nan, inf, infinity (any case)
  kHex,        // 0x... (C's strtod would read it)
  kUnderflow,  // non-zero but below the smallest normal double (2.2e-308) in magnitude
  kOverflow,   // beyond the largest double (1.8e308)
};
NumberStatus ParseDecimal(const std::string& text, double* value);
// Parses a CSV row of exactly `count` decimal numbers ("a,b,c", blanks around each allowed)
// into out; false otherwise (the motion and current-profile files).
bool ParseCsvRow(const std::string& line, int count, double* out);

// Why a number was refused, as a phrase after the quoted text: "is not a number", "is not a
// finite number", "is hexadecimal; write it in decimal", "is out of range: ...".
std::string NumberProblem(NumberStatus status);

// The text as it may appear in a message: itself up to 60 characters, otherwise its first 40
// characters, "...", and its length.
std::string Shown(const std::string& text);

// Optimal-string-alignment edit distance (insertions, deletions, substitutions and
// transpositions of adjacent characters), ignoring ASCII case.
int EditDistance(const std::string& a, const std::string& b);

// "; did you mean 'X'?" for the candidate closest to `word` within edit distance 2 (case
// ignored; an exact case-insensitive match wins), or "".
std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates);

// The declaration kinds mjtether reads from <custom><text> names: "water" alone, the others as
// "KIND:NAME".
const std::vector<std::string>& DeclarationKinds();

// If `text_name` is not one of our declarations but looks like a misspelt one ("Tether:x",
// "tether_x", "Water", "Vehicle:rov", "tehter:x", "watr"), a sentence naming the likely
// intent; otherwise nullopt.
std::optional<std::string> NearMissDeclaration(const std::string& text_name);

// If `text` holds a control character (other than tab, CR, LF) or a non-ASCII space
// (no-break space, zero-width space, byte-order mark, ...), a sentence naming it (U+XXXX and
// its name) and its position (1-based character); otherwise nullopt.
std::optional<std::string> OddCharacter(const std::string& text);

// Fields of one CSV line as RFC 4180 writes them: a field holding a comma, a double quote, CR
// or LF is put in double quotes, a quote inside doubled.
std::string CsvField(const std::string& field);
std::vector<std::string> SplitCsvLine(const std::string& line);

}  // namespace mjtether

#endif  // MJTETHER_SRC_TEXT_CHECK_H_
