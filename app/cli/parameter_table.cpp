#include "app/cli/parameter_table.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace vdmap::app {
namespace {

using K = Parameter::Kind;

}  // namespace

std::span<const Parameter> parameterTable() {
  const std::span<const Parameter> all = parameters();
  const auto advanced = std::find_if(all.begin(), all.end(), [](const Parameter& p) { return !p.slider; });
  return all.first(static_cast<std::size_t>(advanced - all.begin()));
}

double parseValue(const Parameter& p, std::string_view text) {
  const std::string s(text);
  const auto fail = [&](const std::string& expected) -> double {
    throw std::invalid_argument(std::string(p.key) + ": expected " + expected + ", got '" + s + "'");
  };
  switch (p.kind) {
    case K::kBool:
      if (s == "true" || s == "1" || s == "on") return 1;
      if (s == "false" || s == "0" || s == "off") return 0;
      return fail("true or false");
    case K::kChoice:
      for (std::size_t i = 0; i < p.choices.size(); ++i)
        if (s == p.choices[i]) return static_cast<double>(i);
      return fail(validityText(p));
    case K::kInt:
    case K::kReal: {
      std::size_t used = 0;
      double v = 0;
      try {
        v = std::stod(s, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      while (used < s.size() && std::isspace(static_cast<unsigned char>(s[used]))) ++used;
      if (s.empty() || used != s.size()) return fail(p.kind == K::kInt ? "an integer" : "a number");
      if (p.kind == K::kInt && v != std::floor(v)) return fail("an integer");
      return v;
    }
  }
  return fail("a value");
}

void setFromText(const Parameter& p, ParameterValues& params, std::string_view text) {
  const double v = parseValue(p, text);
  checkValue(p, v);
  p.set(params, v);
}

void addParameterOptions(CLI::App& verb, ParameterValues& params) {
  const ParameterValues defaults = params;
  for (const Parameter& p : parameters()) {
    if (p.flag.empty()) continue;
    const std::string flag(p.flag);
    if (p.kind == K::kBool) {
      const std::string help =
          std::string(p.help) + (p.get(defaults) != 0 ? " [on by default; this flag turns it off]"
                                                      : " [off by default; this flag turns it on]");
      // The flag flips the default (--no-occlusion-removal turns a default-on step off).
      verb.add_flag_callback(
          flag, [&params, &p, defaults] { p.set(params, p.get(defaults) != 0 ? 0 : 1); }, help);
      continue;
    }
    const Parameter* rule = p.enabled_by.empty() ? nullptr : findParameter(p.enabled_by);
    const std::string help = std::string(p.help) + " [" + validityText(p) +
                             (!rule                      ? ""
                              : rule->get(defaults) != 0 ? "; no effect with " + std::string(rule->flag)
                                                         : "; only with " + std::string(rule->flag)) +
                             "]";
    verb.add_option_function<std::string>(
            flag,
            [&params, &p, flag](const std::string& text) {
              // A value outside its range is wrong whatever the data: CLI11's error and code
              // (docs/cli.md "Exit codes and errors").
              try {
                setFromText(p, params, text);
              } catch (const std::invalid_argument& e) {
                throw CLI::ValidationError(flag, e.what());
              }
            },
            help)
        ->default_str(formatValue(p, p.get(defaults)))
        ->type_name(p.kind == K::kChoice ? "NAME"
                    : p.kind == K::kInt  ? "INT"
                                         : "NUMBER");
  }
}

nlohmann::json valueJson(const Parameter& p, double value) {
  switch (p.kind) {
    case K::kBool: return value != 0;
    case K::kChoice: return formatValue(p, value);
    case K::kInt: return static_cast<long long>(value);
    case K::kReal: return value;
  }
  return value;
}

}  // namespace vdmap::app
