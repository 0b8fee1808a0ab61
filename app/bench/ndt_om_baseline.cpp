#include "app/bench/ndt_om_baseline.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vdmap {

NdtOmBaseline::NdtOmBaseline(const NdtOmParams& params) : params_(params) {
  if (!(params.resolution_m > 0.0) || !std::isfinite(params.resolution_m))
    throw std::invalid_argument("NDT-OM resolution must be a positive number of metres");
}

NdtOmBaseline::Key NdtOmBaseline::keyOf(const Eigen::Vector3d& p_W) const {
  constexpr std::int64_t kOffset = 1 << 20, kMask = (1 << 21) - 1;
  Key key = 0;
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::int64_t>(std::floor(p_W(k) / params_.resolution_m)) + kOffset;
    key = (key << 21) | static_cast<Key>(std::clamp<std::int64_t>(i, 0, kMask));
  }
  return key;
}

void NdtOmBaseline::integrateFrame(const RgbdFrame& frame, const PinholeCamera& camera) {
  ColoredPointCloud cloud = toPointCloud(frame, camera, params_.depth_range);
  const Eigen::Isometry3f T_W_C = frame.T_W_C.cast<float>();
  for (Eigen::Vector3f& p : cloud.points) p = T_W_C * p;
  integratePoints(cloud.points, cloud.colors);
}

void NdtOmBaseline::integratePoints(const std::vector<Eigen::Vector3f>& points_W,
                                    const std::vector<std::array<std::uint8_t, 3>>& colors) {
  // Pass 1: the cell of each point, and the sum and count of each touched cell's batch.
  slot_of_key_.clear();
  batches_.clear();
  batch_keys_.clear();
  slot_of_point_.resize(points_W.size());
  for (std::size_t i = 0; i < points_W.size(); ++i) {
    const Eigen::Vector3d p = points_W[i].cast<double>();
    const Key key = keyOf(p);
    const auto [it, added] = slot_of_key_.try_emplace(key, static_cast<std::uint32_t>(batches_.size()));
    if (added) batches_.emplace_back(), batch_keys_.push_back(key);
    PointBatch& b = batches_[it->second];
    b.n += 1.0;
    b.sum += p;
    b.color_sum += Eigen::Vector3d(colors[i][0], colors[i][1], colors[i][2]);
    slot_of_point_[i] = it->second;
  }
  // Pass 2: each batch's scatter about its own mean (two-pass, as makeBatch), then the merge.
  for (std::size_t i = 0; i < points_W.size(); ++i) {
    PointBatch& b = batches_[slot_of_point_[i]];
    const Eigen::Vector3d d = points_W[i].cast<double>() - b.sum / b.n;
    b.scatter += d * d.transpose();
  }
  for (std::size_t s = 0; s < batches_.size(); ++s) mergeBatch(batches_[s], &cells_[batch_keys_[s]]);
}

std::vector<Eigen::Vector3f> NdtOmBaseline::means() const {
  std::vector<std::pair<Key, Eigen::Vector3f>> sorted;
  sorted.reserve(cells_.size());
  for (const auto& [key, c] : cells_) sorted.emplace_back(key, c.mean.cast<float>());
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::Vector3f> out;
  out.reserve(sorted.size());
  for (const auto& [key, m] : sorted) out.push_back(m);
  return out;
}

}  // namespace vdmap
