#pragma once
// A bounding-volume hierarchy over axis-aligned boxes for exact nearest-item and first-hit
// queries (docs/method.md 12, 13.4, 13.6). Nodes split at the median of their longest axis; a
// query descends the nearer child first and prunes every node whose box is farther than the best
// item so far. Exact whenever an item's distance is at least the distance to its box (triangles,
// points, ellipsoids in their bounding boxes), and logarithmic even for queries far from
// everything, where a uniform grid has to sweep empty space.
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

namespace vdmap {

class BoxTree {
 public:
  /// Item i has the box [lo[i], hi[i]] (metres); a leaf holds at most leaf_size items (fewer,
  /// larger leaves: less memory, more items tested a query). The tree keeps no reference to the
  /// inputs.
  BoxTree(const std::vector<Eigen::Vector3f>& lo, const std::vector<Eigen::Vector3f>& hi, std::uint32_t leaf_size = 4);

  /// Heap bytes held (nodes and item indices).
  std::size_t memoryBytes() const {
    return nodes_.capacity() * sizeof(Node) + items_.capacity() * sizeof(std::uint32_t);
  }

  /// The identity: ties between items go to the lower index.
  struct ByIndex {
    std::uint32_t operator()(std::uint32_t i) const { return i; }
  };

  /// Index and squared distance of the nearest item to q, where sq_dist(i, q) is the exact
  /// squared distance to item i; ties go to the lower tie_key(i) (by default the lower index).
  /// {-1, inf} when there are no items, or none nearer than sqrt(max_sq_dist). Const, so safe to
  /// call from many threads. sq_dist may take the best squared distance so far as a third
  /// argument: it may then return any value above that bound instead of the exact one for an item
  /// it proves farther.
  template <typename SqDist, typename TieKey = ByIndex>
  std::pair<std::int64_t, double> nearest(const Eigen::Vector3d& q, SqDist&& sq_dist,
                                          double max_sq_dist = std::numeric_limits<double>::infinity(),
                                          TieKey tie_key = {}) const;

  /// The item with the smallest (t, tie_key(item)) hit by the ray o + t d, 0 <= t <= max_t, where
  /// hit(i, bound) returns item i's hit t or +inf, and may return +inf for any hit beyond `bound`
  /// (the best so far). An item's hits must lie within its box. {-1, inf} when nothing is hit.
  /// Nodes are visited nearest entry first (slab test) and pruned past the best hit.
  template <typename Hit, typename TieKey = ByIndex>
  std::pair<std::int64_t, double> firstHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t, Hit&& hit,
                                           TieKey tie_key = {}) const;

 private:
  // 32 bytes: the nodes in depth-first order, so an inner node's left child is the next node.
  struct Node {
    Eigen::Vector3f lo = Eigen::Vector3f::Zero(), hi = Eigen::Vector3f::Zero();
    std::uint32_t first = 0;  // leaf: items_[first, first + count); inner: the right child
    std::uint32_t count = 0;  // 0: inner
  };

  std::uint32_t build(std::uint32_t first, std::uint32_t count, std::uint32_t leaf_size,
                      const std::vector<Eigen::Vector3f>& lo, const std::vector<Eigen::Vector3f>& hi,
                      const std::vector<Eigen::Vector3f>& centre);
  static double sqDistToBox(const Node& n, const Eigen::Vector3d& q) {
    const Eigen::Vector3d d = (n.lo.cast<double>() - q).cwiseMax(q - n.hi.cast<double>()).cwiseMax(0.0);
    return d.squaredNorm();
  }
  /// Entry t of the ray o + t d (inv_d = 1 / d per axis) into node n within [0, max_t]; +inf when it
  /// misses. An axis along which the ray does not move constrains only its origin.
  static double rayEntry(const Node& n, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                         const Eigen::Vector3d& inv_d, double max_t) {
    double t0 = 0, t1 = max_t;
    for (int a = 0; a < 3; ++a) {
      const double lo = n.lo[a], hi = n.hi[a];
      if (d[a] == 0) {
        if (o[a] < lo || o[a] > hi) return std::numeric_limits<double>::infinity();
        continue;
      }
      double ta = (lo - o[a]) * inv_d[a], tb = (hi - o[a]) * inv_d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = ta > t0 ? ta : t0;
      t1 = tb < t1 ? tb : t1;
    }
    return t0 <= t1 ? t0 : std::numeric_limits<double>::infinity();
  }

  std::vector<Node> nodes_;
  std::vector<std::uint32_t> items_;
};

template <typename SqDist, typename TieKey>
std::pair<std::int64_t, double> BoxTree::nearest(const Eigen::Vector3d& q, SqDist&& sq_dist, double max_sq_dist,
                                                 TieKey tie_key) const {
  std::int64_t best = -1;
  double best_d2 = max_sq_dist;
  if (nodes_.empty()) return {best, best_d2};
  std::pair<double, std::uint32_t> stack[64];  // depth <= log2(2^32) + 1 for median splits
  int top = 0;
  stack[top++] = {sqDistToBox(nodes_[0], q), 0};
  while (top > 0) {
    const auto [box_d2, id] = stack[--top];
    if (box_d2 > best_d2) continue;
    const Node& n = nodes_[id];
    if (n.count > 0) {
      for (std::uint32_t j = n.first; j < n.first + n.count; ++j) {
        double d2;
        if constexpr (std::is_invocable_v<SqDist, std::uint32_t, const Eigen::Vector3d&, double>)
          d2 = sq_dist(items_[j], q, best_d2);
        else d2 = sq_dist(items_[j], q);
        if (d2 < best_d2 ||
            (d2 == best_d2 && best >= 0 && tie_key(items_[j]) < tie_key(static_cast<std::uint32_t>(best))))
          best_d2 = d2, best = items_[j];
      }
      continue;
    }
    const std::uint32_t left = id + 1, right = n.first;
    const double dl = sqDistToBox(nodes_[left], q), dr = sqDistToBox(nodes_[right], q);
    // Push the farther child first so the nearer one is searched first.
    if (dl <= dr) stack[top++] = {dr, right}, stack[top++] = {dl, left};
    else stack[top++] = {dl, left}, stack[top++] = {dr, right};
  }
  if (best < 0) best_d2 = std::numeric_limits<double>::infinity();
  return {best, best_d2};
}

template <typename Hit, typename TieKey>
std::pair<std::int64_t, double> BoxTree::firstHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t,
                                                  Hit&& hit, TieKey tie_key) const {
  std::int64_t best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  if (nodes_.empty() || !(max_t >= 0)) return {best, best_t};
  const Eigen::Vector3d inv_d = d.cwiseInverse();
  std::pair<double, std::uint32_t> stack[64];
  int top = 0;
  const double t_root = rayEntry(nodes_[0], o, d, inv_d, max_t);
  if (t_root > max_t) return {best, best_t};
  stack[top++] = {t_root, 0};
  while (top > 0) {
    const auto [box_t, id] = stack[--top];
    if (box_t > best_t) continue;  // ties kept: an item hit at the same t may have a lower index
    const Node& n = nodes_[id];
    const double bound = best_t < max_t ? best_t : max_t;
    if (n.count > 0) {
      for (std::uint32_t j = n.first; j < n.first + n.count; ++j) {
        const double t = hit(items_[j], bound);
        if (t < best_t ||
            (t == best_t && t <= max_t && best >= 0 && tie_key(items_[j]) < tie_key(static_cast<std::uint32_t>(best))))
          best_t = t, best = items_[j];
      }
      continue;
    }
    const std::uint32_t left = id + 1, right = n.first;
    const double tl = rayEntry(nodes_[left], o, d, inv_d, bound), tr = rayEntry(nodes_[right], o, d, inv_d, bound);
    // The farther child first on the stack, so the nearer one is searched first; misses not at all.
    if (tl <= tr) {
      if (tr <= bound) stack[top++] = {tr, right};
      if (tl <= bound) stack[top++] = {tl, left};
    } else {
      if (tl <= bound) stack[top++] = {tl, left};
      if (tr <= bound) stack[top++] = {tr, right};
    }
  }
  if (best_t > max_t) best = -1, best_t = std::numeric_limits<double>::infinity();
  return {best, best_t};
}

}  // namespace vdmap
