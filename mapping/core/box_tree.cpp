#include "mapping/core/box_tree.h"

#include <algorithm>
#include <cassert>

namespace vdmap {

BoxTree::BoxTree(const std::vector<Eigen::Vector3f>& lo, const std::vector<Eigen::Vector3f>& hi,
                 std::uint32_t leaf_size) {
  assert(lo.size() == hi.size());
  if (lo.empty()) return;
  std::vector<Eigen::Vector3f> centre(lo.size());
  for (std::size_t i = 0; i < lo.size(); ++i) centre[i] = 0.5f * (lo[i] + hi[i]);
  items_.resize(lo.size());
  for (std::size_t i = 0; i < items_.size(); ++i) items_[i] = static_cast<std::uint32_t>(i);
  build(0, static_cast<std::uint32_t>(items_.size()), std::max<std::uint32_t>(1, leaf_size), lo, hi, centre);
  nodes_.shrink_to_fit();
}

std::uint32_t BoxTree::build(std::uint32_t first, std::uint32_t count, std::uint32_t leaf_size,
                             const std::vector<Eigen::Vector3f>& lo, const std::vector<Eigen::Vector3f>& hi,
                             const std::vector<Eigen::Vector3f>& centre) {
  const auto id = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back({});
  Node n;
  n.lo = lo[items_[first]];
  n.hi = hi[items_[first]];
  for (std::uint32_t j = first; j < first + count; ++j) {
    n.lo = n.lo.cwiseMin(lo[items_[j]]);
    n.hi = n.hi.cwiseMax(hi[items_[j]]);
  }
  if (count <= leaf_size) {
    n.first = first;
    n.count = count;
  } else {
    int axis;
    (n.hi - n.lo).maxCoeff(&axis);
    const auto begin = items_.begin() + first, mid = begin + count / 2, end = begin + count;
    // Ties broken by index, so the tree (and so every tie in a query) is deterministic.
    std::nth_element(begin, mid, end, [&](std::uint32_t a, std::uint32_t b) {
      return centre[a](axis) < centre[b](axis) || (centre[a](axis) == centre[b](axis) && a < b);
    });
    build(first, count / 2, leaf_size, lo, hi, centre);  // the next node
    n.first = build(first + count / 2, count - count / 2, leaf_size, lo, hi, centre);
  }
  nodes_[id] = n;
  return id;
}

}  // namespace vdmap
