#include "app/bench/query_heldout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <Eigen/Eigenvalues>

#include "app/bench/bench_report.h"
#include "mapping/local_map/ellipsoid_filter.h"
#include "mapping/local_map/sensor_model.h"

namespace vdmap::app {
namespace {

/// Why a surface point is not in a global gate: the first stage that does not hold it.
enum Cause {
  kLostInMerge,
  kLostInOcclusion,
  kLostInFusion,
  kFilteredCell,
  kOutsideGate,
  kNoCell,
  kNoKeyframe,
  kCauses
};
const char* const kCauseName[kCauses] = {"in a kept local cell's gate, not in a merged ellipsoid's",
                                         "in a merged ellipsoid's gate, removed as an occluder",
                                         "in the gate of an ellipsoid fused away",
                                         "only in a filtered cell's gate",
                                         "outside the gate of its pixel's cell",
                                         "no cell at its pixel in any keyframe",
                                         "outside every keyframe's container"};
const char* const kCauseKey[kCauses] = {
    "lost_in_merge", "lost_in_occlusion_removal", "lost_in_fusion", "filtered_cell", "outside_gate", "no_cell",
    "no_keyframe"};

// The filtered cell (of any keyframe) at q's pixel whose gate holds q: its incidence angle (deg,
// smallest-eigenvalue axis against the ray to its mean) and sqrt(lambda_max / lambda_max expected).
bool filteredCellShape(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& qp,
                       const Eigen::Vector3d& q_W, double* theta, double* ratio) {
  for (std::size_t id = 0; id < graph.size(); ++id) {
    const Keyframe& kf = graph.keyframe(static_cast<int>(id));
    const Eigen::Vector3d q = kf.T_W_K.inverse() * q_W;
    if (!(q.z() > 0)) continue;
    const PinholeCamera& cam = kf.container.camera();
    const int g = kf.container.gridIndexOfPixel(cam.fx * q.x() / q.z() + cam.cx, cam.fy * q.y() / q.z() + cam.cy);
    if (g < 0) continue;
    const StoredCell* cell = kf.container.find(g);
    if (!cell || cell->n < static_cast<std::uint32_t>(FilterParams{}.min_points)) continue;
    const std::size_t index = static_cast<std::size_t>(cell - kf.container.cells().data());
    if (global.kept[id][index]) continue;
    const CellStats st = cell->toStats();
    const Eigen::Matrix3d cov = st.covariance();
    const Eigen::Matrix3d A = (cov + qp.min_sigma_m * qp.min_sigma_m * Eigen::Matrix3d::Identity()).inverse();
    if ((q - st.mean).dot(A * (q - st.mean)) > qp.gate_sigma * qp.gate_sigma) continue;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
    const Eigen::Vector2d uv = cam.project(st.mean);
    const Eigen::Matrix3d expected =
        expectedCellCovariance(FilterParams{}.model, cam, uv.x(), uv.y(), st.mean.z(), kf.container.cellSizePx());
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> ee(expected);
    *theta = std::acos(std::min(1.0, std::abs(es.eigenvectors().col(0).dot(st.mean.normalized())))) * 180 / M_PI;
    *ratio = std::sqrt(es.eigenvalues()(2) / ee.eigenvalues()(2));
    return true;
  }
  return false;
}

// `global` with every cell of two or more points kept: what the map would hold without the filter.
GlobalMap everyCell(const KeyframeGraph& graph, const GlobalMap& global) {
  GlobalMap every = global;
  for (std::size_t id = 0; id < graph.size(); ++id) {
    const auto& cells = graph.keyframe(static_cast<int>(id)).container.cells();
    for (std::size_t i = 0; i < cells.size(); ++i) every.kept[id][i] = cells[i].n >= 2;
  }
  return every;
}

// `global` with the cells of too few points for the filter kept too.
GlobalMap withFewPointCells(const KeyframeGraph& graph, const GlobalMap& global) {
  GlobalMap many = global;
  for (std::size_t id = 0; id < graph.size(); ++id) {
    const auto& cells = graph.keyframe(static_cast<int>(id)).container.cells();
    for (std::size_t i = 0; i < cells.size(); ++i)
      many.kept[id][i] = many.kept[id][i] || (cells[i].n >= 2 && cells[i].n < FilterParams{}.min_points);
  }
  return many;
}

// The default thresholds with fusion across groups and occlusion removal on or off.
GlobalMapParams withStages(bool fusion, bool occlusion_removal) {
  GlobalMapParams params;
  params.fuse_across_groups = fusion;
  params.occlusion_removal = occlusion_removal;
  return params;
}

bool anyOccupied(const QueryMap& views, std::size_t keyframes, const Eigen::Vector3d& q) {
  for (std::size_t id = 0; id < keyframes; ++id)
    if (views.keyframeVerdict(static_cast<int>(id), q).state == Occupancy::kOccupied) return true;
  return false;
}

}  // namespace

void OccupancyShares::add(Occupancy s) {
  ++points;
  n_occupied += s == Occupancy::kOccupied, n_free += s == Occupancy::kFree, n_unknown += s == Occupancy::kUnknown;
}

nlohmann::json OccupancyShares::json() const {
  return {{"occupied", rounded(occupied())}, {"free", rounded(free())}, {"unknown", rounded(unknown())}};
}

HeldOutDiagnostics::HeldOutDiagnostics(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& qp)
    : all(QueryMap::build(graph, everyCell(graph, global), qp)),
      few(QueryMap::build(graph, withFewPointCells(graph, global), qp)),
      unfused(QueryMap::build(graph, buildGlobalMap(graph, withStages(false, true)), qp)),
      merged(QueryMap::build(graph, buildGlobalMap(graph, withStages(false, false)), qp)) {}

void addHeldOut(const RgbdFrame& frame, const PinholeCamera& camera, double min_m, double max_m,
                std::size_t frame_index, std::size_t per_frame, HeldOutPoints* out) {
  std::mt19937_64 rng(0x5eedULL + frame_index);
  std::uniform_int_distribution<int> col(1, camera.width - 2), row(1, camera.height - 2);
  const auto depth = [&](int u, int v) { return frame.depth.at<std::uint16_t>(v, u) / camera.depth_scale; };
  std::size_t added = 0;
  for (std::size_t tries = 0; added < per_frame && tries < 20 * per_frame; ++tries) {
    const int u = col(rng), v = row(rng);
    const double d = depth(u, v);
    if (!(d >= min_m && d <= max_m)) continue;
    bool edge = false;
    for (int dv = -1; dv <= 1; ++dv)
      for (int du = -1; du <= 1; ++du) edge |= !(std::abs(depth(u + du, v + dv) - d) < 0.05);
    if (edge) continue;
    const Eigen::Vector3d c = frame.T_W_C.translation();
    const Eigen::Vector3d p = frame.T_W_C * camera.backProject(u, v, d);
    const Eigen::Vector3d ray = (p - c).normalized();
    const double r = (p - c).norm();
    out->surface.push_back(p);
    out->front_2cm.push_back(p - 0.02 * ray);
    out->front_5cm.push_back(p - 0.05 * ray);
    out->half_way.push_back(c + 0.5 * r * ray);
    ++added;
  }
}

namespace {
// Why a point that should be free is unknown: over the keyframes, the best of their reasons.
nlohmann::json reportFreeUnknown(const std::vector<Eigen::Vector3d>& points, const char* what,
                                 const KeyframeGraph& graph, const QueryMap& query, const QueryMap& all,
                                 std::ostringstream* text) {
  const double k = query.params().gate_sigma;
  // 0 beside the gate, 1 within k sigma of the surface, 2 behind it, 3 filtered cell, 4 empty cell, 5 outside
  const char* const names[] = {"in front of a kept cell, the ray beside its gate",
                               "in front of a kept cell by less than k sigma",
                               "behind a kept cell's surface",
                               "a filtered cell at its pixel",
                               "no cell at its pixel",
                               "outside every container"};
  std::size_t count[6] = {}, n_unknown = 0;
  std::vector<Classification> cls(1);
  for (const Eigen::Vector3d& q : points) {
    query.classify({&q, 1}, cls);
    if (cls[0].state != Occupancy::kUnknown) continue;
    ++n_unknown;
    int best = 5;
    for (std::size_t id = 0; id < graph.size(); ++id) {
      const ViewVerdict v = query.keyframeVerdict(static_cast<int>(id), q);
      if (v.sigma_t > 0) {
        best = std::min(best, v.z < -k ? 0 : v.z < 0 ? 1 : 2);
        continue;
      }
      if (all.keyframeVerdict(static_cast<int>(id), q).sigma_t > 0) {
        best = std::min(best, 3);
        continue;
      }
      const Keyframe& kf = graph.keyframe(static_cast<int>(id));
      const Eigen::Vector3d c = kf.T_W_K.inverse() * q;
      const PinholeCamera& cam = kf.container.camera();
      if (c.z() > 0 &&
          kf.container.gridIndexOfPixel(cam.fx * c.x() / c.z() + cam.cx, cam.fy * c.y() / c.z() + cam.cy) >= 0)
        best = std::min(best, 4);
    }
    ++count[best];
  }
  char buf[256];
  std::snprintf(buf, sizeof buf, "vdmap %s points unknown: %zu of %zu; the best keyframe's reason:\n", what, n_unknown,
                points.size());
  *text << buf;
  nlohmann::json out;
  for (int i = 0; i < 6; ++i) {
    std::snprintf(buf, sizeof buf, "  %6zu  %s\n", count[i], names[i]);
    *text << buf;
    out[names[i]] = count[i];
  }
  return out;
}
}  // namespace

nlohmann::json reportHeldOut(const HeldOutPoints& points, const KeyframeGraph& graph, const GlobalMap& global,
                             const QueryMap& query, const HeldOutDiagnostics& diagnostics,
                             const std::vector<HeldOutPeer>& peers, std::ostringstream* text) {
  const std::vector<const std::vector<Eigen::Vector3d>*> sets = {&points.surface, &points.front_2cm, &points.front_5cm,
                                                                 &points.half_way};
  const char* const set_key[] = {"surface", "front_2cm", "front_5cm", "half_way"};
  nlohmann::json out;
  char buf[256];
  std::snprintf(buf, sizeof buf, "\nheld out: %zu pixels of the mapped frames' own depth\n%-16s", points.surface.size(),
                "method");
  *text << buf;
  for (const char* k : set_key) {
    std::snprintf(buf, sizeof buf, " %21s", k);
    *text << buf;
  }
  *text << "\n";
  const auto row = [&](const std::string& name, const std::string& key, const auto& classify) {
    std::snprintf(buf, sizeof buf, "%-16s", name.c_str());
    *text << buf;
    for (std::size_t s = 0; s < sets.size(); ++s) {
      OccupancyShares sh;
      for (const Eigen::Vector3d& q : *sets[s]) sh.add(classify(q));
      out[key][set_key[s]] = sh.json();
      out[key][set_key[s]]["points"] = sh.points;
      std::snprintf(buf, sizeof buf, "  o%5.1f f%5.1f u%5.1f", 100 * sh.occupied(), 100 * sh.free(),
                    100 * sh.unknown());
      *text << buf;
    }
    *text << "\n";
  };
  std::vector<Classification> cls(1);
  row("vdmap", "vdmap", [&](const Eigen::Vector3d& q) {
    query.classify({&q, 1}, cls);
    return cls[0].state;
  });
  for (const HeldOutPeer& p : peers) row(p.name, p.key, p.classify);

  out["vdmap_half_way_unknown"] = reportFreeUnknown(points.half_way, "half-way", graph, query, diagnostics.all, text);
  out["vdmap_front_5cm_unknown"] =
      reportFreeUnknown(points.front_5cm, "5 cm in front", graph, query, diagnostics.all, text);
  out["vdmap_surface_misses"] =
      reportSurfaceMisses(points.surface, "held-out surface", graph, global, query, diagnostics, text);
  return out;
}

nlohmann::json reportSurfaceMisses(const std::vector<Eigen::Vector3d>& points, const char* what,
                                   const KeyframeGraph& graph, const GlobalMap& global, const QueryMap& query,
                                   const HeldOutDiagnostics& diagnostics, std::ostringstream* text) {
  char buf[256];
  nlohmann::json out;
  std::vector<Classification> cls(1);
  // Causes of vdmap's surface points outside every global gate.
  const QueryParams qp = query.params();
  const QueryMap &all = diagnostics.all, &few = diagnostics.few, &unfused = diagnostics.unfused,
                 &merged = diagnostics.merged;
  std::size_t filtered_few = 0;
  std::size_t theta_hist[7] = {};
  std::vector<double> ratios;
  const auto occupiedIn = [&](const QueryMap& map, const Eigen::Vector3d& q) {
    map.classify({&q, 1}, cls);
    return cls[0].state == Occupancy::kOccupied;
  };
  std::size_t cause[kCauses] = {};
  std::vector<double> z_outside;
  for (const Eigen::Vector3d& q : points) {
    query.classify({&q, 1}, cls);
    if (cls[0].state == Occupancy::kOccupied) continue;
    if (anyOccupied(query, graph.size(), q)) {
      ++cause[occupiedIn(unfused, q) ? kLostInFusion : occupiedIn(merged, q) ? kLostInOcclusion : kLostInMerge];
      continue;
    }
    if (anyOccupied(all, graph.size(), q)) {
      ++cause[kFilteredCell];
      filtered_few += anyOccupied(few, graph.size(), q);
      double theta = 0, ratio = 0;
      if (filteredCellShape(graph, global, qp, q, &theta, &ratio)) {
        ++theta_hist[std::min(6, theta < 60 ? 0 : 1 + static_cast<int>((theta - 60) / 5))];
        ratios.push_back(ratio);
      }
      continue;
    }
    bool has_cell = false, in_image = false;
    double best_z = 1e300;
    for (std::size_t id = 0; id < graph.size(); ++id) {
      const ViewVerdict v = all.keyframeVerdict(static_cast<int>(id), q);
      if (v.sigma_t > 0) has_cell = true, best_z = std::min(best_z, std::abs(v.z));
      const Keyframe& kf = graph.keyframe(static_cast<int>(id));
      const Eigen::Vector3d k = kf.T_W_K.inverse() * q;
      const PinholeCamera& cam = kf.container.camera();
      if (k.z() > 0) {  // within the container's extent (twice the image, docs/method.md)
        const double u = cam.fx * k.x() / k.z() + cam.cx + kf.container.offsetU() + 0.5;
        const double v2 = cam.fy * k.y() / k.z() + cam.cy + kf.container.offsetV() + 0.5;
        in_image |= u >= 0 && v2 >= 0 && u < 2.0 * cam.width && v2 < 2.0 * cam.height;
      }
    }
    if (has_cell) {
      ++cause[kOutsideGate];
      z_outside.push_back(best_z);
    } else {
      ++cause[in_image ? kNoCell : kNoKeyframe];
    }
  }
  std::size_t missed = 0;
  for (std::size_t c = 0; c < kCauses; ++c) missed += cause[c];
  std::snprintf(buf, sizeof buf, "vdmap %s points not occupied: %zu of %zu\n", what, missed, points.size());
  *text << buf;
  for (std::size_t c = 0; c < kCauses; ++c) {
    std::snprintf(buf, sizeof buf, "  %6zu  %s\n", cause[c], kCauseName[c]);
    *text << buf;
    out[kCauseKey[c]] = cause[c];
  }
  std::snprintf(buf, sizeof buf, "  filtered: %zu in a cell of fewer than 6 points\n", filtered_few);
  *text << buf;
  std::snprintf(
      buf, sizeof buf,
      "  filtered cells' incidence: <60 %zu, 60-65 %zu, 65-70 %zu, 70-75 %zu, 75-80 %zu, 80-85 %zu, >85 %zu\n",
      theta_hist[0], theta_hist[1], theta_hist[2], theta_hist[3], theta_hist[4], theta_hist[5], theta_hist[6]);
  *text << buf;
  if (!ratios.empty()) {
    std::sort(ratios.begin(), ratios.end());
    std::snprintf(buf, sizeof buf, "  filtered cells' sigma_max / expected: median %.2f, p10 %.2f, p90 %.2f (of %zu)\n",
                  ratios[ratios.size() / 2], ratios[ratios.size() / 10], ratios[ratios.size() * 9 / 10], ratios.size());
    *text << buf;
  }
  if (!z_outside.empty()) {
    std::sort(z_outside.begin(), z_outside.end());
    std::snprintf(buf, sizeof buf, "  outside the gate: median |z| along the ray %.2f sigma, p90 %.2f\n",
                  z_outside[z_outside.size() / 2], z_outside[z_outside.size() * 9 / 10]);
    *text << buf;
  }
  return out;
}

}  // namespace vdmap::app
