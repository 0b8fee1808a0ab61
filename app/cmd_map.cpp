// vdmap map SEQ --keyframe-every N --out DIR: the first end-to-end path (issue #3). Every N-th
// frame starts a new keyframe; every frame updates the current keyframe's local map; the kept
// ellipsoids of all keyframes go to DIR/local_maps.ply in world coordinates.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/commands.h"
#include "app/progress.h"
#include "mapping/export/ply_writer.h"
#include "mapping/io/frame_prefetcher.h"
#include "mapping/local_map/ellipsoid_filter.h"
#include "mapping/local_map/local_map_integrator.h"

namespace vdmap::app {
namespace {

struct MapArgs {
  SequenceArgs sequence;
  int keyframe_every = 10;
  std::string out;
  LocalMapParams local_map;
  std::string sensor_model = "nguyen2012";
  FilterParams filter;
};

struct FixedKeyframe {
  int frame_index;
  Transform T_W_K;
  KeyframeContainer container;
};

void runMap(MapArgs args) {
  namespace fs = std::filesystem;
  if (args.keyframe_every < 1) throw std::invalid_argument("--keyframe-every must be at least 1");
  args.filter.model = parseSensorModel(args.sensor_model);
  const fs::path out_dir = args.out;
  // Fail before any work when DIR cannot be a folder; it is created only when there is a map
  // to write, so a failed run leaves nothing behind.
  if (fs::exists(out_dir) && !fs::is_directory(out_dir))
    throw std::runtime_error(out_dir.string() + ": exists and is not a folder");

  const TumSequence seq = openSequence(args.sequence);
  const PinholeCamera& cam = seq.camera();
  KeyframeContainer(cam, args.local_map.cell_size_px);  // validates the cell size up front
  LocalMapIntegrator integrator(args.local_map);
  std::vector<FixedKeyframe> keyframes;
  FramePrefetcher frames(seq);
  ProgressBar progress("mapping", seq.size());
  std::vector<int> touched;
  std::size_t done = 0;
  while (std::optional<RgbdFrame> frame = frames.next()) {
    if (done % args.keyframe_every == 0)
      keyframes.push_back({frame->index, frame->T_W_C, KeyframeContainer(cam, args.local_map.cell_size_px)});
    FixedKeyframe& kf = keyframes.back();
    integrator.integrateFrame(*frame, cam, kf.T_W_K, &kf.container, &touched);
    progress.update(++done);
  }

  std::vector<Ellipsoid> all;
  std::printf("keyframe  frame  ellipsoids  kept    memory\n");
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    const FixedKeyframe& kf = keyframes[k];
    const std::size_t before = all.size();
    forEachKeptEllipsoid(kf.container, args.filter, kf.T_W_K, static_cast<int>(k),
                         [&all](const Ellipsoid& e) { all.push_back(e); });
    std::printf("%8zu  %5d  %10zu  %6zu  %5.2f MB\n", k, kf.frame_index, kf.container.size(),
                all.size() - before, kf.container.memoryBytes() / 1e6);
  }
  fs::create_directories(out_dir);
  const fs::path ply = out_dir / "local_maps.ply";
  writeEllipsoidPly(ply, all);
  std::printf("%zu frames, %zu keyframes, %zu kept ellipsoids (%s, k = %g, min %d points) -> %s\n",
              done, keyframes.size(), all.size(), sensorModelName(args.filter.model),
              args.filter.filter_sigma_factor, args.filter.min_points, ply.c_str());
}

}  // namespace

void addMapCommand(CLI::App& app) {
  auto* verb = app.add_subcommand(
      "map", "Map a sequence into view-dependent local maps (fixed keyframe spacing for now)");
  auto args = std::make_shared<MapArgs>();
  addSequenceArgs(*verb, args->sequence);
  verb->add_option("--out", args->out, "output folder (created if missing): local_maps.ply")->required();
  verb->add_option("--keyframe-every", args->keyframe_every,
                   "every N-th frame starts a new keyframe (until the covisibility graph decides)")
      ->capture_default_str();
  verb->add_option("--cell-size", args->local_map.cell_size_px, "container cell size, px")
      ->capture_default_str();
  verb->add_option("--min-depth", args->local_map.depth_range.min_m, "nearest valid depth, m")
      ->capture_default_str();
  verb->add_option("--max-depth", args->local_map.depth_range.max_m, "farthest valid depth, m")
      ->capture_default_str();
  verb->add_option("--sensor-model", args->sensor_model, "nguyen2012 or belter2018")
      ->capture_default_str();
  verb->add_option("--filter-sigma-factor", args->filter.filter_sigma_factor,
                   "reject ellipsoids longer than k x the sensor model's expectation")
      ->capture_default_str();
  verb->add_option("--min-points", args->filter.min_points, "reject ellipsoids of fewer points")
      ->capture_default_str();
  verb->callback([args] { runMap(*args); });
}

}  // namespace vdmap::app
