#pragma once
// The report of `vdmap bench`: bench.json, bench.md and the table on stdout (docs/method.md 12).
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/bench/bench_method.h"
#include "app/bench/odometry_timing.h"
#include "app/bench/vdmap_timing.h"
#include "mapping/global_map/global_map.h"

namespace vdmap::app {

/// Everything one `vdmap bench` run measured.
struct BenchFigures {
  std::size_t frames = 0;
  std::string frame_range;  ///< as frameRangeText writes it
  int width = 0, height = 0;
  bool mesh_scored = false;       ///< --mesh: the rows carry their accuracy against it
  std::vector<double> decode_ms;  ///< per frame, CPU
  UpdateTiming update;
  PipelineTiming pipeline;
  int revisits = 0;                ///< the pipeline's Mapper's
  std::size_t keyframes = 0;       ///< the pipeline's keyframes
  GlobalMap global;                ///< of those keyframes
  nlohmann::json global_stats;     ///< globalMapStats of the pipeline's graph and `global`
  std::vector<MethodResult> rows;  ///< vdmap's, then the peers' from rows[first_peer]
  std::size_t first_peer = 0;
  std::optional<TrackingRows> tracking;  ///< --poses track
};

/// Writes bench.json and bench.md into `out_dir` (created) and prints bench.json (--json) or a
/// text summary to stdout.
void writeBenchReport(const BenchFigures& figures, const BenchArgs& args, const std::filesystem::path& out_dir);

/// --query: writes bench.json (`query`: the figures) and bench.md (the table, `text`) into
/// `out_dir` (created) and prints bench.json (--json) or `text` to stdout.
void writeQueryBenchReport(const nlohmann::json& query, const std::string& text, const BenchArgs& args,
                           const std::filesystem::path& out_dir);

}  // namespace vdmap::app
