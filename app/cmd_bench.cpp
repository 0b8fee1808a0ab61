// vdmap bench SEQ --frames N: times the local-map update against OctoMap's insertPointCloud on
// the same frames in the same process (SPEC section 8). Frames are decoded once, before any
// timing; each method then runs over all frames in its own pass, so none of them pays for
// another's cache pollution. Single-threaded throughout (liboctomap on Debian is built without
// OpenMP, the integrator is sequential).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>
#include <octomap/OcTree.h>

#include "app/commands.h"
#include "app/progress.h"
#include "app/timing.h"
#include "mapping/io/frame_prefetcher.h"
#include "mapping/global_map/global_map.h"
#include "mapping/keyframe/mapper.h"
#include "mapping/local_map/local_map_integrator.h"

namespace vdmap::app {
namespace {

struct BenchArgs {
  SequenceArgs sequence;
  int keyframe_every = 10;
  LocalMapParams local_map;
  bool json = false;
  bool no_octomap = false;
};

// The points the integrator uses (every pixel with depth in range), in world coordinates.
octomap::Pointcloud worldCloud(const RgbdFrame& frame, const PinholeCamera& cam, const DepthRange& range) {
  const ColoredPointCloud cloud = toPointCloud(frame, cam, range);
  const Eigen::Isometry3f T = frame.T_W_C.cast<float>();
  octomap::Pointcloud out;
  out.reserve(cloud.size());
  for (const Eigen::Vector3f& p : cloud.points) {
    const Eigen::Vector3f w = T * p;
    out.push_back(w.x(), w.y(), w.z());
  }
  return out;
}

void runBench(BenchArgs args) {
  // A plain number N means the first N frames (0:N) here: "bench --frames 100" reads as a count.
  std::string& frames = args.sequence.frames;
  if (frames.empty()) frames = "0:30";
  else if (frames.find(':') == std::string::npos) frames = "0:" + frames;
  if (args.keyframe_every < 1) throw std::invalid_argument("--keyframe-every must be at least 1");
  const TumSequence seq = openSequence(args.sequence);
  const PinholeCamera& cam = seq.camera();

  std::vector<RgbdFrame> decoded;
  {
    FramePrefetcher prefetcher(seq);
    ProgressBar progress("decoding", seq.size());
    while (std::optional<RgbdFrame> f = prefetcher.next()) {
      decoded.push_back(std::move(*f));
      progress.update(decoded.size());
    }
  }

  // vdmap: every frame into the current keyframe; a new keyframe every N frames (its empty
  // container is made outside the timed region, as a keyframe's creation is not an update).
  std::vector<double> vd_ms;
  std::size_t cells = 0, bytes = 0;
  {
    LocalMapIntegrator integrator(args.local_map);
    std::unique_ptr<KeyframeContainer> container;
    Transform T_W_K;
    std::vector<int> touched;
    for (std::size_t i = 0; i < decoded.size(); ++i) {
      if (i % args.keyframe_every == 0) {
        if (container) cells += container->size(), bytes += container->memoryBytes();
        container = std::make_unique<KeyframeContainer>(cam, args.local_map.cell_size_px);
        T_W_K = decoded[i].T_W_C;
      }
      vd_ms.push_back(timeMs([&] {
        integrator.integrateFrame(decoded[i], cam, T_W_K, container.get(), &touched);
      }));
    }
    if (container) cells += container->size(), bytes += container->memoryBytes();
  }

  // The whole per-frame path (features, keyframe decision, update) on the same frames, then
  // the global map of the keyframes it made.
  std::vector<double> pipeline_ms, features_ms, decision_ms, update_ms;
  Mapper mapper(cam);
  for (const RgbdFrame& frame : decoded) {
    const FrameReport r = mapper.addFrame(frame);
    pipeline_ms.push_back(r.ms.total_ms);
    features_ms.push_back(r.ms.features_ms);
    decision_ms.push_back(r.ms.decision_ms);
    update_ms.push_back(r.ms.update_ms);
  }
  const GlobalMap global = buildGlobalMap(mapper.graph(), {});
  const double t_g_us = global.sigma_e ? 1e6 * global.t_g_s / static_cast<double>(global.sigma_e) : 0.0;

  const double resolutions[3] = {0.10, 0.05, 0.02};
  double octo_ms[3] = {0, 0, 0};
  if (!args.no_octomap) {
    ProgressBar progress("octomap", 3 * decoded.size());
    for (int r = 0; r < 3; ++r) {
      octomap::OcTree tree(resolutions[r]);
      std::vector<double> ms;
      for (std::size_t i = 0; i < decoded.size(); ++i) {
        const octomap::Pointcloud cloud = worldCloud(decoded[i], cam, args.local_map.depth_range);
        const Eigen::Vector3d c = decoded[i].T_W_C.translation();
        const octomap::point3d origin(c.x(), c.y(), c.z());
        ms.push_back(timeMs([&] { tree.insertPointCloud(cloud, origin); }));
        progress.update(r * decoded.size() + i + 1);
      }
      octo_ms[r] = median(ms);
    }
  }

  const double vd = median(vd_ms);
  const auto ratio = [vd](double o) { return vd > 0 ? o / vd : 0.0; };
  if (args.json) {
    nlohmann::json out = {
        {"frames", decoded.size()},
        {"vd_update_ms", vd},
        {"octomap_010_ms", octo_ms[0]},
        {"octomap_005_ms", octo_ms[1]},
        {"octomap_002_ms", octo_ms[2]},
        {"ratio_octomap_010", ratio(octo_ms[0])},
        {"ratio_octomap_005", ratio(octo_ms[1])},
        {"ratio_octomap_002", ratio(octo_ms[2])},
        {"vd_update_ms_max", vd_ms.empty() ? 0.0 : *std::max_element(vd_ms.begin(), vd_ms.end())},
        {"cell_size_px", args.local_map.cell_size_px},
        {"keyframe_every", args.keyframe_every},
        {"ellipsoids", cells},
        {"bytes_per_ellipsoid", sizeof(StoredCell)},
        {"container_bytes", bytes},
        {"vd_pipeline_ms", median(pipeline_ms)},
        {"pipeline_stage_ms", {{"features", median(features_ms)}, {"decision", median(decision_ms)},
                               {"update", median(update_ms)}}},
        {"ratio_octomap_010_pipeline", median(pipeline_ms) > 0 ? octo_ms[0] / median(pipeline_ms) : 0.0},
        {"keyframes", mapper.graph().size()},
        {"revisits", mapper.revisits()},
        {"sigma_e", global.sigma_e},
        {"sigma_e_prime", global.sigma_e_prime},
        {"t_g_s", global.t_g_s},
        {"t_g_us_per_ellipsoid", t_g_us},
    };
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::printf("frames          %zu (%dx%d), keyframe every %d, cell %d px\n", decoded.size(),
              cam.width, cam.height, args.keyframe_every, args.local_map.cell_size_px);
  std::printf("vdmap update    %8.3f ms/frame (median)\n", vd);
  std::printf("vdmap pipeline  %8.3f ms/frame (median): features %.2f, decision %.2f, update %.2f\n",
              median(pipeline_ms), median(features_ms), median(decision_ms), median(update_ms));
  std::printf("global map      %zu keyframes, Sigma_e %zu -> Sigma_e' %zu in %.3f s (%.2f us per ellipsoid)\n",
              mapper.graph().size(), global.sigma_e, global.sigma_e_prime, global.t_g_s, t_g_us);
  if (!args.no_octomap)
    for (int r = 0; r < 3; ++r)
      std::printf("OctoMap %.2f m  %8.2f ms/frame (median)  = %6.1fx vdmap\n", resolutions[r],
                  octo_ms[r], ratio(octo_ms[r]));
  std::printf("ellipsoids      %zu in %.1f MB (%zu B per ellipsoid + 4 B per grid cell)\n", cells,
              bytes / 1e6, sizeof(StoredCell));
}

}  // namespace

void addBenchCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("bench", "Time the local-map update against OctoMap on the same frames");
  auto args = std::make_shared<BenchArgs>();
  addSequenceArgs(*verb, args->sequence);
  verb->get_option("--frames")->description(
      "frames A:B of the depth list; a plain N means 0:N (default 0:30). Frames are held decoded "
      "in memory, ~1.5 MB each at 640x480");
  verb->add_option("--keyframe-every", args->keyframe_every, "every N-th frame starts a keyframe")
      ->capture_default_str();
  verb->add_option("--cell-size", args->local_map.cell_size_px, "container cell size, px")
      ->capture_default_str();
  verb->add_flag("--no-octomap", args->no_octomap, "time vdmap only (for profiling)");
  verb->add_flag("--json", args->json, "print JSON instead of text");
  verb->callback([args] { runBench(*args); });
}

}  // namespace vdmap::app
