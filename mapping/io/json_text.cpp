#include "mapping/io/json_text.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace vdmap {
namespace {

// The fewest significant digits that read back as v; positional between 1e-4 and 1e15 (as
// nlohmann::json writes, 320.0 rather than %g's 3.2e+02), in exponent form outside.
std::string shortest(double v) {
  char text[40];
  int digits = 1;
  for (; digits < 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  const double magnitude = std::fabs(v);
  if (magnitude >= 1e-4 && magnitude < 1e15) {
    const int exponent = static_cast<int>(std::floor(std::log10(magnitude)));
    std::snprintf(text, sizeof text, "%.*f", std::max(0, digits - 1 - exponent), v);
  } else {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
  }
  std::string out = text;
  if (out.find_first_of(".e") == std::string::npos) out += ".0";
  return out;
}

bool isDigit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

std::string jsonText(const nlohmann::json& value, int indent) {
  // JSON text is UTF-8: a string that is not (a path of a non-UTF-8 folder) gets U+FFFD for each
  // invalid byte rather than nlohmann::json's exception.
  const std::string in = value.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size();) {
    std::size_t end = i + 1;
    if (in[i] == '"') {  // a string, escapes and all
      while (end < in.size() && in[end] != '"') end += in[end] == '\\' ? 2 : 1;
      end = std::min(end + 1, in.size());
      out.append(in, i, end - i);
    } else if (in[i] == '-' || isDigit(in[i])) {
      while (end < in.size() && (isDigit(in[end]) || std::strchr("+-.eE", in[end]))) ++end;
      const std::string number = in.substr(i, end - i);
      out += number.find_first_of(".eE") == std::string::npos ? number : shortest(std::strtod(number.c_str(), nullptr));
    } else {
      out += in[i];
    }
    i = end;
  }
  return out;
}

}  // namespace vdmap
