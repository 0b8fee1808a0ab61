#pragma once
// JSON text of the figures vdmap writes (stats.json, bench.json, --json output, settings).
#include <string>

#include <nlohmann/json.hpp>

namespace vdmap {

/// value.dump(indent) with every floating-point number written as the shortest text that reads
/// back as the same double. nlohmann::json writes doubles with Grisu2, which for about 1 in 600
/// gives a longer one (0.010103 as 0.010102999999999999), bringing back the float noise that
/// rounded() took out. Strings are left as they are, but for bytes that are not UTF-8 (a path of
/// a folder named in another encoding), each written as U+FFFD; a whole double keeps its ".0".
std::string jsonText(const nlohmann::json& value, int indent = 2);

}  // namespace vdmap
