#pragma once
// The transforms of a recording's /tf and /tf_static as a tree, looked up at a time: each edge
// parent <- child is either static or a time series interpolated as groundtruth.txt is (linear
// translation, slerp rotation, from transforms within max_dt on both sides).
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "mapping/core/types.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/ros/messages.h"

namespace vdmap::detail {

/// The transform of a rotation (normalised here; recordings store it as written) and a
/// translation: a tf edge, a pose message, RealSense's stream extrinsics.
Transform rigidTransform(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& translation);

class TfTree {
 public:
  /// Adds `t` (the pose of t.child_frame_id in t.header.frame_id). Leading '/' of ROS 1 frame
  /// names are dropped. A child recorded under two parents keeps the first parent.
  void add(const ros::TransformStamped& t, bool is_static);

  /// The frame at the top of `frame`'s chain of parents (itself when it has none).
  std::string root(const std::string& frame) const;
  /// Every frame named, sorted, for messages.
  std::vector<std::string> frames() const;
  bool has(const std::string& frame) const;

  /// T_ancestor_frame at time t: the product of the edges from `frame` up to `ancestor`; nothing
  /// when a dynamic edge has no transforms within max_dt on both sides of t. Throws
  /// std::invalid_argument naming the frames when `ancestor` is not above `frame`.
  std::optional<Transform> lookup(const std::string& ancestor, const std::string& frame, double t, double max_dt) const;

  static std::string name(const std::string& frame);  ///< without ROS 1's leading '/'

 private:
  struct Edge {
    std::string parent;
    bool is_static = false;
    Transform T = Transform::Identity();  ///< static edges
    std::vector<StampedPose> series;      ///< dynamic edges, in time order
  };
  std::optional<Transform> edgeAt(const Edge& edge, double t, double max_dt) const;
  std::map<std::string, Edge> edges_;  ///< by child frame
};

}  // namespace vdmap::detail
