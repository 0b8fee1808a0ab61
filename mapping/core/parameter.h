#pragma once
// One user-set parameter, declared once: its name, flag, unit, valid range, help and enable rule
// (ParameterSpec) and where its value lives in its parameter struct (ParameterRow). Each struct's
// rows are declared beside it (global_map/global_map_parameters.cpp, pipeline/mapper_parameters.cpp)
// and its validate() checks them with checkRanges(); pipeline/parameters.h joins them into the
// table the command line, settings, workbench, session file and docs/parameters.md read.
// The default of a parameter is its struct's in-class default, never repeated here.
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace vdmap {

/// An open end of a parameter's range.
inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Everything about a parameter but where its value lives. Plain data, constant-initialised.
struct ParameterSpec {
  enum class Kind { kInt, kReal, kBool, kChoice };
  std::string_view key;    ///< settings.json key and --set KEY; names it in messages
  std::string_view flag;   ///< the `vdmap map` option; for a bool, the flag that flips the default
  std::string_view label;  ///< the workbench's label, lower case ("occlusion removal")
  std::string_view unit;   ///< "m", "px", "deg", "frames" or ""
  std::string_view help;   ///< what it does, in the method's words (tooltip, --help, docs/parameters.md)
  Kind kind = Kind::kReal;
  double lo = 0, hi = 0;  ///< valid range (+-inf: unbounded); a value must also be finite
  bool lo_open = false, hi_open = false;
  /// false: an advanced parameter, set by flag, settings.json or --set but given no slider.
  bool slider = true;
  double slider_lo = 0, slider_hi = 0;  ///< the slider's span (within the valid range; typing reaches the rest)
  /// kChoice: the names of values 0, 1, ...
  std::span<const char* const> choices = {};
  /// The key of a bool parameter of the same struct that must be on for this one to have an
  /// effect (empty: always has one).
  std::string_view enabled_by = {};
  /// The name validate() gives the range when one message covers several parameters
  /// ("tau and tau_edge"); empty: the key.
  std::string_view range_name = {};
};

/// A parameter and its value in a `Params` struct, read and written as a double (an int, bool or
/// enum converts exactly).
template <typename Params>
struct ParameterRow {
  ParameterSpec spec;
  double (*get)(const Params&) = nullptr;
  void (*set)(Params&, double) = nullptr;
};

/// True when `value` is finite, within the valid range and, for an integer, bool or choice, a
/// whole number of it.
bool inRange(const ParameterSpec& p, double value);
/// "within 0..1", "> 0", ">= 1 px", "nguyen2012 or belter2018": the valid range in words.
/// `with_unit` false leaves out the unit.
std::string validityText(const ParameterSpec& p, bool with_unit = true);
/// A value as the settings file, --help and the docs write it ("0.25", "6", "true", "nguyen2012").
std::string formatValue(const ParameterSpec& p, double value);
/// Throws std::invalid_argument "KEY must be VALIDITY, got VALUE" when `value` is not inRange
/// (the check of a value a user gives).
void checkValue(const ParameterSpec& p, double value);
/// Throws std::invalid_argument "NAME must be VALIDITY" (NAME: range_name or the key; no unit)
/// when `value` is not inRange (the check of a struct's validate()).
void checkRange(const ParameterSpec& p, double value);

/// validate()'s range checks: checkRange() of every row's value in `params`, in row order.
template <typename Params>
void checkRanges(std::span<const ParameterRow<Params>> rows, const Params& params) {
  for (const ParameterRow<Params>& row : rows) checkRange(row.spec, row.get(params));
}

}  // namespace vdmap

/// A ParameterRow's accessors for the struct member `member` (a path such as filter.min_points).
#define VDMAP_PARAMETER_ACCESS(Params, member)                          \
  .get = [](const Params& p) { return static_cast<double>(p.member); }, \
  .set = [](Params& p, double v) { p.member = static_cast<decltype(p.member)>(v); }
