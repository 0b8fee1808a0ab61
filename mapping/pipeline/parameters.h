#pragma once
// The parameter table: every mapping parameter a user sets, the live ones of the global map
// (global_map/global_map_parameters.cpp) and the re-run ones of the Mapper
// (pipeline/mapper_parameters.cpp), each declared once there. Everything that names, checks,
// stores or explains a parameter reads it from here: the structs' validate(), the command line
// and settings.json (app/cli/parameter_table.h, app/view/settings.cpp), the workbench's sliders, the
// session file's PARM section (session_file.cpp) and docs/parameters.md (`vdmap params
// --markdown`). The pose source is no parameter of the table: it belongs to the input (--poses).
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "mapping/core/parameter.h"
#include "mapping/global_map/global_map.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap {

/// The value of every parameter of the table: the re-run ones shape the keyframes and local maps,
/// the live ones only the global map built from them.
struct ParameterValues {
  MapperParams mapper;
  GlobalMapParams global;
  /// Every parameter of the table equal (what the table does not hold, such as the pose source
  /// or the thread count, is not compared).
  bool operator==(const ParameterValues& other) const;
};

/// A row of the table: its declaration and where its value lives in ParameterValues.
struct Parameter : ParameterSpec {
  /// true: a GlobalMapParams value (changing it rebuilds the global map only; settings.json
  /// "thresholds"); false: a MapperParams value (changing it re-maps; settings.json "rerun").
  bool live = false;
  double get(const ParameterValues& values) const;
  void set(ParameterValues& values, double value) const;

  const ParameterRow<GlobalMapParams>* global_row = nullptr;  ///< set when live
  const ParameterRow<MapperParams>* mapper_row = nullptr;     ///< set when not live
};

/// The table: live parameters first, then the re-run ones, each in the workbench's order, the
/// advanced ones (no slider) last. Built once, never changed: safe to read from any thread.
std::span<const Parameter> parameters();
/// The parameter with settings key `key`; null when there is none.
const Parameter* findParameter(std::string_view key);

/// Why `p` has no effect with `values`: "" when it has one, else (p.enabled_by off) the text
/// "<Label of that parameter> is off: this has no effect." (the workbench greys it out).
std::string whyDisabled(const Parameter& p, const ParameterValues& values);

/// Both structs' validate(): every range of the table and the rules between parameters (such as
/// min depth < max depth). Throws std::invalid_argument naming the first value that is wrong.
void validate(const ParameterValues& values);

/// How a parameter is stored in the PARM section of a session file (docs/vdmap-format.md).
struct StoredParameter {
  enum class Type { kI32, kU32, kF64, kBool };  ///< little-endian; kU32 stores a choice's index
  const Parameter* parameter = nullptr;
  Type type = Type::kF64;
  const char* name = "";            ///< what a read error calls the field
  std::uint32_t since_version = 1;  ///< the format version that added it
  /// Its value in files older than since_version; none: the struct's default.
  std::optional<double> older = std::nullopt;
};

/// The PARM section's parameter fields, in file order: the MapperParams ones (`live` false; the
/// pose source follows them) or the GlobalMapParams ones (`live` true). Every parameter of the
/// table is in exactly one of them; their order is the file format's, not the table's.
std::span<const StoredParameter> storedParameters(bool live);

}  // namespace vdmap
