#pragma once
// The accuracy figures of SPEC section 8 as JSON and as a text line, shared by eval and bench.
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "mapping/core/timing.h"
#include "mapping/eval/mesh_accuracy.h"

namespace vdmap::app {

inline nlohmann::json toJson(const AccuracyReport& r) {
  return {{"elements", r.elements},           {"rmse_mm", rounded(r.rmse_mm)},
          {"mean_mm", rounded(r.mean_mm)},    {"median_mm", rounded(r.median_mm)},
          {"completion_mean_mm", rounded(r.completion_mean_mm)}, {"completion_ratio_5cm", rounded(r.completion_ratio)}};
}

inline std::string toText(const AccuracyReport& r) {
  char line[256];
  std::snprintf(line, sizeof line, "%9zu elements  RMSE %7.2f mm  mean %7.2f mm  median %7.2f mm  "
                "completion %7.2f mm, %5.1f%% within 5 cm", r.elements, r.rmse_mm, r.mean_mm, r.median_mm,
                r.completion_mean_mm, 100.0 * r.completion_ratio);
  return line;
}

}  // namespace vdmap::app
