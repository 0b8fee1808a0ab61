#pragma once
// The view-dependent container of one keyframe (docs/method.md 2): a grid of cells over a
// 2W x 2H image plane with the keyframe image in its centre, at most one NDT ellipsoid per cell.

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mapping/core/camera.h"
#include "mapping/local_map/cell_stats.h"

namespace vdmap {

/// One stored ellipsoid. Statistics are accumulated in double (the integrator's scratch and
/// mergeBatch) and stored in float: float keeps a mean at 8 m to ~0.5 um and the scatter to 1e-7
/// relative, far below sensor noise, and halves the memory (docs/method.md 2: accumulated in
/// double, stored in float). Keyframe frame K, metres.
struct StoredCell {
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  std::array<float, 6> scatter{};                   ///< S: xx xy xz yy yz zz
  Eigen::Vector3f color = Eigen::Vector3f::Zero();  ///< mean RGB, 0..255
  std::uint32_t n = 0;
  std::int32_t grid_index = -1;  ///< row * cols + col of the cell in its container

  CellStats toStats() const;
  void fromStats(const CellStats& stats);
};
static_assert(sizeof(StoredCell) <= 64, "an ellipsoid must take at most 64 bytes (one cache line)");

/// Storage: sparse. An int32 slot per grid cell (-1 = empty) points into a vector of the cells
/// that hold an ellipsoid. A 640x480 keyframe has 49152 cells, of which a real keyframe fills
/// only part; dense storage would cost 56 B per grid cell (2.7 MB per keyframe), sparse costs
/// 4 B per grid cell plus 56 B per ellipsoid, and the extra indirection happens once per run of
/// pixels, not per pixel (docs/performance.md; a 7-Scenes keyframe in docs/notes/performance.md).
/// Not thread-safe for writing; concurrent const access is fine.
class KeyframeContainer {
 public:
  /// `camera` is the keyframe's camera. Throws std::invalid_argument when the camera is invalid
  /// or cell_size_px is not in 1..min(width, height).
  KeyframeContainer(const PinholeCamera& camera, int cell_size_px);

  const PinholeCamera& camera() const { return camera_; }
  int cellSizePx() const { return cell_size_px_; }
  int cols() const { return cols_; }  ///< ceil(2W / s)
  int rows() const { return rows_; }  ///< ceil(2H / s)
  /// Container pixel = keyframe pixel + offset: offset = (W/2, H/2), integer division.
  int offsetU() const { return camera_.width / 2; }
  int offsetV() const { return camera_.height / 2; }

  /// The grid index of the cell holding keyframe pixel (u, v), or -1 when it is outside the
  /// container. A container pixel covers [u' - 0.5, u' + 0.5).
  /// Inline: the global map's occlusion removal and the tracker call it for millions of points.
  int gridIndexOfPixel(double u, double v) const {
    const double up = u + offsetU() + 0.5, vp = v + offsetV() + 0.5;
    if (!(up >= 0.0 && vp >= 0.0 && up < 2.0 * camera_.width && vp < 2.0 * camera_.height)) return -1;
    const int col = static_cast<int>(up) / cell_size_px_, row = static_cast<int>(vp) / cell_size_px_;
    return row * cols_ + col;
  }

  /// The stored cell at a grid index, or nullptr.
  const StoredCell* find(int grid_index) const {
    const std::int32_t s = slot_[grid_index];
    return s < 0 ? nullptr : &cells_[s];
  }
  /// The stored cell at a grid index, created empty (n = 0) when absent.
  StoredCell& findOrCreate(int grid_index);

  /// All stored cells (those with n >= 1), in order of creation.
  const std::vector<StoredCell>& cells() const { return cells_; }
  std::size_t size() const { return cells_.size(); }
  /// Gives back the cells' unused capacity (a keyframe that stopped growing). The cells, id() and
  /// revision() stay; pointers into cells() do not.
  void shrinkToFit() { cells_.shrink_to_fit(); }
  /// Heap bytes held: the slot grid plus the cells.
  std::size_t memoryBytes() const;

  /// A number no other container has had: new on construction and copy, handed over by a move
  /// (the moved-from container takes a new one). A cell only changes by gaining points, so a
  /// cache of something computed from cells()[i] stays valid while (id(), i, n) are the same
  /// (the dense refinement's cell distributions).
  std::uint64_t id() const { return id_.value; }
  /// Counts findOrCreate() calls, the only way a cell changes: while (id(), revision()) are the
  /// same, so are the cells (the global map's workspace keeps each keyframe's filter result by it).
  std::uint64_t revision() const { return revision_; }

 private:
  struct UniqueId {
    static std::uint64_t next();
    std::uint64_t value = next();
    UniqueId() = default;
    UniqueId(const UniqueId&) : value(next()) {}
    UniqueId(UniqueId&& other) noexcept : value(other.value) { other.value = next(); }
    UniqueId& operator=(const UniqueId&) {
      value = next();
      return *this;
    }
    UniqueId& operator=(UniqueId&& other) noexcept {
      value = other.value;
      other.value = next();
      return *this;
    }
  };

  PinholeCamera camera_;
  int cell_size_px_;
  int cols_, rows_;
  std::vector<std::int32_t> slot_;
  std::vector<StoredCell> cells_;
  UniqueId id_;
  std::uint64_t revision_ = 0;
};

}  // namespace vdmap
