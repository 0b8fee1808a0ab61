#pragma once
#include <filesystem>
#include <map>
#include <utility>
#include <vector>

namespace vdmap {

/// One undirected covisibility edge, a < b.
struct CovisibilityEdge {
  int a = 0;
  int b = 0;
  double weight = 0.0;
};

/// Weighted undirected edges between keyframe ids. Iteration order is by (a, b), so anything
/// derived from the graph is deterministic. Not thread-safe for writes.
class CovisibilityGraph {
 public:
  /// Adds the edge, or raises an existing edge's weight to `weight` if larger. a != b.
  void strengthen(int a, int b, double weight);
  /// 0 when there is no edge.
  double weight(int a, int b) const;
  bool hasEdge(int a, int b) const;
  /// (neighbour id, weight), sorted by id.
  std::vector<std::pair<int, double>> neighbours(int id) const;
  std::vector<CovisibilityEdge> edges() const;
  std::size_t size() const { return edges_.size(); }
  /// Plain edge list "a b weight", one per line, with a comment header; written atomically.
  void writeEdgeList(const std::filesystem::path& file) const;

 private:
  static std::pair<int, int> key(int a, int b) { return a < b ? std::pair{a, b} : std::pair{b, a}; }
  std::map<std::pair<int, int>, double> edges_;
  std::map<int, std::map<int, double>> adjacency_;
};

}  // namespace vdmap
