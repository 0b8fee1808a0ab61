#include "mapping/global_map/sorted_voxel_grid.h"

namespace vdmap {

void SortedVoxelGrid::findVoxels(int threads) {
  const std::size_t n = entries_.size();
  voxel_start_.clear(), voxel_.clear();
  for (std::size_t k = 0; k < n; ++k)
    if (k == 0 || entries_[k].first != entries_[k - 1].first) {
      voxel_start_.push_back(k);
      voxel_.push_back(entries_[k].first);
    }
  const std::size_t voxels = voxel_.size();
  voxel_start_.push_back(n);
  // Adding an offset keeps the voxels' order, so one pointer per offset walks the sorted list.
  neighbour_.resize(voxels);
  parallelFor(threads, kForwardNeighbours, [&](std::size_t o) {
    const int c = 14 + static_cast<int>(o);  // (dx, dy, dz) = (c % 3, c / 3 % 3, c / 9) - 1
    std::size_t u = 0;
    for (std::size_t v = 0; v < voxels; ++v) {
      neighbour_[v][o] = -1;
      const std::int64_t x = VoxelKey::x(voxel_[v]) + c % 3 - 1;
      const std::int64_t y = VoxelKey::y(voxel_[v]) + c / 3 % 3 - 1;
      const std::int64_t z = VoxelKey::z(voxel_[v]) + c / 9 - 1;
      if (x < 0 || y < 0 || z < 0) continue;
      const std::uint64_t target = VoxelKey::pack(x, y, z);
      while (u < voxels && voxel_[u] < target) ++u;
      if (u < voxels && voxel_[u] == target) neighbour_[v][o] = static_cast<int>(u);
    }
  });
}

}  // namespace vdmap
