// Reads typed values off a fuzz case's bytes. Running out of bytes is not an error: every read
// then returns zero, so any byte string decodes to some input (libFuzzer's and our mutator's
// cases are arbitrary) and a shorter case is always a prefix-decodable shorter program.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace drivetrain_stiffness::fuzz {

class ByteReader {
 public:
  ByteReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  bool empty() const { return pos_ >= size_; }
  std::uint8_t u8() { return empty() ? 0 : data_[pos_++]; }
  std::uint16_t u16() { return static_cast<std::uint16_t>(u8() | (u8() << 8)); }
  std::uint32_t u32() {
    return static_cast<std::uint32_t>(u16()) | (static_cast<std::uint32_t>(u16()) << 16);
  }
  std::uint64_t u64() {
    return static_cast<std::uint64_t>(u32()) | (static_cast<std::uint64_t>(u32()) << 32);
  }
  /// Any bit pattern: NaNs with payloads, infinities, subnormals, -0.
  double rawDouble() {
    const std::uint64_t bits = u64();
    double d;
    std::memcpy(&d, &bits, sizeof d);
    return d;
  }
  /// Up to max_len bytes, length first.
  std::string string(std::size_t max_len) {
    std::string s;
    const std::size_t n = u8() % (max_len + 1);
    for (std::size_t i = 0; i < n && !empty(); ++i) s.push_back(static_cast<char>(u8()));
    return s;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace drivetrain_stiffness::fuzz
