#pragma once
// A bounding-volume hierarchy over axis-aligned boxes for exact nearest-item queries
// (docs/method.md 12). Nodes split at the median of their longest axis; a query descends the
// nearer child first and prunes every node whose box is farther than the best item so far.
// Exact whenever an item's distance is at least the distance to its box (triangles, points),
// and logarithmic even for queries far from everything, where a uniform grid has to sweep
// empty space.
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace vdmap {

class BoxTree {
 public:
  /// Item i has the box [lo[i], hi[i]] (metres). The tree keeps no reference to the inputs.
  BoxTree(const std::vector<Eigen::Vector3f>& lo, const std::vector<Eigen::Vector3f>& hi);

  /// Index and squared distance of the nearest item to q, where sq_dist(i, q) is the exact
  /// squared distance to item i; ties go to the lower index. {-1, inf} when there are no
  /// items. Const, so safe to call from many threads.
  template <typename SqDist>
  std::pair<std::int64_t, double> nearest(const Eigen::Vector3d& q, SqDist&& sq_dist) const;

 private:
  struct Node {
    Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi = Eigen::Vector3f::Zero();
    std::uint32_t first = 0, count = 0;  // leaf: items_[first, first + count); inner: count == 0
    std::uint32_t left = 0, right = 0;   // children (inner nodes)
  };
  static constexpr std::uint32_t kLeafSize = 4;

  std::uint32_t build(std::uint32_t first, std::uint32_t count, const std::vector<Eigen::Vector3f>& lo,
                      const std::vector<Eigen::Vector3f>& hi, const std::vector<Eigen::Vector3f>& centre);
  static double sqDistToBox(const Node& n, const Eigen::Vector3d& q) {
    const Eigen::Vector3d d = (n.lo.cast<double>() - q).cwiseMax(q - n.hi.cast<double>()).cwiseMax(0.0);
    return d.squaredNorm();
  }

  std::vector<Node> nodes_;
  std::vector<std::uint32_t> items_;
};

template <typename SqDist>
std::pair<std::int64_t, double> BoxTree::nearest(const Eigen::Vector3d& q, SqDist&& sq_dist) const {
  std::int64_t best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  if (nodes_.empty()) return {best, best_d2};
  std::pair<double, std::uint32_t> stack[64];  // depth <= log2(2^32 / kLeafSize) + 1 for median splits
  int top = 0;
  stack[top++] = {sqDistToBox(nodes_[0], q), 0};
  while (top > 0) {
    const auto [box_d2, id] = stack[--top];
    if (box_d2 > best_d2) continue;
    const Node& n = nodes_[id];
    if (n.count > 0) {
      for (std::uint32_t j = n.first; j < n.first + n.count; ++j) {
        const double d2 = sq_dist(items_[j], q);
        if (d2 < best_d2 || (d2 == best_d2 && items_[j] < best)) best_d2 = d2, best = items_[j];
      }
      continue;
    }
    const double dl = sqDistToBox(nodes_[n.left], q), dr = sqDistToBox(nodes_[n.right], q);
    // Push the farther child first so the nearer one is searched first.
    if (dl <= dr) stack[top++] = {dr, n.right}, stack[top++] = {dl, n.left};
    else stack[top++] = {dl, n.left}, stack[top++] = {dr, n.right};
  }
  return {best, best_d2};
}

}  // namespace vdmap
