#pragma once
// The accuracy figures of docs/method.md 12 as JSON and as a text line, shared by eval and bench.
#include <cstdio>
#include <string>

#include <nlohmann/json.hpp>

#include "mapping/core/timing.h"
#include "mapping/eval/mesh_accuracy.h"
#include "mapping/eval/trajectory_error.h"

namespace vdmap::app {

inline nlohmann::json toJson(const AccuracyReport& r) {
  return {{"elements", r.elements},
          {"rmse_mm", rounded(r.rmse_mm)},
          {"mean_mm", rounded(r.mean_mm)},
          {"median_mm", rounded(r.median_mm)},
          {"completion_mean_mm", rounded(r.completion_mean_mm)},
          {"completion_ratio_5cm", rounded(r.completion_ratio)}};
}

inline std::string toText(const AccuracyReport& r) {
  char line[256];
  std::snprintf(line, sizeof line,
                "%9zu elements  RMSE %7.2f mm  mean %7.2f mm  median %7.2f mm  "
                "completion %7.2f mm, %5.1f%% within 5 cm",
                r.elements, r.rmse_mm, r.mean_mm, r.median_mm, r.completion_mean_mm, 100.0 * r.completion_ratio);
  return line;
}

inline nlohmann::json toJson(const RelativePoseError& r) {
  const ErrorStats &t = r.translation_m, &a = r.rotation_deg;
  return {{"pairs", t.count},
          {"translation_rmse_m", rounded(t.rmse)},
          {"translation_mean_m", rounded(t.mean)},
          {"translation_median_m", rounded(t.median)},
          {"translation_max_m", rounded(t.max)},
          {"rotation_rmse_deg", rounded(a.rmse)},
          {"rotation_mean_deg", rounded(a.mean)},
          {"rotation_median_deg", rounded(a.median)},
          {"rotation_max_deg", rounded(a.max)}};
}

/// Trajectory error: the ATE figures flat (ate_rmse_m as in stats.json), the RPE nested; figures
/// to 5 significant digits, as the accuracy report's and stats.json's.
inline nlohmann::json toJson(const TrajectoryError& e, const TrajectoryErrorParams& p) {
  nlohmann::json rpe_second = toJson(e.rpe_per_second);
  rpe_second["delta_s"] = p.rpe_delta_s;
  return {{"estimate_poses", e.estimate_poses},
          {"groundtruth_poses", e.groundtruth_poses},
          {"matched", e.matched},
          {"max_difference_s", p.max_difference_s},
          {"offset_s", p.offset_s},
          {"align_scale", p.align_scale},
          {"scale", rounded(e.scale)},
          {"ate_rmse_m", rounded(e.ate_m.rmse)},
          {"ate_mean_m", rounded(e.ate_m.mean)},
          {"ate_median_m", rounded(e.ate_m.median)},
          {"ate_max_m", rounded(e.ate_m.max)},
          {"rpe_per_frame", toJson(e.rpe_per_frame)},
          {"rpe_per_second", rpe_second}};
}

inline std::string toText(const TrajectoryError& e, const TrajectoryErrorParams& p) {
  const auto rpe = [](const char* name, const RelativePoseError& r) {
    char line[256];
    std::snprintf(line, sizeof line,
                  "RPE %-9s %6zu pairs  translation RMSE %7.2f mm  median %7.2f mm  max %7.2f mm  "
                  "rotation RMSE %6.3f deg  median %6.3f deg  max %6.3f deg\n",
                  name, r.translation_m.count, 1e3 * r.translation_m.rmse, 1e3 * r.translation_m.median,
                  1e3 * r.translation_m.max, r.rotation_deg.rmse, r.rotation_deg.median, r.rotation_deg.max);
    return std::string(line);
  };
  char head[512], per_second[32];
  std::snprintf(head, sizeof head,
                "%zu of %zu poses matched (ground truth: %zu poses, within %g s)\n"
                "ATE %s  RMSE %7.2f mm  mean %7.2f mm  median %7.2f mm  max %7.2f mm\n",
                e.matched, e.estimate_poses, e.groundtruth_poses, p.max_difference_s,
                p.align_scale ? "(similarity alignment)" : "(rigid alignment)", 1e3 * e.ate_m.rmse, 1e3 * e.ate_m.mean,
                1e3 * e.ate_m.median, 1e3 * e.ate_m.max);
  std::snprintf(per_second, sizeof per_second, "per %g s", p.rpe_delta_s);
  std::string text = head;
  if (p.align_scale) text += "scale " + std::to_string(e.scale) + "\n";
  return text + rpe("per frame", e.rpe_per_frame) + rpe(per_second, e.rpe_per_second);
}

}  // namespace vdmap::app
