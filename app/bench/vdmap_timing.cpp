#include "app/bench/vdmap_timing.h"

#include <cstdio>
#include <memory>

#include "app/view/progress.h"
#include "mapping/core/timing.h"
#include "mapping/local_map/local_map_integrator.h"

namespace vdmap::app {
namespace {

std::vector<Eigen::Vector3f> means(const std::vector<Ellipsoid>& ellipsoids) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(ellipsoids.size());
  for (const Ellipsoid& e : ellipsoids) out.push_back(e.mean.cast<float>());
  return out;
}

// The row of cell size `s` px, accuracy only: the whole pipeline again, untimed.
MethodResult accuracyRow(const BenchInput& in, int s) {
  MapperParams p = pipelineParams(in.args);
  p.local_map.cell_size_px = s;
  Mapper m(in.cam, p);
  ProgressBar progress("vdmap " + std::to_string(s) + " px", in.frames.size());
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    m.addFrame(in.frames[i]);
    progress.update(i + 1);
  }
  const GlobalMap g = buildGlobalMap(m.graph(), {});
  MethodResult row("vdmap " + std::to_string(s) + " px (accuracy only)", "vd_" + std::to_string(s) + "px");
  in.score(&row, means(g.ellipsoids));
  return row;
}

}  // namespace

UpdateTiming timeVdmapUpdate(const BenchInput& in) {
  UpdateTiming t;
  LocalMapIntegrator integrator(in.args.local_map);
  std::unique_ptr<KeyframeContainer> container;
  Transform T_W_K;
  std::vector<int> touched;
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    if (i % in.args.keyframe_every == 0) {
      if (container) t.cells += container->size(), t.bytes += container->memoryBytes();
      container = std::make_unique<KeyframeContainer>(in.cam, in.args.local_map.cell_size_px);
      T_W_K = in.frames[i].T_W_C;
    }
    t.ms.push_back(
        cpuTimeMs([&] { integrator.integrateFrame(in.frames[i], in.cam, T_W_K, container.get(), &touched); }));
  }
  if (container) t.cells += container->size(), t.bytes += container->memoryBytes();
  return t;
}

MapperParams pipelineParams(const BenchArgs& args) {
  MapperParams params;
  params.local_map = args.local_map;
  return params;
}

PipelineTiming timeVdmapPipeline(const BenchInput& in, Mapper* mapper) {
  PipelineTiming t;
  ProgressBar progress("pipeline", in.frames.size());
  const auto features_ahead = mapper->featuresAhead();
  for (RgbdFrame frame : in.frames) {  // a copy: the features stay out of in.frames
    FrameReport r;
    t.features_ms.push_back(cpuTimeMs([&] { features_ahead(frame); }));
    t.mapping_ms.push_back(cpuTimeMs([&] { r = mapper->addFrame(frame); }));
    t.total_ms.push_back(t.features_ms.back() + t.mapping_ms.back());
    t.decision_ms.push_back(r.ms.decision_ms);
    t.update_ms.push_back(r.ms.update_ms);
    progress.update(t.total_ms.size());
  }
  return t;
}

std::vector<MethodResult> vdmapRows(const BenchInput& in, double update_ms, double pipeline_ms,
                                    const GlobalMap& global) {
  std::vector<MethodResult> rows;
  rows.emplace_back("vdmap update " + std::to_string(in.args.local_map.cell_size_px) + " px", "vd_update", update_ms);
  in.score(&rows.back(), means(global.ellipsoids));
  rows.emplace_back("vdmap pipeline", "vd_pipeline", pipeline_ms);
  rows.back().elements = global.ellipsoids.size();
  rows.back().accuracy = rows[rows.size() - 2].accuracy;
  for (const int s : in.args.accuracy_cell_sizes)
    if (s != in.args.local_map.cell_size_px) rows.push_back(accuracyRow(in, s));
  return rows;
}

std::string pipelineLine(double total_ms, double features_ms, double mapping_ms, double decode_ms, double fps) {
  char line[320];
  std::snprintf(line, sizeof line,
                "Pipeline CPU per frame (median): %.2f ms on one thread (ORB %.2f + decision and update %.2f); with "
                "decoding (%.2f) and ORB on the prefetch thread: latency %.2f ms, throughput %.0f frames/s.",
                total_ms, features_ms, mapping_ms, decode_ms, mapping_ms, fps);
  return line;
}

}  // namespace vdmap::app
