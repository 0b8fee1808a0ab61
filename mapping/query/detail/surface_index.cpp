#include "mapping/query/detail/surface_index.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "mapping/core/box_tree.h"
#include "mapping/core/parallel.h"
#include "mapping/global_map/sorted_voxel_grid.h"

namespace vdmap {

namespace {

// Levels of the gate grid: voxel side g, 2g, 4g, ...; an ellipsoid sits at the finest level where
// its gate box spans at most 2 voxels per axis (so in at most 8 voxels), larger ones in a list
// every lookup scans. A lookup visits one voxel per non-empty level.
constexpr int kLevels = 12;
constexpr double kLevelRatio = 2.0;
// Gates a leaf of the box tree holds at most: 8 halves its nodes against 4 (each node 32 B), and
// a query's leaf tests are cheap lower bounds before the exact distance or entry.
constexpr std::uint32_t kTreeLeafSize = 8;

// An ellipsoid's gate as stored in 80 bytes (instead of an EllipsoidGate's 240): what the gate
// test reads first (mean, A's upper triangle), then the principal frame for distances and views.
// makeGate rounds the shape to float, so the float copies are exact, and the axes are rebuilt
// from the quaternion as makeGate built them. k^2 is the index's. (The mean stays in double: in
// whole 2^-20 m steps from the map's corner, 12 bytes less, it moved thin gates' squared gate
// distances enough to change p_occupied by up to 5e-5 where the classification tests look.)
struct StoredGate {
  double mean[3];
  float a[6];  // A00, A11, A22, A01, A02, A12
  float rotation[4];
  float semi_axes[3];

  void upper(double out[6]) const { std::copy(a, a + 6, out); }
  Eigen::Matrix3d matrixA() const {
    Eigen::Matrix3d m;
    m << a[0], a[3], a[4], a[3], a[1], a[5], a[4], a[5], a[2];
    return m;
  }
  Eigen::Vector3d semiAxes() const { return {semi_axes[0], semi_axes[1], semi_axes[2]}; }
  /// distanceToGate of this gate.
  double distance(double k2, const Eigen::Vector3d& q, Eigen::Vector3d* closest) const {
    double u[6];
    upper(u);
    return distanceToGate(mean, u, k2, axesFromQuaternion(rotation), semiAxes(), q, closest);
  }
};

// One level: the gate ranks sorted by (voxel key, rank), and an open-addressing table from a
// voxel key to its run of ranks, filled in key order (deterministic). The keys are in the table
// alone.
struct GridLevel {
  double side = 0;
  std::vector<std::int32_t> entries;
  struct Slot {  // one cache access per probe
    std::uint64_t key = kEmpty;
    std::uint32_t begin = 0, end = 0;
  };
  std::vector<Slot> slots;
  std::uint64_t mask = 0;
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};

  static std::uint64_t hash(std::uint64_t key) {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return key;
  }

  /// From the sorted (voxel key, rank) pairs.
  void build(const std::vector<std::pair<std::uint64_t, std::int32_t>>& pairs) {
    std::size_t voxels = 0;
    for (std::size_t i = 0; i < pairs.size(); ++i) voxels += i == 0 || pairs[i].first != pairs[i - 1].first;
    std::size_t size = 16;
    while (size < 2 * voxels) size *= 2;
    mask = size - 1;
    slots.assign(size, Slot{});
    for (std::size_t i = 0; i < pairs.size();) {
      std::size_t j = i;
      while (j < pairs.size() && pairs[j].first == pairs[i].first) ++j;
      std::uint64_t s = hash(pairs[i].first) & mask;
      while (slots[s].key != kEmpty) s = (s + 1) & mask;
      slots[s] = {pairs[i].first, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)};
      i = j;
    }
    entries.resize(pairs.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) entries[i] = pairs[i].second;
  }

  // The pairs of voxel `key`, or an empty run.
  std::pair<std::uint32_t, std::uint32_t> find(std::uint64_t key) const {
    if (entries.empty()) return {0, 0};
    for (std::uint64_t s = hash(key) & mask;; s = (s + 1) & mask) {
      if (slots[s].key == key) return {slots[s].begin, slots[s].end};
      if (slots[s].key == kEmpty) return {0, 0};
    }
  }

  std::size_t memoryBytes() const {
    return entries.capacity() * sizeof(std::int32_t) + slots.capacity() * sizeof(Slot);
  }
};

// Integer voxel coordinate of x along an axis, or nothing outside the key's range.
std::optional<std::int64_t> voxelCoord(double x, double origin, double side) {
  const double c = std::floor((x - origin) / side);
  if (!(c >= 0) || c > static_cast<double>(VoxelKey::kAxisMax)) return std::nullopt;
  return static_cast<std::int64_t>(c);
}

// The gate's box rounded outward to float and grown by a millionth of its size (and a nanometre),
// so that rounding in the gate kernels never puts a point or hit of the gate outside its box.
void gateBox(const EllipsoidGate& g, Eigen::Vector3f* lo, Eigen::Vector3f* hi) {
  const double pad = 1e-6 * g.half_extent.maxCoeff() + 1e-9;
  for (int a = 0; a < 3; ++a) {
    (*lo)[a] = std::nextafter(static_cast<float>(g.mean[a] - g.half_extent[a] - pad), -INFINITY);
    (*hi)[a] = std::nextafter(static_cast<float>(g.mean[a] + g.half_extent[a] + pad), INFINITY);
  }
}

}  // namespace

struct SurfaceIndex::Impl {
  double k2 = 0;
  // The gates in Morton order of their means (a lookup's candidates are neighbours, so they share
  // cache lines); per rank the ellipsoid's index and per ellipsoid its rank. The grid's entries
  // hold ranks.
  std::vector<StoredGate> gates;
  std::vector<std::int32_t> test_ellipsoid, rank_of;
  std::vector<int> levels_used;                      // the non-empty levels
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the grid's lower corner
  GridLevel levels[kLevels];
  std::vector<std::int32_t> oversize;  // the ranks of gates too large for every level, ascending
  std::optional<BoxTree> tree;         // over the gate boxes; its items are ranks
};

SurfaceIndex SurfaceIndex::build(const std::vector<Ellipsoid>& ellipsoids_W, const QueryParams& params) {
  auto impl = std::make_shared<Impl>();
  const std::size_t n = ellipsoids_W.size();
  impl->k2 = params.gate_sigma * params.gate_sigma;
  std::vector<EllipsoidGate> gates(n);  // by index, while building
  parallelFor(params.threads, n,
              [&](std::size_t i) { gates[i] = makeGate(ellipsoids_W[i], params.gate_sigma, params.min_sigma_m); });
  std::vector<Eigen::Vector3f> lo(n), hi(n);
  parallelFor(params.threads, n, [&](std::size_t i) { gateBox(gates[i], &lo[i], &hi[i]); });
  if (n == 0) {
    impl->tree.emplace(lo, hi);
    SurfaceIndex index;
    index.impl_ = std::move(impl);
    return index;
  }

  // The gate grid: finest side twice the median gate half-width (docs/method.md 13.4), at least
  // what keeps the map's extent within a key.
  std::vector<double> half(n);
  Eigen::Vector3d lo_all = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi_all = -lo_all;
  for (std::size_t i = 0; i < n; ++i) {
    half[i] = gates[i].half_extent.maxCoeff();
    lo_all = lo_all.cwiseMin(lo[i].cast<double>());
    hi_all = hi_all.cwiseMax(hi[i].cast<double>());
  }
  std::nth_element(half.begin(), half.begin() + n / 2, half.end());
  const double extent = (hi_all - lo_all).maxCoeff();
  double side = std::max({2.0 * half[n / 2], 1e-6, extent / static_cast<double>(VoxelKey::kAxisMax - 2)});
  impl->origin = lo_all;

  // Gate tests in Morton order of the means at the finest side (ties: index), ranks in the grid.
  {
    const auto spread = [](std::uint64_t v) {  // 21 bits -> every third bit of 63
      v &= 0x1fffff;
      v = (v | v << 32) & 0x1f00000000ffffULL;
      v = (v | v << 16) & 0x1f0000ff0000ffULL;
      v = (v | v << 8) & 0x100f00f00f00f00fULL;
      v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
      v = (v | v << 2) & 0x1249249249249249ULL;
      return v;
    };
    std::vector<std::pair<std::uint64_t, std::int32_t>> order(n);
    parallelFor(params.threads, n, [&](std::size_t i) {
      std::uint64_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const double c = std::clamp(std::floor((gates[i].mean[a] - impl->origin[a]) / side), 0.0,
                                    static_cast<double>(VoxelKey::kAxisMax));
        code |= spread(static_cast<std::uint64_t>(c)) << a;
      }
      order[i] = {code, static_cast<std::int32_t>(i)};
    });
    parallelSort(params.threads, order.begin(), order.end());
    impl->gates.resize(n);
    impl->test_ellipsoid.resize(n);
    impl->rank_of.resize(n);
    parallelFor(params.threads, n, [&](std::size_t r) {
      const EllipsoidGate& g = gates[static_cast<std::size_t>(order[r].second)];
      StoredGate& s = impl->gates[r];
      std::copy(g.mean.data(), g.mean.data() + 3, s.mean);
      double a[6];
      gateUpper(g, a);
      for (int k = 0; k < 6; ++k) s.a[k] = static_cast<float>(a[k]);
      for (int k = 0; k < 4; ++k) s.rotation[k] = g.rotation[k];
      for (int k = 0; k < 3; ++k) s.semi_axes[k] = static_cast<float>(g.semi_axes[k]);
      impl->test_ellipsoid[r] = order[r].second;
      impl->rank_of[static_cast<std::size_t>(order[r].second)] = static_cast<std::int32_t>(r);
    });
  }
  // The box tree's items are ranks too: a leaf's gates are neighbours in memory, one lookup away.
  {
    std::vector<Eigen::Vector3f> lo_r(n), hi_r(n);
    for (std::size_t r = 0; r < n; ++r) {
      const auto i = static_cast<std::size_t>(impl->test_ellipsoid[r]);
      lo_r[r] = lo[i], hi_r[r] = hi[i];
    }
    impl->tree.emplace(lo_r, hi_r, kTreeLeafSize);
  }

  // Per ellipsoid its level and its voxels there.
  std::vector<int> level_of(n, kLevels);
  for (int l = 0; l < kLevels; ++l) impl->levels[l].side = side * std::pow(kLevelRatio, l);
  parallelFor(params.threads, n, [&](std::size_t i) {
    for (int l = 0; l < kLevels; ++l) {
      const double s = impl->levels[l].side;
      bool fits = true;
      for (int a = 0; a < 3 && fits; ++a)
        fits = std::floor((hi[i][a] - impl->origin[a]) / s) - std::floor((lo[i][a] - impl->origin[a]) / s) <= 1;
      if (fits) {
        level_of[i] = l;
        return;
      }
    }
  });
  for (int l = 0; l < kLevels; ++l) {
    GridLevel& level = impl->levels[l];
    std::vector<std::pair<std::uint64_t, std::int32_t>> pairs;
    for (std::size_t r = 0; r < n; ++r) {
      const auto i = static_cast<std::size_t>(impl->test_ellipsoid[r]);
      if (level_of[i] != l) continue;
      std::int64_t c0[3], c1[3];
      for (int a = 0; a < 3; ++a) {
        c0[a] = static_cast<std::int64_t>(std::floor((lo[i][a] - impl->origin[a]) / level.side));
        c1[a] = static_cast<std::int64_t>(std::floor((hi[i][a] - impl->origin[a]) / level.side));
        c0[a] = std::clamp<std::int64_t>(c0[a], 0, VoxelKey::kAxisMax);
        c1[a] = std::clamp<std::int64_t>(c1[a], 0, VoxelKey::kAxisMax);
      }
      for (std::int64_t x = c0[0]; x <= c1[0]; ++x)
        for (std::int64_t y = c0[1]; y <= c1[1]; ++y)
          for (std::int64_t z = c0[2]; z <= c1[2]; ++z)
            pairs.push_back({VoxelKey::pack(x, y, z), static_cast<std::int32_t>(r)});
    }
    parallelSort(params.threads, pairs.begin(), pairs.end());
    level.build(pairs);
    if (!level.entries.empty()) impl->levels_used.push_back(l);
  }
  for (std::size_t r = 0; r < n; ++r)
    if (level_of[static_cast<std::size_t>(impl->test_ellipsoid[r])] == kLevels)
      impl->oversize.push_back(static_cast<std::int32_t>(r));

  SurfaceIndex index;
  index.impl_ = std::move(impl);
  return index;
}

std::size_t SurfaceIndex::size() const { return impl_ ? impl_->gates.size() : 0; }

std::size_t SurfaceIndex::memoryBytes() const {
  if (!impl_) return 0;
  std::size_t bytes = impl_->gates.capacity() * sizeof(StoredGate) + impl_->test_ellipsoid.capacity() * 4 +
                      impl_->rank_of.capacity() * 4 + impl_->oversize.capacity() * 4;
  for (const GridLevel& level : impl_->levels) bytes += level.memoryBytes();
  return bytes + impl_->tree->memoryBytes();
}

std::int32_t SurfaceIndex::ellipsoidAtRank(std::size_t r) const { return impl_->test_ellipsoid[r]; }

Eigen::Vector3d SurfaceIndex::normalOf(std::size_t i, const Eigen::Vector3d& p) const {
  const StoredGate& s = impl_->gates[static_cast<std::size_t>(impl_->rank_of[i])];
  return gateNormal(s.matrixA(), Eigen::Vector3d(s.mean), p);
}

EllipsoidGate SurfaceIndex::rayGateOf(std::size_t i) const {
  const StoredGate& s = impl_->gates[static_cast<std::size_t>(impl_->rank_of[i])];
  EllipsoidGate g;
  g.mean = Eigen::Vector3d(s.mean);
  g.A = s.matrixA();
  g.k2 = impl_->k2;
  return g;
}

EllipsoidGate SurfaceIndex::gateAtRank(std::size_t r) const {
  const StoredGate& s = impl_->gates[r];
  EllipsoidGate g;
  g.mean = Eigen::Vector3d(s.mean);
  g.A = s.matrixA();
  g.rotation = Eigen::Vector4f(s.rotation);
  g.axes = axesFromQuaternion(s.rotation);
  g.semi_axes = s.semiAxes();
  g.k2 = impl_->k2;
  return g;
}

Eigen::Vector4d SurfaceIndex::ballAtRank(std::size_t r) const {
  const StoredGate& s = impl_->gates[r];
  const Eigen::Vector3d m = Eigen::Vector3d(s.mean);
  return {m.x(), m.y(), m.z(), s.semi_axes[0]};
}

std::pair<std::int32_t, double> SurfaceIndex::gate(const Eigen::Vector3d& q_W) const {
  std::pair<std::int32_t, double> best{-1, std::numeric_limits<double>::infinity()};
  if (!impl_) return best;
  const auto consider = [&](std::int32_t r) {  // a test's rank (Morton order)
    const StoredGate& g = impl_->gates[static_cast<std::size_t>(r)];
    const Eigen::Vector3d m = Eigen::Vector3d(g.mean);
    const double m2 = gateQuadratic(q_W.x() - m.x(), q_W.y() - m.y(), q_W.z() - m.z(), g.a[0], g.a[1], g.a[2], g.a[3],
                                    g.a[4], g.a[5]);
    if (m2 > impl_->k2 || m2 > best.second) return;
    const std::int32_t i = impl_->test_ellipsoid[static_cast<std::size_t>(r)];
    if (m2 < best.second || i < best.first) best = {i, m2};
  };
  for (const int l : impl_->levels_used) {
    const GridLevel& level = impl_->levels[l];
    const auto x = voxelCoord(q_W.x(), impl_->origin.x(), level.side);
    const auto y = voxelCoord(q_W.y(), impl_->origin.y(), level.side);
    const auto z = voxelCoord(q_W.z(), impl_->origin.z(), level.side);
    if (!x || !y || !z) continue;
    const auto [b, e] = level.find(VoxelKey::pack(*x, *y, *z));
    for (std::uint32_t k = b; k < e; ++k) consider(level.entries[k]);
  }
  for (const std::int32_t i : impl_->oversize) consider(i);
  return best;
}

SurfaceIndex::Nearest SurfaceIndex::nearest(const Eigen::Vector3d& q_W, double max_distance) const {
  Nearest best;
  if (!impl_ || impl_->gates.empty()) return best;
  const auto inside = gate(q_W);
  if (inside.first >= 0) {
    best.ellipsoid = inside.first, best.distance = 0, best.closest = q_W;
    return best;
  }
  const Impl& im = *impl_;
  const auto index_at = [&](std::uint32_t r) { return static_cast<std::uint32_t>(im.test_ellipsoid[r]); };
  const auto [r, d2] = im.tree->nearest(
      q_W,
      [&](std::uint32_t j, const Eigen::Vector3d& q, double bound) {
        const StoredGate& g = im.gates[j];
        // A lower bound first (with slack for rounding): the coin that holds the gate (|offset
        // along the shortest axis| <= e2, across it <= e0), tight for the flat patches of a
        // surface, of which many are almost equally near a point far from them. The shortest
        // axis is the quaternion's rotation's third column.
        const Eigen::Vector3d r = q - Eigen::Vector3d(g.mean);
        const double x = g.rotation[0], y = g.rotation[1], z = g.rotation[2], w = g.rotation[3];
        const Eigen::Vector3d normal =
            Eigen::Vector3d(2 * (x * z + w * y), 2 * (y * z - w * x), w * w + z * z - x * x - y * y) /
            (x * x + y * y + z * z + w * w);
        const double h = r.dot(normal);
        const double across = std::sqrt(std::max(0.0, r.squaredNorm() - h * h));
        const double dh = std::max(0.0, std::abs(h) - g.semi_axes[2]), da = std::max(0.0, across - g.semi_axes[0]);
        const double lower2 = dh * dh + da * da;
        if (lower2 > bound * (1 + 1e-9) + 1e-18) return lower2;
        const double d = g.distance(im.k2, q, nullptr);
        return d * d;
      },
      max_distance * max_distance, index_at);
  if (r < 0) return best;
  best.ellipsoid = im.test_ellipsoid[static_cast<std::size_t>(r)];
  best.distance = im.gates[static_cast<std::size_t>(r)].distance(im.k2, q_W, &best.closest);
  (void)d2;
  return best;
}

SurfaceIndex::Hit SurfaceIndex::firstHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t) const {
  Hit best;
  if (!impl_ || impl_->gates.empty()) return best;
  const Impl& im = *impl_;
  const auto [r, t] = im.tree->firstHit(
      o, d, max_t,
      [&](std::uint32_t j, double bound) {
        const StoredGate& g = im.gates[j];
        double a[6];
        g.upper(a);
        return gateRayEntry(a, gateRayOrigin(g.mean, a, im.k2, o), d, bound);
      },
      [&](std::uint32_t j) { return im.test_ellipsoid[j]; });
  if (r >= 0) best = {im.test_ellipsoid[static_cast<std::size_t>(r)], t};
  return best;
}

}  // namespace vdmap
