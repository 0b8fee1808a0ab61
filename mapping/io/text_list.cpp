#include "mapping/io/text_list.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "mapping/core/error.h"

namespace vdmap {

std::vector<ListLine> readListFile(const std::filesystem::path& file, int columns, const char* expected) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "cannot open (missing or unreadable)");
  std::vector<ListLine> lines;
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const auto first = text.find_first_not_of(" \t");
    if (first == std::string::npos || text[first] == '#') continue;
    std::istringstream words(text);
    ListLine line{number, {}};
    for (std::string w; words >> w;) line.tokens.push_back(w);
    if (static_cast<int>(line.tokens.size()) != columns)
      throw InputError(
          file.string(), number,
          "expected '" + std::string(expected) + "', got " + std::to_string(line.tokens.size()) + " fields");
    lines.push_back(std::move(line));
  }
  return lines;
}

double parseListNumber(const std::string& token, const std::filesystem::path& file, int line, const char* what) {
  double value = 0.0;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, value);
  if (ec != std::errc() || ptr != end)
    throw InputError(file.string(), line, std::string("expected a number for ") + what + ", got '" + token + "'");
  if (!std::isfinite(value))
    throw InputError(file.string(), line, std::string(what) + " is not finite ('" + token + "')");
  return value;
}

void checkTimestamp(double t, const std::filesystem::path& file, int line) {
  if (std::abs(t) <= kMaxTimestampS) return;
  char text[32];
  std::snprintf(text, sizeof text, "%g", t);
  throw InputError(file.string(), line,
                   std::string("timestamp ") + text + " is out of range: timestamps are seconds within 1e11 of 0");
}

void checkIncreasing(double t, double* previous, const std::filesystem::path& file, int line) {
  checkTimestamp(t, file, line);
  if (t <= *previous)
    throw InputError(file.string(), line,
                     "timestamp " + std::to_string(t) + " is not after the previous one (" + std::to_string(*previous) +
                         "): timestamps must increase");
  *previous = t;
}

std::string asciiLower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace vdmap
