#include "render/lod_order.h"

#include <algorithm>
#include <cmath>

namespace vdmap::render {
namespace {

// An open-addressing set of 64-bit cell keys (the keys are never 0: see cellKey).
class CellSet {
 public:
  explicit CellSet(std::size_t expected) {
    std::size_t size = 16;
    while (size < 2 * expected) size *= 2;
    slots_.assign(size, 0);
  }
  // Inserts `key`; false when it was present.
  bool insert(std::uint64_t key) {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = mix(key) & mask;; i = (i + 1) & mask) {
      if (slots_[i] == key) return false;
      if (slots_[i] == 0) {
        slots_[i] = key;
        return true;
      }
    }
  }

 private:
  static std::size_t mix(std::uint64_t x) {  // splitmix64's finaliser
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    return static_cast<std::size_t>(x ^ (x >> 31));
  }
  std::vector<std::uint64_t> slots_;
};

// 21 bits per axis (cells within +-1M cells of the origin), with a set top bit so no key is 0.
std::uint64_t cellKey(const glm::vec3& p, float inv_size) {
  auto axis = [inv_size](float v) {
    const auto c = static_cast<std::int64_t>(std::floor(v * inv_size)) + (1 << 20);
    return static_cast<std::uint64_t>(std::clamp<std::int64_t>(c, 0, (1 << 21) - 1));
  };
  return (1ull << 63) | (axis(p.x) << 42) | (axis(p.y) << 21) | axis(p.z);
}

}  // namespace

std::vector<std::uint32_t> lodOrder(std::span<const glm::vec3> centres) {
  const std::size_t n = centres.size();
  std::vector<std::uint32_t> order;
  order.reserve(n);
  std::vector<std::uint8_t> taken(n, 0);
  std::vector<std::uint8_t> finite(n);
  for (std::size_t i = 0; i < n; ++i)
    finite[i] = std::isfinite(centres[i].x) && std::isfinite(centres[i].y) && std::isfinite(centres[i].z);
  for (const float size : kLodCellSizesM) {
    const float inv = 1.f / size;
    CellSet cells(n);
    // The cells the coarser levels' picks represent already.
    for (const std::uint32_t i : order) cells.insert(cellKey(centres[i], inv));
    for (std::size_t i = 0; i < n; ++i) {
      if (taken[i] || !finite[i] || !cells.insert(cellKey(centres[i], inv))) continue;
      taken[i] = 1;
      order.push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!taken[i] && finite[i]) order.push_back(static_cast<std::uint32_t>(i));
  for (std::size_t i = 0; i < n; ++i)
    if (!finite[i]) order.push_back(static_cast<std::uint32_t>(i));
  return order;
}

std::vector<std::uint32_t> lodOrder(std::span<const Ellipsoid> ellipsoids) {
  std::vector<glm::vec3> centres(ellipsoids.size());
  for (std::size_t i = 0; i < ellipsoids.size(); ++i)
    centres[i] = {ellipsoids[i].mean.x(), ellipsoids[i].mean.y(), ellipsoids[i].mean.z()};
  return lodOrder(centres);
}

}  // namespace vdmap::render
