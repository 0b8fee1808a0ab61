#include "mapping/pipeline/parameters.h"

#include <cctype>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "mapping/global_map/global_map_parameters.h"
#include "mapping/pipeline/mapper_parameters.h"

namespace vdmap {
namespace {

template <typename Params>
void appendRows(std::span<const ParameterRow<Params>> rows, std::vector<Parameter>* table) {
  for (const ParameterRow<Params>& row : rows) {
    Parameter p;
    static_cast<ParameterSpec&>(p) = row.spec;
    if constexpr (std::is_same_v<Params, GlobalMapParams>) {
      p.live = true;
      p.global_row = &row;
    } else {
      p.mapper_row = &row;
    }
    table->push_back(p);
  }
}

std::vector<Parameter> joinRows() {
  std::vector<Parameter> table;
  appendRows(globalMapParameters(), &table);
  appendRows(mapperParameters(), &table);
  return table;
}

const std::vector<Parameter>& table() {
  static const std::vector<Parameter> rows = joinRows();
  return rows;
}

// The PARM section's layout (docs/vdmap-format.md): the file format's order, frozen; a table
// parameter that the file does not store yet needs a new format version.
struct StoredField {
  std::string_view key;
  StoredParameter::Type type;
  const char* name;
  std::uint32_t since_version = 1;
  std::optional<double> older = std::nullopt;
};
using T = StoredParameter::Type;

constexpr StoredField kMapperFields[] = {
    {"cell_size", T::kI32, "cell_size_px"},
    {"min_depth", T::kF64, "min_depth"},
    {"max_depth", T::kF64, "max_depth"},
    {"orb_features", T::kI32, "orb_features"},
    {"tau", T::kF64, "tau"},
    {"tau_edge", T::kF64, "tau_edge"},
    {"prefilter", T::kBool, "prefilter enabled"},
    {"prefilter_max_distance", T::kF64, "prefilter max_distance"},
    {"prefilter_max_angle", T::kF64, "prefilter max_angle"},
    {"min_frame_features", T::kI32, "min_frame_features"},
    {"max_hamming", T::kI32, "max_hamming"},
    {"lowe_ratio", T::kF64, "lowe_ratio"},
    {"max_reprojection", T::kF64, "max_reprojection"},
    {"keyframe_every", T::kI32, "keyframe_every"},
};

constexpr StoredField kGlobalFields[] = {
    {"sensor_model", T::kU32, "sensor model"},
    {"filter_sigma_factor", T::kF64, "filter_sigma_factor"},
    {"min_points", T::kI32, "min_points"},
    {"tau_group", T::kF64, "tau_group"},
    {"merge_distance", T::kF64, "merge_distance"},
    {"occlusion_removal", T::kBool, "occlusion_removal"},
    {"occlusion_distance", T::kF64, "occlusion_distance"},
    {"occlusion_angle", T::kF64, "occlusion_angle"},
    // Versions 1 and 2 predate fusion across groups: their maps were built without it.
    {"fuse_across_groups", T::kBool, "fuse_across_groups", 3, 0.0},
    {"fusion_max_distance", T::kF64, "fusion_max_distance", 3},
};

std::vector<StoredParameter> resolve(std::span<const StoredField> fields) {
  std::vector<StoredParameter> out;
  for (const StoredField& f : fields) {
    const Parameter* p = findParameter(f.key);
    if (p == nullptr) throw std::logic_error("the PARM layout names no parameter '" + std::string(f.key) + "'");
    out.push_back({p, f.type, f.name, f.since_version, f.older});
  }
  return out;
}

}  // namespace

double Parameter::get(const ParameterValues& values) const {
  return live ? global_row->get(values.global) : mapper_row->get(values.mapper);
}

void Parameter::set(ParameterValues& values, double value) const {
  if (live) global_row->set(values.global, value);
  else mapper_row->set(values.mapper, value);
}

bool ParameterValues::operator==(const ParameterValues& other) const {
  for (const Parameter& p : parameters())
    if (p.get(*this) != p.get(other)) return false;
  return true;
}

std::span<const Parameter> parameters() { return table(); }

const Parameter* findParameter(std::string_view key) {
  for (const Parameter& p : table())
    if (p.key == key) return &p;
  return nullptr;
}

std::string whyDisabled(const Parameter& p, const ParameterValues& values) {
  if (p.enabled_by.empty()) return "";
  const Parameter* rule = findParameter(p.enabled_by);
  if (rule == nullptr)
    throw std::logic_error(std::string(p.key) + " is enabled by no parameter '" + std::string(p.enabled_by) + "'");
  if (rule->get(values) != 0) return "";
  std::string text(rule->label);
  if (!text.empty()) text[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[0])));
  return text + " is off: this has no effect.";
}

void validate(const ParameterValues& values) {
  values.mapper.validate();
  values.global.validate();
}

std::span<const StoredParameter> storedParameters(bool live) {
  static const std::vector<StoredParameter> mapper = resolve(kMapperFields), global = resolve(kGlobalFields);
  return live ? global : mapper;
}

}  // namespace vdmap
