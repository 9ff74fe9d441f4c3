#pragma once
// Little-endian bytes of a state (io/checkpoint.hpp's layout): what each component writes of
// itself and reads back (the mappings' run totals, the checkpoint payload). Integers are
// little-endian, reals IEEE-754 binary64 little-endian; str = u64 length + bytes, f64[] and
// i64[] = u64 count + values.
#include <fmt/format.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/types.hpp"

namespace mpm {

class ByteWriter {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int k = 0; k < 4; ++k) u8(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void u64(std::uint64_t v) {
    for (int k = 0; k < 8; ++k) u8(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void i64(std::int64_t v) { u64(static_cast<std::uint64_t>(v)); }
  void f64(double v) { u64(std::bit_cast<std::uint64_t>(v)); }
  void str(std::string_view s) {
    u64(s.size());
    out_.append(s);
  }
  void reals(const std::vector<double>& v) {
    u64(v.size());
    for (double x : v) f64(x);
  }
  void ints(const std::vector<std::int64_t>& v) {
    u64(v.size());
    for (auto x : v) i64(x);
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

// Reads what ByteWriter wrote. Reading past the end, or a length prefix longer than what is left,
// throws InputError naming `name` (the file, or the part of it) and the byte offset.
class ByteReader {
 public:
  ByteReader(std::string_view in, std::string name) : in_(in), name_(std::move(name)) {}
  std::uint8_t u8() {
    need(1);
    return static_cast<std::uint8_t>(in_[pos_++]);
  }
  // A flag that ByteWriter wrote as 0 or 1; any other byte is malformed (decoding it as true
  // would not encode back to the same bytes: found by fuzz/fuzz_checkpoint.cpp).
  bool flag() {
    need(1);
    const auto b = static_cast<std::uint8_t>(in_[pos_]);
    if (b > 1) fail();
    ++pos_;
    return b == 1;
  }
  std::uint32_t u32() {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v |= static_cast<std::uint32_t>(u8()) << (8 * k);
    return v;
  }
  std::uint64_t u64() {
    std::uint64_t v = 0;
    for (int k = 0; k < 8; ++k) v |= static_cast<std::uint64_t>(u8()) << (8 * k);
    return v;
  }
  std::int64_t i64() { return static_cast<std::int64_t>(u64()); }
  double f64() { return std::bit_cast<double>(u64()); }
  std::string str() {
    const auto n = count(1);
    std::string s(in_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  std::vector<double> reals() {
    std::vector<double> v(count(8));
    for (double& x : v) x = f64();
    return v;
  }
  std::vector<std::int64_t> ints() {
    std::vector<std::int64_t> v(count(8));
    for (auto& x : v) x = i64();
    return v;
  }
  bool done() const { return pos_ == in_.size(); }
  // Throws unless every byte was read.
  void expect_done() const {
    if (!done())
      throw InputError(fmt::format("checkpoint '{}': {} unexpected bytes after the data", name_,
                                   in_.size() - pos_));
  }

 private:
  // A length prefix whose elements of `size` bytes must still fit into the input.
  std::size_t count(std::size_t size) {
    const std::uint64_t n = u64();
    if (n > (in_.size() - pos_) / size) fail();
    return static_cast<std::size_t>(n);
  }
  void need(std::size_t n) {
    if (in_.size() - pos_ < n) fail();
  }
  [[noreturn]] void fail() const {
    throw InputError(fmt::format(
        "checkpoint '{}': the payload ends early or is malformed (at byte {} of {}); it was "
        "written by an incompatible mpm",
        name_, pos_, in_.size()));
  }

  std::string_view in_;
  std::string name_;
  std::size_t pos_ = 0;
};

}  // namespace mpm
