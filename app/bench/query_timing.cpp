#include "app/bench/query_timing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>
#include <octomap/OcTree.h>
#include <opencv2/core.hpp>

#include "app/bench/bench_report.h"
#include "app/bench/octomap_timing.h"
#include "app/bench/query_detail.h"
#include "app/bench/query_heldout.h"
#include "app/bench/vdmap_timing.h"
#include "app/view/progress.h"
#include "mapping/core/box_tree.h"
#include "mapping/core/timing.h"
#include "mapping/eval/mesh_accuracy.h"
#include "mapping/eval/occupancy_truth.h"
#include "mapping/files/map_export.h"
#include "mapping/query/query_map.h"

namespace vdmap::app {
namespace {

constexpr int kPasses = 3;                     // every speed figure is the median of this many passes
constexpr std::uint32_t kSeed = 36;            // the speed points' draw
constexpr std::size_t kHeldOutPerFrame = 200;  // pixels of each frame's own depth (query_heldout.h)
constexpr std::size_t kOctoViews = 3;          // OctoMap's per-pixel castRay costs seconds a view: the first 3 views

// One OctoMap peer: the tree, and for its distance a BoxTree over its occupied leaves' boxes
// (the exact distance to the nearest occupied leaf).
struct OctoPeer {
  double res_m;
  octomap::OcTree tree;
  std::vector<double> insert_ms;
  std::vector<Eigen::Vector3f> lo, hi;
  std::unique_ptr<BoxTree> boxes;

  explicit OctoPeer(double res) : res_m(res), tree(res) {}

  std::string name() const {
    char buf[32];
    std::snprintf(buf, sizeof buf, "OctoMap %.2f m", res_m);
    return buf;
  }
  std::string key() const { return res_m > 0.03 ? "octomap_005" : "octomap_002"; }
  /// The box tree over the occupied leaves that its distance needs beside the tree.
  std::size_t distanceIndexBytes() const {
    return (lo.capacity() + hi.capacity()) * sizeof(Eigen::Vector3f) + (boxes ? boxes->memoryBytes() : 0);
  }

  void indexOccupied() {
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
      if (!tree.isNodeOccupied(*it)) continue;
      const Eigen::Vector3f c(it.getX(), it.getY(), it.getZ());
      const Eigen::Vector3f h = Eigen::Vector3f::Constant(static_cast<float>(it.getSize() / 2));
      lo.push_back(c - h);
      hi.push_back(c + h);
    }
    boxes = std::make_unique<BoxTree>(lo, hi);
  }

  Occupancy state(const Eigen::Vector3d& p) const {
    const octomap::OcTreeNode* node = tree.search(p.x(), p.y(), p.z());
    if (!node) return Occupancy::kUnknown;
    return tree.isNodeOccupied(node) ? Occupancy::kOccupied : Occupancy::kFree;
  }

  double distance(const Eigen::Vector3d& p) const {
    const auto sq = [&](std::uint32_t i, const Eigen::Vector3d& q) {
      return (lo[i].cast<double>() - q).cwiseMax(q - hi[i].cast<double>()).cwiseMax(0.0).squaredNorm();
    };
    return std::sqrt(boxes->nearest(p, sq).second);
  }
};

// Everything the frames built: vdmap's map and queries, the OctoMaps, the truth's exact frames.
struct Maps {
  std::size_t frames = 0, octomap_frames = 0;
  int octomap_every = 1;
  double max_depth_m = 0;
  std::unique_ptr<Mapper> mapper;
  GlobalMap global;
  QueryMap query;
  double query_build_ms = 0;
  std::vector<std::unique_ptr<OctoPeer>> peers;
  std::optional<OccupancyTruth> truth;
  HeldOutPoints held_out;
};

Maps buildMaps(const BenchArgs& args) {
  const Sequence seq = openSequence(args.sequence);
  noteCameraGuess(seq, "bench");
  std::optional<Sequence> exact;
  if (!args.truth.empty()) {
    SequenceArgs truth_args = args.sequence;
    truth_args.folder = args.truth;
    exact = openSequence(truth_args);
    if (exact->size() != seq.size() || !(exact->camera() == seq.camera()))
      throw std::invalid_argument("--truth: " + args.truth + ": expected the same frames and camera as " +
                                  args.sequence.folder + " (" + std::to_string(seq.size()) + " frames), found " +
                                  std::to_string(exact->size()));
  }
  const PinholeCamera& cam = seq.camera();
  Maps m;
  m.frames = seq.size();
  m.octomap_every = args.octomap_every > 0 ? args.octomap_every : static_cast<int>((m.frames + 499) / 500);
  MapperParams params = pipelineParams(args);
  params.poses = PoseSource::kGroundTruth;
  m.mapper = std::make_unique<Mapper>(cam, params);
  if (!args.no_octomap)
    for (const double res : {0.05, 0.02}) m.peers.push_back(std::make_unique<OctoPeer>(res));
  OccupancyTruthParams truth_params;
  truth_params.occupied = truth_params.free = truth_params.unknown = args.truth_points;
  truth_params.free_near = args.truth_points / 2;
  if (exact) m.truth.emplace(cam, truth_params);
  const DepthRange& range = args.local_map.depth_range;
  ProgressBar progress("mapping", m.frames);
  for (std::size_t i = 0; i < m.frames; ++i) {
    const RgbdFrame frame = seq.load(i);
    double lo = 0, hi = 0;
    cv::minMaxLoc(frame.depth, &lo, &hi);
    m.max_depth_m = std::max(m.max_depth_m, std::min(hi / cam.depth_scale, range.max_m));
    if (!m.peers.empty() && i % static_cast<std::size_t>(m.octomap_every) == 0) {
      const octomap::Pointcloud cloud = worldCloud(frame, cam, range);
      const Eigen::Vector3d c = frame.T_W_C.translation();
      for (auto& peer : m.peers)
        peer->insert_ms.push_back(
            cpuTimeMs([&] { peer->tree.insertPointCloud(cloud, octomap::point3d(c.x(), c.y(), c.z())); }));
      ++m.octomap_frames;
    }
    addHeldOut(frame, cam, range.min_m, range.max_m, i, kHeldOutPerFrame, &m.held_out);
    m.mapper->addFrame(frame);
    if (exact) {
      const RgbdFrame e = exact->load(i);
      m.truth->addFrame(e.depth, e.T_W_C);
    }
    progress.update(i + 1);
  }
  m.global = buildGlobalMap(m.mapper->graph(), {});
  QueryParams qp;
  qp.threads = 1;
  m.query_build_ms = medianCpuTimeMs(kPasses, [&] { m.query = QueryMap::build(m.mapper->graph(), m.global, qp); });
  for (auto& peer : m.peers) peer->indexOccupied();
  return m;
}

// Half uniform in the seen box, half at global ellipsoid means + N(0, 2 cm) (seeded).
std::vector<Eigen::Vector3d> speedPoints(const Maps& m, std::size_t n) {
  std::mt19937_64 rng(kSeed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> jitter(0.0, 0.02);
  Eigen::Vector3d lo, hi;
  m.query.seenBounds(&lo, &hi);
  const auto& ell = m.global.ellipsoids;
  std::vector<Eigen::Vector3d> points;
  points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d p;
    if ((i % 2 == 0 || ell.empty()) && (lo.array() <= hi.array()).all()) {
      for (int k = 0; k < 3; ++k) p[k] = lo[k] + unit(rng) * (hi[k] - lo[k]);
    } else if (!ell.empty()) {
      p = ell[std::min(ell.size() - 1, static_cast<std::size_t>(unit(rng) * ell.size()))].mean;
      for (int k = 0; k < 3; ++k) p[k] += jitter(rng);
    } else {
      p.setZero();
    }
    points.push_back(p);
  }
  return points;
}

// The poses castView is timed from: `views` keyframes spread evenly over the map.
std::vector<Transform> viewPoses(const KeyframeGraph& graph, int views) {
  std::vector<Transform> poses;
  const std::size_t k = graph.size();
  const std::size_t v = std::min<std::size_t>(static_cast<std::size_t>(views), k);
  for (std::size_t i = 0; i < v; ++i) poses.push_back(graph.keyframe(static_cast<int>(i * k / v)).T_W_K);
  return poses;
}

// OctoMap's view: castRay (unknown cells ignored) through every pixel centre; returns the hits.
std::size_t octoView(const OctoPeer& peer, const PinholeCamera& cam, const Transform& T_W_C, double max_range) {
  const Eigen::Vector3d o = T_W_C.translation();
  const octomap::point3d origin(o.x(), o.y(), o.z());
  std::size_t hits = 0;
  octomap::point3d end;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d = T_W_C.linear() * cam.backProject(u, v, 1.0);
      hits += peer.tree.castRay(origin, octomap::point3d(d.x(), d.y(), d.z()), end, true, max_range);
    }
  return hits;
}

struct Speed {
  std::size_t points = 0, distance_points = 0, views = 0, octo_views = 0;
  double classify_ms = 0, distance_ms = 0, view_ms = 0;
  std::vector<double> octo_classify_ms, octo_distance_ms, octo_view_ms;
  nlohmann::json detail;  // vdmap alone (query_detail.h)
  std::string detail_text;
};

Speed timeQueries(const Maps& m, const BenchArgs& args, const PinholeCamera& cam) {
  Speed s;
  const std::vector<Eigen::Vector3d> points = speedPoints(m, args.query_points);
  s.points = points.size();
  std::vector<Classification> cls(points.size());
  s.classify_ms = medianCpuTimeMs(kPasses, [&] { m.query.classify(points, cls); });
  const std::span<const Eigen::Vector3d> near(points.data(), std::max<std::size_t>(1, points.size() / 10));
  s.distance_points = near.size();
  std::vector<DistanceResult> dist(near.size());
  s.distance_ms = medianCpuTimeMs(kPasses, [&] { m.query.distance(near, dist); });
  const std::vector<Transform> poses = viewPoses(m.mapper->graph(), args.views);
  s.views = poses.size();
  if (!poses.empty())
    s.view_ms = medianCpuTimeMs(kPasses,
                                [&] {
                                  for (const Transform& T : poses) (void)m.query.castView(cam, T, m.max_depth_m);
                                }) /
                static_cast<double>(poses.size());
  std::ostringstream detail;
  s.detail = timeQueryDetail(
      {m.mapper->graph(), m.global, m.query, kPasses, points, cls, s.classify_ms, near, cam, poses, m.max_depth_m},
      &detail);
  s.detail_text = detail.str();
  s.octo_views = std::min(kOctoViews, poses.size());
  for (const auto& peer : m.peers) {
    std::vector<std::uint8_t> states(points.size());
    s.octo_classify_ms.push_back(medianCpuTimeMs(kPasses, [&] {
      for (std::size_t i = 0; i < points.size(); ++i) states[i] = static_cast<std::uint8_t>(peer->state(points[i]));
    }));
    std::vector<double> d(near.size());
    s.octo_distance_ms.push_back(medianCpuTimeMs(kPasses, [&] {
      for (std::size_t i = 0; i < near.size(); ++i) d[i] = peer->distance(near[i]);
    }));
    std::vector<double> view_ms;
    ProgressBar progress(peer->name() + " views", s.octo_views);
    for (std::size_t i = 0; i < s.octo_views; ++i) {
      view_ms.push_back(cpuTimeMs([&] { (void)octoView(*peer, cam, poses[i], m.max_depth_m); }));
      progress.update(i + 1);
    }
    s.octo_view_ms.push_back(median(view_ms));  // 0 without views
  }
  return s;
}

// One method's answers on the truth sets.
struct Accuracy {
  std::string name, key;
  OccupancyShares o, f, f_near, u;  // each set's shares classified occupied / free / unknown
  double balanced = 0;
  double dist_median_mm = 0, dist_p95_mm = 0, over_1cm = 0;  // |error| and share over-estimated by > 1 cm
  double memory_mb = 0;
};

using Classifier = std::function<std::vector<Occupancy>(const std::vector<Eigen::Vector3d>&)>;
using Distancer = std::function<std::vector<double>(const std::vector<Eigen::Vector3d>&)>;

OccupancyShares shares(const std::vector<Occupancy>& states) {
  OccupancyShares s;
  for (const Occupancy o : states) s.add(o);
  return s;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

Accuracy score(const OccupancyTruthSets& sets, const Classifier& classify, const Distancer& distance) {
  Accuracy a;
  a.o = shares(classify(sets.occupied));
  a.f = shares(classify(sets.free));
  a.f_near = shares(classify(sets.free_near));
  a.u = shares(classify(sets.unknown));
  a.balanced = (a.o.occupied() + a.f.free() + a.u.unknown()) / 3.0;
  std::vector<Eigen::Vector3d> pts = sets.free;
  pts.insert(pts.end(), sets.free_near.begin(), sets.free_near.end());
  // Truth: the distance to the part of the mesh the frames saw (what a map of them can know).
  std::vector<double> truth = sets.free_seen_distance_m;
  truth.insert(truth.end(), sets.free_near_seen_distance_m.begin(), sets.free_near_seen_distance_m.end());
  const std::vector<double> d = distance(pts);
  std::vector<double> err;
  std::size_t over = 0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    err.push_back(std::abs(d[i] - truth[i]));
    over += d[i] > truth[i] + 0.01;
  }
  a.dist_median_mm = 1e3 * quantile(err, 0.5);
  a.dist_p95_mm = 1e3 * quantile(err, 0.95);
  a.over_1cm = d.empty() ? 0.0 : static_cast<double>(over) / static_cast<double>(d.size());
  return a;
}

std::vector<Accuracy> scoreMaps(const Maps& m, const OccupancyTruthSets& sets, std::size_t kept_bytes) {
  std::vector<Accuracy> rows;
  {
    const Classifier classify = [&](const std::vector<Eigen::Vector3d>& p) {
      std::vector<Classification> c(p.size());
      m.query.classify(p, c);
      std::vector<Occupancy> out;
      for (const Classification& x : c) out.push_back(x.state);
      return out;
    };
    const Distancer distance = [&](const std::vector<Eigen::Vector3d>& p) {
      std::vector<DistanceResult> r(p.size());
      m.query.distance(p, r);
      std::vector<double> out;
      for (const DistanceResult& x : r) out.push_back(x.distance_m);
      return out;
    };
    Accuracy a = score(sets, classify, distance);
    a.name = "vdmap " + std::to_string(m.mapper->params().local_map.cell_size_px) + " px";
    a.key = "vdmap";
    a.memory_mb = static_cast<double>(m.query.memoryBytes() + kept_bytes) / (1024.0 * 1024.0);
    rows.push_back(a);
  }
  for (const auto& peer : m.peers) {
    const Classifier classify = [&](const std::vector<Eigen::Vector3d>& p) {
      std::vector<Occupancy> out;
      for (const Eigen::Vector3d& x : p) out.push_back(peer->state(x));
      return out;
    };
    const Distancer distance = [&](const std::vector<Eigen::Vector3d>& p) {
      std::vector<double> out;
      for (const Eigen::Vector3d& x : p) out.push_back(peer->distance(x));
      return out;
    };
    Accuracy a = score(sets, classify, distance);
    a.name = peer->name();
    a.key = peer->key();
    a.memory_mb = static_cast<double>(peer->tree.memoryUsage()) / (1024.0 * 1024.0);
    rows.push_back(a);
  }
  return rows;
}

// Bytes of the local maps' cells the global map kept (what a QueryMap is rebuilt from).
std::size_t keptCellBytes(const GlobalMap& global) {
  std::size_t cells = 0;
  for (const auto& kept : global.kept) cells += static_cast<std::size_t>(std::count(kept.begin(), kept.end(), true));
  return cells * sizeof(StoredCell);
}

// The speed table: vdmap and each OctoMap peer, and the peers' ratios to vdmap.
nlohmann::json reportSpeed(const Maps& m, const Speed& s, std::size_t kept_bytes, std::ostringstream& text) {
  char buf[512];
  std::snprintf(buf, sizeof buf, "%-16s %14s %10s %14s %10s %12s %10s %12s %10s\n", "method", "classify [/s]",
                "x vdmap", "distance [/s]", "x vdmap", "view [ms]", "x vdmap", "memory [MB]", "x vdmap");
  text << buf;
  const auto ratio = [](double a, double b) { return b > 0 ? a / b : 0.0; };  // 0: not timed
  const auto perSec = [](std::size_t n, double ms) { return ms > 0 ? 1e3 * static_cast<double>(n) / ms : 0.0; };
  const auto mb = [](std::size_t bytes) { return static_cast<double>(bytes) / (1024.0 * 1024.0); };
  const std::size_t vdmap_bytes = m.query.memoryBytes();
  std::snprintf(buf, sizeof buf, "%-16s %14.0f %10s %14.0f %10s %12.2f %10s %12.1f %10s\n", "vdmap",
                perSec(s.points, s.classify_ms), "1", perSec(s.distance_points, s.distance_ms), "1", s.view_ms, "1",
                mb(vdmap_bytes), "1");
  text << buf;
  nlohmann::json speed = {{"points", s.points},
                          {"distance_points", s.distance_points},
                          {"views", s.views},
                          {"octomap_views", s.octo_views},
                          {"view_max_range_m", rounded(m.max_depth_m)},
                          {"vdmap",
                           {{"classify_ms", rounded(s.classify_ms)},
                            {"classify_per_s", rounded(perSec(s.points, s.classify_ms))},
                            {"distance_ms", rounded(s.distance_ms)},
                            {"distance_per_s", rounded(perSec(s.distance_points, s.distance_ms))},
                            {"view_ms", rounded(s.view_ms)},
                            {"memory_bytes", vdmap_bytes},
                            {"kept_cell_bytes", kept_bytes}}}};
  for (std::size_t p = 0; p < m.peers.size(); ++p) {
    const double c = s.octo_classify_ms[p], d = s.octo_distance_ms[p], v = s.octo_view_ms[p];
    const std::size_t bytes = m.peers[p]->tree.memoryUsage();
    std::snprintf(buf, sizeof buf, "%-16s %14.0f %10.2f %14.0f %10.2f %12.2f %10.2f %12.1f %10.2f\n",
                  m.peers[p]->name().c_str(), perSec(s.points, c), ratio(c, s.classify_ms),
                  perSec(s.distance_points, d), ratio(d, s.distance_ms), v, ratio(v, s.view_ms), mb(bytes),
                  ratio(static_cast<double>(bytes), static_cast<double>(vdmap_bytes)));
    text << buf;
    speed[m.peers[p]->key()] = {
        {"classify_ms", rounded(c)},
        {"classify_per_s", rounded(perSec(s.points, c))},
        {"classify_ratio_to_vdmap", rounded(ratio(c, s.classify_ms))},
        {"distance_ms", rounded(d)},
        {"distance_ratio_to_vdmap", rounded(ratio(d, s.distance_ms))},
        {"view_ms", rounded(v)},
        {"view_ratio_to_vdmap", rounded(ratio(v, s.view_ms))},
        {"insert_ms_median", rounded(median(m.peers[p]->insert_ms))},
        {"memory_bytes", bytes},
        {"memory_ratio_to_vdmap", rounded(ratio(static_cast<double>(bytes), static_cast<double>(vdmap_bytes)))},
        {"distance_index_bytes", m.peers[p]->distanceIndexBytes()}};
  }
  std::snprintf(buf, sizeof buf,
                "(x vdmap: the peer's time or memory over vdmap's; OctoMap's distance is to the nearest occupied "
                "leaf's box through a BoxTree; memory: QueryMap::memoryBytes, without the %.1f MB of kept local-map "
                "cells it is built from, and OctoMap's memoryUsage, without its distance's BoxTree)\n",
                mb(kept_bytes));
  text << buf;
  return speed;
}

// The accuracy table against the exact frames' occupancy truth.
nlohmann::json reportAccuracy(const Maps& m, const ColoredTriangleMesh& mesh, const BenchArgs& args,
                              std::size_t kept_bytes, const HeldOutDiagnostics& diagnostics, std::ostringstream& text) {
  char buf[512];
  ProgressBar progress("truth", 1);
  const OccupancyTruthSets sets = m.truth->sample(mesh);
  progress.update(1);
  const std::vector<Accuracy> rows = scoreMaps(m, sets, kept_bytes);
  const nlohmann::json misses =
      reportSurfaceMisses(sets.occupied, "O", m.mapper->graph(), m.global, m.query, diagnostics, &text);
  std::snprintf(buf, sizeof buf,
                "\naccuracy against %s and %zu exact frames: O %zu, F %zu, F_near %zu, U %zu points (%zu O candidates "
                "seen free by a grazing view left out); distance on F + F_near to the seen %zu of %zu triangles\n",
                args.mesh.c_str(), m.truth->frames(), sets.occupied.size(), sets.free.size(), sets.free_near.size(),
                sets.unknown.size(), sets.ambiguous_occupied, sets.seen_triangles, mesh.triangles.size());
  text << buf;
  std::snprintf(buf, sizeof buf, "%-16s %8s %7s %7s %8s %7s %8s %9s %9s %8s %11s\n", "method", "bal.acc", "rec O",
                "rec F", "rec Fnear", "rec U", "O free", "|d| med", "|d| p95", "over 1cm", "memory [MB]");
  text << buf;
  nlohmann::json acc = {{"sets",
                         {{"occupied", sets.occupied.size()},
                          {"free", sets.free.size()},
                          {"free_near", sets.free_near.size()},
                          {"unknown", sets.unknown.size()},
                          {"ambiguous_occupied", sets.ambiguous_occupied}}},
                        {"seen_triangles", sets.seen_triangles},
                        {"truth_frames", m.truth->frames()},
                        {"vdmap_query_bytes", m.query.memoryBytes()},
                        {"vdmap_kept_cell_bytes", kept_bytes},
                        {"vdmap_O_misses", misses}};
  for (const Accuracy& a : rows) {
    std::snprintf(buf, sizeof buf, "%-16s %8.3f %7.3f %7.3f %8.3f %7.3f %8.4f %6.1f mm %6.1f mm %8.3f %11.2f\n",
                  a.name.c_str(), a.balanced, a.o.occupied(), a.f.free(), a.f_near.free(), a.u.unknown(), a.o.free(),
                  a.dist_median_mm, a.dist_p95_mm, a.over_1cm, a.memory_mb);
    text << buf;
    acc[a.key] = {{"name", a.name},
                  {"balanced_accuracy", rounded(a.balanced)},
                  {"O", a.o.json()},
                  {"F", a.f.json()},
                  {"F_near", a.f_near.json()},
                  {"U", a.u.json()},
                  {"false_free_O", rounded(a.o.free())},
                  {"distance_abs_error_median_mm", rounded(a.dist_median_mm)},
                  {"distance_abs_error_p95_mm", rounded(a.dist_p95_mm)},
                  {"distance_over_1cm", rounded(a.over_1cm)},
                  {"memory_mb", rounded(a.memory_mb)}};
  }
  text << "(rec: share of a set given its true class, O occupied, F and F_near free, U unknown; bal.acc: mean of "
          "rec O, F, U; O free: share of O called free; |d|: distance error on F + F_near; over 1cm: share "
          "over-estimated by more than 1 cm; memory: vdmap QueryMap::memoryBytes + kept cells, OctoMap "
          "memoryUsage)\n";
  return acc;
}

}  // namespace

void runQueryBench(const BenchArgs& args, const std::filesystem::path& out_dir) {
  checkExportFolder(out_dir);
  std::optional<ColoredTriangleMesh> mesh;
  if (!args.mesh.empty()) mesh = readPlyMesh(args.mesh);  // fail before any work on a bad mesh
  const Maps m = buildMaps(args);
  const PinholeCamera& cam = m.mapper->camera();
  const Speed s = timeQueries(m, args, cam);
  const std::size_t kept_bytes = keptCellBytes(m.global);

  std::ostringstream text;
  char buf[512];
  const std::string octomap = m.peers.empty() ? "no OctoMap (--no-octomap)"
                                              : "OctoMap from every " + std::to_string(m.octomap_every) + ". frame (" +
                                                    std::to_string(m.octomap_frames) + " frames)";
  std::snprintf(buf, sizeof buf,
                "query bench: %zu frames of %s, %zu keyframes (gt poses, cell %d px), %zu global ellipsoids; %s; "
                "QueryMap built in %.0f ms (one thread, median of %d)\n",
                m.frames, args.sequence.folder.c_str(), m.mapper->graph().size(),
                m.mapper->params().local_map.cell_size_px, m.global.ellipsoids.size(), octomap.c_str(),
                m.query_build_ms, kPasses);
  text << buf;
  std::snprintf(buf, sizeof buf,
                "speed: one thread, process CPU, median of %d passes; classify %zu points, distance %zu, views %dx%d "
                "to %.2f m%s\n",
                kPasses, s.points, s.distance_points, cam.width, cam.height, m.max_depth_m,
                m.peers.empty() ? ""
                                : (" (OctoMap: the first " + std::to_string(s.octo_views) +
                                   " views, castRay per pixel, unknown ignored)")
                                      .c_str());
  text << buf;
  nlohmann::json speed = reportSpeed(m, s, kept_bytes, text);
  text << s.detail_text;
  nlohmann::json query = {{"frames", m.frames},
                          {"keyframes", m.mapper->graph().size()},
                          {"cell_size_px", m.mapper->params().local_map.cell_size_px},
                          {"ellipsoids", m.global.ellipsoids.size()},
                          {"octomap_every", m.octomap_every},
                          {"octomap_frames", m.octomap_frames},
                          {"query_build_ms", rounded(m.query_build_ms)},
                          {"speed", speed},
                          {"vdmap", s.detail}};

  std::vector<HeldOutPeer> held_out_peers;
  for (const auto& peer : m.peers)
    held_out_peers.push_back({peer->name(), peer->key(), [&](const Eigen::Vector3d& q) { return peer->state(q); }});
  // The maps the causes of vdmap's misses are found with, for both reports.
  const HeldOutDiagnostics diagnostics(m.mapper->graph(), m.global, m.query.params());
  query["held_out"] =
      reportHeldOut(m.held_out, m.mapper->graph(), m.global, m.query, diagnostics, held_out_peers, &text);
  if (m.truth && mesh) query["accuracy"] = reportAccuracy(m, *mesh, args, kept_bytes, diagnostics, text);
  writeQueryBenchReport(query, text.str(), args, out_dir);
}

}  // namespace vdmap::app
