// Merge groups (docs/method.md 6.1): each keyframe goes into exactly one group, around the centre
// whose edges to keyframes not yet grouped weigh most.
#include <algorithm>

#include "mapping/global_map/global_map.h"

namespace vdmap {

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

}  // namespace vdmap
