#include "app/bench/bench_report.h"

#include "app/cli/command_line.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "app/cli/eval_report.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"
#include "mapping/local_map/keyframe_container.h"

namespace vdmap::app {
namespace {

// A peer that did not run has null figures, as at the top level of bench.json (not 0).
nlohmann::json methodJson(const MethodResult& r) {
  const bool ran = r.note.empty();
  nlohmann::json j = {{"name", r.name},
                      {"ms_per_frame", ran ? nlohmann::json(rounded(r.ms)) : nlohmann::json(nullptr)},
                      {"elements", ran ? nlohmann::json(r.elements) : nlohmann::json(nullptr)}};
  if (r.accuracy) j["accuracy"] = toJson(*r.accuracy);
  if (!r.note.empty()) j["note"] = r.note;
  return j;
}

std::string markdownTable(const std::vector<MethodResult>& rows, double vd_ms, bool accuracy) {
  std::ostringstream md;
  md << "| method | t_u [ms/frame] | x vdmap update | elements |";
  if (accuracy) md << " RMSE [mm] | mean [mm] | median [mm] | completion [mm] | within 5 cm |";
  md << "\n|---|---:|---:|---:|" << (accuracy ? "---:|---:|---:|---:|---:|" : "") << "\n";
  char buf[512];
  for (const MethodResult& r : rows) {
    if (!r.note.empty()) {
      md << "| " << r.name << " | not run: " << r.note << " |\n";
      continue;
    }
    std::snprintf(buf, sizeof buf, "| %s | %.2f | %.1f | %zu |", r.name.c_str(), r.ms, vd_ms > 0 ? r.ms / vd_ms : 0.0,
                  r.elements);
    md << buf;
    if (accuracy && r.accuracy) {
      const AccuracyReport& a = *r.accuracy;
      std::snprintf(buf, sizeof buf, " %.2f | %.2f | %.2f | %.1f | %.1f%% |", a.rmse_mm, a.mean_mm, a.median_mm,
                    a.completion_mean_mm, 100 * a.completion_ratio);
      md << buf;
    } else if (accuracy) {
      md << " | | | | |";
    }
    md << "\n";
  }
  return md.str();
}

nlohmann::json odometryJson(const OdometryRow& r, std::size_t frames) {
  nlohmann::json j = {{"name", r.run.name}, {"frames", frames}};
  if (!r.run.note.empty()) {
    j["note"] = r.run.note;
    return j;
  }
  j["ms_per_frame"] = rounded(r.ms);
  j["failures"] = r.run.failures;
  if (r.run.keyframes > 0) j["keyframes"] = r.run.keyframes;
  j["ate_rmse_m"] = r.error ? nlohmann::json(rounded(r.error->ate_m.rmse)) : nlohmann::json(nullptr);
  if (r.error) j["rpe_per_frame"] = toJson(r.error->rpe_per_frame);
  return j;
}

std::string odometryTable(const std::vector<OdometryRow>& rows) {
  std::ostringstream md;
  md << "| method | t [ms/frame] | ATE RMSE [cm] | frames not registered | keyframes |\n|---|---:|---:|---:|---:|\n";
  for (const OdometryRow& r : rows) {
    if (!r.run.note.empty()) {
      md << "| " << r.run.name << " | not run: " << r.run.note << " |\n";
      continue;
    }
    char buf[256], ate[32] = "-", keyframes[32] = "-";  // per row: a row without them shows "-"
    if (r.error) std::snprintf(ate, sizeof ate, "%.2f", 100 * r.error->ate_m.rmse);
    if (r.run.keyframes > 0) std::snprintf(keyframes, sizeof keyframes, "%d", r.run.keyframes);
    std::snprintf(buf, sizeof buf, "| %s | %.2f | %s | %d | %s |\n", r.run.name.c_str(), r.ms, ate, r.run.failures,
                  keyframes);
    md << buf;
  }
  return md.str();
}

// The medians every part of the report quotes.
struct Medians {
  double update = 0, pipeline = 0, features = 0, mapping = 0, decision = 0, stage_update = 0, decode = 0, fps = 0;
  std::string pipeline_line;
};

Medians mediansOf(const BenchFigures& f) {
  Medians m;
  m.update = median(f.update.ms);
  m.pipeline = median(f.pipeline.total_ms);
  m.features = median(f.pipeline.features_ms);
  m.mapping = median(f.pipeline.mapping_ms);
  m.decision = median(f.pipeline.decision_ms);
  m.stage_update = median(f.pipeline.update_ms);
  m.decode = median(f.decode_ms);
  m.fps = 1e3 / std::max({m.decode + m.features, m.mapping, 1e-9});
  m.pipeline_line = pipelineLine(m.pipeline, m.features, m.mapping, m.decode, m.fps);
  return m;
}

// A ratio to vdmap's update time (0 without one).
double toUpdate(double ms, const Medians& m) { return m.update > 0 ? ms / m.update : 0.0; }

// The run's figures, vdmap's update and pipeline, and the global map's (globalMapStats).
nlohmann::json runJson(const BenchFigures& f, const BenchArgs& args, const Medians& m) {
  nlohmann::json out = {
      {"frames", f.frames},
      {"frame_range", f.frame_range},
      {"vd_update_ms", rounded(m.update)},
      {"vd_update_ms_max",
       rounded(f.update.ms.empty() ? 0.0 : *std::max_element(f.update.ms.begin(), f.update.ms.end()))},
      {"cell_size_px", args.local_map.cell_size_px},
      {"keyframe_every", args.keyframe_every},
      {"ellipsoids", f.update.cells},
      {"bytes_per_ellipsoid", sizeof(StoredCell)},
      {"container_bytes", f.update.bytes},
      {"vd_pipeline_ms", rounded(m.pipeline)},
      {"pipeline_stage_ms",
       {{"features", rounded(m.features)},
        {"decision", rounded(m.decision)},
        {"update", rounded(m.stage_update)},
        {"decode", rounded(m.decode)}}},
      {"vd_pipeline_latency_ms", rounded(m.mapping)},
      {"vd_pipeline_fps", rounded(m.fps)},
      {"revisits", f.revisits},
  };
  out.update(f.global_stats);  // keyframes, sigma_e, sigma_e', t_g, ...
  return out;
}

// The methods: the peers' times and ratios at the top level, every row under "methods".
void addMethods(const BenchFigures& f, const Medians& m, nlohmann::json* out) {
  nlohmann::json& j = *out;
  for (std::size_t i = f.first_peer; i < f.rows.size(); ++i) {
    const MethodResult& r = f.rows[i];
    j[r.key + "_ms"] = r.note.empty() ? nlohmann::json(rounded(r.ms)) : nlohmann::json(nullptr);
    j["ratio_" + r.key] = r.note.empty() ? nlohmann::json(rounded(toUpdate(r.ms, m))) : nlohmann::json(nullptr);
  }
  j["ratio_octomap_010_pipeline"] = m.pipeline > 0 && f.rows[f.first_peer].note.empty()
                                        ? nlohmann::json(rounded(f.rows[f.first_peer].ms / m.pipeline))
                                        : nlohmann::json(nullptr);
  j["methods"] = nlohmann::json::object();  // sorted by key, so the table's order goes beside it
  j["method_order"] = nlohmann::json::array();
  for (const MethodResult& r : f.rows) {
    j["methods"][r.key] = methodJson(r);
    j["method_order"].push_back(r.key);
  }
}

// The tracking rows (--poses track).
void addTracking(const TrackingRows& t, const BenchArgs& args, std::size_t frames, const Medians& m,
                 nlohmann::json* out) {
  nlohmann::json& j = *out;
  j["odometry"] = nlohmann::json::object();
  j["odometry_order"] = nlohmann::json::array();
  for (const OdometryRow& r : t.rows) {
    j["odometry"][r.run.key] = odometryJson(r, frames);
    j["odometry_order"].push_back(r.run.key);
  }
  // What tracking adds to the pipeline: the tracked pipeline's median CPU time per frame
  // minus the ground-truth pipeline's, on the same frames.
  j["vd_tracking_added_ms"] = t.rows.front().ms - m.pipeline;
  j["odometry"]["vdmap_track"]["loop_closures"] = t.loop_closures;
  j["odometry"]["vdmap_track"]["map_refinement"] = args.sequence.refine;
  j["odometry"]["vdmap_track"]["map_refinement_ms"] = rounded(t.refinement.ms);
}

nlohmann::json benchJson(const BenchFigures& f, const BenchArgs& args, const Medians& m) {
  nlohmann::json out = runJson(f, args, m);
  addMethods(f, m, &out);
  if (f.mesh_scored) out["mesh"] = args.mesh;
  out["poses"] = args.poses;
  if (f.tracking && !f.tracking->rows.empty()) addTracking(*f.tracking, args, f.frames, m, &out);
  return out;
}

std::string benchMarkdown(const BenchFigures& f, const BenchArgs& args, const Medians& m, const nlohmann::json& out) {
  std::ostringstream md;
  char global_line[256];
  std::snprintf(global_line, sizeof global_line,
                "Global map of the pipeline's %s, Sigma_e %zu -> Sigma_e' %zu in %.3f s (%.2f us per ellipsoid).\n",
                counted(f.keyframes, "keyframe").c_str(), f.global.sigma_e, f.global.sigma_e_prime, f.global.t_g_s,
                out["t_g_us_per_ellipsoid"].get<double>());
  md << "# vdmap bench\n\n"
     << f.frames << " frames of `" << args.sequence.folder << "` (" << f.width << "x" << f.height << "), frames "
     << f.frame_range << "; the update row starts a keyframe every " << args.keyframe_every
     << " frames, the pipeline by covisibility (" << counted(f.keyframes, "keyframe")
     << "), one thread. Times are medians of CPU time per frame.\n\n"
     << markdownTable(f.rows, m.update, f.mesh_scored) << "\n"
     << m.pipeline_line << "\n\n"
     << global_line;
  if (f.tracking && !f.tracking->rows.empty())
    md << "\nTracking (--poses track) on the same frames, one thread: median CPU time per frame (vdmap: its whole "
          "pipeline, which tracking makes "
       << out["vd_tracking_added_ms"].get<double>()
       << " ms slower than with "
          "ground-truth poses; the peers: registration only), ATE after the rigid alignment against the sequence's "
          "ground truth. vdmap closed "
       << f.tracking->loop_closures
       << " loops; with loop closure its keyframe poses are "
          "refined from the local maps after the last frame (--refine "
       << args.sequence.refine << ", " << rounded(f.tracking->refinement.ms) << " ms, not in the per-frame time).\n\n"
       << odometryTable(f.tracking->rows);
  return md.str();
}

void printMethods(const std::vector<MethodResult>& rows, const Medians& m) {
  std::printf("\n%-34s %12s %10s %10s\n", "method", "ms/frame", "x vdmap", "elements");
  for (const MethodResult& r : rows) {
    if (!r.note.empty()) {
      std::printf("%-34s not run: %s\n", r.name.c_str(), r.note.c_str());
      continue;
    }
    std::printf("%-34s %12.2f %10.1f %10zu\n", r.name.c_str(), r.ms, toUpdate(r.ms, m), r.elements);
    if (r.accuracy) std::printf("    %s\n", toText(*r.accuracy).c_str());
  }
}

void printTracking(const TrackingRows& t, const BenchArgs& args, const nlohmann::json& out) {
  std::printf("\n%-48s %12s %10s %10s %10s\n", "tracking (vdmap: whole pipeline)", "ms/frame", "ATE [cm]", "lost",
              "keyframes");
  for (const OdometryRow& r : t.rows) {
    if (!r.run.note.empty()) {
      std::printf("%-44s not run: %s\n", r.run.name.c_str(), r.run.note.c_str());
      continue;
    }
    char ate[32] = "-";
    if (r.error) std::snprintf(ate, sizeof ate, "%.2f", 100 * r.error->ate_m.rmse);
    std::printf("%-48s %12.2f %10s %10d %10s\n", r.run.name.c_str(), r.ms, ate, r.run.failures,
                r.run.keyframes > 0 ? std::to_string(r.run.keyframes).c_str() : "-");
  }
  std::printf("tracking adds %.2f ms per frame to vdmap's pipeline (CPU medians); %d loop closures; keyframe poses "
              "refined from the local maps after the last frame (--refine %s) in %.0f ms (wall)\n",
              out["vd_tracking_added_ms"].get<double>(), t.loop_closures, args.sequence.refine.c_str(),
              t.refinement.ms);
}

void printBench(const BenchFigures& f, const BenchArgs& args, const Medians& m, const nlohmann::json& out) {
  // Two keyframe rules: the update row's fixed one (--keyframe-every), and the pipeline's own
  // decision by covisibility, whose keyframes the global map is built from.
  std::printf("frames          %zu of %s (%dx%d), cell %d px\n", f.frames, f.frame_range.c_str(), f.width, f.height,
              args.local_map.cell_size_px);
  std::printf("keyframes       the update row starts one every %s; the pipeline made %s (covisibility)\n",
              args.keyframe_every == 1 ? "frame" : (std::to_string(args.keyframe_every) + " frames").c_str(),
              counted(f.keyframes, "keyframe").c_str());
  std::printf("%s\n", m.pipeline_line.c_str());
  std::printf("Wall-clock stages on the mapping thread: decision %.2f, update %.2f ms\n", m.decision, m.stage_update);
  std::printf("global map      of the pipeline's %s, Sigma_e %zu -> Sigma_e' %zu in %.3f s (%.2f us per ellipsoid)\n",
              counted(f.keyframes, "keyframe").c_str(), f.global.sigma_e, f.global.sigma_e_prime, f.global.t_g_s,
              out["t_g_us_per_ellipsoid"].get<double>());
  printMethods(f.rows, m);
  if (f.tracking && !f.tracking->rows.empty()) printTracking(*f.tracking, args, out);
}

}  // namespace

void writeBenchReport(const BenchFigures& figures, const BenchArgs& args, const std::filesystem::path& out_dir) {
  const Medians m = mediansOf(figures);
  const nlohmann::json out = benchJson(figures, args, m);
  std::filesystem::create_directories(out_dir);
  writeFileAtomically(out_dir / "bench.json", jsonText(out) + "\n");
  writeFileAtomically(out_dir / "bench.md", benchMarkdown(figures, args, m, out));
  if (args.json) {
    std::cout << jsonText(out) << "\n";
    return;
  }
  printBench(figures, args, m, out);
  std::printf("\nwrote %s and %s\n", (out_dir / "bench.json").c_str(), (out_dir / "bench.md").c_str());
}

void writeQueryBenchReport(const nlohmann::json& query, const std::string& text, const BenchArgs& args,
                           const std::filesystem::path& out_dir) {
  const nlohmann::json out = {{"sequence", args.sequence.folder}, {"poses", "gt"}, {"query", query}};
  std::filesystem::create_directories(out_dir);
  writeFileAtomically(out_dir / "bench.json", jsonText(out) + "\n");
  writeFileAtomically(out_dir / "bench.md", "# vdmap bench --query\n\n```\n" + text + "```\n");
  if (args.json) {
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::printf("%s\nwrote %s and %s\n", text.c_str(), (out_dir / "bench.json").c_str(), (out_dir / "bench.md").c_str());
}

}  // namespace vdmap::app
