#include "mapping/io/json_text.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace vdmap {
namespace {

std::string shortest(double v) {
  char text[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, v);
    if (std::strtod(text, nullptr) == v) break;
  }
  std::string out = text;
  if (out.find_first_of(".e") == std::string::npos) out += ".0";
  return out;
}

bool isDigit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

std::string jsonText(const nlohmann::json& value, int indent) {
  const std::string in = value.dump(indent);
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
