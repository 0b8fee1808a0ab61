#include "mapping/global_map/level_up.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

#include <Eigen/Eigenvalues>

namespace vdmap {
namespace {

constexpr double kRadiusM = 0.12;                     // a patch: the means within this of its centre (at least)
constexpr std::size_t kMaxPoints = 60000;             // means looked at (evenly strided)
constexpr std::size_t kMaxPatches = 3000;             // patch centres (evenly strided)
const double kAlign = std::cos(10.0 * M_PI / 180.0);  // a normal along a direction: within 10 degrees

struct Patch {
  Eigen::Vector3d centre, normal;
};

// The flat neighbourhoods of `points` (the smallest of the three PCA variances under 3% of their
// sum) at up to kMaxPatches evenly strided centres, with their unit normals.
std::vector<Patch> flatPatches(const std::vector<Eigen::Vector3d>& points, double radius) {
  const auto cell = [radius](const Eigen::Vector3d& p) {
    return Eigen::Vector3i(static_cast<int>(std::floor(p.x() / radius)), static_cast<int>(std::floor(p.y() / radius)),
                           static_cast<int>(std::floor(p.z() / radius)));
  };
  const auto key = [](const Eigen::Vector3i& c) {
    return (static_cast<std::int64_t>(c.x() & 0x1fffff) << 42) | (static_cast<std::int64_t>(c.y() & 0x1fffff) << 21) |
           static_cast<std::int64_t>(c.z() & 0x1fffff);
  };
  std::unordered_map<std::int64_t, std::vector<std::size_t>> grid;
  for (std::size_t i = 0; i < points.size(); ++i) grid[key(cell(points[i]))].push_back(i);
  std::vector<Patch> patches;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / kMaxPatches);
  for (std::size_t i = 0; i < points.size(); i += stride) {
    const Eigen::Vector3d& c = points[i];
    const Eigen::Vector3i home = cell(c);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    int n = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key(home + Eigen::Vector3i(dx, dy, dz)));
          if (it == grid.end()) continue;
          for (const std::size_t j : it->second)
            if ((points[j] - c).squaredNorm() < radius * radius) {
              mean += points[j];
              second += points[j] * points[j].transpose();
              ++n;
            }
        }
    if (n < 8) continue;
    mean /= n;
    const Eigen::Matrix3d cov = second / n - mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d l = eig.eigenvalues();
    if (!(l(0) < 0.03 * l.sum())) continue;
    patches.push_back({c, eig.eigenvectors().col(0)});
  }
  return patches;
}

// The direction (sign-free) among `candidates` that most `normals` lie along, refined to the
// principal direction of those normals; `count` receives how many.
Eigen::Vector3d commonDirection(const std::vector<Eigen::Vector3d>& normals,
                                const std::vector<Eigen::Vector3d>& candidates, std::size_t* count) {
  Eigen::Vector3d best = candidates.front();
  std::size_t best_n = 0;
  for (const Eigen::Vector3d& c : candidates) {
    std::size_t n = 0;
    for (const Eigen::Vector3d& m : normals) n += std::abs(m.dot(c)) > kAlign;
    if (n > best_n) best_n = n, best = c;
  }
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& m : normals)
    if (std::abs(m.dot(best)) > kAlign) scatter += m * m.transpose();
  if (best_n > 0) best = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(2);
  *count = best_n;
  return best;
}

}  // namespace

std::optional<LevelUp> levelUp(std::span<const Ellipsoid> map) {
  const std::size_t stride = std::max<std::size_t>(1, map.size() / kMaxPoints);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < map.size(); i += stride) points.push_back(map[i].mean);
  // Coarse maps (an OctoMap's voxels) get patches of at least four voxels' radius, so a voxel
  // staircase along a sloping surface is not taken for a grid-aligned plane: the side of the
  // cube each ellipsoid's covariance stands for (sqrt(12 var), a uniform cube's), median.
  std::vector<double> sides;
  for (std::size_t i = 0; i < map.size(); i += stride) sides.push_back(std::sqrt(12.0 * map[i].cov.trace() / 3.0));
  double radius = kRadiusM;
  if (!sides.empty()) {
    std::nth_element(sides.begin(), sides.begin() + static_cast<long>(sides.size() / 2), sides.end());
    radius = std::max(kRadiusM, 4.0 * sides[sides.size() / 2]);
  }
  const std::vector<Patch> patches = flatPatches(points, radius);
  std::vector<Eigen::Vector3d> normals;
  for (const Patch& p : patches) normals.push_back(p.normal);
  if (normals.size() < 30) return std::nullopt;
  LevelUp out;
  out.patches = normals.size();
  // The three plane directions: the most common normal, the most common one at right angles to
  // it (normals within 10 degrees of perpendicular, projected), and their cross product.
  std::size_t n1 = 0, n2 = 0, n3 = 0;
  const Eigen::Vector3d a1 = commonDirection(normals, normals, &n1);
  std::vector<Eigen::Vector3d> across;
  for (const Eigen::Vector3d& m : normals) {
    const Eigen::Vector3d p = m - m.dot(a1) * a1;
    if (p.norm() > kAlign) across.push_back(p.normalized());
  }
  Eigen::Vector3d a2 = a1.unitOrthogonal();
  if (!across.empty()) a2 = commonDirection(normals, across, &n2);
  a2 = (a2 - a2.dot(a1) * a1).normalized();
  const Eigen::Vector3d a3 = a1.cross(a2);
  for (const Eigen::Vector3d& m : normals) n3 += std::abs(m.dot(a3)) > kAlign;
  out.axes << a1, a2, a3;
  out.share = Eigen::Vector3d(static_cast<double>(n1), static_cast<double>(n2), static_cast<double>(n3)) /
              static_cast<double>(normals.size());
  // Per direction: the means' 2-98 % extent along it, and the share of the patches facing it
  // that lie below the means' median.
  std::vector<double> below(3, 0.0), extent(3, 0.0);
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d a = out.axes.col(k);
    std::vector<double> sorted;
    for (const Eigen::Vector3d& p : points) sorted.push_back(a.dot(p));
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    extent[k] = sorted[sorted.size() * 98 / 100] - sorted[sorted.size() * 2 / 100];
    std::size_t facing = 0, low = 0;
    for (const Patch& p : patches)
      if (std::abs(p.normal.dot(a)) > kAlign) ++facing, low += a.dot(p.centre) < median;
    below[k] = facing ? static_cast<double>(low) / static_cast<double>(facing) : 0.5;
  }
  // Up: the direction whose planes are most common for the map's extent along it. Level
  // surfaces (floor, tables, counters) are seen from above by a camera held at eye height, so
  // they outnumber any one wall direction, and a room is lower than it is wide.
  double best = -1.0;
  for (int k = 0; k < 3; ++k)
    if (const double score = out.share(k) / std::max(extent[k], 1e-3); score > best) best = score, out.up_column = k;
  // Its sign: the level patches lie mostly in the lower half of the map (floors, tables and
  // counters below eye level), so up points from them into the map.
  out.up = out.axes.col(out.up_column);
  if (below[static_cast<std::size_t>(out.up_column)] < 0.5) out.up = -out.up;
  return out;
}

}  // namespace vdmap
