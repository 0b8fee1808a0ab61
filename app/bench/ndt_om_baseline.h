#pragma once
// BASELINE, not part of vdmap's method: an NDT-OM-style map (Saarinen et al. 2013) for the
// comparisons of docs/method.md 12 and the paper's Table I. A sparse 3-D grid of NDT cells at one
// fixed resolution in the world frame, each updated with vdmap's own cell statistics
// (docs/method.md 2, cell_stats.h), so the comparison is of the map layout, not of the arithmetic.
// Only the NDT statistics are kept: no occupancy and no ray casting of free space, so this is
// a lower bound on NDT-OM's update time and the timing comparison favours the baseline.
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "mapping/core/camera.h"
#include "mapping/core/rgbd_frame.h"
#include "mapping/core/types.h"
#include "mapping/local_map/cell_stats.h"

namespace vdmap {

struct NdtOmParams {
  double resolution_m = 0.1;  ///< edge of a cubic cell (the paper's NDT-OM column: 0.1 m)
  DepthRange depth_range;     ///< pixels outside are skipped, as in the local-map integrator
};

/// Sparse world-frame NDT grid. Not thread-safe; one owner updates it.
class NdtOmBaseline {
 public:
  /// Cell index: floor(p_W / resolution) per axis, packed 21 bits each (+-1 M cells per axis).
  using Key = std::uint64_t;

  /// Throws std::invalid_argument when the resolution is not positive and finite.
  explicit NdtOmBaseline(const NdtOmParams& params = {});

  /// Adds every pixel of `frame` with depth in range, back-projected with `camera` and moved
  /// to the world frame by frame.T_W_C. Points are grouped by cell and each group merges into
  /// its cell as one batch, exactly as the local map does (docs/method.md 2, the batch merge).
  void integrateFrame(const RgbdFrame& frame, const PinholeCamera& camera);
  /// The same for points already in the world frame (metres) with colours (0..255).
  void integratePoints(const std::vector<Eigen::Vector3f>& points_W,
                       const std::vector<std::array<std::uint8_t, 3>>& colors);

  Key keyOf(const Eigen::Vector3d& p_W) const;
  const std::unordered_map<Key, CellStats>& cells() const { return cells_; }
  std::size_t size() const { return cells_.size(); }
  /// Cell means (world frame) in key order, so the output does not depend on hash order.
  std::vector<Eigen::Vector3f> means() const;

 private:
  NdtOmParams params_;
  std::unordered_map<Key, CellStats> cells_;
  // Per-frame scratch, kept to avoid reallocation.
  std::unordered_map<Key, std::uint32_t> slot_of_key_;
  std::vector<std::uint32_t> slot_of_point_;
  std::vector<PointBatch> batches_;
  std::vector<Key> batch_keys_;
};

}  // namespace vdmap
