#pragma once
// The one table of the mapping parameters a user sets (SPEC section 9 and the keyframe
// schedule): for each its name, `vdmap map` flag, settings.json / --set key, unit, valid range,
// slider range and help text. It drives the command line (addParameterOptions), the settings
// file and --set (app/gui/settings.cpp) and the workbench's sliders, so a value is accepted or
// refused the same way everywhere. The valid ranges are those the parameters' validate()
// functions enforce (tests/test_gui_parameters.cpp probes every bound against them).
#include <span>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "mapping/global_map/global_map.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap::app {

/// Every parameter of the table: the re-run ones shape the keyframes and local maps, the live
/// ones only the global map built from them.
struct ParameterValues {
  MapperParams mapper;
  GlobalMapParams global;
  bool operator==(const ParameterValues& other) const;
};

struct Parameter {
  enum class Kind { kInt, kReal, kBool, kChoice };
  std::string_view key;    ///< settings.json key (in "thresholds" when live, else "rerun") and --set KEY
  std::string_view flag;   ///< the `vdmap map` option; for a bool, the flag that flips the default
  std::string_view label;  ///< the slider's label
  std::string_view unit;   ///< "m", "px", "deg" or ""
  std::string_view help;   ///< what it is, in the method's words (tooltip and --help)
  Kind kind = Kind::kReal;
  bool live = false;       ///< true: changing it rebuilds the global map only; false: re-maps
  double lo = 0, hi = 0;   ///< valid range (+-inf: unbounded)
  bool lo_open = false, hi_open = false;
  double slider_lo = 0, slider_hi = 0;  ///< the slider's span (within the valid range; typing reaches the rest)
  double (*get)(const ParameterValues&) = nullptr;
  void (*set)(ParameterValues&, double) = nullptr;
  /// kChoice: the names of values 0, 1, ...
  std::span<const char* const> choices = {};
};

/// The table, live parameters first, in the workbench's order.
std::span<const Parameter> parameterTable();
/// The parameter with settings key `key`; null when there is none.
const Parameter* findParameter(std::string_view key);

/// "within 0..1", "> 0", ">= 1 px", ...: the valid range in words.
std::string validityText(const Parameter& p);
/// A value as the settings file and --help write it ("0.25", "6", "true", "nguyen2012").
std::string formatValue(const Parameter& p, double value);
/// Parses text for `p` (a number, true/false, a choice name). Throws std::invalid_argument
/// "KEY: expected ..., got 'TEXT'".
double parseValue(const Parameter& p, std::string_view text);
/// Throws std::invalid_argument "KEY must be VALIDITY, got VALUE" when value is out of range
/// (or not an integer for an integer parameter).
void checkValue(const Parameter& p, double value);
/// parseValue, checkValue and set in one step (the path of --set, settings.json and the CLI).
void setFromText(const Parameter& p, ParameterValues& params, std::string_view text);
/// Both structs' validate() (cross-parameter rules, such as min depth < max depth).
void validate(const ParameterValues& params);

/// Registers every parameter that has a flag as an option of `verb` writing into `params`
/// (which must outlive the parse): a value is parsed and range-checked as everywhere else and a
/// bad one fails the parse with "--FLAG: KEY must be ...".
void addParameterOptions(CLI::App& verb, ParameterValues& params);

}  // namespace vdmap::app
