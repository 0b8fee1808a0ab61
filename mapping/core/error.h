#pragma once
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace vdmap {

/// An expected failure at an input boundary (a missing file, a malformed line, a bad image).
/// what() is one line: "<file>[:<line>]: <what was wrong / what was expected>".
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& message) : std::runtime_error(file + ": " + message) {}
  InputError(const std::string& file, int line, const std::string& message)
      : std::runtime_error(file + ":" + std::to_string(line) + ": " + message) {}
};

/// `text` from a file, fit for a one-line message: in single quotes, bytes that are not printable
/// ASCII as \xNN, cut after `max_chars` with "..." (a binary file read as text must not put raw
/// bytes or a page of garbage on the terminal).
inline std::string printable(std::string_view text, std::size_t max_chars = 40) {
  std::string out(1, '\'');
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (i == max_chars) {
      out += "...";
      break;
    }
    const char ch = text[i];
    if (ch >= 0x20 && ch < 0x7F) {
      out += ch;
    } else {
      constexpr char kHex[] = "0123456789abcdef";
      const auto b = static_cast<std::uint8_t>(ch);
      out += {'\\', 'x', kHex[b >> 4], kHex[b & 15]};
    }
  }
  out += '\'';
  return out;
}

}  // namespace vdmap
