#include "mutator.hpp"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>

namespace drivetrain_stiffness::fuzz {
namespace {

// Values a hostile or careless file puts where a number, a string or a block goes.
const char* const kHostileValues[] = {"nan",
                                      ".nan",
                                      ".NaN",
                                      ".inf",
                                      "-.inf",
                                      "+.inf",
                                      "inf",
                                      "1e999",
                                      "-1e999",
                                      "1e-999",
                                      "4.9e-324",
                                      "-0",
                                      "0",
                                      "-1",
                                      "1e308",
                                      "1.7976931348623157e308",
                                      "2147483648",
                                      "-2147483649",
                                      "99999999999999999999",
                                      "0x7fffffff",
                                      "0o777",
                                      "1_000",
                                      "~",
                                      "null",
                                      "",
                                      "''",
                                      "\"\"",
                                      "[]",
                                      "{}",
                                      "[1, 2]",
                                      "[1, 2, 3]",
                                      "[.nan, 1]",
                                      "[[1]]",
                                      "{a: 1}",
                                      "true",
                                      "yes",
                                      "&a 1",
                                      "*a",
                                      "*b",
                                      "!!binary aGVsbG8=",
                                      "!!str 12",
                                      "!!float nan",
                                      "!!int 7",
                                      "|\n  1",
                                      ">\n  2",
                                      "1.0e5",
                                      "1.0e+5",
                                      "12abc",
                                      "0.5",
                                      "1",
                                      "12",
                                      "1e6",
                                      "1000001",
                                      "-1e6",
                                      "0.999999",
                                      "1.0000001",
                                      "[0.0, 0.0]",
                                      "[1e-3, -1e-3]",
                                      "\"\\x00\"",
                                      "'a: b'",
                                      "- 1",
                                      "? a",
                                      "<<: *a"};
// Tokens that change the structure.
const std::string kTokens[] = {
    "{",  "}",    "[",           "]",     "&a ",   "*a",       "!!str ", "!!map ",
    "? ", "- ",   "'",           "\"",    "#",     "\t",       "\\",     ":",
    ": ", ",",    "%YAML 1.2\n", "---\n", "...\n", "<<: *a\n", "\xff",   std::string(1, '\0'),
    "\r", "\n  ", "|",           ">"};

std::vector<std::string> splitLines(const Bytes& b) {
  std::vector<std::string> lines(1);
  for (std::uint8_t c : b) {
    if (c == '\n')
      lines.emplace_back();
    else
      lines.back().push_back(static_cast<char>(c));
  }
  return lines;
}

Bytes joinLines(const std::vector<std::string>& lines) {
  Bytes b;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (i) b.push_back('\n');
    b.insert(b.end(), lines[i].begin(), lines[i].end());
  }
  return b;
}

}  // namespace

std::uint64_t Mutator::next() {
  std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

std::uint64_t Mutator::below(std::uint64_t n) { return next() % n; }

Bytes Mutator::mutate(const Bytes& input, const Bytes& other, bool text, std::size_t max_size) {
  Bytes b = input;
  const int edits = 1 + static_cast<int>(below(6));
  for (int i = 0; i < edits; ++i) {
    if (text && below(4) != 0)
      textEdit(b);
    else
      byteEdit(b, other);
  }
  if (b.size() > max_size) b.resize(max_size);
  return b;
}

void Mutator::byteEdit(Bytes& b, const Bytes& other) {
  const auto at = [&] { return static_cast<std::size_t>(below(b.size() + 1)); };
  switch (below(8)) {
    case 0:
      if (!b.empty()) b[below(b.size())] ^= static_cast<std::uint8_t>(1u << below(8));
      break;
    case 1:
      if (!b.empty()) b[below(b.size())] = static_cast<std::uint8_t>(next());
      break;
    case 2: {
      const std::uint8_t interesting[] = {0x00, 0xff, 0x7f, 0x80, 0x01, 0xfe};
      if (!b.empty()) b[below(b.size())] = interesting[below(sizeof interesting)];
      break;
    }
    case 3: {  // insert random bytes
      const std::size_t n = 1 + below(8);
      Bytes r(n);
      for (auto& c : r) c = static_cast<std::uint8_t>(next());
      b.insert(b.begin() + static_cast<std::ptrdiff_t>(at()), r.begin(), r.end());
      break;
    }
    case 4: {  // delete a range
      if (b.empty()) break;
      const std::size_t from = below(b.size()),
                        n = 1 + below(std::min<std::size_t>(b.size() - from, 32));
      b.erase(b.begin() + static_cast<std::ptrdiff_t>(from),
              b.begin() + static_cast<std::ptrdiff_t>(from + n));
      break;
    }
    case 5: {  // duplicate a range
      if (b.empty()) break;
      const std::size_t from = below(b.size()),
                        n = 1 + below(std::min<std::size_t>(b.size() - from, 64));
      const Bytes slice(b.begin() + static_cast<std::ptrdiff_t>(from),
                        b.begin() + static_cast<std::ptrdiff_t>(from + n));
      b.insert(b.begin() + static_cast<std::ptrdiff_t>(at()), slice.begin(), slice.end());
      break;
    }
    case 6: {  // splice in a slice of another seed
      if (other.empty()) break;
      const std::size_t from = below(other.size()),
                        n = 1 + below(std::min<std::size_t>(other.size() - from, 128));
      b.insert(b.begin() + static_cast<std::ptrdiff_t>(at()),
               other.begin() + static_cast<std::ptrdiff_t>(from),
               other.begin() + static_cast<std::ptrdiff_t>(from + n));
      break;
    }
    default: {  // small arithmetic on a byte (a length, a count, a mode)
      if (!b.empty()) b[below(b.size())] += static_cast<std::uint8_t>(below(71) - 35);
      break;
    }
  }
}

void Mutator::textEdit(Bytes& b) {
  std::vector<std::string> lines = splitLines(b);
  std::string& line = lines[below(lines.size())];
  switch (below(9)) {
    case 0:
    case 1: {  // the value after "key:" or "- " becomes a hostile one (the comment goes with it)
      auto pos = line.find(": ");
      if (pos != std::string::npos)
        pos += 2;
      else if ((pos = line.find("- ")) != std::string::npos)
        pos += 2;
      else
        pos = line.size();
      line = line.substr(0, pos) + kHostileValues[below(std::size(kHostileValues))];
      break;
    }
    case 2: {  // the key becomes another key of the schema (or a parameter name)
      const auto colon = line.find(':');
      const auto indent = line.find_first_not_of(" -");
      if (colon == std::string::npos || indent == std::string::npos || indent > colon ||
          dictionary_.empty())
        break;
      line = line.substr(0, indent) + dictionary_[below(dictionary_.size())] + line.substr(colon);
      break;
    }
    case 3: lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(below(lines.size()))); break;
    case 4: {
      const std::string copy = line;
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(below(lines.size() + 1)), copy);
      break;
    }
    case 5: std::swap(line, lines[below(lines.size())]); break;
    case 6:  // re-indent
      if (below(2))
        line.insert(0, below(4) ? "  " : "\t");
      else if (line.rfind("  ", 0) == 0)
        line.erase(0, 2);
      break;
    case 7: {  // a new "key: value" line, indented like this one
      if (dictionary_.empty()) break;
      const std::string indent = line.substr(
          0, line.find_first_not_of(' ') == std::string::npos ? 0 : line.find_first_not_of(' '));
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(below(lines.size() + 1)),
                   indent + dictionary_[below(dictionary_.size())] + ": " +
                       kHostileValues[below(std::size(kHostileValues))]);
      break;
    }
    default: {  // a structural token, or deep nesting, somewhere in the line
      const std::size_t at = below(line.size() + 1);
      if (below(16) == 0)
        line.insert(at, std::string(1 + below(3000), below(2) ? '[' : '{'));
      else
        line.insert(at, kTokens[below(std::size(kTokens))]);
      break;
    }
  }
  b = joinLines(lines);
}

}  // namespace drivetrain_stiffness::fuzz
