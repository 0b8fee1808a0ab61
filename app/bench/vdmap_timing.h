#pragma once
// vdmap's own rows of `vdmap bench` (docs/method.md 12): the local-map update alone, and the whole
// per-frame pipeline with the global map of the keyframes it made.
#include <string>
#include <vector>

#include "app/bench/bench_method.h"
#include "mapping/global_map/global_map.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap::app {

/// The local-map update alone: per frame, its CPU time (ms); the containers' cells and bytes.
struct UpdateTiming {
  std::vector<double> ms;
  std::size_t cells = 0, bytes = 0;
};

/// Every frame into the current keyframe's container, a new keyframe every args.keyframe_every
/// frames (its empty container is made outside the timed region, as a keyframe's creation is not
/// an update).
UpdateTiming timeVdmapUpdate(const BenchInput& in);

/// The whole per-frame path, per frame (ms): features computed as the prefetch thread does
/// (Mapper::featuresAhead) and timed apart from the mapping thread's share (decision and update),
/// whose sum is the pipeline's CPU time; and the Mapper's own wall-clock stage split.
struct PipelineTiming {
  std::vector<double> total_ms, features_ms, mapping_ms, decision_ms, update_ms;
};

/// The MapperParams of the pipeline rows: the bench's local-map parameters, the rest defaults.
MapperParams pipelineParams(const BenchArgs& args);

/// Feeds every frame (copies: the features stay out of in.frames) to `mapper`, timed.
PipelineTiming timeVdmapPipeline(const BenchInput& in, Mapper* mapper);

/// vdmap's rows: the update's median time and the pipeline's, both with the global map's
/// ellipsoid means as their elements (scored once), then with args.accuracy_cell_sizes one
/// untimed row per other cell size (the whole pipeline again, accuracy only).
std::vector<MethodResult> vdmapRows(const BenchInput& in, double update_ms, double pipeline_ms,
                                    const GlobalMap& global);

/// The pipeline's CPU per frame (medians) as one line: all of it on one thread, the mapping
/// thread's share (latency once the features are ready) and the frame rate with decoding and ORB
/// on the prefetch thread (bound by the slower of the two threads).
std::string pipelineLine(double total_ms, double features_ms, double mapping_ms, double decode_ms, double fps);

}  // namespace vdmap::app
