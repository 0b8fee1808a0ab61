#include "mapping/local_map/keyframe_container.h"

#include <atomic>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vdmap {

CellStats StoredCell::toStats() const {
  CellStats s;
  s.n = n;
  s.mean = mean.cast<double>();
  s.scatter << scatter[0], scatter[1], scatter[2],  //
      scatter[1], scatter[3], scatter[4],           //
      scatter[2], scatter[4], scatter[5];
  s.color = color.cast<double>();
  return s;
}

void StoredCell::fromStats(const CellStats& s) {
  n = static_cast<std::uint32_t>(s.n);
  mean = s.mean.cast<float>();
  scatter = {float(s.scatter(0, 0)), float(s.scatter(0, 1)), float(s.scatter(0, 2)),
             float(s.scatter(1, 1)), float(s.scatter(1, 2)), float(s.scatter(2, 2))};
  color = s.color.cast<float>();
}

std::uint64_t KeyframeContainer::UniqueId::next() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

KeyframeContainer::KeyframeContainer(const PinholeCamera& camera, int cell_size_px)
    : camera_(camera), cell_size_px_(cell_size_px) {
  camera_.validate();
  if (cell_size_px < 1 || cell_size_px > std::min(camera.width, camera.height))
    throw std::invalid_argument("cell size " + std::to_string(cell_size_px) + " px must be within 1.." +
                                std::to_string(std::min(camera.width, camera.height)) + " (the image's smaller side)");
  cols_ = (2 * camera.width + cell_size_px - 1) / cell_size_px;
  rows_ = (2 * camera.height + cell_size_px - 1) / cell_size_px;
  slot_.assign(static_cast<std::size_t>(cols_) * rows_, -1);
}

StoredCell& KeyframeContainer::findOrCreate(int grid_index) {
  ++revision_;
  std::int32_t& s = slot_[grid_index];
  if (s < 0) {
    s = static_cast<std::int32_t>(cells_.size());
    cells_.emplace_back();
    cells_.back().grid_index = grid_index;
  }
  return cells_[s];
}

std::size_t KeyframeContainer::memoryBytes() const {
  return slot_.capacity() * sizeof(std::int32_t) + cells_.capacity() * sizeof(StoredCell);
}

}  // namespace vdmap
