// A deterministic mutator for the ctest and long-run drivers (libFuzzer brings its own): from a
// fixed seed it derives the same cases on every machine and compiler (own integer draws, no
// std::uniform_int_distribution, whose results the standard leaves to the library).
//
// Text (YAML) cases get edits that keep them YAML-like, so the loaders' checks are reached and not
// only the parser: a value replaced by a hostile one (nan, .inf, 1e999, -0, huge integers, a
// sequence or map where a number goes, an alias, a tag), a key replaced by another key of the
// schema, lines deleted, duplicated, swapped or re-indented. Every case also may get raw byte
// edits.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace drivetrain_stiffness::fuzz {

using Bytes = std::vector<std::uint8_t>;

class Mutator {
 public:
  Mutator(std::uint64_t seed, std::vector<std::string> dictionary)
      : state_(seed), dictionary_(std::move(dictionary)) {}

  /// 1 to 6 stacked edits of `input`; `other` is spliced in by some of them. At most max_size
  /// bytes.
  Bytes mutate(const Bytes& input, const Bytes& other, bool text, std::size_t max_size);
  /// A draw in [0, n); n > 0.
  std::uint64_t below(std::uint64_t n);

 private:
  std::uint64_t next();  ///< splitmix64
  void byteEdit(Bytes& b, const Bytes& other);
  void textEdit(Bytes& b);

  std::uint64_t state_;
  std::vector<std::string> dictionary_;
};

}  // namespace drivetrain_stiffness::fuzz
