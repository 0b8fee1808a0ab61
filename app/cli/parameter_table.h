#pragma once
// The command line's and the settings' side of the parameter table (mapping/pipeline/parameters.h):
// text to values, and the `vdmap map` options. A value is accepted or refused the same way by the
// flags, settings.json, --set and the workbench's sliders (tests/workbench/test_gui_parameters.cpp).
#include <span>
#include <string_view>

#include <CLI/CLI.hpp>
#include <nlohmann/json_fwd.hpp>

#include "mapping/pipeline/parameters.h"

namespace vdmap::app {

/// The parameters the workbench shows as sliders, in its order: parameters() without the
/// advanced ones (which come last). Only the workbench's view reads this; everything else
/// takes every parameter, parameters().
std::span<const Parameter> parameterTable();

/// Parses text for `p` (a number, true/false, a choice name). Throws std::invalid_argument
/// "KEY: expected ..., got 'TEXT'".
double parseValue(const Parameter& p, std::string_view text);
/// parseValue, checkValue and set in one step (the path of --set, settings.json and the CLI).
void setFromText(const Parameter& p, ParameterValues& params, std::string_view text);

/// Registers every parameter that has a flag as an option of `verb` writing into `params`
/// (which must outlive the parse; its values when called are the defaults --help shows): a value
/// is parsed and range-checked as everywhere else and a bad one fails the parse with
/// "--FLAG: KEY must be ...".
void addParameterOptions(CLI::App& verb, ParameterValues& params);

/// `value` of `p` as JSON, the way settings.json and stats.json write it: a bool, an integer, a
/// number or a choice's name.
nlohmann::json valueJson(const Parameter& p, double value);

}  // namespace vdmap::app
