#include "mapping/global_map/global_map.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <span>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <tbb/enumerable_thread_specific.h>

#include "mapping/core/parallel.h"
#include "mapping/core/timing.h"
#include "mapping/local_map/cell_stats.h"

namespace vdmap {
namespace {

using Clock = std::chrono::steady_clock;

// Occlusion test of SPEC 6.3: A occludes B when the ray to B passes within Mahalanobis distance 2
// of A, i.e. a squared distance of at most 4.
constexpr double kOcclusionGate2 = 4.0;
// Added to every covariance before it is inverted (m^2, a 10 um standard deviation): a flat
// surface cell has a near-zero axis and must stay invertible; real cells are far wider.
constexpr double kCovFloor_m2 = 1e-10;

Eigen::Matrix3d floored(const Eigen::Matrix3d& cov) { return cov + kCovFloor_m2 * Eigen::Matrix3d::Identity(); }

// A floored covariance as its six distinct entries, with the closed forms the Bhattacharyya
// distance needs (fusion evaluates it for millions of pairs).
struct SymmetricCov {
  double xx, xy, xz, yy, yz, zz;
  static SymmetricCov of(const Eigen::Matrix3d& cov) {
    return {cov(0, 0) + kCovFloor_m2, cov(0, 1), cov(0, 2), cov(1, 1) + kCovFloor_m2, cov(1, 2), cov(2, 2) + kCovFloor_m2};
  }
  SymmetricCov average(const SymmetricCov& o) const {
    return {0.5 * (xx + o.xx), 0.5 * (xy + o.xy), 0.5 * (xz + o.xz), 0.5 * (yy + o.yy), 0.5 * (yz + o.yz), 0.5 * (zz + o.zz)};
  }
  double determinant() const { return xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz); }
  // d^T S^-1 d through the adjugate.
  double inverseQuadratic(const Eigen::Vector3d& d) const {
    const double axx = yy * zz - yz * yz, axy = xz * yz - xy * zz, axz = xy * yz - xz * yy;
    const double ayy = xx * zz - xz * xz, ayz = xy * xz - xx * yz, azz = xx * yy - xy * xy;
    const double x = d.x(), y = d.y(), z = d.z();
    return (x * (axx * x + axy * y + axz * z) + y * (axy * x + ayy * y + ayz * z) + z * (axz * x + ayz * y + azz * z)) /
           determinant();
  }
};

// The two terms of the Bhattacharyya distance, S = (Sa + Sb) / 2: the offset of the means
// 1/8 d^T S^-1 d, and the difference of the shapes 1/2 ln(det S / sqrt(det Sa det Sb)) >= 0.
double meanTerm(const Eigen::Vector3d& d, const SymmetricCov& S) { return 0.125 * S.inverseQuadratic(d); }
double shapeTerm(const SymmetricCov& S, const SymmetricCov& Sa, const SymmetricCov& Sb) {
  return 0.5 * std::log(S.determinant() / std::sqrt(Sa.determinant() * Sb.determinant()));
}

// fusionHalfWidth in median standard deviations. Copies of one surface cell lie within a fraction
// of a cell of each other: on the Replica 3 px map (333 frames) 1, 1.5 and 3 sigmas leave 520k,
// 508k and 505k ellipsoids.
constexpr double kFusionCubeSigmas = 1.5;

// fusionHalfWidth from the ellipsoids' lambda_max.
double fusionHalfWidth(std::vector<double> lambda_max) {
  if (lambda_max.empty()) return 0.0;
  const auto middle = lambda_max.begin() + static_cast<std::ptrdiff_t>(lambda_max.size() / 2);
  std::nth_element(lambda_max.begin(), middle, lambda_max.end());
  return std::max(kFusionCubeSigmas * std::sqrt(*middle), 1e-5);
}

// Indices 0..keys.size()-1 grouped by key (a stable counting sort); negative keys are left out.
// Bucket b holds order[start[b] .. start[b + 1]).
struct Buckets {
  std::vector<int> start;
  std::vector<int> order;
};

// bucketByKey into `b`, reusing its memory (`fill` is scratch).
void bucketByKey(const std::vector<int>& keys, std::size_t buckets, Buckets* b, std::vector<int>* fill) {
  b->start.assign(buckets + 1, 0);
  for (int k : keys)
    if (k >= 0) ++b->start[static_cast<std::size_t>(k) + 1];
  std::partial_sum(b->start.begin(), b->start.end(), b->start.begin());
  b->order.resize(static_cast<std::size_t>(b->start.back()));
  fill->assign(b->start.begin(), b->start.end() - 1);
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (keys[i] >= 0) b->order[static_cast<std::size_t>((*fill)[static_cast<std::size_t>(keys[i])]++)] = static_cast<int>(i);
}

Ellipsoid transformed(const Ellipsoid& e, const Transform& T_B_A) {
  Ellipsoid out = e;
  out.mean = T_B_A * e.mean;
  out.cov = T_B_A.linear() * e.cov * T_B_A.linear().transpose();
  return out;
}

// meanShiftClusters into `label` (resized to the means).
void meanShiftClusters(const std::vector<Eigen::Vector3d>& means, const std::vector<double>& weights, double h,
                       std::vector<int>* label);

// What merging one group needs besides its output; one per thread, reused across groups and builds.
struct MergeScratch {
  struct Source {
    int member;      // index into group.members
    int cell_index;  // into that keyframe's container cells()
  };
  std::vector<Transform> T_C_K;
  std::vector<Source> sources;
  std::vector<int> cell_of, fill, label;
  Buckets by_cell;
  std::vector<Ellipsoid> in_cell;
  std::vector<Eigen::Vector3d> means;
  std::vector<double> weights;
  std::vector<const Ellipsoid*> cluster;
};

// SPEC section 6 step 2 for one group: members' kept ellipsoids re-projected into the centre's
// container and merged cell by cell, into `out` (replacing what it held). Output order: cells
// ascending, then the pass-throughs.
void mergeGroup(const KeyframeGraph& graph, const MergeGroup& group, const GlobalMapParams& params,
                const std::vector<std::vector<bool>>& kept, MergeScratch* scratch, std::vector<Ellipsoid>* out) {
  MergeScratch& s = *scratch;
  const Keyframe& centre = graph.keyframe(group.centre);
  const KeyframeContainer& box = centre.container;
  const Transform T_C_W = centre.T_W_K.inverse();
  // First only the means, to find each kept ellipsoid's cell in the centre; the whole ellipsoid
  // is made when its cell is merged (holding all of them would write ~120 bytes per ellipsoid).
  s.T_C_K.clear();
  s.sources.clear();
  s.cell_of.clear();
  for (int m = 0; m < static_cast<int>(group.members.size()); ++m) {
    const int id = group.members[static_cast<std::size_t>(m)];
    const Keyframe& k = graph.keyframe(id);
    const std::vector<bool>& kept_cells = kept[static_cast<std::size_t>(id)];
    s.T_C_K.push_back(T_C_W * k.T_W_K);
    for (std::size_t i = 0; i < kept_cells.size(); ++i) {
      if (!kept_cells[i]) continue;
      const Eigen::Vector3d mean = s.T_C_K.back() * k.container.cells()[i].mean.cast<double>();
      int cell = -1;
      if (mean.z() > 0.0) {
        const Eigen::Vector2d uv = box.camera().project(mean);
        cell = box.gridIndexOfPixel(uv.x(), uv.y());
      }
      s.sources.push_back({m, static_cast<int>(i)});
      s.cell_of.push_back(cell);
    }
  }
  auto inCentre = [&](int source) {
    const MergeScratch::Source& src = s.sources[static_cast<std::size_t>(source)];
    const int id = group.members[static_cast<std::size_t>(src.member)];
    return cellEllipsoid(graph.keyframe(id).container.cells()[static_cast<std::size_t>(src.cell_index)],
                         s.T_C_K[static_cast<std::size_t>(src.member)], id);
  };

  // By cell, stable: members in id order, cells in container order.
  const std::size_t cells = static_cast<std::size_t>(box.cols()) * box.rows();
  bucketByKey(s.cell_of, cells, &s.by_cell, &s.fill);
  const std::vector<int>& start = s.by_cell.start;
  const std::vector<int>& order = s.by_cell.order;

  out->clear();
  out->reserve(s.sources.size());
  for (std::size_t c = 0; c < cells; ++c) {
    const int begin = start[c], end = start[c + 1];
    if (end - begin == 1) out->push_back(transformed(inCentre(order[begin]), centre.T_W_K));
    if (end - begin <= 1) continue;
    s.in_cell.clear();
    s.means.clear();
    s.weights.clear();
    for (int i = begin; i < end; ++i) {
      s.in_cell.push_back(inCentre(order[i]));
      s.means.push_back(s.in_cell.back().mean);
      s.weights.push_back(s.in_cell.back().count);
    }
    meanShiftClusters(s.means, s.weights, params.merge_distance_m, &s.label);
    const int clusters = *std::max_element(s.label.begin(), s.label.end()) + 1;
    for (int k = 0; k < clusters; ++k) {
      s.cluster.clear();
      for (std::size_t i = 0; i < s.in_cell.size(); ++i)
        if (s.label[i] == k) s.cluster.push_back(&s.in_cell[i]);
      Ellipsoid merged = momentMatch(s.cluster);
      merged.keyframe = group.centre;
      merged.grid_index = static_cast<int>(c);
      out->push_back(transformed(merged, centre.T_W_K));
    }
  }
  for (std::size_t i = 0; i < s.cell_of.size(); ++i)
    if (s.cell_of[i] < 0) out->push_back(transformed(inCentre(static_cast<int>(i)), centre.T_W_K));
}

// SPEC 6.3: the keyframes whose ellipsoids viewpoint K judges: K, its covisibility neighbours,
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
      : offset_u_(box.offsetU()), offset_v_(box.offsetV()),
        width_(2.0 * box.camera().width), height_(2.0 * box.camera().height),
        col_(static_cast<std::size_t>(2 * box.camera().width)), row_start_(static_cast<std::size_t>(2 * box.camera().height)) {
    for (std::size_t x = 0; x < col_.size(); ++x) col_[x] = static_cast<int>(x) / box.cellSizePx();
    for (std::size_t y = 0; y < row_start_.size(); ++y) row_start_[y] = static_cast<int>(y) / box.cellSizePx() * box.cols();
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

// An ellipsoid as one occlusion viewpoint sees it.
struct ViewItem {
  double z;             // depth in the viewpoint's camera
  double lambda_max;    // largest eigenvalue of its covariance: smaller is more precise
  Eigen::Vector3d ray;  // mean - viewpoint centre, world frame
  int j;                // into the occlusion's by-keyframe arrays (its information matrix)
  int index;            // into the ellipsoids
};

// The ellipsoids of one viewpoint cell: appends to `removed` every A that occludes a more precise
// B behind it (SPEC 6.3). `cell` is reordered near to far (ties by index; the result does not
// depend on their order, as only a B strictly farther than A counts); `finest_behind` is scratch.
void removeOccludersInCell(std::span<ViewItem> cell, const std::vector<Eigen::Matrix3d>& information,
                           std::vector<double>* finest_behind, std::vector<int>* removed) {
  std::sort(cell.begin(), cell.end(),
            [](const ViewItem& a, const ViewItem& b) { return a.z != b.z ? a.z < b.z : a.index < b.index; });
  // finest[a]: the smallest lambda_max from a to the end of the cell.
  std::vector<double>& finest = *finest_behind;
  finest.assign(cell.size() + 1, std::numeric_limits<double>::infinity());
  for (std::size_t j = cell.size(); j-- > 0;) finest[j] = std::min(finest[j + 1], cell[j].lambda_max);
  for (std::size_t a = 0; a + 1 < cell.size(); ++a) {
    if (!(finest[a + 1] < cell[a].lambda_max)) continue;  // nothing more precise behind A
    const Eigen::Matrix3d& P = information[static_cast<std::size_t>(cell[a].j)];
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

// What one occlusion viewpoint needs; one per thread, reused across viewpoints and builds (fresh
// buffers cost a page fault per 4 KiB).
struct OcclusionScratch {
  // A point of the viewpoint's group that falls into one of its cells. Most cells hold one point
  // and are never judged, so this carries only what finds its cell's others.
  struct Seen {
    int cell;
    int j;  // into OcclusionBuffers' by-keyframe arrays
    double z;
  };
  std::vector<Seen> seen;
  std::vector<int> count, start, fill;  // per cell
  std::vector<ViewItem> items;          // the judged cells' (two or more points), cell by cell
  std::vector<double> finest;
};

// Occlusion removal's buffers, reused across builds.
struct OcclusionBuffers {
  std::vector<int> keyframe_of, fill;
  Buckets by_keyframe;  // ellipsoid indices by keyframe; j indexes its order
  struct Point {
    Eigen::Vector3d mean;
    double lambda_max;
  };
  std::vector<Point> point;                  // by j
  std::vector<Eigen::Matrix3d> information;  // by j: the floored covariance's inverse
  std::vector<std::vector<int>> removed_by;  // per viewpoint, ellipsoid indices
  tbb::enumerable_thread_specific<OcclusionScratch> scratch;
};

}  // namespace

std::vector<MergeGroup> mergeGroups(const KeyframeGraph& graph, double tau_group) {
  const int n = static_cast<int>(graph.size());
  std::vector<bool> assigned(static_cast<std::size_t>(n), false);
  std::vector<MergeGroup> groups;
  for (int remaining = n; remaining > 0;) {
    int centre = -1;
    double best = -1.0;
    for (int k = 0; k < n; ++k) {
      if (assigned[static_cast<std::size_t>(k)]) continue;
      double sum = 0.0;
      for (const auto& [other, w] : graph.edges().neighbours(k))
        if (!assigned[static_cast<std::size_t>(other)]) sum += w;
      if (sum > best) best = sum, centre = k;
    }
    MergeGroup group{centre, {centre}};
    assigned[static_cast<std::size_t>(centre)] = true;
    for (const auto& [other, w] : graph.edges().neighbours(centre)) {
      if (assigned[static_cast<std::size_t>(other)] || w < tau_group) continue;
      assigned[static_cast<std::size_t>(other)] = true;
      group.members.push_back(other);
    }
    std::sort(group.members.begin(), group.members.end());
    remaining -= static_cast<int>(group.members.size());
    groups.push_back(std::move(group));
  }
  return groups;
}

std::vector<int> meanShiftClusters(const std::vector<Eigen::Vector3d>& means, const std::vector<double>& weights,
                                   double h) {
  std::vector<int> label;
  meanShiftClusters(means, weights, h, &label);
  return label;
}

namespace {

void meanShiftClusters(const std::vector<Eigen::Vector3d>& means, const std::vector<double>& weights, double h,
                       std::vector<int>* label) {
  // Most cells of a merge group hold one surface seen from a few keyframes, all means within h of
  // each other. Then every seed's first window holds every mean, so its first step lands it on the
  // same weighted mean (the same sum in the same order); that point lies in the means' convex hull,
  // hence within h of each of them, so its window again holds them all and it stays: one cluster.
  // The margin on h^2 is far above the rounding of that weighted mean. Not for h = 0 (equal modes
  // still start new clusters there: a distance of 0 is not below h/2) nor without positive weights.
  const double one_kernel_m2 = h * h * (1.0 - 1e-9);
  bool one_cluster = h > 0.0;
  for (std::size_t i = 0; i < means.size() && one_cluster; ++i) {
    one_cluster = weights[i] > 0.0;
    for (std::size_t j = i + 1; j < means.size() && one_cluster; ++j)
      one_cluster = (means[i] - means[j]).squaredNorm() <= one_kernel_m2;
  }
  if (one_cluster)
    label->assign(means.size(), 0);
  else
    *label = meanShiftClustersByIteration(means, weights, h);
}

}  // namespace

std::vector<int> meanShiftClustersByIteration(const std::vector<Eigen::Vector3d>& means,
                                              const std::vector<double>& weights, double h) {
  constexpr double kConverged = 1e-4;  // m (SPEC)
  constexpr int kMaxSteps = 50;
  const double h2 = h * h;
  std::vector<Eigen::Vector3d> modes;
  std::vector<int> label(means.size());
  for (std::size_t i = 0; i < means.size(); ++i) {
    Eigen::Vector3d x = means[i];
    for (int step = 0; step < kMaxSteps; ++step) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      double total = 0.0;
      for (std::size_t j = 0; j < means.size(); ++j) {
        if ((means[j] - x).squaredNorm() > h2) continue;
        sum += weights[j] * means[j];
        total += weights[j];
      }
      if (total <= 0.0) break;
      const Eigen::Vector3d next = sum / total;
      const double shift = (next - x).norm();
      x = next;
      if (shift < kConverged) break;
    }
    int k = 0;
    while (k < static_cast<int>(modes.size()) && (modes[static_cast<std::size_t>(k)] - x).norm() >= h / 2) ++k;
    if (k == static_cast<int>(modes.size())) modes.push_back(x);
    label[i] = k;
  }
  return label;
}

Ellipsoid momentMatch(const std::vector<const Ellipsoid*>& cluster) {
  // SPEC writes Sigma = sum n_i (Sigma_i + d_i d_i^T) / n with population covariances. Ellipsoids
  // carry sample covariances S_i / (n_i - 1), so the scatters are combined instead:
  // S = sum (S_i + n_i d_i d_i^T), Sigma = S / (n - 1): exactly the statistics of the union.
  CellStats u;  // the statistics of the union
  for (const Ellipsoid* e : cluster) {
    u.n += e->count;
    u.mean += e->count * e->mean;
    u.color += e->count * e->color.cast<double>();
  }
  u.mean /= u.n;
  u.color /= u.n;
  for (const Ellipsoid* e : cluster) {
    const Eigen::Vector3d d = e->mean - u.mean;
    u.scatter += (e->count > 1 ? e->count - 1.0 : 0.0) * e->cov + e->count * d * d.transpose();
  }
  Ellipsoid out = *cluster.front();
  out.mean = u.mean;
  out.cov = u.covariance();
  out.color = u.color.cast<float>();
  out.count = static_cast<std::uint32_t>(u.n);
  return out;
}

namespace {

// Largest eigenvalue of every ellipsoid's floored covariance, m^2 (occlusion removal and fusion both rank by it).
std::vector<double> largestEigenvalues(const std::vector<Ellipsoid>& ellipsoids, int threads) {
  std::vector<double> lambda_max(ellipsoids.size());
  parallelFor(threads, ellipsoids.size(), [&](std::size_t i) { lambda_max[i] = largestEigenvalue(floored(ellipsoids[i].cov)); });
  return lambda_max;
}

// Occlusion removal (SPEC 6.3) of n world-frame ellipsoids, at(i) being the i-th and lambda_max[i]
// its largest eigenvalue: removed[i] (resized to n) is 1 when it is removed.
template <typename At>
void occludingEllipsoids(const KeyframeGraph& graph, std::size_t n, const At& at, const std::vector<double>& lambda_max,
                         const GlobalMapParams& params, OcclusionBuffers* buffers, std::vector<char>* removed) {
  OcclusionBuffers& o = *buffers;
  // What the viewpoints read, contiguous by keyframe, so that each streams through its group's
  // ellipsoids instead of gathering them from the big records.
  o.keyframe_of.resize(n);
  for (std::size_t i = 0; i < n; ++i) o.keyframe_of[i] = at(i).keyframe;
  bucketByKey(o.keyframe_of, graph.size(), &o.by_keyframe, &o.fill);
  o.point.resize(n);
  o.information.resize(n);
  parallelFor(params.threads, n, [&](std::size_t j) {
    const std::size_t i = static_cast<std::size_t>(o.by_keyframe.order[j]);
    const Ellipsoid& e = at(i);
    o.point[j] = {e.mean, lambda_max[i]};
    o.information[j] = floored(e.cov).inverse();
  });

  o.removed_by.resize(graph.size());
  parallelFor(params.threads, graph.size(), [&](std::size_t v) {
    const Keyframe& K = graph.keyframe(static_cast<int>(v));
    const Transform T_K_W = K.T_W_K.inverse();
    const Eigen::Vector3d centre = K.T_W_K.translation();
    OcclusionScratch& s = o.scratch.local();
    const std::size_t cells = static_cast<std::size_t>(K.container.cols()) * K.container.rows();
    const CellOfPixel cellOfPixel(K.container);
    s.count.assign(cells, 0);
    s.seen.clear();
    for (int g : occlusionGroup(graph, K, params))
      for (int j = o.by_keyframe.start[static_cast<std::size_t>(g)]; j < o.by_keyframe.start[static_cast<std::size_t>(g) + 1]; ++j) {
        const Eigen::Vector3d p = T_K_W * o.point[static_cast<std::size_t>(j)].mean;
        if (p.z() <= 0.0) continue;
        const Eigen::Vector2d uv = K.container.camera().project(p);
        const int cell = cellOfPixel(uv.x(), uv.y());
        if (cell < 0) continue;
        s.seen.push_back({cell, j, p.z()});
        ++s.count[static_cast<std::size_t>(cell)];
      }
    // The judged cells' points, written cell by cell in one more pass over the group (in order of
    // j, so the reads stream) rather than gathered cell by cell from anywhere in the map.
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
          e.z, q.lambda_max, q.mean - centre, e.j, o.by_keyframe.order[static_cast<std::size_t>(e.j)]};
    }
    std::vector<int>& removed_here = o.removed_by[v];
    removed_here.clear();
    for (std::size_t cell = 0; cell < cells; ++cell)
      if (s.count[cell] >= 2)
        removeOccludersInCell(std::span<ViewItem>(s.items).subspan(static_cast<std::size_t>(s.start[cell]),
                                                                   static_cast<std::size_t>(s.count[cell])),
                              o.information, &s.finest, &removed_here);
  });
  removed->assign(n, 0);
  for (const std::vector<int>& list : o.removed_by)
    for (int i : list) (*removed)[static_cast<std::size_t>(i)] = 1;
}

// A match of fusion: ellipsoids a and b are copies of one surface at this distance.
struct FusionMatch {
  int a, b;
  double distance;
};

// Fusion's buffers, reused across builds (names as in fuseAcrossGroups).
struct FusionBuffers {
  std::vector<std::pair<std::uint64_t, int>> entries;
  std::vector<Eigen::Vector3d> mean;
  std::vector<SymmetricCov> cov;
  std::vector<double> lambda;
  std::vector<int> group, index;
  std::vector<std::size_t> voxel_start, slot;
  std::vector<std::uint64_t> voxel;
  std::vector<std::array<int, 13>> neighbour;
  std::vector<std::vector<FusionMatch>> found;
  std::vector<int> partner_start, fill, seed_of, member_of;
  std::vector<std::pair<int, double>> partner, taken;
  std::vector<std::pair<double, int>> order;
  Buckets members;
};

// fuseAcrossGroups of n ellipsoids, at(i) being the i-th, with lambda_max = their largest eigenvalues.
template <typename At>
std::vector<Ellipsoid> fuseAcrossGroups(std::size_t n, const At& at, const std::vector<int>& group_of,
                                        const std::vector<double>& lambda_max, const GlobalMapParams& params,
                                        FusionBuffers* buffers);

}  // namespace

std::vector<bool> occludingEllipsoids(const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids,
                                      const GlobalMapParams& params) {
  OcclusionBuffers buffers;
  std::vector<char> removed;
  occludingEllipsoids(
      graph, ellipsoids.size(), [&](std::size_t i) -> const Ellipsoid& { return ellipsoids[i]; },
      largestEigenvalues(ellipsoids, params.threads), params, &buffers, &removed);
  return std::vector<bool>(removed.begin(), removed.end());
}

double bhattacharyyaDistance(const Ellipsoid& a, const Ellipsoid& b) {
  const SymmetricCov Sa = SymmetricCov::of(a.cov), Sb = SymmetricCov::of(b.cov), S = Sa.average(Sb);
  return meanTerm(a.mean - b.mean, S) + shapeTerm(S, Sa, Sb);
}

double fusionHalfWidth(const std::vector<Ellipsoid>& ellipsoids, const GlobalMapParams& params) {
  return fusionHalfWidth(largestEigenvalues(ellipsoids, params.threads));
}

std::vector<Ellipsoid> fuseAcrossGroups(const std::vector<Ellipsoid>& ellipsoids, const std::vector<int>& group_of,
                                        const GlobalMapParams& params) {
  FusionBuffers buffers;
  return fuseAcrossGroups(
      ellipsoids.size(), [&](std::size_t i) -> const Ellipsoid& { return ellipsoids[i]; }, group_of,
      largestEigenvalues(ellipsoids, params.threads), params, &buffers);
}

namespace {

template <typename At>
std::vector<Ellipsoid> fuseAcrossGroups(std::size_t n, const At& at, const std::vector<int>& group_of,
                                        const std::vector<double>& lambda_max, const GlobalMapParams& params,
                                        FusionBuffers* buffers) {
  FusionBuffers& f = *buffers;
  const double max_distance = params.fusion_max_distance;
  // Voxels of side >= half, so that the cube around a mean lies in the 27 voxels around its own,
  // counted from the map's corner and packed 21 bits per axis into one key that sorts like (x, y,
  // z); a map wider than 2^21 - 2 voxels along an axis gets larger voxels.
  const double half = fusionHalfWidth(lambda_max);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) lo = lo.cwiseMin(at(i).mean), hi = hi.cwiseMax(at(i).mean);
  constexpr std::int64_t kAxisVoxels = (std::int64_t{1} << 21) - 2;
  const double side = n > 0 ? std::max(half, (hi - lo).maxCoeff() / static_cast<double>(kAxisVoxels - 1)) : half;
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::uint64_t>(x) << 42 | static_cast<std::uint64_t>(y) << 21 | static_cast<std::uint64_t>(z);
  };
  auto& entries = f.entries;  // (voxel key, index), sorted
  entries.resize(n);
  parallelFor(params.threads, n, [&](std::size_t i) {
    const Eigen::Vector3d c = ((at(i).mean - lo) / side).array().floor();
    entries[i] = {key(static_cast<std::int64_t>(c.x()), static_cast<std::int64_t>(c.y()), static_cast<std::int64_t>(c.z())),
                  static_cast<int>(i)};
  });
  parallelSort(params.threads, entries.begin(), entries.end());
  // What the search reads, in that order.
  auto& mean = f.mean;
  auto& cov = f.cov;
  auto& lambda = f.lambda;
  auto &group = f.group, &index = f.index;
  mean.resize(n), cov.resize(n), lambda.resize(n), group.resize(n), index.resize(n);
  parallelFor(params.threads, n, [&](std::size_t k) {
    const std::size_t i = static_cast<std::size_t>(entries[k].second);
    const Ellipsoid& e = at(i);
    mean[k] = e.mean, cov[k] = SymmetricCov::of(e.cov), lambda[k] = lambda_max[i];
    group[k] = group_of[i], index[k] = entries[k].second;
  });
  auto& voxel_start = f.voxel_start;  // voxel v holds sorted positions voxel_start[v] .. voxel_start[v + 1]
  auto& voxel = f.voxel;
  voxel_start.clear(), voxel.clear();
  for (std::size_t k = 0; k < n; ++k)
    if (k == 0 || entries[k].first != entries[k - 1].first) {
      voxel_start.push_back(k);
      voxel.push_back(entries[k].first);
    }
  const std::size_t voxels = voxel.size();
  voxel_start.push_back(n);
  // Each pair of neighbouring voxels once: the 13 offsets that are positive in (dz, dy, dx) order.
  // Adding an offset keeps the voxels' order, so one pointer per offset walks the sorted list.
  constexpr int kForward = 13;
  auto& neighbour = f.neighbour;  // -1: none
  neighbour.resize(voxels);
  constexpr std::uint64_t kMask = (std::uint64_t{1} << 21) - 1;
  parallelFor(params.threads, kForward, [&](std::size_t o) {
    const int c = 14 + static_cast<int>(o);  // (dx, dy, dz) = (c % 3, c / 3 % 3, c / 9) - 1
    std::size_t u = 0;
    for (std::size_t v = 0; v < voxels; ++v) {
      neighbour[v][static_cast<std::size_t>(o)] = -1;
      const std::int64_t x = static_cast<std::int64_t>(voxel[v] >> 42) + c % 3 - 1;
      const std::int64_t y = static_cast<std::int64_t>(voxel[v] >> 21 & kMask) + c / 3 % 3 - 1;
      const std::int64_t z = static_cast<std::int64_t>(voxel[v] & kMask) + c / 9 - 1;
      if (x < 0 || y < 0 || z < 0) continue;
      const std::uint64_t target = key(x, y, z);
      while (u < voxels && voxel[u] < target) ++u;
      if (u < voxels && voxel[u] == target) neighbour[v][o] = static_cast<int>(u);
    }
  });

  // Every pair of different groups within the cube whose distance is at most max_distance.
  // The shape term is >= 0 and the mean term >= |d|^2 / (8 lambda_max(S)) >= |d|^2 / (4 (lambda_a +
  // lambda_b)): most pairs are rejected before the distance is computed (the margin keeps rounding
  // from rejecting a pair on the boundary), most others after its mean term. Each pair is met
  // once: within a voxel as k < l, across voxels from one side.
  constexpr std::size_t kChunk = 256;  // voxels per task; each task fills its own list
  auto& found = f.found;
  found.resize((voxels + kChunk - 1) / kChunk);
  parallelFor(params.threads, found.size(), [&](std::size_t chunk) {
    found[chunk].clear();
    for (std::size_t v = chunk * kChunk; v < std::min(voxels, (chunk + 1) * kChunk); ++v)
      for (int o = -1; o < kForward; ++o) {
        const int u = o < 0 ? static_cast<int>(v) : neighbour[v][static_cast<std::size_t>(o)];
        if (u < 0) continue;
        const std::size_t end = voxel_start[static_cast<std::size_t>(u) + 1];
        for (std::size_t k = voxel_start[v]; k < voxel_start[v + 1]; ++k)
          for (std::size_t l = o < 0 ? k + 1 : voxel_start[static_cast<std::size_t>(u)]; l < end; ++l) {
            if (group[l] == group[k]) continue;
            const Eigen::Vector3d d = mean[k] - mean[l];
            if (d.cwiseAbs().maxCoeff() > half || d.squaredNorm() > 4.0 * max_distance * (lambda[k] + lambda[l]) * (1.0 + 1e-9))
              continue;
            const SymmetricCov S = cov[k].average(cov[l]);
            const double mean_term = meanTerm(d, S);
            if (mean_term > max_distance) continue;
            const double distance = mean_term + shapeTerm(S, cov[k], cov[l]);
            if (distance <= max_distance) found[chunk].push_back({index[k], index[l], distance});
          }
      }
  });
  // Both directions of every match, per ellipsoid (partners of i: partner[start[i] .. start[i + 1])).
  auto& partner_start = f.partner_start;
  partner_start.assign(n + 1, 0);
  for (const std::vector<FusionMatch>& list : found)
    for (const FusionMatch& m : list) ++partner_start[static_cast<std::size_t>(m.a) + 1], ++partner_start[static_cast<std::size_t>(m.b) + 1];
  std::partial_sum(partner_start.begin(), partner_start.end(), partner_start.begin());
  auto& partner = f.partner;
  partner.resize(static_cast<std::size_t>(partner_start[n]));
  {
    std::vector<int>& fill = f.fill;
    fill.assign(partner_start.begin(), partner_start.end() - 1);
    for (const std::vector<FusionMatch>& list : found)
      for (const FusionMatch& m : list) {
        partner[static_cast<std::size_t>(fill[static_cast<std::size_t>(m.a)]++)] = {m.b, m.distance};
        partner[static_cast<std::size_t>(fill[static_cast<std::size_t>(m.b)]++)] = {m.a, m.distance};
      }
  }

  // Greedy, most precise first (ellipsoids without partners stay as they are, in any order).
  auto& order = f.order;
  order.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (partner_start[i + 1] > partner_start[i]) order.push_back({lambda_max[i], static_cast<int>(i)});
  parallelSort(params.threads, order.begin(), order.end());
  auto& seed_of = f.seed_of;  // the seed whose cluster ellipsoid i joined; -1: alone
  seed_of.assign(n, -1);
  auto& taken = f.taken;  // per partner group: its nearest partner so far
  for (const auto& [lambda_s, s] : order) {
    if (seed_of[static_cast<std::size_t>(s)] >= 0) continue;
    taken.clear();
    for (int k = partner_start[static_cast<std::size_t>(s)]; k < partner_start[static_cast<std::size_t>(s) + 1]; ++k) {
      const auto [other, distance] = partner[static_cast<std::size_t>(k)];
      if (seed_of[static_cast<std::size_t>(other)] >= 0) continue;
      const int g = group_of[static_cast<std::size_t>(other)];
      auto best = std::find_if(taken.begin(), taken.end(),
                               [&](const auto& t) { return group_of[static_cast<std::size_t>(t.first)] == g; });
      if (best == taken.end())
        taken.push_back({other, distance});
      else if (distance < best->second || (distance == best->second && other < best->first))
        *best = {other, distance};
    }
    if (taken.empty()) continue;
    seed_of[static_cast<std::size_t>(s)] = s;
    for (const auto& t : taken) seed_of[static_cast<std::size_t>(t.first)] = s;
  }

  // One ellipsoid per cluster or lone ellipsoid, in the order of the seeds' indices.
  auto& member_of = f.member_of;  // the seed an ellipsoid joined, -1 for seeds and lone ones
  member_of.resize(n);
  for (std::size_t i = 0; i < n; ++i) member_of[i] = seed_of[i] == static_cast<int>(i) ? -1 : seed_of[i];
  bucketByKey(member_of, n, &f.members, &f.fill);
  const Buckets& members = f.members;
  auto& slot = f.slot;  // where seed or lone ellipsoid i goes in the output
  slot.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) slot[i + 1] = slot[i] + (member_of[i] < 0 ? 1 : 0);
  std::vector<Ellipsoid> out(slot[n]);
  parallelFor(params.threads, (n + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    std::vector<const Ellipsoid*> cluster;
    for (std::size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i) {
      if (seed_of[i] < 0) {
        out[slot[i]] = at(i);
      } else if (seed_of[i] == static_cast<int>(i)) {
        cluster.assign(1, &at(i));
        for (int k = members.start[i]; k < members.start[i + 1]; ++k)
          cluster.push_back(&at(static_cast<std::size_t>(members.order[static_cast<std::size_t>(k)])));
        out[slot[i]] = momentMatch(cluster);  // keeps the seed's keyframe and cell
      }
    }
  });
  return out;
}

}  // namespace

std::vector<Ellipsoid> localEllipsoids(const KeyframeGraph& graph, const GlobalMap& map) {
  std::vector<Ellipsoid> local;
  local.reserve(map.sigma_e);
  for (const Keyframe& k : graph.keyframes())
    forEachKeptEllipsoid(k.container, map.kept.at(static_cast<std::size_t>(k.id)), k.T_W_K, k.id,
                         [&local](const Ellipsoid& e) { local.push_back(e); });
  return local;
}

struct GlobalMapWorkspace::Buffers {
  // Per keyframe id: its kept cells and what they were computed from.
  struct Kept {
    std::uint64_t container = 0, revision = 0;
    FilterParams filter;
    std::vector<bool> kept;
  };
  std::vector<Kept> kept;
  std::vector<std::vector<Ellipsoid>> merged;  // per merge group
  tbb::enumerable_thread_specific<MergeScratch> merge_scratch;
  std::vector<std::size_t> offset, kept_offset;
  std::vector<int> group_of, kept_group_of;
  std::vector<double> lambda_max, kept_lambda_max;
  std::vector<char> removed;
  std::vector<const Ellipsoid*> survivor;  // into merged: what occlusion removal kept, in order
  OcclusionBuffers occlusion;
  FusionBuffers fusion;
};

GlobalMapWorkspace::GlobalMapWorkspace() : buffers_(std::make_unique<Buffers>()) {}
GlobalMapWorkspace::~GlobalMapWorkspace() = default;

GlobalMap buildGlobalMap(const KeyframeGraph& graph, const GlobalMapParams& params, GlobalMapWorkspace* workspace) {
  params.validate();
  std::unique_ptr<GlobalMapWorkspace> own;  // this build's, without one given
  if (workspace == nullptr) workspace = (own = std::make_unique<GlobalMapWorkspace>()).get();
  GlobalMapWorkspace::Buffers& ws = *workspace->buffers_;
  GlobalMap map;
  const auto start = Clock::now();
  map.groups = mergeGroups(graph, params.tau_group);
  map.groups_ms = msSince(start);

  const auto merge_start = Clock::now();
  // The filter's answer depends on a container and the filter parameters only, not on poses: a
  // rebuild after a loop closure reuses it for every keyframe.
  ws.kept.resize(graph.size());
  parallelFor(params.threads, graph.size(), [&](std::size_t k) {
    const KeyframeContainer& box = graph.keyframe(static_cast<int>(k)).container;
    GlobalMapWorkspace::Buffers::Kept& cached = ws.kept[k];
    // (id, revision) name the container's cells exactly (keyframe_container.h); ids start at 1, so
    // a new entry (container 0) never matches.
    if (cached.container != box.id() || cached.revision != box.revision() || cached.filter != params.filter)
      cached = {box.id(), box.revision(), params.filter, keptCells(box, params.filter)};
  });
  map.kept.resize(graph.size());
  for (std::size_t k = 0; k < graph.size(); ++k) {
    map.kept[k] = ws.kept[k].kept;
    map.sigma_e += static_cast<std::size_t>(std::count(map.kept[k].begin(), map.kept[k].end(), true));
  }
  ws.merged.resize(map.groups.size());
  parallelFor(params.threads, map.groups.size(), [&](std::size_t g) {
    mergeGroup(graph, map.groups[g], params, map.kept, &ws.merge_scratch.local(), &ws.merged[g]);
  });
  // Ellipsoid i of the merge is ws.merged[g][i - offset[g]], g = group_of[i].
  const std::size_t groups = ws.merged.size();
  ws.offset.assign(groups + 1, 0);
  for (std::size_t g = 0; g < groups; ++g) ws.offset[g + 1] = ws.offset[g] + ws.merged[g].size();
  const std::size_t n = ws.offset.back();
  map.merged = n;
  const bool need_lambda = params.occlusion_removal || params.fuse_across_groups;
  ws.group_of.resize(n);
  ws.lambda_max.resize(need_lambda ? n : 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    for (std::size_t l = 0; l < ws.merged[g].size(); ++l) {
      ws.group_of[ws.offset[g] + l] = static_cast<int>(g);
      if (need_lambda) ws.lambda_max[ws.offset[g] + l] = largestEigenvalue(floored(ws.merged[g][l].cov));
    }
  });
  map.merge_ms = msSince(merge_start);

  // Occlusion removal before fusion: it judges each viewpoint's own group's ellipsoids, and a
  // fused ellipsoid carries only its seed's keyframe, so fusing first would hide copies from the
  // viewpoints whose coarse occluders they remove.
  const auto occlusion_start = Clock::now();
  if (params.occlusion_removal) {
    auto at = [&](std::size_t i) -> const Ellipsoid& {
      const std::size_t g = static_cast<std::size_t>(ws.group_of[i]);
      return ws.merged[g][i - ws.offset[g]];
    };
    occludingEllipsoids(graph, n, at, ws.lambda_max, params, &ws.occlusion, &ws.removed);
  } else {
    ws.removed.assign(n, 0);
  }
  // The survivors, in order: their indices, groups and lambda_max.
  ws.kept_offset.assign(groups + 1, 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    ws.kept_offset[g + 1] = static_cast<std::size_t>(
        std::count(ws.removed.begin() + static_cast<std::ptrdiff_t>(ws.offset[g]),
                   ws.removed.begin() + static_cast<std::ptrdiff_t>(ws.offset[g + 1]), 0));
  });
  std::partial_sum(ws.kept_offset.begin(), ws.kept_offset.end(), ws.kept_offset.begin());
  const std::size_t kept = ws.kept_offset.back();
  ws.survivor.resize(kept);
  ws.kept_group_of.resize(kept);
  ws.kept_lambda_max.resize(need_lambda ? kept : 0);
  parallelFor(params.threads, groups, [&](std::size_t g) {
    std::size_t to = ws.kept_offset[g];
    for (std::size_t i = ws.offset[g]; i < ws.offset[g + 1]; ++i) {
      if (ws.removed[i]) continue;
      ws.survivor[to] = ws.merged[g].data() + (i - ws.offset[g]);
      ws.kept_group_of[to] = static_cast<int>(g);
      if (need_lambda) ws.kept_lambda_max[to] = ws.lambda_max[i];
      ++to;
    }
  });
  map.occlusion_ms = msSince(occlusion_start);

  const auto fusion_start = Clock::now();
  auto survivor = [&](std::size_t k) -> const Ellipsoid& { return *ws.survivor[k]; };
  if (params.fuse_across_groups) {
    map.ellipsoids = fuseAcrossGroups(kept, survivor, ws.kept_group_of, ws.kept_lambda_max, params, &ws.fusion);
    map.merged_across_groups = kept - map.ellipsoids.size();
  } else {
    map.ellipsoids.resize(kept);
    parallelFor(params.threads, kept, [&](std::size_t k) { map.ellipsoids[k] = survivor(k); });
  }
  map.fusion_ms = msSince(fusion_start);
  map.sigma_e_prime = map.ellipsoids.size();
  map.t_g_s = secondsSince(start);
  return map;
}

}  // namespace vdmap
