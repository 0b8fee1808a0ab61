#include "mapping/global_map/global_map.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
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

  // Counting sort by cell (stable: members in id order, cells in container order).
  const std::size_t cells = static_cast<std::size_t>(box.cols()) * box.rows();
  std::vector<int> start(cells + 1, 0);
  for (int c : cell_of)
    if (c >= 0) ++start[static_cast<std::size_t>(c) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int> order(static_cast<std::size_t>(start.back()));
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < cell_of.size(); ++i)
      if (cell_of[i] >= 0) order[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[i])]++)] = static_cast<int>(i);
  }

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
  const std::size_t keyframes = graph.size();
  // Ellipsoid indices and means grouped by keyframe, contiguous, so that each viewpoint streams
  // through its group's ellipsoids instead of gathering them from the big records.
  std::vector<int> first(keyframes + 1, 0);
  for (const Ellipsoid& e : ellipsoids) ++first[static_cast<std::size_t>(e.keyframe) + 1];
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<int> index_by_keyframe(ellipsoids.size());
  std::vector<Eigen::Vector3d> mean_by_keyframe(ellipsoids.size());
  {
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (std::size_t i = 0; i < ellipsoids.size(); ++i) {
      const std::size_t slot = static_cast<std::size_t>(fill[static_cast<std::size_t>(ellipsoids[i].keyframe)]++);
      index_by_keyframe[slot] = static_cast<int>(i);
      mean_by_keyframe[slot] = ellipsoids[i].mean;
    }
  }
  // Per ellipsoid, once: the inverse covariance (slightly regularised so that a flat surface
  // cell stays invertible) and the largest eigenvalue.
  std::vector<Eigen::Matrix3d> information(ellipsoids.size());
  std::vector<double> lambda_max(ellipsoids.size());
  parallelFor(params.threads, ellipsoids.size(), [&](std::size_t i) {
    const Eigen::Matrix3d cov = ellipsoids[i].cov + 1e-10 * Eigen::Matrix3d::Identity();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    lambda_max[i] = eig.eigenvalues()(2);
    information[i] = cov.inverse();
  });

  const double cos_angle = std::cos(params.occlusion_angle_deg * M_PI / 180.0);
  std::vector<std::vector<int>> removed_by(keyframes);
  parallelFor(params.threads, keyframes, [&](std::size_t v) {
    const Keyframe& K = graph.keyframe(static_cast<int>(v));
    std::vector<int> group = {K.id};
    for (const auto& [other, w] : graph.edges().neighbours(K.id)) group.push_back(other);
    for (const Keyframe& other : graph.keyframes()) {
      if (other.id == K.id) continue;
      if ((other.T_W_K.translation() - K.T_W_K.translation()).norm() <= params.occlusion_distance_m &&
          other.T_W_K.linear().col(2).dot(K.T_W_K.linear().col(2)) >= cos_angle - 1e-12)
        group.push_back(other.id);
    }
    std::sort(group.begin(), group.end());
    group.erase(std::unique(group.begin(), group.end()), group.end());

    // Bucket the group's ellipsoids by K's cell (counting sort), then each cell by depth.
    const Transform T_K_W = K.T_W_K.inverse();
    const Eigen::Vector3d c = K.T_W_K.translation();
    struct Item {
      double z;
      double lambda_max;
      Eigen::Vector3d ray;  // mean - c, world frame
      int index;
    };
    std::vector<int> cell_of;
    std::vector<Item> projected;
    for (int g : group)
      for (int j = first[static_cast<std::size_t>(g)]; j < first[static_cast<std::size_t>(g) + 1]; ++j) {
        const Eigen::Vector3d& mean = mean_by_keyframe[static_cast<std::size_t>(j)];
        const Eigen::Vector3d p = T_K_W * mean;
        if (p.z() <= 0.0) continue;
        const Eigen::Vector2d uv = K.container.camera().project(p);
        const int cell = K.container.gridIndexOfPixel(uv.x(), uv.y());
        if (cell < 0) continue;
        cell_of.push_back(cell);
        const int i = index_by_keyframe[static_cast<std::size_t>(j)];
        projected.push_back({p.z(), lambda_max[static_cast<std::size_t>(i)], mean - c, i});
      }
    const std::size_t cells = static_cast<std::size_t>(K.container.cols()) * K.container.rows();
    std::vector<int> start(cells + 1, 0);
    for (int cell : cell_of) ++start[static_cast<std::size_t>(cell) + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<Item> items(projected.size());
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (std::size_t j = 0; j < projected.size(); ++j)
        items[static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_of[j])]++)] = projected[j];
    }
    std::vector<double> suffix_min;  // smallest lambda_max among the items from here to the cell's end
    for (std::size_t cell = 0; cell < cells; ++cell) {
      const std::size_t b0 = static_cast<std::size_t>(start[cell]), b1 = static_cast<std::size_t>(start[cell + 1]);
      if (b1 - b0 < 2) continue;
      std::sort(items.begin() + static_cast<std::ptrdiff_t>(b0), items.begin() + static_cast<std::ptrdiff_t>(b1),
                [](const Item& a, const Item& b) { return a.z != b.z ? a.z < b.z : a.index < b.index; });
      suffix_min.resize(b1 - b0 + 1);
      suffix_min[b1 - b0] = std::numeric_limits<double>::infinity();
      for (std::size_t j = b1; j-- > b0;)
        suffix_min[j - b0] = std::min(suffix_min[j - b0 + 1], items[j].lambda_max);
      for (std::size_t a = b0; a + 1 < b1; ++a) {  // A nearer than B: A before B in the cell
        const std::size_t ia = static_cast<std::size_t>(items[a].index);
        if (!(suffix_min[a + 1 - b0] < items[a].lambda_max)) continue;  // no finer B behind A
        const Eigen::Vector3d& mu = items[a].ray;
        const Eigen::Matrix3d& P = information[ia];
        const Eigen::Vector3d P_mu = P * mu;
        const double mu_P_mu = mu.dot(P_mu);
        for (std::size_t b = a + 1; b < b1; ++b) {
          if (!(items[b].z > items[a].z) || !(items[b].lambda_max < items[a].lambda_max)) continue;
          // Squared Mahalanobis distance from A's mean to the ray c + t d: minimised over t.
          const Eigen::Vector3d d = items[b].ray.normalized();
          const double dPd = d.dot(P * d), dPmu = d.dot(P_mu);
          if (mu_P_mu - dPmu * dPmu / dPd <= 4.0) {
            removed_by[v].push_back(static_cast<int>(ia));
            break;
          }
        }
      }
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
