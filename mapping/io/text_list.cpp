#include "mapping/io/text_list.h"

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "mapping/core/error.h"
#include "mapping/core/message_text.h"

namespace vdmap {

std::vector<ListLine> readListFile(const std::filesystem::path& file, int columns, const char* expected) {
  checkNotAFolder(file);
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "cannot open (missing or unreadable)");
  std::vector<ListLine> lines;
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    if (!text.empty() && text.back() == '\r') text.pop_back();  // a CRLF file: not part of the line shown
    ListLine line{number, listWords(text)};
    if (line.tokens.empty()) continue;
    if (static_cast<int>(line.tokens.size()) != columns)
      throw InputError(file.string(), number,
                       "expected '" + std::string(expected) + "', got " +
                           counted(static_cast<long long>(line.tokens.size()), "field") + ": " + printable(text));
    lines.push_back(std::move(line));
  }
  if (in.bad()) throw InputError(file.string(), "cannot be read");
  return lines;
}

std::vector<std::string> listWords(const std::string& line) {
  std::vector<std::string> words;
  std::istringstream in(line);
  for (std::string w; in >> w && w[0] != '#';) words.push_back(std::move(w));
  return words;
}

void checkNotAFolder(const std::filesystem::path& file) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) throw InputError(file.string(), "is a folder, not a file");
}

std::string readWholeFile(const std::filesystem::path& file) {
  checkNotAFolder(file);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string(), std::string("cannot be read (") + std::strerror(errno) + ")");
  std::ostringstream text;
  text << in.rdbuf();  // a read error sets the stream's state; it never throws from here
  if (in.bad() || text.bad()) throw InputError(file.string(), "cannot be read");
  return text.str();
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
