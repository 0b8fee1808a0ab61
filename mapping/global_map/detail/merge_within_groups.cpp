#include "mapping/global_map/detail/merge_within_groups.h"

#include <algorithm>

#include "mapping/local_map/cell_stats.h"

namespace vdmap {
namespace global_map_detail {
namespace {

Ellipsoid transformed(const Ellipsoid& e, const Transform& T_B_A) {
  Ellipsoid out = e;
  out.mean = T_B_A * e.mean;
  out.cov = T_B_A.linear() * e.cov * T_B_A.linear().transpose();
  return out;
}

// First only the means, to find each kept ellipsoid's cell in the centre; the whole ellipsoid is
// made when its cell is merged (holding all of them would write ~120 bytes per ellipsoid). Fills
// the scratch's T_C_K (per member), sources and cell_of (per kept ellipsoid, -1: in no cell).
void locateInCentre(const KeyframeGraph& graph, const MergeGroup& group, const std::vector<std::vector<bool>>& kept,
                    MergeScratch* scratch) {
  MergeScratch& s = *scratch;
  const Keyframe& centre = graph.keyframe(group.centre);
  const KeyframeContainer& box = centre.container;
  const Transform T_C_W = centre.T_W_K.inverse();
  s.T_C_K.clear();
  s.sources.clear();
  s.cell_of.clear();
  for (int m = 0; m < static_cast<int>(group.members.size()); ++m) {
    const int id = group.members[static_cast<std::size_t>(m)];
    const Keyframe& k = graph.keyframe(id);
    const std::vector<bool>& kept_cells = kept[static_cast<std::size_t>(id)];
    s.T_C_K.push_back(T_C_W * k.T_W_K);
    for (std::size_t i = 0; i < kept_cells.size(); ++i) {
      if (!kept_cells[i]) continue;
      const Eigen::Vector3d mean = s.T_C_K.back() * k.container.cells()[i].mean.cast<double>();
      int cell = -1;
      if (mean.z() > 0.0) {
        const Eigen::Vector2d uv = box.camera().project(mean);
        cell = box.gridIndexOfPixel(uv.x(), uv.y());
      }
      s.sources.push_back({m, static_cast<int>(i)});
      s.cell_of.push_back(cell);
    }
  }
}

// Kept ellipsoid `source` (locateInCentre's numbering) in the centre's frame.
Ellipsoid inCentre(const KeyframeGraph& graph, const MergeGroup& group, const MergeScratch& s, int source) {
  const MergeScratch::Source& src = s.sources[static_cast<std::size_t>(source)];
  const int id = group.members[static_cast<std::size_t>(src.member)];
  return cellEllipsoid(graph.keyframe(id).container.cells()[static_cast<std::size_t>(src.cell_index)],
                       s.T_C_K[static_cast<std::size_t>(src.member)], id);
}

// meanShiftClusters into `label` (resized to the means).
void meanShiftClusters(const std::vector<Eigen::Vector3d>& means, const std::vector<double>& weights, double h,
                       std::vector<int>* label) {
  // Most cells of a merge group hold one surface seen from a few keyframes, all means within h of
  // each other. Then every seed's first window holds every mean, so its first step lands it on the
  // same weighted mean (the same sum in the same order); that point lies in the means' convex hull,
  // hence within h of each of them, so its window again holds them all and it stays: one cluster.
  // The margin on h^2 is far above the rounding of that weighted mean. Not for h = 0 (equal modes
  // still start new clusters there: a distance of 0 is not below h/2) nor without positive weights.
  const double one_kernel_m2 = h * h * (1.0 - 1e-9);
  bool one_cluster = h > 0.0;
  for (std::size_t i = 0; i < means.size() && one_cluster; ++i) {
    one_cluster = weights[i] > 0.0;
    for (std::size_t j = i + 1; j < means.size() && one_cluster; ++j)
      one_cluster = (means[i] - means[j]).squaredNorm() <= one_kernel_m2;
  }
  if (one_cluster) label->assign(means.size(), 0);
  else *label = meanShiftClustersByIteration(means, weights, h);
}

// The kept ellipsoids of centre cell c (s->in_cell, s->means, s->weights; two or more): one
// ellipsoid per mean-shift cluster of radius h, moment matched, appended to `out` in the world frame.
void mergeCell(const MergeGroup& group, std::size_t c, double h, const Transform& T_W_C, MergeScratch* scratch,
               std::vector<Ellipsoid>* out) {
  MergeScratch& s = *scratch;
  meanShiftClusters(s.means, s.weights, h, &s.label);
  const int clusters = *std::max_element(s.label.begin(), s.label.end()) + 1;
  for (int k = 0; k < clusters; ++k) {
    s.cluster.clear();
    for (std::size_t i = 0; i < s.in_cell.size(); ++i)
      if (s.label[i] == k) s.cluster.push_back(&s.in_cell[i]);
    Ellipsoid merged = momentMatch(s.cluster);
    merged.keyframe = group.centre;
    merged.grid_index = static_cast<int>(c);
    out->push_back(transformed(merged, T_W_C));
  }
}

}  // namespace

void mergeGroup(const KeyframeGraph& graph, const MergeGroup& group, const GlobalMapParams& params,
                const std::vector<std::vector<bool>>& kept, MergeScratch* scratch, std::vector<Ellipsoid>* out) {
  MergeScratch& s = *scratch;
  const Keyframe& centre = graph.keyframe(group.centre);
  locateInCentre(graph, group, kept, &s);
  // By cell, stable: members in id order, cells in container order.
  const std::size_t cells = static_cast<std::size_t>(centre.container.cols()) * centre.container.rows();
  bucketByKey(s.cell_of, cells, &s.by_cell, &s.fill);
  const std::vector<int>& start = s.by_cell.start;
  const std::vector<int>& order = s.by_cell.order;
  out->clear();
  out->reserve(s.sources.size());
  for (std::size_t c = 0; c < cells; ++c) {
    const int begin = start[c], end = start[c + 1];
    if (end - begin == 1) out->push_back(transformed(inCentre(graph, group, s, order[begin]), centre.T_W_K));
    if (end - begin <= 1) continue;
    s.in_cell.clear();
    s.means.clear();
    s.weights.clear();
    for (int i = begin; i < end; ++i) {
      s.in_cell.push_back(inCentre(graph, group, s, order[i]));
      s.means.push_back(s.in_cell.back().mean);
      s.weights.push_back(s.in_cell.back().count);
    }
    mergeCell(group, c, params.merge_distance_m, centre.T_W_K, &s, out);
  }
  for (std::size_t i = 0; i < s.cell_of.size(); ++i)
    if (s.cell_of[i] < 0) out->push_back(transformed(inCentre(graph, group, s, static_cast<int>(i)), centre.T_W_K));
}

}  // namespace global_map_detail

std::vector<int> meanShiftClusters(const std::vector<Eigen::Vector3d>& means, const std::vector<double>& weights,
                                   double h) {
  std::vector<int> label;
  global_map_detail::meanShiftClusters(means, weights, h, &label);
  return label;
}

std::vector<int> meanShiftClustersByIteration(const std::vector<Eigen::Vector3d>& means,
                                              const std::vector<double>& weights, double h) {
  constexpr double kConverged = 1e-4;  // m (docs/method.md 6.2)
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
  // Moment matching (docs/method.md 6.2) is Sigma = sum n_i (Sigma_i + d_i d_i^T) / n with population covariances. Ellipsoids
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

}  // namespace vdmap
