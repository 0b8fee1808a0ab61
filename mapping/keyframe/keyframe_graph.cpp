#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/core/message_text.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "mapping/core/error.h"

namespace vdmap {

KeyframeMemory Keyframe::memory() const {
  KeyframeMemory m;
  m.images = rgb_image.compressedBytes() + depth_image.compressedBytes();
  m.features = features.keypoints.capacity() * sizeof(cv::KeyPoint) + features.descriptors.total() +
               features.depth_m.capacity() * sizeof(float);
  m.ellipsoids = container.cells().capacity() * sizeof(StoredCell);
  m.cell_slots = container.memoryBytes() - m.ellipsoids;
  for (const FrameFreeSpace& f : frames_free) m.free_space += f.memoryBytes();
  return m;
}

Keyframe& KeyframeGraph::add(Keyframe keyframe) {
  keyframe.id = static_cast<int>(keyframes_.size());
  keyframes_.push_back(std::move(keyframe));
  return keyframes_.back();
}

std::vector<KeyframeView> KeyframeGraph::views() const {
  std::vector<KeyframeView> out;
  out.reserve(keyframes_.size());
  for (const Keyframe& k : keyframes_) out.push_back({k.id, &k.T_W_K, &k.features});
  return out;
}

void KeyframeGraph::setKeyframePose(int id, const Transform& T_W_K) {
  if (id < 0 || id >= static_cast<int>(keyframes_.size()))
    throw std::invalid_argument("no keyframe " + std::to_string(id) + " (the map has " +
                                std::to_string(keyframes_.size()) + ")");
  if (!isValidTransform(T_W_K)) throw std::invalid_argument("keyframe pose must be a finite rigid transform");
  keyframes_[static_cast<std::size_t>(id)].T_W_K = T_W_K;
}

TrajectoryMatch KeyframeGraph::applyTrajectory(std::span<const StampedPose> poses, double tolerance_s) {
  TrajectoryMatch match;
  std::vector<bool> seen(keyframes_.size(), false);
  for (const StampedPose& p : poses) {
    // Keyframe timestamps increase with id (keyframes are created in sequence order).
    auto it = std::lower_bound(keyframes_.begin(), keyframes_.end(), p.t - tolerance_s,
                               [](const Keyframe& k, double t) { return k.timestamp < t; });
    if (it == keyframes_.end() || std::abs(it->timestamp - p.t) > tolerance_s) {
      ++match.unknown;
      continue;
    }
    it->T_W_K = p.T_W_C;
    if (!seen[static_cast<std::size_t>(it->id)]) ++match.matched;
    seen[static_cast<std::size_t>(it->id)] = true;
  }
  match.untouched = static_cast<int>(std::count(seen.begin(), seen.end(), false));
  if (match.matched == 0)
    throw std::invalid_argument("no pose matches a keyframe timestamp (" +
                                counted(static_cast<long long>(poses.size()), "pose") + ", " +
                                counted(static_cast<long long>(keyframes_.size()), "keyframe") + ")");
  return match;
}

TrajectoryMatch applyTrajectoryFile(KeyframeGraph& graph, const std::filesystem::path& file) {
  const std::vector<StampedPose> poses = readTumTrajectory(file);
  try {
    return graph.applyTrajectory(poses);
  } catch (const std::invalid_argument& e) {
    throw InputError(file.string(), e.what());
  }
}

}  // namespace vdmap
