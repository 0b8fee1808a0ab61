#include "mapping/query/keyframe_views.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "mapping/core/parallel.h"

namespace vdmap {
namespace {

/// One kept cell as the queries use it (docs/method.md 13.1): mean and A = (Sigma + s0^2 I)^-1 in
/// the keyframe frame. The point's terms are taken relative to the mean (d = q - mu), so the gate
/// distance m^2 = d^T A d has no cancellation; a = q^T A q and q^T A d = a - b follow from A q.
struct Cell {
  double a[6];   // A: xx xy xz yy yz zz
  double mu[3];
};

struct CellTerms {
  double m2;   // (q - mu)^T A (q - mu)
  double a;    // q^T A q
  double qad;  // q^T A (q - mu) = a - b
};

inline double gate2(const Cell& c, const Eigen::Vector3d& q) {
  const double dx = q.x() - c.mu[0], dy = q.y() - c.mu[1], dz = q.z() - c.mu[2];
  const double ax = c.a[0] * dx + c.a[1] * dy + c.a[2] * dz;
  const double ay = c.a[1] * dx + c.a[3] * dy + c.a[4] * dz;
  const double az = c.a[2] * dx + c.a[4] * dy + c.a[5] * dz;
  return dx * ax + dy * ay + dz * az;
}

inline CellTerms terms(const Cell& c, const Eigen::Vector3d& q) {
  const double dx = q.x() - c.mu[0], dy = q.y() - c.mu[1], dz = q.z() - c.mu[2];
  const double ax = c.a[0] * dx + c.a[1] * dy + c.a[2] * dz;
  const double ay = c.a[1] * dx + c.a[3] * dy + c.a[4] * dz;
  const double az = c.a[2] * dx + c.a[4] * dy + c.a[5] * dz;
  const double qx = c.a[0] * q.x() + c.a[1] * q.y() + c.a[2] * q.z();
  const double qy = c.a[1] * q.x() + c.a[3] * q.y() + c.a[4] * q.z();
  const double qz = c.a[2] * q.x() + c.a[4] * q.y() + c.a[5] * q.z();
  return {dx * ax + dy * ay + dz * az, q.x() * qx + q.y() * qy + q.z() * qz, q.x() * ax + q.y() * ay + q.z() * az};
}

/// One keyframe: its current pose, camera and container grid, and its kept cells.
struct View {
  Eigen::Matrix3d R_K_W = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_K_W = Eigen::Vector3d::Zero();
  double fx = 1, fy = 1, cx = 0, cy = 0;
  double width2 = 0, height2 = 0;  // 2W, 2H: the container's extent in container pixels
  double offset_u = 0, offset_v = 0;
  int cell_px = 1, cols = 0, rows = 0;
  std::vector<std::int32_t> slot;  // per grid cell: index into cells, -1 = no kept cell (empty when no cells)
  std::vector<Cell> cells;
  int rank = 0;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  double z_max = 0;  // farthest gate along the optical axis (keyframe frame)

  /// Keyframe-frame point, its grid column and row; false when the container does not hold it.
  bool locate(const Eigen::Vector3d& q_W, Eigen::Vector3d* q, int* col, int* row) const {
    if (cells.empty()) return false;
    *q = R_K_W * q_W + t_K_W;
    if (!(q->z() > 0.0)) return false;
    // As KeyframeContainer::gridIndexOfPixel (a container pixel covers [u' - 0.5, u' + 0.5)).
    const double u = fx * q->x() / q->z() + cx, v = fy * q->y() / q->z() + cy;
    const double up = u + offset_u + 0.5, vp = v + offset_v + 0.5;
    if (!(up >= 0.0 && vp >= 0.0 && up < width2 && vp < height2)) return false;
    *col = static_cast<int>(up) / cell_px;
    *row = static_cast<int>(vp) / cell_px;
    return true;
  }
};

}  // namespace

struct KeyframeViews::Impl {
  QueryParams params;
  double k = 3, k2 = 9;
  std::vector<View> views;
  // Visibility index (docs/method.md 13.1): a dense voxel grid over the seen box; per voxel the
  // ascending ids of the keyframes whose cut frustum may touch it (ids[begin[v] .. begin[v + 1])).
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double voxel_m = 0.25;
  int nx = 0, ny = 0, nz = 0;
  std::vector<std::uint32_t> begin;
  std::vector<std::int32_t> ids;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

  ViewVerdict verdict(const View& view, const Eigen::Vector3d& q_W) const {
    ViewVerdict out;
    Eigen::Vector3d q;
    int col = 0, row = 0;
    if (!view.locate(q_W, &q, &col, &row)) return out;
    // Occupied: the nearest gate among the 3x3 cells (a gate reaches past its cell's border).
    double best_m2 = std::numeric_limits<double>::infinity();
    const Cell* best = nullptr;
    for (int r = std::max(row - 1, 0); r <= std::min(row + 1, view.rows - 1); ++r)
      for (int c = std::max(col - 1, 0); c <= std::min(col + 1, view.cols - 1); ++c) {
        const std::int32_t s = view.slot[static_cast<std::size_t>(r) * view.cols + c];
        if (s < 0) continue;
        const double m2 = gate2(view.cells[s], q);
        if (m2 < best_m2) best_m2 = m2, best = &view.cells[s];
      }
    if (best != nullptr && best_m2 <= k2) {
      const CellTerms t = terms(*best, q);
      out.state = Occupancy::kOccupied;
      out.m2 = best_m2;
      out.z = t.qad / std::sqrt(t.a);
      out.sigma_t = q.norm() / std::sqrt(t.a);
      return out;
    }
    const std::int32_t own = view.slot[static_cast<std::size_t>(row) * view.cols + col];
    if (own < 0) return out;
    const CellTerms t = terms(view.cells[own], q);
    const double sqrt_a = std::sqrt(t.a);
    out.z = t.qad / sqrt_a;
    out.m2 = t.m2;
    out.sigma_t = q.norm() / sqrt_a;
    // Free: in front of the surface by more than k sigma along the ray, and the ray meets the
    // cell's ellipsoid within its gate (m_lat^2 = m^2 - z^2 <= k^2).
    if (out.z < -k && t.m2 - out.z * out.z <= k2) out.state = Occupancy::kFree;
    return out;
  }

  /// verdict() == kFree, without the occupied answer's terms: the fast path of ConflictRule::kOccupied.
  bool isFree(const View& view, const Eigen::Vector3d& q_W, ViewVerdict* out) const {
    Eigen::Vector3d q;
    int col = 0, row = 0;
    if (!view.locate(q_W, &q, &col, &row)) return false;
    const std::int32_t own = view.slot[static_cast<std::size_t>(row) * view.cols + col];
    if (own < 0) return false;
    const CellTerms t = terms(view.cells[own], q);
    const double sqrt_a = std::sqrt(t.a);
    const double z = t.qad / sqrt_a;
    if (!(z < -k && t.m2 - z * z <= k2)) return false;
    // No gate of the 3x3 cells may hold the point (the own cell's cannot: m^2 >= z^2 > k^2).
    for (int r = std::max(row - 1, 0); r <= std::min(row + 1, view.rows - 1); ++r)
      for (int c = std::max(col - 1, 0); c <= std::min(col + 1, view.cols - 1); ++c) {
        const std::int32_t s = view.slot[static_cast<std::size_t>(r) * view.cols + c];
        if (s >= 0 && gate2(view.cells[s], q) <= k2) return false;
      }
    out->state = Occupancy::kFree;
    out->z = z;
    out->m2 = t.m2;
    out->sigma_t = q.norm() / sqrt_a;
    return true;
  }

  std::span<const std::int32_t> candidates(const Eigen::Vector3d& q_W) const {
    if (nx == 0) return {};
    const Eigen::Vector3d f = (q_W - origin) / voxel_m;
    if (!(f.x() >= 0 && f.y() >= 0 && f.z() >= 0 && f.x() < nx && f.y() < ny && f.z() < nz)) return {};
    const std::size_t v =
        (static_cast<std::size_t>(f.z()) * ny + static_cast<std::size_t>(f.y())) * nx + static_cast<std::size_t>(f.x());
    return {ids.data() + begin[v], ids.data() + begin[v + 1]};
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
  v.cell_px = container.cellSizePx(), v.cols = container.cols(), v.rows = container.rows();
  v.rank = rank;
  const auto& cells = container.cells();
  std::size_t n_kept = 0;
  for (std::size_t i = 0; i < cells.size(); ++i) n_kept += kept[i] ? 1 : 0;
  if (n_kept == 0) return v;
  v.slot.assign(static_cast<std::size_t>(v.cols) * v.rows, -1);
  v.cells.reserve(n_kept);
  const Eigen::Matrix3d R_W_K = kf.T_W_K.linear();
  const Eigen::Vector3d centre_W = kf.T_W_K.translation();
  v.lo = v.hi = centre_W;
  v.z_max = 0;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (!kept[i]) continue;
    const Ellipsoid e = cellEllipsoid(cells[i], Transform::Identity(), 0);
    const Eigen::Matrix3d cov = e.cov + s0 * s0 * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d A = cov.inverse();
    Cell c;
    c.a[0] = A(0, 0), c.a[1] = A(0, 1), c.a[2] = A(0, 2), c.a[3] = A(1, 1), c.a[4] = A(1, 2), c.a[5] = A(2, 2);
    c.mu[0] = e.mean.x(), c.mu[1] = e.mean.y(), c.mu[2] = e.mean.z();
    v.slot[static_cast<std::size_t>(cells[i].grid_index)] = static_cast<std::int32_t>(v.cells.size());
    v.cells.push_back(c);
    // Every point with a verdict lies in a gate or on the segment from the centre to a gate:
    // inside the box of the centre and the gates' boxes, and no farther along z than a gate.
    v.z_max = std::max(v.z_max, e.mean.z() + k * std::sqrt(cov(2, 2)));
    const Eigen::Matrix3d cov_W = R_W_K * cov * R_W_K.transpose();
    const Eigen::Vector3d half = k * cov_W.diagonal().cwiseSqrt();
    const Eigen::Vector3d mean_W = kf.T_W_K * e.mean;
    v.lo = v.lo.cwiseMin(mean_W - half);
    v.hi = v.hi.cwiseMax(mean_W + half);
  }
  return v;
}

/// True when a ball (centre c_W, radius r) may meet the view's container frustum cut at z_max.
bool ballMeetsFrustum(const View& v, const Eigen::Vector3d& c_W, double r) {
  const Eigen::Vector3d p = v.R_K_W * c_W + v.t_K_W;
  if (p.z() < -r || p.z() > v.z_max + r) return false;
  // Container pixels u in [-offset_u - 0.5, 2W - offset_u - 0.5): x / z within [xl, xr].
  const double xl = (-v.offset_u - 0.5 - v.cx) / v.fx, xr = (v.width2 - v.offset_u - 0.5 - v.cx) / v.fx;
  const double yl = (-v.offset_v - 0.5 - v.cy) / v.fy, yr = (v.height2 - v.offset_v - 0.5 - v.cy) / v.fy;
  const auto outside = [&](double nx, double nz, double px, double pz) {  // n . p < -r |n|
    return nx * px + nz * pz < -r * std::hypot(nx, nz);
  };
  if (outside(1.0, -xl, p.x(), p.z()) || outside(-1.0, xr, p.x(), p.z())) return false;
  if (outside(1.0, -yl, p.y(), p.z()) || outside(-1.0, yr, p.y(), p.z())) return false;
  return true;
}

}  // namespace

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
    impl->views[id] = makeView(graph.keyframe(static_cast<int>(id)), global.kept[id], params.min_sigma_m,
                               params.gate_sigma, rank);
  });
  for (const View& v : impl->views) {
    impl->lo = impl->lo.cwiseMin(v.lo);
    impl->hi = impl->hi.cwiseMax(v.hi);
  }
  if (impl->lo.x() <= impl->hi.x()) {
    // Voxels of 0.25 m (a room is a few thousand), coarser when the box would need more than
    // 2^23 of them (a large map: the index stays under ~40 MB).
    const Eigen::Vector3d extent = impl->hi - impl->lo;
    const double volume = (extent.array() + 0.25).prod();
    impl->voxel_m = std::max(0.25, std::cbrt(volume / double(1 << 23)) * 1.01);
    impl->origin = impl->lo;
    impl->nx = static_cast<int>(std::floor(extent.x() / impl->voxel_m)) + 1;
    impl->ny = static_cast<int>(std::floor(extent.y() / impl->voxel_m)) + 1;
    impl->nz = static_cast<int>(std::floor(extent.z() / impl->voxel_m)) + 1;
    const std::size_t voxels = static_cast<std::size_t>(impl->nx) * impl->ny * impl->nz;
    // Per keyframe, the voxels of its box whose bounding ball meets its frustum (a superset).
    std::vector<std::vector<std::uint32_t>> touched(n);
    const double voxel = impl->voxel_m, radius = 0.5 * std::sqrt(3.0) * voxel;
    parallelFor(params.threads, n, [&](std::size_t id) {
      const View& v = impl->views[id];
      if (v.cells.empty()) return;
      const Eigen::Vector3i a = ((v.lo - impl->origin) / voxel).array().floor().cast<int>().max(0);
      const Eigen::Vector3i b = ((v.hi - impl->origin) / voxel).array().floor().cast<int>();
      for (int z = a.z(); z <= std::min(b.z(), impl->nz - 1); ++z)
        for (int y = a.y(); y <= std::min(b.y(), impl->ny - 1); ++y)
          for (int x = a.x(); x <= std::min(b.x(), impl->nx - 1); ++x) {
            const Eigen::Vector3d centre = impl->origin + voxel * Eigen::Vector3d(x + 0.5, y + 0.5, z + 0.5);
            if (ballMeetsFrustum(v, centre, radius))
              touched[id].push_back(static_cast<std::uint32_t>((static_cast<std::size_t>(z) * impl->ny + y) * impl->nx + x));
          }
    });
    // Counting sort by voxel; filling in id order keeps each voxel's list ascending.
    impl->begin.assign(voxels + 1, 0);
    for (const auto& t : touched)
      for (std::uint32_t vox : t) ++impl->begin[vox + 1];
    for (std::size_t i = 0; i < voxels; ++i) impl->begin[i + 1] += impl->begin[i];
    impl->ids.resize(impl->begin[voxels]);
    std::vector<std::uint32_t> fill(impl->begin.begin(), impl->begin.end() - 1);
    for (std::size_t id = 0; id < n; ++id)
      for (std::uint32_t vox : touched[id]) impl->ids[fill[vox]++] = static_cast<std::int32_t>(id);
  }
  KeyframeViews out;
  out.impl_ = std::move(impl);
  return out;
}

std::size_t KeyframeViews::size() const { return impl_ ? impl_->views.size() : 0; }

std::size_t KeyframeViews::memoryBytes() const {
  if (!impl_) return 0;
  std::size_t bytes = sizeof(Impl) + impl_->views.capacity() * sizeof(View) +
                      impl_->begin.capacity() * sizeof(std::uint32_t) + impl_->ids.capacity() * sizeof(std::int32_t);
  for (const View& v : impl_->views)
    bytes += v.slot.capacity() * sizeof(std::int32_t) + v.cells.capacity() * sizeof(Cell);
  return bytes;
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
                                std::to_string(size()) + " keyframes)");
  return impl_->verdict(impl_->views[static_cast<std::size_t>(id)], q_W);
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
    case ConflictRule::kOccupied:
      for (const std::int32_t id : ids)
        if (im.isFree(im.views[static_cast<std::size_t>(id)], q_W, &best)) {
          *keyframe = id;
          return best;
        }
      return ViewVerdict{};
    case ConflictRule::kRecent:
      for (const std::int32_t id : ids) {
        const View& v = im.views[static_cast<std::size_t>(id)];
        if (*keyframe >= 0 && v.rank <= im.views[static_cast<std::size_t>(*keyframe)].rank) continue;
        const ViewVerdict verdict = im.verdict(v, q_W);
        if (verdict.state != Occupancy::kUnknown) best = verdict, *keyframe = id;
      }
      return best;
    case ConflictRule::kPrecise:
      for (const std::int32_t id : ids) {
        const ViewVerdict verdict = im.verdict(im.views[static_cast<std::size_t>(id)], q_W);
        if (verdict.state != Occupancy::kUnknown && (*keyframe < 0 || verdict.sigma_t < best.sigma_t))
          best = verdict, *keyframe = id;
      }
      return best;
  }
  return best;
}

}  // namespace vdmap
