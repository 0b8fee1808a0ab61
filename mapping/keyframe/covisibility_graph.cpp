#include "mapping/keyframe/covisibility_graph.h"

#include <cassert>
#include <sstream>

#include "mapping/core/atomic_file.h"

namespace vdmap {

void CovisibilityGraph::strengthen(int a, int b, double weight) {
  assert(a != b);
  double& w = edges_.try_emplace(key(a, b), weight).first->second;
  if (weight > w) w = weight;
  adjacency_[a][b] = w;
  adjacency_[b][a] = w;
}

double CovisibilityGraph::weight(int a, int b) const {
  const auto it = edges_.find(key(a, b));
  return it == edges_.end() ? 0.0 : it->second;
}

bool CovisibilityGraph::hasEdge(int a, int b) const { return edges_.count(key(a, b)) > 0; }

std::vector<std::pair<int, double>> CovisibilityGraph::neighbours(int id) const {
  const auto it = adjacency_.find(id);
  if (it == adjacency_.end()) return {};
  return {it->second.begin(), it->second.end()};
}

std::vector<CovisibilityEdge> CovisibilityGraph::edges() const {
  std::vector<CovisibilityEdge> out;
  out.reserve(edges_.size());
  for (const auto& [ab, w] : edges_) out.push_back({ab.first, ab.second, w});
  return out;
}

void CovisibilityGraph::writeEdgeList(const std::filesystem::path& file) const {
  std::ostringstream out;
  out << "# covisibility edges: keyframe_a keyframe_b weight (fraction of re-observed ORB features)\n";
  for (const CovisibilityEdge& e : edges()) out << e.a << " " << e.b << " " << e.weight << "\n";
  writeFileAtomically(file, out.str());
}

}  // namespace vdmap
