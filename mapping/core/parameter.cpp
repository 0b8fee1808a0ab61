#include "mapping/core/parameter.h"

#include <cmath>
#include <cstdio>

namespace vdmap {
namespace {

using Kind = ParameterSpec::Kind;

std::string number(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

}  // namespace

bool inRange(const ParameterSpec& p, double value) {
  const bool whole = p.kind == Kind::kReal || value == std::floor(value);
  return whole && std::isfinite(value) && (p.lo_open ? value > p.lo : value >= p.lo) &&
         (p.hi_open ? value < p.hi : value <= p.hi);
}

std::string validityText(const ParameterSpec& p, bool with_unit) {
  if (p.kind == Kind::kBool) return "true or false";
  if (p.kind == Kind::kChoice) {
    std::string names;
    for (std::size_t i = 0; i < p.choices.size(); ++i)
      names += (i == 0 ? "" : i + 1 == p.choices.size() ? " or " : ", ") + std::string(p.choices[i]);
    return names;
  }
  const bool has_lo = std::isfinite(p.lo), has_hi = std::isfinite(p.hi);
  std::string unit;
  if (with_unit && !p.unit.empty()) unit.append(" ").append(p.unit);
  if (has_lo && has_hi && !p.lo_open && !p.hi_open) return "within " + number(p.lo) + ".." + number(p.hi) + unit;
  std::string text;
  if (has_lo) text = (p.lo_open ? "> " : ">= ") + number(p.lo) + unit;
  if (has_hi) text += (text.empty() ? "" : " and ") + std::string(p.hi_open ? "< " : "<= ") + number(p.hi) + unit;
  return text;
}

std::string formatValue(const ParameterSpec& p, double value) {
  if (p.kind == Kind::kBool) return value != 0 ? "true" : "false";
  if (p.kind == Kind::kChoice) {
    const auto i = static_cast<std::size_t>(value);
    return value >= 0 && i < p.choices.size() ? p.choices[i] : number(value);
  }
  return number(value);
}

void checkValue(const ParameterSpec& p, double value) {
  if (!inRange(p, value))
    throw std::invalid_argument(std::string(p.key) + " must be " + validityText(p) + ", got " + formatValue(p, value));
}

void checkRange(const ParameterSpec& p, double value) {
  // Without the unit: validate()'s messages were written so ("keyframe_every must be >= 0").
  if (!inRange(p, value))
    throw std::invalid_argument(std::string(p.range_name.empty() ? p.key : p.range_name) + " must be " +
                                validityText(p, false));
}

}  // namespace vdmap
