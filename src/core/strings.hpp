#pragma once
// Small string helpers the readers of text input share (configuration lists, CSV fields).
#include <string>
#include <string_view>
#include <vector>

namespace mpm {

// `s` without the characters of `blanks` at either end.
inline std::string_view trim(std::string_view s, std::string_view blanks = " \t") {
  const auto first = s.find_first_not_of(blanks);
  if (first == std::string_view::npos) return {};
  return s.substr(first, s.find_last_not_of(blanks) - first + 1);
}

// The items of a list separated by `separator`, each trimmed of spaces and tabs; empty items
// are kept (the caller decides whether one is an error).
inline std::vector<std::string> split_trimmed(std::string_view text, char separator) {
  std::vector<std::string> out;
  std::size_t b = 0;
  while (true) {
    const std::size_t e = text.find(separator, b);
    out.emplace_back(
        trim(text.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b)));
    if (e == std::string_view::npos) return out;
    b = e + 1;
  }
}

}  // namespace mpm
