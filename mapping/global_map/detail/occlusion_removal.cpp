#include "mapping/global_map/detail/occlusion_removal.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "mapping/core/parallel.h"

namespace vdmap {
namespace global_map_detail {
namespace {

// Occlusion test of docs/method.md 6.3: A occludes B when the ray to B passes within Mahalanobis distance 2
// of A, i.e. a squared distance of at most 4.
constexpr double kOcclusionGate2 = 4.0;

// docs/method.md 6.3: the keyframes whose ellipsoids viewpoint K judges: K, its covisibility neighbours,
// and every keyframe within occlusion_distance whose optical axis is within occlusion_angle of
// K's. Ascending ids.
std::vector<int> occlusionGroup(const KeyframeGraph& graph, const Keyframe& K, const GlobalMapParams& params) {
  // An angle of exactly occlusion_angle counts, whatever the rounding of the cosines.
  constexpr double kCosTolerance = 1e-12;
  const double cos_angle = std::cos(params.occlusion_angle_deg * M_PI / 180.0);
  std::vector<int> group = {K.id};
  for (const auto& [other, w] : graph.edges().neighbours(K.id)) group.push_back(other);
  for (const Keyframe& other : graph.keyframes()) {
    if (other.id == K.id) continue;
    if ((other.T_W_K.translation() - K.T_W_K.translation()).norm() <= params.occlusion_distance_m &&
        other.T_W_K.linear().col(2).dot(K.T_W_K.linear().col(2)) >= cos_angle - kCosTolerance)
      group.push_back(other.id);
  }
  std::sort(group.begin(), group.end());
  group.erase(std::unique(group.begin(), group.end()), group.end());
  return group;
}

// KeyframeContainer::gridIndexOfPixel with its two divisions by the cell size looked up in
// tables: occlusion removal asks it for ~10^7 points per build. The same answer for every pixel.
class CellOfPixel {
 public:
  explicit CellOfPixel(const KeyframeContainer& box)
      : offset_u_(box.offsetU()), offset_v_(box.offsetV()), width_(2.0 * box.camera().width),
        height_(2.0 * box.camera().height), col_(static_cast<std::size_t>(2 * box.camera().width)),
        row_start_(static_cast<std::size_t>(2 * box.camera().height)) {
    for (std::size_t x = 0; x < col_.size(); ++x) col_[x] = static_cast<int>(x) / box.cellSizePx();
    for (std::size_t y = 0; y < row_start_.size(); ++y)
      row_start_[y] = static_cast<int>(y) / box.cellSizePx() * box.cols();
  }
  int operator()(double u, double v) const {
    const double up = u + offset_u_ + 0.5, vp = v + offset_v_ + 0.5;  // rounded as gridIndexOfPixel rounds
    if (!(up >= 0.0 && vp >= 0.0 && up < width_ && vp < height_)) return -1;
    return row_start_[static_cast<std::size_t>(vp)] + col_[static_cast<std::size_t>(up)];
  }

 private:
  double offset_u_, offset_v_, width_, height_;
  std::vector<int> col_, row_start_;
};

// The ellipsoids of one viewpoint cell: appends to `removed` every A that occludes a more precise
// B behind it (docs/method.md 6.3). `cell` is reordered near to far (ties by index; the result does not
// depend on their order, as only a B strictly farther than A counts); `finest_behind` is scratch.
void removeOccludersInCell(std::span<ViewItem> cell, std::span<const Ellipsoid* const> ellipsoids,
                           std::vector<double>* finest_behind, std::vector<int>* removed) {
  std::sort(cell.begin(), cell.end(),
            [](const ViewItem& a, const ViewItem& b) { return a.z != b.z ? a.z < b.z : a.index < b.index; });
  // finest[a]: the smallest lambda_max from a to the end of the cell.
  std::vector<double>& finest = *finest_behind;
  finest.assign(cell.size() + 1, std::numeric_limits<double>::infinity());
  for (std::size_t j = cell.size(); j-- > 0;) finest[j] = std::min(finest[j + 1], cell[j].lambda_max);
  for (std::size_t a = 0; a + 1 < cell.size(); ++a) {
    if (!(finest[a + 1] < cell[a].lambda_max)) continue;  // nothing more precise behind A
    // A's information matrix, computed where it is needed rather than kept for every ellipsoid
    // (72 bytes each, the largest buffer of a build): only an A with something finer behind it needs one.
    const Eigen::Matrix3d P = floored(ellipsoids[static_cast<std::size_t>(cell[a].index)]->cov).inverse();
    const Eigen::Vector3d& mu = cell[a].ray;
    const Eigen::Vector3d P_mu = P * mu;
    const double mu_P_mu = mu.dot(P_mu);
    for (std::size_t b = a + 1; b < cell.size(); ++b) {
      if (!(cell[b].z > cell[a].z) || !(cell[b].lambda_max < cell[a].lambda_max)) continue;
      // Squared Mahalanobis distance from A's mean to the ray t d through B, minimised over t.
      const Eigen::Vector3d d = cell[b].ray.normalized();
      const double dPd = d.dot(P * d), dPmu = d.dot(P_mu);
      if (mu_P_mu - dPmu * dPmu / dPd <= kOcclusionGate2) {
        removed->push_back(cell[a].index);
        break;
      }
    }
  }
}

// What the viewpoints read, contiguous by keyframe, so that each streams through its group's
// ellipsoids instead of gathering them from the big records.
void gatherByKeyframe(const KeyframeGraph& graph, std::span<const Ellipsoid* const> ellipsoids,
                      const std::vector<double>& lambda_max, int threads, OcclusionBuffers* buffers) {
  OcclusionBuffers& o = *buffers;
  const std::size_t n = ellipsoids.size();
  o.keyframe_of.resize(n);
  for (std::size_t i = 0; i < n; ++i) o.keyframe_of[i] = ellipsoids[i]->keyframe;
  bucketByKey(o.keyframe_of, graph.size(), &o.by_keyframe, &o.fill);
  o.point.resize(n);
  parallelFor(threads, n, [&](std::size_t j) {
    const std::size_t i = static_cast<std::size_t>(o.by_keyframe.order[j]);
    o.point[j] = {ellipsoids[i]->mean, lambda_max[i]};
  });
}

// The judged cells' points (cells seen with two or more) as ViewItems from viewpoint `centre`:
// s->items, cell by cell from s->start[cell]. Written in one more pass over the group (in order of
// j, so the reads stream) rather than gathered cell by cell from anywhere in the map.
void itemsOfJudgedCells(const Eigen::Vector3d& centre, std::size_t cells, const OcclusionBuffers& o,
                        OcclusionScratch* scratch) {
  OcclusionScratch& s = *scratch;
  s.start.resize(cells + 1);
  s.start[0] = 0;
  for (std::size_t cell = 0; cell < cells; ++cell)
    s.start[cell + 1] = s.start[cell] + (s.count[cell] >= 2 ? s.count[cell] : 0);
  s.items.resize(static_cast<std::size_t>(s.start[cells]));
  s.fill.assign(s.start.begin(), s.start.end() - 1);
  for (const OcclusionScratch::Seen& e : s.seen) {
    if (s.count[static_cast<std::size_t>(e.cell)] < 2) continue;
    const OcclusionBuffers::Point& q = o.point[static_cast<std::size_t>(e.j)];
    s.items[static_cast<std::size_t>(s.fill[static_cast<std::size_t>(e.cell)]++)] = {
        e.z, q.lambda_max, q.mean - centre, o.by_keyframe.order[static_cast<std::size_t>(e.j)]};
  }
}

// Viewpoint K's judgement: the ellipsoids it removes, into `removed` (replacing what it held).
void judgeFrom(const KeyframeGraph& graph, const Keyframe& K, std::span<const Ellipsoid* const> ellipsoids,
               const GlobalMapParams& params, const OcclusionBuffers& o, OcclusionScratch* scratch,
               std::vector<int>* removed) {
  OcclusionScratch& s = *scratch;
  const std::size_t cells = static_cast<std::size_t>(K.container.cols()) * K.container.rows();
  // The points of K's occlusion group that fall into one of K's cells, and the count per cell.
  const Transform T_K_W = K.T_W_K.inverse();
  const CellOfPixel cellOfPixel(K.container);
  s.count.assign(cells, 0);
  s.seen.clear();
  for (int g : occlusionGroup(graph, K, params))
    for (int j = o.by_keyframe.start[static_cast<std::size_t>(g)];
         j < o.by_keyframe.start[static_cast<std::size_t>(g) + 1]; ++j) {
      const Eigen::Vector3d p = T_K_W * o.point[static_cast<std::size_t>(j)].mean;
      if (p.z() <= 0.0) continue;
      const Eigen::Vector2d uv = K.container.camera().project(p);
      const int cell = cellOfPixel(uv.x(), uv.y());
      if (cell < 0) continue;
      s.seen.push_back({cell, j, p.z()});
      ++s.count[static_cast<std::size_t>(cell)];
    }
  itemsOfJudgedCells(K.T_W_K.translation(), cells, o, &s);
  removed->clear();
  for (std::size_t cell = 0; cell < cells; ++cell)
    if (s.count[cell] >= 2)
      removeOccludersInCell(std::span<ViewItem>(s.items).subspan(static_cast<std::size_t>(s.start[cell]),
                                                                 static_cast<std::size_t>(s.count[cell])),
                            ellipsoids, &s.finest, removed);
}

}  // namespace

void releaseOcclusionBuffers(OcclusionBuffers* buffers) {
  OcclusionBuffers& o = *buffers;
  releaseVector(&o.keyframe_of), releaseVector(&o.fill), releaseVector(&o.point);
  releaseVector(&o.by_keyframe.start), releaseVector(&o.by_keyframe.order), releaseVector(&o.removed_by);
  o.scratch.clear();
}

void occludingEllipsoids(const KeyframeGraph& graph, std::span<const Ellipsoid* const> ellipsoids,
                         const std::vector<double>& lambda_max, const GlobalMapParams& params,
                         OcclusionBuffers* buffers, std::vector<char>* removed) {
  OcclusionBuffers& o = *buffers;
  gatherByKeyframe(graph, ellipsoids, lambda_max, params.threads, &o);
  o.removed_by.resize(graph.size());
  parallelFor(params.threads, graph.size(), [&](std::size_t v) {
    judgeFrom(graph, graph.keyframe(static_cast<int>(v)), ellipsoids, params, o, &o.scratch.local(), &o.removed_by[v]);
  });
  removed->assign(ellipsoids.size(), 0);
  for (const std::vector<int>& list : o.removed_by)
    for (int i : list) (*removed)[static_cast<std::size_t>(i)] = 1;
}

}  // namespace global_map_detail

std::vector<bool> occludingEllipsoids(const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids,
                                      const GlobalMapParams& params) {
  global_map_detail::OcclusionBuffers buffers;
  std::vector<char> removed;
  global_map_detail::occludingEllipsoids(graph, global_map_detail::addressesOf(ellipsoids),
                                         global_map_detail::largestEigenvalues(ellipsoids, params.threads), params,
                                         &buffers, &removed);
  return std::vector<bool>(removed.begin(), removed.end());
}

}  // namespace vdmap
