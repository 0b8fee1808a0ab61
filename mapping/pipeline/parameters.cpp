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

}  // namespace

double Parameter::get(const ParameterValues& values) const {
  return live ? global_row->get(values.global) : mapper_row->get(values.mapper);
}

void Parameter::set(ParameterValues& values, double value) const {
  if (live)
    global_row->set(values.global, value);
  else
    mapper_row->set(values.mapper, value);
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
  if (rule == nullptr) throw std::logic_error(std::string(p.key) + " is enabled by no parameter '" +
                                              std::string(p.enabled_by) + "'");
  if (rule->get(values) != 0) return "";
  std::string text(rule->label);
  if (!text.empty()) text[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(text[0])));
  return text + " is off: this has no effect.";
}

void validate(const ParameterValues& values) {
  values.mapper.validate();
  values.global.validate();
}

}  // namespace vdmap
