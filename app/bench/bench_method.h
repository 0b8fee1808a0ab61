#pragma once
// What the methods of `vdmap bench` share: the command's arguments, the frames they all run on,
// and one row of the comparison (docs/method.md 12).
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "app/bench/bench_long.h"
#include "app/cli/sequence_args.h"
#include "mapping/eval/mesh_accuracy.h"
#include "mapping/local_map/local_map_integrator.h"

namespace vdmap::app {

/// The options the renderer's and the 3-D view's timings (--ellipsoids, --view) share.
struct DrawTimingOptions {
  std::string size;                   ///< --size WxH ("": the mode's default)
  std::optional<float> points_below;  ///< --points-below PX: splats below this projected radius (nullopt: default)
  std::string png;                    ///< --png PREFIX: the last frames as PNG files ("": none)
};

/// What --view's own options set.
struct ViewTimingOptions {
  int replicate = 1;  ///< --replicate: copies of the map side by side along x (offset by its extent)
  int steps = 20;     ///< --steps: orbit steps, 0.03 rad apart as the window's --measure-orbit
  float zoom = 1.f;   ///< --zoom: the orbit's distance over the framed one (< 1: inside the map)
  std::vector<std::size_t> fast_budgets;  ///< --fast-budget: fast-pass sizes K (empty: 50k, 100k, 200k, 400k)
};

/// The options of `vdmap bench`.
struct BenchArgs {
  SequenceArgs sequence;
  int keyframe_every = 10;
  LocalMapParams local_map;
  std::string mesh;
  std::vector<int> accuracy_cell_sizes;
  std::string out = ".";
  bool json = false;
  bool no_octomap = false;
  bool no_open3d = false;
  std::string poses = "gt";
  bool long_run = false;
  LongRunOptions long_options;
  std::size_t completion_samples = AccuracyParams{}.completion_samples;
  bool surfaces = false;  ///< --surfaces: the surface meshes (app/bench/surface_timing.h)
  // --query: the point queries against OctoMap and ground truth (app/bench/query_timing.h)
  bool query = false;
  std::string truth;                     ///< the same poses rendered without noise (--truth)
  std::size_t query_points = 1'000'000;  ///< points classified per pass
  int octomap_every = 0;                 ///< frames between OctoMap insertions (0: ceil(frames / 500))
  int views = 10;                        ///< castView poses
  std::size_t truth_points = 100'000;    ///< O, F and U points each (F_near: half as many)
  // --ellipsoids: the ellipsoid renderer alone (app/bench/ellipsoid_timing.h)
  int ellipsoids = 0;
  std::optional<int> sphere_level;
  // --view: the 3-D view's frame times on a saved session or map (app/bench/view_timing.h)
  bool view = false;
  ViewTimingOptions view_options;
  DrawTimingOptions draw;  ///< --ellipsoids and --view
  // --suite: a render suite's speed (app/bench/suite_timing.h)
  std::string suite;
  int runs = 3;
};

/// One row of the comparison.
struct MethodResult {
  std::string name;  ///< e.g. "OctoMap 0.05 m"
  std::string key;   ///< JSON prefix, e.g. "octomap_005"
  double ms = 0.0;   ///< median update time per frame
  std::size_t elements = 0;
  std::optional<AccuracyReport> accuracy;
  std::string note;  ///< why a peer did not run

  MethodResult(std::string n, std::string k, double t = 0.0, std::string why = "")
      : name(std::move(n)), key(std::move(k)), ms(t), note(std::move(why)) {}
};

/// The row of a peer at a resolution: "OctoMap 0.05 m" and "octomap_005" for name "OctoMap",
/// key "octomap" and 0.05 m; `note` says why it did not run (empty: it ran).
MethodResult peerRow(const std::string& name, const std::string& key, double res_m, const std::string& note = "");

/// What every method runs on: the decoded frames (poses in the world frame), their camera and
/// the arguments, and the reference mesh (null: no accuracy). Borrowed, not owned.
struct BenchInput {
  const std::vector<RgbdFrame>& frames;
  const PinholeCamera& cam;
  const BenchArgs& args;
  const ColoredTriangleMesh* mesh;

  /// Sets r->elements to the number of a method's map points (world frame) and, with a mesh,
  /// r->accuracy to their accuracy against it.
  void score(MethodResult* r, const std::vector<Eigen::Vector3f>& points) const;
};

}  // namespace vdmap::app
