#include "app/view/junit_xml.h"

#include <charconv>
#include <cmath>
#include <cstdint>
#include <system_error>

#include "mapping/core/atomic_file.h"

namespace vdmap::app {
namespace {

// The code point of the UTF-8 sequence at text[i] and its length, or length 0 for a byte that
// starts no well-formed sequence (a stray continuation byte, a truncated, overlong or surrogate
// sequence, or one above U+10FFFF).
struct CodePoint {
  std::uint32_t value = 0;
  std::size_t length = 0;
};

CodePoint decodeUtf8(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  if (lead < 0x80) return {lead, 1};
  std::size_t length = 0;
  std::uint32_t value = 0, smallest = 0;
  if ((lead & 0xE0) == 0xC0) length = 2, value = lead & 0x1F, smallest = 0x80;
  else if ((lead & 0xF0) == 0xE0) length = 3, value = lead & 0x0F, smallest = 0x800;
  else if ((lead & 0xF8) == 0xF0) length = 4, value = lead & 0x07, smallest = 0x10000;
  else return {};
  if (i + length > text.size()) return {};
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return {};
    value = (value << 6) | (byte(i + k) & 0x3F);
  }
  if (value < smallest || value > 0x10FFFF || (value >= 0xD800 && value <= 0xDFFF)) return {};
  return {value, length};
}

// Whether XML 1.0 may carry the character at all (its Char production).
bool isXmlChar(std::uint32_t c) {
  return c == 0x9 || c == 0xA || c == 0xD || (c >= 0x20 && c <= 0xD7FF) || (c >= 0xE000 && c <= 0xFFFD) || c >= 0x10000;
}

// Seconds with three decimals whatever the locale (a comma would break every JUnit reader).
std::string secondsText(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0) seconds = 0;
  char buffer[64];
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, seconds, std::chars_format::fixed, 3);
  return error == std::errc() ? std::string(buffer, end) : std::string("0.000");
}

long failuresOf(const SuiteReport& report) {
  long n = 0;
  for (const SuiteCase& c : report.cases) n += c.passed ? 0 : 1;
  return n;
}

std::string attribute(const char* name, std::string_view value) {
  return std::string(" ") + name + "=\"" + escapeXml(value) + "\"";
}

std::string testcase(const SuiteCase& c) {
  std::string out = "    <testcase" + attribute("classname", "vdmap.render." + c.map) + attribute("name", c.view) +
                    attribute("time", secondsText(c.seconds));
  if (c.passed) return out + "/>\n";
  return out + ">\n      <failure" + attribute("message", c.message) + attribute("type", "image differs") + ">" +
         escapeXml(c.details) + "</failure>\n    </testcase>\n";
}

}  // namespace

std::string escapeXml(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const CodePoint c = decodeUtf8(text, i);
    if (c.length == 0 || !isXmlChar(c.value)) {
      out += '?';
      i += c.length == 0 ? 1 : c.length;
      continue;
    }
    switch (c.value) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      case '\t': out += "&#9;"; break;
      case '\n': out += "&#10;"; break;
      case '\r': out += "&#13;"; break;
      default: out.append(text.substr(i, c.length));
    }
    i += c.length;
  }
  return out;
}

std::string junitXml(const SuiteReport& report) {
  const std::string counts = attribute("tests", std::to_string(report.cases.size())) +
                             attribute("failures", std::to_string(failuresOf(report))) + attribute("errors", "0") +
                             attribute("time", secondsText(report.seconds));
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<testsuites" + attribute("name", report.name) +
                    counts + ">\n  <testsuite" + attribute("name", report.name) + counts + ">\n";
  for (const SuiteCase& c : report.cases) out += testcase(c);
  return out + "  </testsuite>\n</testsuites>\n";
}

void writeJUnit(const std::filesystem::path& file, const SuiteReport& report) {
  writeFileAtomically(file, junitXml(report));
}

}  // namespace vdmap::app
