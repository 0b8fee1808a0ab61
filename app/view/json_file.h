#pragma once
// Reading the JSON files vdmap takes from users (settings, view files) strictly: a key given twice
// in one object is an error naming its line, and keys the reader does not know are named with
// the valid ones.
#include <string>

#include <nlohmann/json.hpp>

namespace vdmap::app {

/// Parses `text`, the contents of `file`. Throws InputError "FILE:LINE: key 'K' is given twice in
/// one object" for a duplicate key and "FILE: not valid JSON (WHAT)" for text that does not parse.
nlohmann::json parseJsonStrictly(const std::string& text, const std::string& file);

/// Throws std::invalid_argument "unknown key 'SECTION.KEY' (valid: A, B, ...)" for the first key
/// of `given` that `known` lacks, looking into the objects both have (`prefix` names the level).
void refuseUnknownKeys(const nlohmann::json& given, const nlohmann::json& known, const std::string& prefix = "");

}  // namespace vdmap::app
