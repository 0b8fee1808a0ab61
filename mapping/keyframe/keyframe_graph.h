#pragma once
#include <deque>
#include <filesystem>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "mapping/io/compressed_image.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/keyframe/covisibility_graph.h"
#include "mapping/keyframe/frame_features.h"
#include "mapping/keyframe/keyframe_selector.h"
#include "mapping/local_map/frame_free_space.h"
#include "mapping/local_map/keyframe_container.h"

namespace vdmap {

/// Heap bytes one keyframe holds, by part (what stays resident while the graph grows).
struct KeyframeMemory {
  std::size_t images = 0;      ///< the compressed colour and depth images
  std::size_t features = 0;    ///< keypoints, descriptors, keypoint depths
  std::size_t cell_slots = 0;  ///< the local map's slot grid (4 B per grid cell)
  std::size_t ellipsoids = 0;  ///< the local map's stored cells
  std::size_t free_space = 0;  ///< the integrated frames' free space (FrameFreeSpace blocks)
};

/// A keyframe (docs/method.md 2): its pose, its own images and features, and its local map.
/// The images are held compressed (CompressedImage: the files they were read from, or a PNG or
/// JPEG) and decoded by rgb() / depth() when shown or saved; nothing on the per-frame path reads
/// them.
struct Keyframe {
  int id = 0;
  int frame_index = 0;   ///< the sequence frame that created it
  double timestamp = 0;  ///< s, that frame's depth timestamp
  Transform T_W_K = Transform::Identity();
  CompressedImage rgb_image;    ///< CV_8UC3 RGB, for the container view
  CompressedImage depth_image;  ///< CV_16UC1 raw units
  FrameFeatures features;
  KeyframeContainer container;
  int frames_integrated = 0;
  /// Per integrated frame (in order), what it saw free (docs/method.md 13.2); its pose is kept
  /// relative to the keyframe, so it follows a corrected keyframe pose like the local map.
  std::vector<FrameFreeSpace> frames_free;

  /// The colour image, decoded (a few ms; cache it where it is shown every UI frame).
  cv::Mat rgb() const { return rgb_image.decode(); }
  cv::Mat depth() const { return depth_image.decode(); }
  KeyframeMemory memory() const;
};

/// What applyTrajectory() matched.
struct TrajectoryMatch {
  int matched = 0;    ///< keyframes whose pose was replaced
  int unknown = 0;    ///< file poses whose timestamp is no keyframe's (ignored)
  int untouched = 0;  ///< keyframes the file does not mention (pose kept)
};

/// The keyframes (ids 0..size-1, in creation order) and their covisibility edges. Keyframe
/// addresses are stable. Not thread-safe for writes.
class KeyframeGraph {
 public:
  Keyframe& add(Keyframe keyframe);
  std::size_t size() const { return keyframes_.size(); }
  const Keyframe& keyframe(int id) const { return keyframes_.at(static_cast<std::size_t>(id)); }
  Keyframe& keyframe(int id) { return keyframes_.at(static_cast<std::size_t>(id)); }
  const std::deque<Keyframe>& keyframes() const { return keyframes_; }
  const CovisibilityGraph& edges() const { return edges_; }
  CovisibilityGraph& edges() { return edges_; }
  /// Non-owning views for the keyframe decision.
  std::vector<KeyframeView> views() const;

  /// Replaces a keyframe's pose (loop-closure correction). The local map is untouched: it
  /// lives in the keyframe frame. Throws std::invalid_argument for an unknown id or a pose that
  /// is not a finite rigid transform.
  void setKeyframePose(int id, const Transform& T_W_K);

  /// Replaces the poses of the keyframes whose timestamps appear in `poses` (T_W_C, matched
  /// within `tolerance_s`; timestamps increasing). Poses at unknown timestamps are ignored and
  /// counted; keyframes not named keep their pose. Throws std::invalid_argument, changing
  /// nothing, when no pose matches a keyframe (almost surely the wrong trajectory). Reading a
  /// file is applyTrajectoryFile's job (below).
  TrajectoryMatch applyTrajectory(std::span<const StampedPose> poses, double tolerance_s = 1e-3);

 private:
  std::deque<Keyframe> keyframes_;
  CovisibilityGraph edges_;
};

/// Reads a corrected TUM trajectory and applies it to the graph's keyframes by timestamp
/// (KeyframeGraph::applyTrajectory). Throws InputError naming the file for a malformed file or
/// one that matches no keyframe (the graph is then unchanged).
TrajectoryMatch applyTrajectoryFile(KeyframeGraph& graph, const std::filesystem::path& file);

}  // namespace vdmap
