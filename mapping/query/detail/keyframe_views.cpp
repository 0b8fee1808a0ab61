#include "mapping/query/detail/keyframe_views.h"
#include "mapping/core/message_text.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Dense>

#include "mapping/core/parallel.h"
#include "mapping/local_map/sensor_model.h"

namespace vdmap {
namespace {

/// One kept cell as the queries use it (docs/method.md 13.1): mean and A = (Sigma + s0^2 I)^-1 in
/// the keyframe frame. The point's terms are taken relative to the mean (d = q - mu), so the gate
/// distance m^2 = d^T A d has no cancellation; a = q^T A q and q^T A d = a - b follow from A q.
/// Stored in 36 B (instead of 80 in double: the cells are most of the views' memory and every
/// cell read is a cache miss); the terms are evaluated in double. A is rounded to float (1e-7
/// relative, far below the sensor's noise); the mean as storedViewMean() (MeanCoder) reads it.
struct Cell {
  float a[6];            // A: xx xy xz yy yz zz
  float z;               // mu_z, the container's float mean's
  std::uint16_t ray[2];  // mu_x / mu_z and mu_y / mu_z, in MeanCoder's steps
  /// Two bounds along z (keyframe frame) as offsets from mu_z in kZUnit, rounded outwards
  /// (kZNone: unbounded). far: the farthest z of this cell's gate; a point behind it is neither in
  /// the gate nor in front of the surface (its ray's closest approach t* q/|q| lies in the gate).
  /// near: the nearest z of the gates of the 3x3 cells around this one; a point nearer lies in
  /// none of them (a gate spans mu_z +- k sqrt(Sigma'_zz) along z). Only rejections read them.
  std::uint16_t near_3x3, far;

  double zFar() const;
  double zNear3x3() const;
};
static_assert(sizeof(Cell) == 36);

constexpr double kZUnit = 1e-4;  // m: the z bounds' step (they reach 6.5 m)
constexpr std::uint16_t kZNone = 0xFFFF;
/// A bound's offset from mu_z in kZUnit, rounded up (kZNone when it does not fit).
std::uint16_t zOffset(double metres) {
  const double units = std::ceil(metres / kZUnit);
  return units < kZNone ? static_cast<std::uint16_t>(std::max(units, 0.0)) : kZNone;
}
double Cell::zFar() const { return far == kZNone ? std::numeric_limits<double>::infinity() : double(z) + far * kZUnit; }
double Cell::zNear3x3() const {
  return near_3x3 == kZNone ? -std::numeric_limits<double>::infinity() : double(z) - near_3x3 * kZUnit;
}

/// Which grid cells of a keyframe's box hold a kept cell: one bit per grid cell (row-major), and
/// per 64 of them the number of kept cells before. The cells are stored in the same order, so a
/// grid cell's kept cell is its rank among the set bits: 2 bits per grid cell instead of an
/// index and a bound (8 bytes).
struct OccupancyWord {
  std::uint64_t bits = 0;
  std::uint32_t before = 0;
};

constexpr int kTile = 8;  // grid cells per side of a visibility tile

/// Bounds of a gate along z rounded outwards (they reject, never accept).
constexpr double kZMargin = 1e-6;  // m

struct CellTerms {
  double m2;   // (q - mu)^T A (q - mu)
  double a;    // q^T A q
  double qad;  // q^T A (q - mu) = a - b
};

/// A kept cell's mean is stored as its z (the container's float) and its ray's tangents mu_x / mu_z
/// and mu_y / mu_z in 16 bits each, over the tangents of its grid cell's rays grown by half a
/// cell on each side (the mean of points seen through the cell lies in its cone): a step of
/// 1/32768 of a cell (2.3e-7 rad at 8 px and a 525 px focal length, 0.7 um at 3 m).
struct MeanCoder {
  double base[2] = {0, 0}, cell[2] = {1, 1}, step[2] = {1, 1};  // per axis u, v
  MeanCoder() = default;
  explicit MeanCoder(const KeyframeContainer& c) {
    const PinholeCamera& cam = c.camera();
    // Grid column j covers container pixels [j s - 0.5, (j + 1) s - 0.5), keyframe u = u' - offset.
    const double f[2] = {cam.fx, cam.fy}, centre[2] = {cam.cx, cam.cy};
    const int offset[2] = {c.offsetU(), c.offsetV()};
    for (int i = 0; i < 2; ++i) {
      cell[i] = c.cellSizePx() / f[i];
      base[i] = (-0.5 - offset[i] - centre[i]) / f[i] - 0.5 * cell[i];
      step[i] = 2.0 * cell[i] / 65535.0;
    }
  }
  std::uint16_t encode(int axis, int index, double tangent) const {
    const double s = std::round((tangent - (base[axis] + index * cell[axis])) / step[axis]);
    return static_cast<std::uint16_t>(std::clamp(s, 0.0, 65535.0));
  }
  /// The mean of a cell of container column col and row.
  Eigen::Vector3d decode(float z, const std::uint16_t ray[2], int col, int row) const {
    return {z * (base[0] + col * cell[0] + ray[0] * step[0]), z * (base[1] + row * cell[1] + ray[1] * step[1]), z};
  }
};

// A v for the cell's symmetric A, stored as its upper triangle (a0 a1 a2 / a3 a4 / a5).
inline Eigen::Vector3d timesA(const Cell& c, double x, double y, double z) {
  const double a0 = c.a[0], a1 = c.a[1], a2 = c.a[2], a3 = c.a[3], a4 = c.a[4], a5 = c.a[5];
  return {a0 * x + a1 * y + a2 * z, a1 * x + a3 * y + a4 * z, a2 * x + a4 * y + a5 * z};
}

// The gate's squared Mahalanobis distance (q - mu)^T A (q - mu).
inline double gate2(const Cell& c, const Eigen::Vector3d& mu, const Eigen::Vector3d& q) {
  const double dx = q.x() - mu.x(), dy = q.y() - mu.y(), dz = q.z() - mu.z();
  const Eigen::Vector3d ad = timesA(c, dx, dy, dz);
  return dx * ad.x() + dy * ad.y() + dz * ad.z();
}

inline CellTerms terms(const Cell& c, const Eigen::Vector3d& mu, const Eigen::Vector3d& q) {
  const double dx = q.x() - mu.x(), dy = q.y() - mu.y(), dz = q.z() - mu.z();
  const Eigen::Vector3d ad = timesA(c, dx, dy, dz), aq = timesA(c, q.x(), q.y(), q.z());
  return {dx * ad.x() + dy * ad.y() + dz * ad.z(), q.x() * aq.x() + q.y() * aq.y() + q.z() * aq.z(),
          q.x() * ad.x() + q.y() * ad.y() + q.z() * ad.z()};
}

/// One keyframe: its current pose, camera and container grid, and its kept cells.
struct View {
  Eigen::Matrix3d R_K_W = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_K_W = Eigen::Vector3d::Zero();
  double fx = 1, fy = 1, cx = 0, cy = 0;
  double width2 = 0, height2 = 0;  // 2W, 2H: the container's extent in container pixels
  double offset_u = 0, offset_v = 0;
  int cell_px = 1;
  MeanCoder coder;
  // The box of the kept cells grown by one, the container's grid cells [col0, col0 + cols) x
  // [row0, row0 + rows) (a point outside it has no kept cell among its 3x3): which of them hold a
  // kept cell, and those cells in the box's row-major order.
  int col0 = 0, row0 = 0, cols = 0, rows = 0;
  std::vector<OccupancyWord> occupied;  // empty when the keyframe has no kept cell
  std::vector<Cell> cells;
  int rank = 0;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  double z_max = 0;  // farthest gate along the optical axis (keyframe frame)
  /// Build only: per tile of kTile x kTile grid cells, the farthest zFar() of its kept cells
  /// (-inf: none), for the visibility index.
  std::vector<double> tile_z_far;
  int tile_cols = 0, tile_rows = 0;

  const OccupancyWord& wordOf(int row, int col) const {
    return occupied[(static_cast<std::size_t>(row) * cols + col) / 64];
  }
  /// The kept cell of the box's grid cell (row, col), or nullptr.
  const Cell* cellAt(int row, int col) const {
    const unsigned bit = (static_cast<unsigned>(row) * cols + col) % 64;
    const OccupancyWord& w = wordOf(row, col);
    if (!((w.bits >> bit) & 1)) return nullptr;
    return &cells[w.before + std::popcount(w.bits & ((std::uint64_t{1} << bit) - 1))];
  }

  /// The mean of `cell`, the kept cell of the box's grid cell (row, col).
  Eigen::Vector3d meanOf(const Cell& cell, int row, int col) const {
    return coder.decode(cell.z, cell.ray, col + col0, row + row0);
  }

  /// Keyframe-frame point, its grid column and row; false when the container does not hold it.
  bool locate(const Eigen::Vector3d& q_W, Eigen::Vector3d* q, int* col, int* row) const {
    if (cells.empty()) return false;
    *q = R_K_W * q_W + t_K_W;
    if (!(q->z() > 0.0)) return false;
    // As KeyframeContainer::gridIndexOfPixel (a container pixel covers [u' - 0.5, u' + 0.5)).
    const double u = fx * q->x() / q->z() + cx, v = fy * q->y() / q->z() + cy;
    const double up = u + offset_u + 0.5, vp = v + offset_v + 0.5;
    if (!(up >= 0.0 && vp >= 0.0 && up < width2 && vp < height2)) return false;
    *col = static_cast<int>(up) / cell_px - col0;
    *row = static_cast<int>(vp) / cell_px - row0;
    return *col >= 0 && *row >= 0 && *col < cols && *row < rows;
  }
};

/// One integrated frame's free space (docs/method.md 13.2) at its keyframe's current pose.
struct FrameView {
  Eigen::Matrix3d R_F_W = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_F_W = Eigen::Vector3d::Zero();
  int keyframe = 0;
  int cols = 0;
  const std::uint16_t* near_mm = nullptr;  // into KeyframeViews::Impl::blocks
  double z_max = 0;                        // farthest block, m
};

/// Per voxel of a grid over a box, the ascending ids of the items (keyframes or frames) that may
/// see it: ids[begin[v] .. begin[v + 1]).
struct VoxelLists {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double voxel_m = 0.25;
  int nx = 0, ny = 0, nz = 0;
  std::vector<std::uint32_t> begin;
  std::vector<std::int32_t> ids;

  std::span<const std::int32_t> at(const Eigen::Vector3d& q_W) const {
    if (nx == 0) return {};
    const Eigen::Vector3d f = (q_W - origin) / voxel_m;
    if (!(f.x() >= 0 && f.y() >= 0 && f.z() >= 0 && f.x() < nx && f.y() < ny && f.z() < nz)) return {};
    const std::size_t v =
        (static_cast<std::size_t>(f.z()) * ny + static_cast<std::size_t>(f.y())) * nx + static_cast<std::size_t>(f.x());
    return {ids.data() + begin[v], ids.data() + begin[v + 1]};
  }
  std::size_t memoryBytes() const {
    return begin.capacity() * sizeof(std::uint32_t) + ids.capacity() * sizeof(std::int32_t);
  }
};

/// Lists over the box [lo, hi] in voxels of at least `min_voxel_m` (coarser when the box would
/// need more than 2^23 of them: the index stays under ~40 MB). Item i lists a voxel of its box
/// [item_lo[i], item_hi[i]] when mayTouch(i, voxel centre, bounding radius) says so.
template <typename MayTouch>
VoxelLists buildVoxelLists(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double min_voxel_m,
                           const std::vector<Eigen::Vector3d>& item_lo, const std::vector<Eigen::Vector3d>& item_hi,
                           int threads, const MayTouch& mayTouch) {
  VoxelLists out;
  if (!(lo.x() <= hi.x())) return out;
  const std::size_t n = item_lo.size();
  const Eigen::Vector3d extent = hi - lo;
  const double volume = (extent.array() + 2 * min_voxel_m).prod();
  out.voxel_m = std::max(min_voxel_m, std::cbrt(volume / double(1 << 23)) * 1.01);
  out.origin = lo;
  out.nx = static_cast<int>(std::floor(extent.x() / out.voxel_m)) + 1;
  out.ny = static_cast<int>(std::floor(extent.y() / out.voxel_m)) + 1;
  out.nz = static_cast<int>(std::floor(extent.z() / out.voxel_m)) + 1;
  const std::size_t voxels = static_cast<std::size_t>(out.nx) * out.ny * out.nz;
  std::vector<std::vector<std::uint32_t>> touched(n);
  const double voxel = out.voxel_m, radius = 0.5 * std::sqrt(3.0) * voxel;
  parallelFor(threads, n, [&](std::size_t id) {
    if (!(item_lo[id].x() <= item_hi[id].x())) return;
    const Eigen::Vector3i a = ((item_lo[id] - out.origin) / voxel).array().floor().cast<int>().max(0);
    const Eigen::Vector3i b = ((item_hi[id] - out.origin) / voxel).array().floor().cast<int>();
    for (int z = a.z(); z <= std::min(b.z(), out.nz - 1); ++z)
      for (int y = a.y(); y <= std::min(b.y(), out.ny - 1); ++y)
        for (int x = a.x(); x <= std::min(b.x(), out.nx - 1); ++x) {
          const Eigen::Vector3d centre = out.origin + voxel * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
          if (mayTouch(id, centre, radius))
            touched[id].push_back(static_cast<std::uint32_t>((static_cast<std::size_t>(z) * out.ny + y) * out.nx + x));
        }
  });
  // Counting sort by voxel; filling in id order keeps each voxel's list ascending.
  std::size_t pairs = 0;
  for (const auto& t : touched) pairs += t.size();
  if (pairs > std::numeric_limits<std::uint32_t>::max())  // ~16 GB of lists: thousands of keyframes
    throw std::invalid_argument("the visibility index would list " + std::to_string(pairs) +
                                " (voxel, item) pairs, more than it can address");
  out.begin.assign(voxels + 1, 0);
  for (const auto& t : touched)
    for (std::uint32_t vox : t) ++out.begin[vox + 1];
  for (std::size_t i = 0; i < voxels; ++i) out.begin[i + 1] += out.begin[i];
  out.ids.resize(out.begin[voxels]);
  std::vector<std::uint32_t> fill(out.begin.begin(), out.begin.end() - 1);
  for (std::size_t id = 0; id < n; ++id)
    for (std::uint32_t vox : touched[id]) out.ids[fill[vox]++] = static_cast<std::int32_t>(id);
  return out;
}

}  // namespace

struct KeyframeViews::Impl {
  QueryParams params;
  double k = 3, k2 = 9;
  std::vector<View> views;
  // Visibility index (docs/method.md 13.1): a dense voxel grid over the seen box; per voxel the
  // ascending ids of the keyframes whose cut frustum may touch it.
  VoxelLists index;
  // The integrated frames' free space (docs/method.md 13.2), keyframe by keyframe in their order:
  // keyframe K's are frames[first_frame[K] .. first_frame[K + 1]); their blocks, and their index.
  PinholeCamera camera;
  std::vector<FrameView> frames;
  std::vector<std::uint32_t> first_frame;
  std::vector<std::uint16_t> blocks;
  VoxelLists frame_index;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

  ViewVerdict verdict(const View& view, const Eigen::Vector3d& q_W) const {
    Eigen::Vector3d q;
    int col = 0, row = 0;
    if (!view.locate(q_W, &q, &col, &row)) return {};
    return verdictAt(view, q, col, row);
  }

  /// verdict() of a point located in the view (keyframe frame q, its grid column and row).
  ViewVerdict verdictAt(const View& view, const Eigen::Vector3d& q, int col, int row) const {
    ViewVerdict out;
    // Occupied: the nearest gate among the 3x3 cells (a gate reaches past its cell's border).
    double best_m2 = std::numeric_limits<double>::infinity();
    const Cell* best = nullptr;
    Eigen::Vector3d best_mu = Eigen::Vector3d::Zero();
    for (int r = std::max(row - 1, 0); r <= std::min(row + 1, view.rows - 1); ++r)
      for (int c = std::max(col - 1, 0); c <= std::min(col + 1, view.cols - 1); ++c) {
        const Cell* cell = view.cellAt(r, c);
        if (cell == nullptr || !(q.z() < cell->zFar())) continue;  // behind the gate: m^2 > k^2
        const Eigen::Vector3d mu = view.meanOf(*cell, r, c);
        const double m2 = gate2(*cell, mu, q);
        if (m2 < best_m2) best_m2 = m2, best = cell, best_mu = mu;
      }
    if (best != nullptr && best_m2 <= k2) {
      const CellTerms t = terms(*best, best_mu, q);
      out.state = Occupancy::kOccupied;
      out.m2 = best_m2;
      out.z = t.qad / std::sqrt(t.a);
      out.sigma_t = q.norm() / std::sqrt(t.a);
      return out;
    }
    const Cell* own = view.cellAt(row, col);
    if (own == nullptr) return out;
    const CellTerms t = terms(*own, view.meanOf(*own, row, col), q);
    const double sqrt_a = std::sqrt(t.a);
    out.z = t.qad / sqrt_a;
    out.m2 = t.m2;
    out.sigma_t = q.norm() / sqrt_a;
    // Free: in front of the surface by more than k sigma along the ray, and the ray meets the
    // cell's ellipsoid within its gate (m_lat^2 = m^2 - z^2 <= k^2).
    if (out.z < -k && t.m2 - out.z * out.z <= k2) out.state = Occupancy::kFree;
    return out;
  }

  /// verdict() == kFree for a point located in the view, `cell` its own grid cell's kept cell.
  bool isFreeAt(const View& view, const Eigen::Vector3d& q, int col, int row, const Cell& cell,
                ViewVerdict* out) const {
    if (!(q.z() < cell.zFar())) return false;  // behind the gate: not in front of the surface
    const CellTerms t = terms(cell, view.meanOf(cell, row, col), q);
    const double sqrt_a = std::sqrt(t.a);
    const double z = t.qad / sqrt_a;
    if (!(z < -k && t.m2 - z * z <= k2)) return false;
    // No gate of the 3x3 cells may hold the point (the own cell's cannot: m^2 >= z^2 > k^2);
    // none can when the point is nearer than all of them (nearly always: free is far in front).
    if (!(q.z() < cell.zNear3x3()))
      for (int r = std::max(row - 1, 0); r <= std::min(row + 1, view.rows - 1); ++r)
        for (int c = std::max(col - 1, 0); c <= std::min(col + 1, view.cols - 1); ++c) {
          const Cell* other = view.cellAt(r, c);
          if (other != nullptr && gate2(*other, view.meanOf(*other, r, c), q) <= k2) return false;
        }
    out->state = Occupancy::kFree;
    out->z = z;
    out->m2 = t.m2;
    out->sigma_t = q.norm() / sqrt_a;
    return true;
  }

  /// Calls visit(id, verdict) for each of `ids` in turn until it returns false; the 3x3 cells'
  /// occupancy words, then the cells, of each batch of candidates are prefetched first (as firstFree).
  template <typename Visit>
  void scanVerdicts(std::span<const std::int32_t> ids, const Eigen::Vector3d& q_W, const Visit& visit) const {
    constexpr std::size_t kBatch = 8;
    struct Located {
      const View* view;
      Eigen::Vector3d q;
      int col, row;
      bool ok;
    };
    Located loc[kBatch];
    for (std::size_t start = 0; start < ids.size(); start += kBatch) {
      const std::size_t m = std::min(kBatch, ids.size() - start);
      for (std::size_t j = 0; j < m; ++j) {
        Located& l = loc[j];
        l.view = &views[static_cast<std::size_t>(ids[start + j])];
        l.ok = l.view->locate(q_W, &l.q, &l.col, &l.row);
        if (!l.ok) continue;
        for (int r = std::max(l.row - 1, 0); r <= std::min(l.row + 1, l.view->rows - 1); ++r) {
          __builtin_prefetch(&l.view->wordOf(r, std::max(l.col - 1, 0)));
          __builtin_prefetch(&l.view->wordOf(r, std::min(l.col + 1, l.view->cols - 1)));
        }
      }
      for (std::size_t j = 0; j < m; ++j) {  // the 3x3's cells: a row's are contiguous
        const Located& l = loc[j];
        if (!l.ok) continue;
        for (int r = std::max(l.row - 1, 0); r <= std::min(l.row + 1, l.view->rows - 1); ++r) {
          const Cell *first = nullptr, *last = nullptr;
          for (int c = std::max(l.col - 1, 0); c <= std::min(l.col + 1, l.view->cols - 1); ++c)
            if (const Cell* cell = l.view->cellAt(r, c)) last = cell, first = first != nullptr ? first : cell;
          if (first == nullptr) continue;
          __builtin_prefetch(first);
          __builtin_prefetch(reinterpret_cast<const char*>(last + 1) - 1);
        }
      }
      for (std::size_t j = 0; j < m; ++j) {
        const Located& l = loc[j];
        if (!visit(ids[start + j], l.ok ? verdictAt(*l.view, l.q, l.col, l.row) : ViewVerdict{})) return;
      }
    }
  }

  /// The first of `ids` (in their order) whose verdict is free, or -1: verdict() == kFree without
  /// the occupied answer's terms, the fast path of ConflictRule::kOccupied. Candidates go in
  /// batches: each batch's occupancy words, then cells, are prefetched before any is read, so that their
  /// cache misses overlap instead of following one another (the answer is the sequential one).
  int firstFree(std::span<const std::int32_t> ids, const Eigen::Vector3d& q_W, ViewVerdict* out) const {
    constexpr std::size_t kBatch = 8;
    struct Located {
      const View* view;
      Eigen::Vector3d q;
      int col, row;
      const Cell* cell;
    };
    Located loc[kBatch];
    for (std::size_t start = 0; start < ids.size(); start += kBatch) {
      const std::size_t m = std::min(kBatch, ids.size() - start);
      for (std::size_t j = 0; j < m; ++j) {
        Located& l = loc[j];
        l.view = &views[static_cast<std::size_t>(ids[start + j])];
        l.cell = nullptr;
        if (!l.view->locate(q_W, &l.q, &l.col, &l.row)) {
          l.view = nullptr;
          continue;
        }
        __builtin_prefetch(&l.view->wordOf(l.row, l.col));
      }
      for (std::size_t j = 0; j < m; ++j) {
        Located& l = loc[j];
        if (l.view == nullptr) continue;
        l.cell = l.view->cellAt(l.row, l.col);
        if (l.cell == nullptr) continue;
        __builtin_prefetch(l.cell);
        __builtin_prefetch(reinterpret_cast<const char*>(l.cell) + sizeof(Cell) - 1);
      }
      for (std::size_t j = 0; j < m; ++j) {
        const Located& l = loc[j];
        if (l.cell != nullptr && isFreeAt(*l.view, l.q, l.col, l.row, *l.cell, out)) return ids[start + j];
      }
    }
    return -1;
  }

  std::span<const std::int32_t> candidates(const Eigen::Vector3d& q_W) const { return index.at(q_W); }

  /// Frame f's verdict: free when q_W projects into a block with depth and lies nearer than the
  /// block's nearest depth d by more than k sigma (sigma^2 = the sensor's axial variance at d +
  /// s0^2); otherwise none.
  bool frameFree(const FrameView& f, const Eigen::Vector3d& q_W, ViewVerdict* out) const {
    Eigen::Vector3d q;
    const std::uint16_t* block = frameBlock(f, q_W, &q);
    return block != nullptr && blockFree(*block, q, out);
  }

  /// The block of frame f that q_W (frame coordinates q) projects into, or nullptr.
  const std::uint16_t* frameBlock(const FrameView& f, const Eigen::Vector3d& q_W, Eigen::Vector3d* q) const {
    *q = f.R_F_W * q_W + f.t_F_W;
    if (!(q->z() > 0.0)) return nullptr;
    const double u = camera.fx * q->x() / q->z() + camera.cx, v = camera.fy * q->y() / q->z() + camera.cy;
    if (!(u >= 0.0 && v >= 0.0 && u < camera.width && v < camera.height)) return nullptr;
    return &f.near_mm[static_cast<std::size_t>(static_cast<int>(v) / kFreeBlockPx) * f.cols +
                      static_cast<int>(u) / kFreeBlockPx];
  }

  /// frameFree() of a point q (frame coordinates) in the block of nearest depth `mm`.
  bool blockFree(std::uint16_t mm, const Eigen::Vector3d& q, ViewVerdict* out) const {
    if (mm == 0) return false;
    const double d = 1e-3 * mm, sd = nguyenAxialSd(d);
    const double sigma = std::sqrt(sd * sd + params.min_sigma_m * params.min_sigma_m);
    const double z = (q.z() - d) / sigma;
    if (!(z < -k)) return false;
    out->state = Occupancy::kFree;
    out->z = z;
    out->sigma_t = sigma;
    out->m2 = 0;
    return true;
  }

  /// The keyframe of the first frame (in their order) of `ids` that sees q_W free, or -1.
  int firstFreeFrame(std::span<const std::int32_t> ids, const Eigen::Vector3d& q_W, ViewVerdict* out) const {
    for (const std::int32_t id : ids) {
      const FrameView& f = frames[static_cast<std::size_t>(id)];
      if (frameFree(f, q_W, out)) return f.keyframe;
    }
    return -1;
  }
};

namespace {

/// Builds one keyframe's view: its cells (pose-independent), then its world box and frustum bound.
View makeView(const Keyframe& kf, const std::vector<bool>& kept, double s0, double k, int rank) {
  View v;
  const KeyframeContainer& container = kf.container;
  const PinholeCamera& cam = container.camera();
  const Transform T_K_W = kf.T_W_K.inverse();
  v.R_K_W = T_K_W.linear();
  v.t_K_W = T_K_W.translation();
  v.fx = cam.fx, v.fy = cam.fy, v.cx = cam.cx, v.cy = cam.cy;
  v.width2 = 2.0 * cam.width, v.height2 = 2.0 * cam.height;
  v.offset_u = container.offsetU(), v.offset_v = container.offsetV();
  v.cell_px = container.cellSizePx();
  v.coder = MeanCoder(container);
  v.rank = rank;
  const auto& cells = container.cells();
  std::size_t n_kept = 0;
  int c_lo = container.cols(), c_hi = -1, r_lo = container.rows(), r_hi = -1;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (!kept[i]) continue;
    ++n_kept;
    const int col = cells[i].grid_index % container.cols(), row = cells[i].grid_index / container.cols();
    c_lo = std::min(c_lo, col), c_hi = std::max(c_hi, col), r_lo = std::min(r_lo, row), r_hi = std::max(r_hi, row);
  }
  if (n_kept == 0) return v;
  v.col0 = std::max(c_lo - 1, 0), v.row0 = std::max(r_lo - 1, 0);
  v.cols = std::min(c_hi + 1, container.cols() - 1) - v.col0 + 1;
  v.rows = std::min(r_hi + 1, container.rows() - 1) - v.row0 + 1;
  // Per grid cell of the box, its kept cell's index in the container (-1: none).
  const std::size_t box = static_cast<std::size_t>(v.cols) * v.rows;
  std::vector<std::int32_t> source(box, -1);
  for (std::size_t i = 0; i < cells.size(); ++i)
    if (kept[i])
      source[static_cast<std::size_t>(cells[i].grid_index / container.cols() - v.row0) * v.cols +
             static_cast<std::size_t>(cells[i].grid_index % container.cols() - v.col0)] = static_cast<std::int32_t>(i);
  v.occupied.assign((box + 63) / 64, OccupancyWord{});
  std::vector<double> z_near(box, std::numeric_limits<double>::infinity());
  v.cells.reserve(n_kept);
  v.tile_cols = (v.cols + kTile - 1) / kTile, v.tile_rows = (v.rows + kTile - 1) / kTile;
  v.tile_z_far.assign(static_cast<std::size_t>(v.tile_cols) * v.tile_rows, -std::numeric_limits<double>::infinity());
  const Eigen::Matrix3d R_W_K = kf.T_W_K.linear();
  const Eigen::Vector3d centre_W = kf.T_W_K.translation();
  v.lo = v.hi = centre_W;
  v.z_max = 0;
  for (std::size_t at = 0; at < box; ++at) {
    if (source[at] < 0) continue;
    const StoredCell& stored = cells[static_cast<std::size_t>(source[at])];
    const Ellipsoid e = cellEllipsoid(stored, Transform::Identity(), 0);
    const Eigen::Matrix3d cov = e.cov + s0 * s0 * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d A = cov.inverse();
    Cell c;
    const double upper[6] = {A(0, 0), A(0, 1), A(0, 2), A(1, 1), A(1, 2), A(2, 2)};
    for (int j = 0; j < 6; ++j) c.a[j] = static_cast<float>(upper[j]);
    const int row = static_cast<int>(at / static_cast<std::size_t>(v.cols)), col = static_cast<int>(at % v.cols);
    c.z = stored.mean.z();
    c.ray[0] = v.coder.encode(0, col + v.col0, double(stored.mean.x()) / stored.mean.z());
    c.ray[1] = v.coder.encode(1, row + v.row0, double(stored.mean.y()) / stored.mean.z());
    const Eigen::Vector3d mean = v.meanOf(c, row, col);
    const double half_z = k * std::sqrt(cov(2, 2));
    c.far = zOffset(half_z + kZMargin);
    z_near[at] = mean.z() - half_z - kZMargin;
    v.occupied[at / 64].bits |= std::uint64_t{1} << (at % 64);
    v.cells.push_back(c);
    double& tile = v.tile_z_far[static_cast<std::size_t>(row / kTile) * v.tile_cols + col / kTile];
    tile = std::max(tile, c.zFar());
    // Every point with a verdict lies in a gate or on the segment from the centre to a gate:
    // inside the box of the centre and the gates' boxes, and no farther along z than a gate.
    v.z_max = std::max(v.z_max, mean.z() + half_z);
    const Eigen::Matrix3d cov_W = R_W_K * cov * R_W_K.transpose();
    const Eigen::Vector3d half = k * cov_W.diagonal().cwiseSqrt();
    const Eigen::Vector3d mean_W = kf.T_W_K * mean;
    v.lo = v.lo.cwiseMin(mean_W - half);
    v.hi = v.hi.cwiseMax(mean_W + half);
  }
  for (std::size_t w = 1; w < v.occupied.size(); ++w)
    v.occupied[w].before = v.occupied[w - 1].before + static_cast<std::uint32_t>(std::popcount(v.occupied[w - 1].bits));
  std::size_t next = 0;
  for (int row = 0; row < v.rows; ++row)
    for (int col = 0; col < v.cols; ++col) {
      const std::size_t at = static_cast<std::size_t>(row) * v.cols + col;
      if (source[at] < 0) continue;
      double nearest = std::numeric_limits<double>::infinity();
      for (int r = std::max(row - 1, 0); r <= std::min(row + 1, v.rows - 1); ++r)
        for (int c = std::max(col - 1, 0); c <= std::min(col + 1, v.cols - 1); ++c)
          nearest = std::min(nearest, z_near[static_cast<std::size_t>(r) * v.cols + c]);
      Cell& cell = v.cells[next++];
      cell.near_3x3 = zOffset(cell.z - nearest);
    }
  return v;
}

/// True when a ball (centre c_W, radius r) may hold a point the view has a verdict about: a point
/// that projects into a kept cell (or next to one: the 3x3 gates) no farther than that cell's gate
/// reaches (z_far). False is exact; true may be wrong (a superset).
/// False when the ball (camera-frame centre p, radius r) lies wholly outside the frustum
/// x / z in [xl, xr], y / z in [yl, yr], 0 <= z <= z_max. True may be wrong (a superset).
bool ballMayMeetFrustum(const Eigen::Vector3d& p, double r, double xl, double xr, double yl, double yr, double z_max) {
  if (p.z() < -r || p.z() > z_max + r) return false;
  const auto outside = [&](double nx, double nz, double px, double pz) {  // n . p < -r |n|
    return nx * px + nz * pz < -r * std::hypot(nx, nz);
  };
  return !(outside(1.0, -xl, p.x(), p.z()) || outside(-1.0, xr, p.x(), p.z()) || outside(1.0, -yl, p.y(), p.z()) ||
           outside(-1.0, yr, p.y(), p.z()));
}

/// The image interval f x / z + shift of a ball's extent [c - r, c + r] along one axis, at every
/// depth z in [z0, z1] (z0 > 0): its box's extreme ratios.
std::pair<double, double> projectedInterval(double c, double r, double z0, double z1, double f, double shift) {
  const double a = std::min((c - r) / z0, (c - r) / z1), b = std::max((c + r) / z0, (c + r) / z1);
  return {f * a + shift, f * b + shift};
}

bool ballMaySee(const View& v, const Eigen::Vector3d& c_W, double r) {
  const Eigen::Vector3d p = v.R_K_W * c_W + v.t_K_W;
  // Container pixels u in [-offset_u - 0.5, 2W - offset_u - 0.5): x / z within [xl, xr].
  const double xl = (-v.offset_u - 0.5 - v.cx) / v.fx, xr = (v.width2 - v.offset_u - 0.5 - v.cx) / v.fx;
  const double yl = (-v.offset_v - 0.5 - v.cy) / v.fy, yr = (v.height2 - v.offset_v - 0.5 - v.cy) / v.fy;
  if (!ballMayMeetFrustum(p, r, xl, xr, yl, yr, v.z_max)) return false;
  const double z0 = p.z() - r, z1 = p.z() + r;
  if (z0 < 1e-3) return true;  // the ball reaches the camera: its image is unbounded
  // The ball's box projects within the extreme ratios of its corners; its grid cells, grown by
  // one for the neighbours' gates, and the tiles that hold them.
  const auto range = [&](double c, double f, double centre, double offset, double first, int cells, int* lo, int* hi) {
    const auto [p0, p1] = projectedInterval(c, r, z0, z1, f, centre + offset + 0.5);
    *lo = static_cast<int>(std::clamp(std::floor(p0 / v.cell_px) - 1 - first, 0.0, cells - 1.0));
    *hi = static_cast<int>(std::clamp(std::floor(p1 / v.cell_px) + 1 - first, 0.0, cells - 1.0));
  };
  // (Clamped to the view's box: a superset when the ball's cells lie outside it.)
  int c0 = 0, c1 = 0, r0 = 0, r1 = 0;
  range(p.x(), v.fx, v.cx, v.offset_u, v.col0, v.cols, &c0, &c1);
  range(p.y(), v.fy, v.cy, v.offset_v, v.row0, v.rows, &r0, &r1);
  for (int tr = r0 / kTile; tr <= r1 / kTile; ++tr)
    for (int tc = c0 / kTile; tc <= c1 / kTile; ++tc)
      if (v.tile_z_far[static_cast<std::size_t>(tr) * v.tile_cols + tc] >= z0) return true;
  return false;
}

/// The integrated frames' free space at their keyframes' current poses, its bounds added to the
/// seen box, and its index (voxels of 0.25 m: a frame's frustum is coarse, its blocks are 8 px).
void addFrames(const KeyframeGraph& graph, int threads, KeyframeViews::Impl* impl) {
  const std::size_t n = graph.size();
  impl->first_frame.assign(n + 1, 0);
  std::size_t blocks = 0;
  for (std::size_t id = 0; id < n; ++id) {
    const Keyframe& kf = graph.keyframe(static_cast<int>(id));
    impl->first_frame[id + 1] = impl->first_frame[id] + static_cast<std::uint32_t>(kf.frames_free.size());
    for (const FrameFreeSpace& f : kf.frames_free) blocks += f.near_mm.size();
    if (!kf.frames_free.empty()) impl->camera = kf.container.camera();
  }
  impl->frames.resize(impl->first_frame[n]);
  impl->blocks.resize(blocks);
  const PinholeCamera& cam = impl->camera;
  const double xl = -cam.cx / cam.fx, xr = (cam.width - cam.cx) / cam.fx;
  const double yl = -cam.cy / cam.fy, yr = (cam.height - cam.cy) / cam.fy;
  // Each frame's world box (lo > hi: it sees nothing) and their union.
  const Eigen::Vector3d inf = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  std::vector<Eigen::Vector3d> lo(impl->frames.size(), inf), hi(impl->frames.size(), -inf);
  Eigen::Vector3d all_lo = inf, all_hi = -inf;
  std::size_t at = 0;
  for (std::size_t id = 0; id < n; ++id) {
    const Keyframe& kf = graph.keyframe(static_cast<int>(id));
    for (std::size_t j = 0; j < kf.frames_free.size(); ++j) {
      const FrameFreeSpace& src = kf.frames_free[j];
      const std::size_t i = impl->first_frame[id] + j;
      FrameView& f = impl->frames[i];
      const Transform T_W_F = kf.T_W_K * src.T_K_C;
      const Transform T_F_W = T_W_F.inverse();
      f.R_F_W = T_F_W.linear();
      f.t_F_W = T_F_W.translation();
      f.keyframe = static_cast<int>(id);
      f.cols = src.cols;
      std::copy(src.near_mm.begin(), src.near_mm.end(), impl->blocks.begin() + static_cast<std::ptrdiff_t>(at));
      f.near_mm = impl->blocks.data() + at;
      at += src.near_mm.size();
      f.z_max = 1e-3 * *std::max_element(src.near_mm.begin(), src.near_mm.end());
      if (!(f.z_max > 0)) continue;  // no block with depth: sees nothing (its box stays empty)
      lo[i] = hi[i] = T_W_F.translation();
      for (const double x : {xl, xr})
        for (const double y : {yl, yr}) {
          const Eigen::Vector3d corner = T_W_F * Eigen::Vector3d(x * f.z_max, y * f.z_max, f.z_max);
          lo[i] = lo[i].cwiseMin(corner), hi[i] = hi[i].cwiseMax(corner);
        }
      all_lo = all_lo.cwiseMin(lo[i]), all_hi = all_hi.cwiseMax(hi[i]);
    }
  }
  impl->lo = impl->lo.cwiseMin(all_lo);
  impl->hi = impl->hi.cwiseMax(all_hi);
  // A frame lists a voxel whose ball meets its frustum and projects onto some block whose depth
  // lies beyond the ball's nearest point (elsewhere no point of the ball is in front of the frame's
  // depth): voxels behind the surfaces the frame saw are left out.
  impl->frame_index =
      buildVoxelLists(all_lo, all_hi, 0.25, lo, hi, threads, [&](std::size_t i, const Eigen::Vector3d& c, double r) {
        const FrameView& f = impl->frames[i];
        const Eigen::Vector3d p = f.R_F_W * c + f.t_F_W;
        if (!ballMayMeetFrustum(p, r, xl, xr, yl, yr, f.z_max)) return false;
        const double z0 = p.z() - r, z1 = p.z() + r;
        if (z0 < 1e-3) return true;  // the ball reaches the camera: its image is unbounded
        const auto blocks = [&](double centre, double focal, double shift, int count, int* b0, int* b1) {
          const auto [p0, p1] = projectedInterval(centre, r, z0, z1, focal, shift);
          *b0 = static_cast<int>(std::clamp(std::floor(p0 / kFreeBlockPx), 0.0, count - 1.0));
          *b1 = static_cast<int>(std::clamp(std::floor(p1 / kFreeBlockPx), 0.0, count - 1.0));
        };
        const int rows = (cam.height + kFreeBlockPx - 1) / kFreeBlockPx;
        int c0 = 0, c1 = 0, r0 = 0, r1 = 0;
        blocks(p.x(), cam.fx, cam.cx, f.cols, &c0, &c1);
        blocks(p.y(), cam.fy, cam.cy, rows, &r0, &r1);
        for (int row = r0; row <= r1; ++row)
          for (int col = c0; col <= c1; ++col)
            if (1e-3 * f.near_mm[static_cast<std::size_t>(row) * f.cols + col] > z0) return true;
        return false;
      });
}

}  // namespace

Eigen::Vector3d storedViewMean(const KeyframeContainer& container, const StoredCell& cell) {
  const MeanCoder coder(container);
  const int col = cell.grid_index % container.cols(), row = cell.grid_index / container.cols();
  const std::uint16_t ray[2] = {coder.encode(0, col, double(cell.mean.x()) / cell.mean.z()),
                                coder.encode(1, row, double(cell.mean.y()) / cell.mean.z())};
  return coder.decode(cell.mean.z(), ray, col, row);
}

KeyframeViews KeyframeViews::build(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& params,
                                   std::span<const int> keyframe_rank) {
  params.validate();
  const std::size_t n = graph.size();
  if (global.kept.size() != n)
    throw std::invalid_argument("the global map was built from " + std::to_string(global.kept.size()) +
                                " keyframes, the graph has " + std::to_string(n));
  if (!keyframe_rank.empty() && keyframe_rank.size() != n)
    throw std::invalid_argument("keyframe_rank has " + std::to_string(keyframe_rank.size()) +
                                " entries, the graph has " + std::to_string(n) + " keyframes");
  for (std::size_t id = 0; id < n; ++id)
    if (global.kept[id].size() != graph.keyframe(static_cast<int>(id)).container.size())
      throw std::invalid_argument("the global map's kept cells of keyframe " + std::to_string(id) +
                                  " do not match its container");
  auto impl = std::make_shared<Impl>();
  impl->params = params;
  impl->k = params.gate_sigma;
  impl->k2 = params.gate_sigma * params.gate_sigma;
  impl->views.resize(n);
  parallelFor(params.threads, n, [&](std::size_t id) {
    const int rank = keyframe_rank.empty() ? static_cast<int>(id) : keyframe_rank[id];
    impl->views[id] =
        makeView(graph.keyframe(static_cast<int>(id)), global.kept[id], params.min_sigma_m, params.gate_sigma, rank);
  });
  for (const View& v : impl->views) {
    impl->lo = impl->lo.cwiseMin(v.lo);
    impl->hi = impl->hi.cwiseMax(v.hi);
  }
  std::vector<Eigen::Vector3d> view_lo(n), view_hi(n);  // a view without cells has lo > hi: lists nothing
  for (std::size_t id = 0; id < n; ++id) view_lo[id] = impl->views[id].lo, view_hi[id] = impl->views[id].hi;
  // Voxels of 0.125 m (a room is a few ten thousand).
  impl->index = buildVoxelLists(
      impl->lo, impl->hi, 0.125, view_lo, view_hi, params.threads,
      [&](std::size_t id, const Eigen::Vector3d& c, double r) { return ballMaySee(impl->views[id], c, r); });
  // kRecent scans the highest rank first (ties: lower id) and stops at the first verdict.
  if (params.conflict == ConflictRule::kRecent) {
    VoxelLists& x = impl->index;
    parallelFor(params.threads, x.begin.empty() ? 0 : x.begin.size() - 1, [&](std::size_t vox) {
      std::sort(x.ids.begin() + x.begin[vox], x.ids.begin() + x.begin[vox + 1], [&](std::int32_t a, std::int32_t b) {
        const int ra = impl->views[static_cast<std::size_t>(a)].rank,
                  rb = impl->views[static_cast<std::size_t>(b)].rank;
        return ra != rb ? ra > rb : a < b;
      });
    });
  }
  addFrames(graph, params.threads, impl.get());
  for (View& v : impl->views) v.tile_z_far = {};
  KeyframeViews out;
  out.impl_ = std::move(impl);
  return out;
}

std::size_t KeyframeViews::size() const { return impl_ ? impl_->views.size() : 0; }

std::size_t KeyframeViews::memoryBytes() const {
  if (!impl_) return 0;
  const Impl& im = *impl_;
  std::size_t bytes = sizeof(Impl) + im.views.capacity() * sizeof(View) + im.index.memoryBytes();
  for (const View& v : im.views)
    bytes += v.occupied.capacity() * sizeof(OccupancyWord) + v.cells.capacity() * sizeof(Cell);
  return bytes;
}

std::size_t KeyframeViews::frameMemoryBytes() const {
  if (!impl_) return 0;
  const Impl& im = *impl_;
  return im.frames.capacity() * sizeof(FrameView) + im.first_frame.capacity() * sizeof(std::uint32_t) +
         im.blocks.capacity() * sizeof(std::uint16_t) + im.frame_index.memoryBytes();
}

void KeyframeViews::seenBounds(Eigen::Vector3d* lo, Eigen::Vector3d* hi) const {
  if (!impl_) {
    *lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    *hi = -*lo;
    return;
  }
  *lo = impl_->lo;
  *hi = impl_->hi;
}

ViewVerdict KeyframeViews::verdict(int id, const Eigen::Vector3d& q_W) const {
  if (!impl_ || id < 0 || static_cast<std::size_t>(id) >= impl_->views.size())
    throw std::invalid_argument("keyframe " + std::to_string(id) + " is not in the map (" +
                                counted(static_cast<long long>(size()), "keyframe") + ")");
  return impl_->verdict(impl_->views[static_cast<std::size_t>(id)], q_W);
}

ViewVerdict KeyframeViews::localMapVerdict(int id, const Eigen::Vector3d& q_W) const {
  ViewVerdict v = verdict(id, q_W);
  if (v.state != Occupancy::kUnknown) return v;
  const Impl& im = *impl_;
  for (std::uint32_t f = im.first_frame[static_cast<std::size_t>(id)];
       f < im.first_frame[static_cast<std::size_t>(id) + 1]; ++f)
    if (im.frameFree(im.frames[f], q_W, &v)) return v;
  return ViewVerdict{};
}

std::span<const std::int32_t> KeyframeViews::candidates(const Eigen::Vector3d& q_W) const {
  return impl_ ? impl_->candidates(q_W) : std::span<const std::int32_t>{};
}

ViewVerdict KeyframeViews::combined(const Eigen::Vector3d& q_W, int* keyframe) const {
  *keyframe = -1;
  ViewVerdict best;
  if (!impl_) return best;
  const Impl& im = *impl_;
  const std::span<const std::int32_t> ids = im.candidates(q_W);
  switch (im.params.conflict) {
    case ConflictRule::kOccupied: *keyframe = im.firstFree(ids, q_W, &best); break;
    case ConflictRule::kRecent:  // candidates by rank, highest first: the first verdict decides
      im.scanVerdicts(ids, q_W, [&](std::int32_t id, const ViewVerdict& v) {
        if (v.state == Occupancy::kUnknown) return true;
        best = v, *keyframe = id;
        return false;
      });
      break;
    case ConflictRule::kPrecise:
      im.scanVerdicts(ids, q_W, [&](std::int32_t id, const ViewVerdict& v) {
        if (v.state != Occupancy::kUnknown && (*keyframe < 0 || v.sigma_t < best.sigma_t)) best = v, *keyframe = id;
        return true;
      });
      break;
  }
  if (*keyframe >= 0) return best;
  // No keyframe's view has a verdict: what the integrated frames saw free (docs/method.md 13.2).
  best = ViewVerdict{};
  *keyframe = im.firstFreeFrame(im.frame_index.at(q_W), q_W, &best);
  return *keyframe >= 0 ? best : ViewVerdict{};
}

}  // namespace vdmap
