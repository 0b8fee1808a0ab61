#pragma once
// Numbers and counts as messages print them: short, and in plain English.
#include <cstdio>
#include <string>
#include <string_view>

namespace vdmap {

/// "1 keyframe", "2 keyframes", "20 bodies", "3 boxes": a count with its noun. `plural` is for a
/// noun English does not make by rule ("1 vertex", "2 vertices").
inline std::string counted(long long n, std::string_view noun, std::string_view plural = {}) {
  std::string text = std::to_string(n) + " ";
  if (n == 1 || n == -1) return text += noun;
  if (!plural.empty()) return text += plural;
  const auto ends = [noun](std::string_view tail) { return noun.ends_with(tail); };
  const bool consonant_y = noun.size() >= 2 && noun.back() == 'y' &&
                           std::string_view("aeiou").find(noun[noun.size() - 2]) == std::string_view::npos;
  if (consonant_y) return text += std::string(noun.substr(0, noun.size() - 1)) + "ies";
  if (ends("s") || ends("x") || ends("ch") || ends("sh")) return text += std::string(noun) + "es";
  return text += std::string(noun) + "s";
}

/// `v` as a message echoes a number: at most 9 significant digits, an exponent when large or
/// small ("0.1", "123456000", "1e+308"; never the 309 digits of std::to_string(1e308)).
inline std::string shortNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}
/// A float as short: 7 significant digits, so that 1e38f reads "1e+38", not "9.99999968e+37".
inline std::string shortNumber(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.7g", static_cast<double>(v));
  return text;
}

}  // namespace vdmap
