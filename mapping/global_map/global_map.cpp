#include "mapping/global_map/global_map.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "mapping/core/timing.h"
#include "mapping/local_map/cell_stats.h"

namespace vdmap {
namespace {

using Clock = std::chrono::steady_clock;

// Occlusion test of SPEC 6.3: A occludes B when the ray to B passes within Mahalanobis distance 2
// of A, i.e. a squared distance of at most 4.
constexpr double kOcclusionGate2 = 4.0;
// Added to every covariance before it is inverted (m^2, a 10 um standard deviation): a flat
// surface cell has a near-zero axis and must stay invertible; real cells are far wider.
constexpr double kCovFloor_m2 = 1e-10;

Eigen::Matrix3d floored(const Eigen::Matrix3d& cov) { return cov + kCovFloor_m2 * Eigen::Matrix3d::Identity(); }

// Indices 0..keys.size()-1 grouped by key (a stable counting sort); negative keys are left out.
// Bucket b holds order[start[b] .. start[b + 1]).
struct Buckets {
  std::vector<int> start;
  std::vector<int> order;
};

Buckets bucketByKey(const std::vector<int>& keys, std::size_t buckets) {
  Buckets b;
  b.start.assign(buckets + 1, 0);
  for (int k : keys)
    if (k >= 0) ++b.start[static_cast<std::size_t>(k) + 1];
  std::partial_sum(b.start.begin(), b.start.end(), b.start.begin());
  b.order.resize(static_cast<std::size_t>(b.start.back()));
  std::vector<int> fill(b.start.begin(), b.start.end() - 1);
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (keys[i] >= 0) b.order[static_cast<std::size_t>(fill[static_cast<std::size_t>(keys[i])]++)] = static_cast<int>(i);
  return b;
}

Ellipsoid transformed(const Ellipsoid& e, const Transform& T_B_A) {
  Ellipsoid out = e;
  out.mean = T_B_A * e.mean;
  out.cov = T_B_A.linear() * e.cov * T_B_A.linear().transpose();
  return out;
}

// SPEC section 6 step 2 for one group: members' kept ellipsoids re-projected into the centre's
// container and merged cell by cell. Output order: cells ascending, then the pass-throughs.
std::vector<Ellipsoid> mergeGroup(const KeyframeGraph& graph, const MergeGroup& group, const GlobalMapParams& params,
                                  const std::vector<std::vector<bool>>& kept) {
  const Keyframe& centre = graph.keyframe(group.centre);
  const KeyframeContainer& box = centre.container;
  const Transform T_C_W = centre.T_W_K.inverse();
  std::vector<Ellipsoid> in_centre;
  std::vector<int> cell_of;
  for (int id : group.members) {
    const Keyframe& k = graph.keyframe(id);
    forEachKeptEllipsoid(k.container, kept[static_cast<std::size_t>(id)], T_C_W * k.T_W_K, id, [&](const Ellipsoid& e) {
      int cell = -1;
      if (e.mean.z() > 0.0) {
        const Eigen::Vector2d uv = box.camera().project(e.mean);
        cell = box.gridIndexOfPixel(uv.x(), uv.y());
      }
      in_centre.push_back(e);
      cell_of.push_back(cell);
    });
  }

  // By cell, stable: members in id order, cells in container order.
  const std::size_t cells = static_cast<std::size_t>(box.cols()) * box.rows();
  const Buckets by_cell = bucketByKey(cell_of, cells);
  const std::vector<int>& start = by_cell.start;
  const std::vector<int>& order = by_cell.order;

  std::vector<Ellipsoid> out;
  out.reserve(in_centre.size());
  std::vector<Eigen::Vector3d> means;
  std::vector<double> weights;
  std::vector<const Ellipsoid*> cluster;
  for (std::size_t c = 0; c < cells; ++c) {
    const int begin = start[c], end = start[c + 1];
    if (end - begin == 1) out.push_back(transformed(in_centre[static_cast<std::size_t>(order[begin])], centre.T_W_K));
    if (end - begin <= 1) continue;
    means.clear();
    weights.clear();
    for (int i = begin; i < end; ++i) {
      const Ellipsoid& e = in_centre[static_cast<std::size_t>(order[i])];
      means.push_back(e.mean);
      weights.push_back(e.count);
    }
    const std::vector<int> label = meanShiftClusters(means, weights, params.merge_distance_m);
    const int clusters = *std::max_element(label.begin(), label.end()) + 1;
    for (int k = 0; k < clusters; ++k) {
      cluster.clear();
      for (int i = begin; i < end; ++i)
        if (label[static_cast<std::size_t>(i - begin)] == k) cluster.push_back(&in_centre[static_cast<std::size_t>(order[i])]);
      Ellipsoid merged = momentMatch(cluster);
      merged.keyframe = group.centre;
      merged.grid_index = static_cast<int>(c);
      out.push_back(transformed(merged, centre.T_W_K));
    }
  }
  for (std::size_t i = 0; i < cell_of.size(); ++i)
    if (cell_of[i] < 0) out.push_back(transformed(in_centre[i], centre.T_W_K));
  return out;
}

// Runs body(i) for i in [0, n) on `threads` threads (0: all). Each i writes only its own slot,
// so the result is the same for any thread count.
template <typename Body>
void parallelFor(int threads, std::size_t n, const Body& body) {
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] { tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) { body(i); }); });
}

// SPEC 6.3: the keyframes whose ellipsoids viewpoint K judges: K, its covisibility neighbours,
// and every keyframe within occlusion_distance whose optical axis is within occlusion_angle of
// K's. Ascending ids.
std::vector<int> occlusionGroup(const KeyframeGraph& graph, const Keyframe& K, const GlobalMapParams& params) {
  // An angle of exactly occlusion_angle counts, whatever the rounding of the cosines.
  constexpr double kCosTolerance = 1e-12;
  const double cos_angle = std::cos(params.occlusion_angle_deg * M_PI / 180.0);
  std::vector<int> group = {K.id};
  for (const auto& [other, w] : graph.edges().neighbours(K.id)) group.push_back(other);
  for (const Keyframe& other : graph.keyframes()) {
    if (other.id == K.id) continue;
    if ((other.T_W_K.translation() - K.T_W_K.translation()).norm() <= params.occlusion_distance_m &&
        other.T_W_K.linear().col(2).dot(K.T_W_K.linear().col(2)) >= cos_angle - kCosTolerance)
      group.push_back(other.id);
  }
  std::sort(group.begin(), group.end());
  group.erase(std::unique(group.begin(), group.end()), group.end());
  return group;
}

// An ellipsoid as one occlusion viewpoint sees it.
struct ViewItem {
  double z;             // depth in the viewpoint's camera
  double lambda_max;    // largest eigenvalue of its covariance: smaller is more precise
  Eigen::Vector3d ray;  // mean - viewpoint centre, world frame
  int index;            // into the ellipsoids
};

// The ellipsoids of one viewpoint cell: appends to `removed` every A that occludes a more precise
// B behind it (SPEC 6.3). `cell` is reordered near to far; `finest_behind` is scratch space.
void removeOccludersInCell(std::span<ViewItem> cell, const std::vector<Eigen::Matrix3d>& information,
                           std::vector<double>* finest_behind, std::vector<int>* removed) {
  std::sort(cell.begin(), cell.end(),
            [](const ViewItem& a, const ViewItem& b) { return a.z != b.z ? a.z < b.z : a.index < b.index; });
  // finest[a]: the smallest lambda_max from a to the end of the cell.
  std::vector<double>& finest = *finest_behind;
  finest.assign(cell.size() + 1, std::numeric_limits<double>::infinity());
  for (std::size_t j = cell.size(); j-- > 0;) finest[j] = std::min(finest[j + 1], cell[j].lambda_max);
  for (std::size_t a = 0; a + 1 < cell.size(); ++a) {
    if (!(finest[a + 1] < cell[a].lambda_max)) continue;  // nothing more precise behind A
    const Eigen::Matrix3d& P = information[static_cast<std::size_t>(cell[a].index)];
    const Eigen::Vector3d& mu = cell[a].ray;
    const Eigen::Vector3d P_mu = P * mu;
    const double mu_P_mu = mu.dot(P_mu);
    for (std::size_t b = a + 1; b < cell.size(); ++b) {
      if (!(cell[b].z > cell[a].z) || !(cell[b].lambda_max < cell[a].lambda_max)) continue;
      // Squared Mahalanobis distance from A's mean to the ray t d through B, minimised over t.
      const Eigen::Vector3d d = cell[b].ray.normalized();
      const double dPd = d.dot(P * d), dPmu = d.dot(P_mu);
      if (mu_P_mu - dPmu * dPmu / dPd <= kOcclusionGate2) {
        removed->push_back(cell[a].index);
        break;
      }
    }
  }
}

}  // namespace

void GlobalMapParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!(filter.filter_sigma_factor > 0.0)) fail("filter_sigma_factor must be > 0");
  if (filter.min_points < 0) fail("min_points must be >= 0");
  if (!(tau_group >= 0.0 && tau_group <= 1.0)) fail("tau_group must be within 0..1");
  if (!(merge_distance_m >= 0.0) || !std::isfinite(merge_distance_m)) fail("merge_distance must be >= 0 m");
  if (!(occlusion_distance_m >= 0.0) || !std::isfinite(occlusion_distance_m)) fail("occlusion_distance must be >= 0 m");
  if (!(occlusion_angle_deg >= 0.0 && occlusion_angle_deg <= 180.0)) fail("occlusion_angle must be within 0..180 degrees");
  if (threads < 0) fail("threads must be >= 0");
}

std::vector<MergeGroup> mergeGroups(const KeyframeGraph& graph, double tau_group) {
  const int n = static_cast<int>(graph.size());
  std::vector<bool> assigned(static_cast<std::size_t>(n), false);
  std::vector<MergeGroup> groups;
  for (int remaining = n; remaining > 0;) {
    int centre = -1;
    double best = -1.0;
    for (int k = 0; k < n; ++k) {
      if (assigned[static_cast<std::size_t>(k)]) continue;
      double sum = 0.0;
      for (const auto& [other, w] : graph.edges().neighbours(k))
        if (!assigned[static_cast<std::size_t>(other)]) sum += w;
      if (sum > best) best = sum, centre = k;
    }
    MergeGroup group{centre, {centre}};
    assigned[static_cast<std::size_t>(centre)] = true;
    for (const auto& [other, w] : graph.edges().neighbours(centre)) {
      if (assigned[static_cast<std::size_t>(other)] || w < tau_group) continue;
      assigned[static_cast<std::size_t>(other)] = true;
      group.members.push_back(other);
    }
    std::sort(group.members.begin(), group.members.end());
    remaining -= static_cast<int>(group.members.size());
    groups.push_back(std::move(group));
  }
  return groups;
}

std::vector<int> meanShiftClusters(const std::vector<Eigen::Vector3d>& means, const std::vector<double>& weights,
                                   double h) {
  constexpr double kConverged = 1e-4;  // m (SPEC)
  constexpr int kMaxSteps = 50;
  const double h2 = h * h;
  std::vector<Eigen::Vector3d> modes;
  std::vector<int> label(means.size());
  for (std::size_t i = 0; i < means.size(); ++i) {
    Eigen::Vector3d x = means[i];
    for (int step = 0; step < kMaxSteps; ++step) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      double total = 0.0;
      for (std::size_t j = 0; j < means.size(); ++j) {
        if ((means[j] - x).squaredNorm() > h2) continue;
        sum += weights[j] * means[j];
        total += weights[j];
      }
      if (total <= 0.0) break;
      const Eigen::Vector3d next = sum / total;
      const double shift = (next - x).norm();
      x = next;
      if (shift < kConverged) break;
    }
    int k = 0;
    while (k < static_cast<int>(modes.size()) && (modes[static_cast<std::size_t>(k)] - x).norm() >= h / 2) ++k;
    if (k == static_cast<int>(modes.size())) modes.push_back(x);
    label[i] = k;
  }
  return label;
}

Ellipsoid momentMatch(const std::vector<const Ellipsoid*>& cluster) {
  // SPEC writes Sigma = sum n_i (Sigma_i + d_i d_i^T) / n with population covariances. Ellipsoids
  // carry sample covariances S_i / (n_i - 1), so the scatters are combined instead:
  // S = sum (S_i + n_i d_i d_i^T), Sigma = S / (n - 1): exactly the statistics of the union.
  CellStats u;  // the statistics of the union
  for (const Ellipsoid* e : cluster) {
    u.n += e->count;
    u.mean += e->count * e->mean;
    u.color += e->count * e->color.cast<double>();
  }
  u.mean /= u.n;
  u.color /= u.n;
  for (const Ellipsoid* e : cluster) {
    const Eigen::Vector3d d = e->mean - u.mean;
    u.scatter += (e->count > 1 ? e->count - 1.0 : 0.0) * e->cov + e->count * d * d.transpose();
  }
  Ellipsoid out = *cluster.front();
  out.mean = u.mean;
  out.cov = u.covariance();
  out.color = u.color.cast<float>();
  out.count = static_cast<std::uint32_t>(u.n);
  return out;
}

std::vector<bool> occludingEllipsoids(const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids,
                                      const GlobalMapParams& params) {
  // Ellipsoid indices and means by keyframe, contiguous, so that each viewpoint streams through
  // its group's ellipsoids instead of gathering them from the big records.
  std::vector<int> keyframe_of(ellipsoids.size());
  for (std::size_t i = 0; i < ellipsoids.size(); ++i) keyframe_of[i] = ellipsoids[i].keyframe;
  const Buckets by_keyframe = bucketByKey(keyframe_of, graph.size());
  std::vector<Eigen::Vector3d> mean_by_keyframe(ellipsoids.size());
  for (std::size_t j = 0; j < ellipsoids.size(); ++j)
    mean_by_keyframe[j] = ellipsoids[static_cast<std::size_t>(by_keyframe.order[j])].mean;
  // Per ellipsoid, once: the inverse covariance and the largest eigenvalue.
  std::vector<Eigen::Matrix3d> information(ellipsoids.size());
  std::vector<double> lambda_max(ellipsoids.size());
  parallelFor(params.threads, ellipsoids.size(), [&](std::size_t i) {
    const Eigen::Matrix3d cov = floored(ellipsoids[i].cov);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    lambda_max[i] = eig.eigenvalues()(2);
    information[i] = cov.inverse();
  });

  std::vector<std::vector<int>> removed_by(graph.size());
  parallelFor(params.threads, graph.size(), [&](std::size_t v) {
    const Keyframe& K = graph.keyframe(static_cast<int>(v));
    const Transform T_K_W = K.T_W_K.inverse();
    const Eigen::Vector3d centre = K.T_W_K.translation();
    std::vector<ViewItem> projected;
    std::vector<int> cell_of;
    for (int g : occlusionGroup(graph, K, params))
      for (int j = by_keyframe.start[static_cast<std::size_t>(g)]; j < by_keyframe.start[static_cast<std::size_t>(g) + 1]; ++j) {
        const Eigen::Vector3d& mean = mean_by_keyframe[static_cast<std::size_t>(j)];
        const Eigen::Vector3d p = T_K_W * mean;
        if (p.z() <= 0.0) continue;
        const Eigen::Vector2d uv = K.container.camera().project(p);
        const int cell = K.container.gridIndexOfPixel(uv.x(), uv.y());
        if (cell < 0) continue;
        const int i = by_keyframe.order[static_cast<std::size_t>(j)];
        projected.push_back({p.z(), lambda_max[static_cast<std::size_t>(i)], mean - centre, i});
        cell_of.push_back(cell);
      }
    const Buckets by_cell = bucketByKey(cell_of, static_cast<std::size_t>(K.container.cols()) * K.container.rows());
    std::vector<ViewItem> items(projected.size());
    for (std::size_t j = 0; j < items.size(); ++j) items[j] = projected[static_cast<std::size_t>(by_cell.order[j])];
    std::vector<double> scratch;
    for (std::size_t cell = 0; cell + 1 < by_cell.start.size(); ++cell) {
      const auto begin = items.begin() + by_cell.start[cell], end = items.begin() + by_cell.start[cell + 1];
      if (end - begin >= 2) removeOccludersInCell(std::span<ViewItem>(begin, end), information, &scratch, &removed_by[v]);
    }
  });
  std::vector<bool> removed(ellipsoids.size(), false);
  for (const std::vector<int>& list : removed_by)
    for (int i : list) removed[static_cast<std::size_t>(i)] = true;
  return removed;
}

std::vector<Ellipsoid> localEllipsoids(const KeyframeGraph& graph, const GlobalMap& map) {
  std::vector<Ellipsoid> local;
  local.reserve(map.sigma_e);
  for (const Keyframe& k : graph.keyframes())
    forEachKeptEllipsoid(k.container, map.kept.at(static_cast<std::size_t>(k.id)), k.T_W_K, k.id,
                         [&local](const Ellipsoid& e) { local.push_back(e); });
  return local;
}

GlobalMap buildGlobalMap(const KeyframeGraph& graph, const GlobalMapParams& params) {
  params.validate();
  GlobalMap map;
  const auto start = Clock::now();
  map.groups = mergeGroups(graph, params.tau_group);
  map.groups_ms = msSince(start);

  const auto merge_start = Clock::now();
  map.kept.resize(graph.size());
  parallelFor(params.threads, graph.size(),
              [&](std::size_t k) { map.kept[k] = keptCells(graph.keyframe(static_cast<int>(k)).container, params.filter); });
  for (const std::vector<bool>& kept : map.kept) map.sigma_e += static_cast<std::size_t>(std::count(kept.begin(), kept.end(), true));
  std::vector<std::vector<Ellipsoid>> merged(map.groups.size());
  parallelFor(params.threads, map.groups.size(),
              [&](std::size_t g) { merged[g] = mergeGroup(graph, map.groups[g], params, map.kept); });
  std::vector<Ellipsoid> all;
  for (const std::vector<Ellipsoid>& group : merged) all.insert(all.end(), group.begin(), group.end());
  map.merged = all.size();
  map.merge_ms = msSince(merge_start);

  const auto occlusion_start = Clock::now();
  if (params.occlusion_removal) {
    const std::vector<bool> removed = occludingEllipsoids(graph, all, params);
    for (std::size_t i = 0; i < all.size(); ++i)
      if (!removed[i]) map.ellipsoids.push_back(all[i]);
  } else {
    map.ellipsoids = std::move(all);
  }
  map.occlusion_ms = msSince(occlusion_start);
  map.sigma_e_prime = map.ellipsoids.size();
  map.t_g_s = secondsSince(start);
  return map;
}

}  // namespace vdmap
