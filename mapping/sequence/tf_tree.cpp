#include "mapping/sequence/detail/tf_tree.h"

#include <algorithm>
#include <set>
#include <stdexcept>

namespace vdmap::detail {
Transform rigidTransform(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation) {
  Transform T = Transform::Identity();
  T.linear() = rotation.normalized().toRotationMatrix();
  T.translation() = translation;
  return T;
}

std::string TfTree::name(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

void TfTree::add(const ros::TransformStamped& t, bool is_static) {
  const std::string child = name(t.child_frame_id), parent = name(t.header.frame_id);
  if (child.empty() || parent.empty() || child == parent) return;
  auto [it, inserted] = edges_.try_emplace(child);
  Edge& edge = it->second;
  if (inserted) {
    edge.parent = parent;
    edge.is_static = is_static;
  }
  if (edge.parent != parent) return;
  if (edge.is_static) {
    edge.T = rigidTransform(t.rotation, t.translation);
    return;
  }
  // Kept in time order (after any of the same stamp): transforms mostly come in order, so this is
  // an append.
  const auto at = std::upper_bound(edge.series.begin(), edge.series.end(), t.header.stamp,
                                   [](double stamp, const StampedPose& p) { return stamp < p.t; });
  edge.series.insert(at, {t.header.stamp, rigidTransform(t.rotation, t.translation)});
}

std::string TfTree::root(const std::string& frame) const {
  std::string f = name(frame);
  for (std::size_t steps = 0; steps <= edges_.size(); ++steps) {  // a loop in the tree ends too
    auto it = edges_.find(f);
    if (it == edges_.end()) return f;
    f = it->second.parent;
  }
  return f;
}

std::vector<std::string> TfTree::frames() const {
  std::set<std::string> all;
  for (const auto& [child, edge] : edges_) all.insert({child, edge.parent});
  return {all.begin(), all.end()};
}

bool TfTree::has(const std::string& frame) const {
  const std::string f = name(frame);
  if (edges_.count(f)) return true;
  return std::any_of(edges_.begin(), edges_.end(), [&](const auto& e) { return e.second.parent == f; });
}

std::optional<Transform> TfTree::edgeAt(const Edge& edge, double t, double max_dt) const {
  if (edge.is_static) return edge.T;
  return interpolatePose(edge.series, t, max_dt);
}

std::optional<Transform> TfTree::lookup(const std::string& ancestor_in, const std::string& frame_in, double t,
                                        double max_dt) const {
  const std::string ancestor = name(ancestor_in);
  std::string f = name(frame_in);
  Transform T = Transform::Identity();  // T_f_frame
  bool missing = false;
  for (std::size_t steps = 0; f != ancestor; ++steps) {
    auto it = edges_.find(f);
    if (it == edges_.end() || steps > edges_.size())
      throw std::invalid_argument("tf has no path from '" + name(frame_in) + "' up to '" + ancestor + "'");
    const std::optional<Transform> edge = edgeAt(it->second, t, max_dt);
    if (!edge) missing = true;
    else T = *edge * T;
    f = it->second.parent;
  }
  if (missing) return std::nullopt;
  return T;
}

}  // namespace vdmap::detail
