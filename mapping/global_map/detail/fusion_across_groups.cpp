#include "mapping/global_map/detail/fusion_across_groups.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "mapping/core/parallel.h"

namespace vdmap {
namespace global_map_detail {
namespace {

// The two terms of the Bhattacharyya distance, S = (Sa + Sb) / 2: the offset of the means
// 1/8 d^T S^-1 d, and the difference of the shapes 1/2 ln(det S / sqrt(det Sa det Sb)) >= 0.
double meanTerm(const Eigen::Vector3d& d, const SymmetricCov& S) { return 0.125 * S.inverseQuadratic(d); }
double shapeTerm(const SymmetricCov& S, const SymmetricCov& Sa, const SymmetricCov& Sb) {
  return 0.5 * std::log(S.determinant() / std::sqrt(Sa.determinant() * Sb.determinant()));
}

// fusionHalfWidth in median standard deviations. Copies of one surface cell lie within a fraction
// of a cell of each other: a narrower cube misses some of them, a wider one finds few more and
// searches more (docs/notes/global-map.md, "Fusion", has the counts).
constexpr double kFusionCubeSigmas = 1.5;

// Voxels (search) or ellipsoids (output) per task; each task fills its own list or slots.
constexpr std::size_t kChunk = 256;

// fusionHalfWidth from the ellipsoids' lambda_max.
double fusionHalfWidth(std::vector<double> lambda_max) {
  if (lambda_max.empty()) return 0.0;
  const auto middle = lambda_max.begin() + static_cast<std::ptrdiff_t>(lambda_max.size() / 2);
  std::nth_element(lambda_max.begin(), middle, lambda_max.end());
  return std::max(kFusionCubeSigmas * std::sqrt(*middle), 1e-5);
}

// What the search reads, in the grid's sorted order: f->mean, cov, lambda, group and index.
void gatherInGridOrder(std::span<const Ellipsoid* const> ellipsoids, const std::vector<int>& group_of,
                       const std::vector<double>& lambda_max, int threads, FusionBuffers* buffers) {
  FusionBuffers& f = *buffers;
  const std::size_t n = ellipsoids.size();
  f.mean.resize(n), f.cov.resize(n), f.lambda.resize(n), f.group.resize(n), f.index.resize(n);
  parallelFor(threads, n, [&](std::size_t k) {
    const int point = f.grid.pointAt(k);
    const std::size_t i = static_cast<std::size_t>(point);
    const Ellipsoid& e = *ellipsoids[i];
    f.mean[k] = e.mean, f.cov[k] = SymmetricCov::of(e.cov), f.lambda[k] = lambda_max[i];
    f.group[k] = group_of[i], f.index[k] = point;
  });
}

// Every pair of different groups within the cube of half-width `half` whose distance is at most
// max_distance, into f->found (per chunk of voxels). The shape term is >= 0 and the mean term >=
// |d|^2 / (8 lambda_max(S)) >= |d|^2 / (4 (lambda_a + lambda_b)): most pairs are rejected before
// the distance is computed (the margin keeps rounding from rejecting a pair on the boundary), most
// others after its mean term. Each pair is met once: within a voxel as k < l, across voxels from
// one side.
void findCopies(double half, double max_distance, int threads, FusionBuffers* buffers) {
  FusionBuffers& f = *buffers;
  const SortedVoxelGrid& grid = f.grid;
  const std::size_t voxels = grid.voxelCount();
  f.found.resize((voxels + kChunk - 1) / kChunk);
  parallelFor(threads, f.found.size(), [&](std::size_t chunk) {
    std::vector<FusionMatch>& found = f.found[chunk];
    found.clear();
    for (std::size_t v = chunk * kChunk; v < std::min(voxels, (chunk + 1) * kChunk); ++v)
      for (int o = -1; o < SortedVoxelGrid::kForwardNeighbours; ++o) {
        const int u = o < 0 ? static_cast<int>(v) : grid.forwardNeighbour(v, static_cast<std::size_t>(o));
        if (u < 0) continue;
        const std::size_t end = grid.voxelEnd(static_cast<std::size_t>(u));
        for (std::size_t k = grid.voxelBegin(v); k < grid.voxelEnd(v); ++k)
          for (std::size_t l = o < 0 ? k + 1 : grid.voxelBegin(static_cast<std::size_t>(u)); l < end; ++l) {
            if (f.group[l] == f.group[k]) continue;
            const Eigen::Vector3d d = f.mean[k] - f.mean[l];
            if (d.cwiseAbs().maxCoeff() > half ||
                d.squaredNorm() > 4.0 * max_distance * (f.lambda[k] + f.lambda[l]) * (1.0 + 1e-9))
              continue;
            const SymmetricCov S = f.cov[k].average(f.cov[l]);
            const double mean_term = meanTerm(d, S);
            if (mean_term > max_distance) continue;
            const double distance = mean_term + shapeTerm(S, f.cov[k], f.cov[l]);
            if (distance <= max_distance) found.push_back({f.index[k], f.index[l], distance});
          }
      }
  });
}

// Both directions of every match found, per ellipsoid: f->partner_start and f->partner.
void partnersOf(std::size_t n, FusionBuffers* buffers) {
  FusionBuffers& f = *buffers;
  auto& partner_start = f.partner_start;
  partner_start.assign(n + 1, 0);
  for (const std::vector<FusionMatch>& list : f.found)
    for (const FusionMatch& m : list)
      ++partner_start[static_cast<std::size_t>(m.a) + 1], ++partner_start[static_cast<std::size_t>(m.b) + 1];
  std::partial_sum(partner_start.begin(), partner_start.end(), partner_start.begin());
  f.partner.resize(static_cast<std::size_t>(partner_start[n]));
  f.fill.assign(partner_start.begin(), partner_start.end() - 1);
  for (const std::vector<FusionMatch>& list : f.found)
    for (const FusionMatch& m : list) {
      f.partner[static_cast<std::size_t>(f.fill[static_cast<std::size_t>(m.a)]++)] = {m.b, m.distance};
      f.partner[static_cast<std::size_t>(f.fill[static_cast<std::size_t>(m.b)]++)] = {m.a, m.distance};
    }
}

// Seed s's nearest partner per other group among those not yet fused (ties: lowest index), into f->taken.
void nearestPerGroup(int s, const std::vector<int>& group_of, FusionBuffers* buffers) {
  FusionBuffers& f = *buffers;
  auto& taken = f.taken;
  taken.clear();
  for (int k = f.partner_start[static_cast<std::size_t>(s)]; k < f.partner_start[static_cast<std::size_t>(s) + 1];
       ++k) {
    const auto [other, distance] = f.partner[static_cast<std::size_t>(k)];
    if (f.seed_of[static_cast<std::size_t>(other)] >= 0) continue;
    const int g = group_of[static_cast<std::size_t>(other)];
    auto best = std::find_if(taken.begin(), taken.end(),
                             [&](const auto& t) { return group_of[static_cast<std::size_t>(t.first)] == g; });
    if (best == taken.end()) taken.push_back({other, distance});
    else if (distance < best->second || (distance == best->second && other < best->first)) *best = {other, distance};
  }
}

// The clusters, greedily, most precise first: f->seed_of[i] is the seed whose cluster ellipsoid i
// joined, -1 when it stays alone (ellipsoids without partners stay as they are, in any order).
void clusterGreedily(std::size_t n, const std::vector<int>& group_of, const std::vector<double>& lambda_max,
                     int threads, FusionBuffers* buffers) {
  FusionBuffers& f = *buffers;
  f.order.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (f.partner_start[i + 1] > f.partner_start[i]) f.order.push_back({lambda_max[i], static_cast<int>(i)});
  parallelSort(threads, f.order.begin(), f.order.end());
  f.seed_of.assign(n, -1);
  for (const auto& [lambda_s, s] : f.order) {
    if (f.seed_of[static_cast<std::size_t>(s)] >= 0) continue;
    nearestPerGroup(s, group_of, &f);
    if (f.taken.empty()) continue;
    f.seed_of[static_cast<std::size_t>(s)] = s;
    for (const auto& t : f.taken) f.seed_of[static_cast<std::size_t>(t.first)] = s;
  }
}

// One ellipsoid per cluster (moment matched, with the seed's keyframe and cell) or lone
// ellipsoid, in the order of the seeds' indices.
std::vector<Ellipsoid> fuseClusters(std::span<const Ellipsoid* const> ellipsoids, int threads, FusionBuffers* buffers) {
  FusionBuffers& f = *buffers;
  const std::size_t n = ellipsoids.size();
  auto& member_of = f.member_of;  // the seed an ellipsoid joined, -1 for seeds and lone ones
  member_of.resize(n);
  for (std::size_t i = 0; i < n; ++i) member_of[i] = f.seed_of[i] == static_cast<int>(i) ? -1 : f.seed_of[i];
  bucketByKey(member_of, n, &f.members, &f.fill);
  const Buckets& members = f.members;
  auto& slot = f.slot;  // where seed or lone ellipsoid i goes in the output
  slot.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) slot[i + 1] = slot[i] + (member_of[i] < 0 ? 1 : 0);
  std::vector<Ellipsoid> out(slot[n]);
  parallelFor(threads, (n + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    std::vector<const Ellipsoid*> cluster;
    for (std::size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i) {
      if (f.seed_of[i] < 0) {
        out[slot[i]] = *ellipsoids[i];
      } else if (f.seed_of[i] == static_cast<int>(i)) {
        cluster.assign(1, ellipsoids[i]);
        for (int k = members.start[i]; k < members.start[i + 1]; ++k)
          cluster.push_back(ellipsoids[static_cast<std::size_t>(members.order[static_cast<std::size_t>(k)])]);
        out[slot[i]] = momentMatch(cluster);  // keeps the seed's keyframe and cell
      }
    }
  });
  return out;
}

}  // namespace

std::vector<Ellipsoid> fuseAcrossGroups(std::span<const Ellipsoid* const> ellipsoids, const std::vector<int>& group_of,
                                        const std::vector<double>& lambda_max, const GlobalMapParams& params,
                                        FusionBuffers* buffers) {
  // Voxels of side >= half, so that the cube around a mean lies in the 27 voxels around its own.
  const double half = fusionHalfWidth(lambda_max);
  buffers->grid.build(
      ellipsoids.size(), [&](std::size_t i) -> const Eigen::Vector3d& { return ellipsoids[i]->mean; }, half,
      params.threads);
  gatherInGridOrder(ellipsoids, group_of, lambda_max, params.threads, buffers);
  findCopies(half, params.fusion_max_distance, params.threads, buffers);
  FusionBuffers& f = *buffers;
  if (!f.keep) {  // the search's copies of the ellipsoids, in grid order
    f.grid.release();
    releaseVector(&f.mean), releaseVector(&f.cov), releaseVector(&f.lambda), releaseVector(&f.group);
    releaseVector(&f.index);
  }
  partnersOf(ellipsoids.size(), buffers);
  if (!f.keep) releaseVector(&f.found);
  clusterGreedily(ellipsoids.size(), group_of, lambda_max, params.threads, buffers);
  if (!f.keep)
    releaseVector(&f.partner_start), releaseVector(&f.partner), releaseVector(&f.taken), releaseVector(&f.order);
  return fuseClusters(ellipsoids, params.threads, buffers);
}

}  // namespace global_map_detail

double bhattacharyyaDistance(const Ellipsoid& a, const Ellipsoid& b) {
  using global_map_detail::SymmetricCov;
  const SymmetricCov Sa = SymmetricCov::of(a.cov), Sb = SymmetricCov::of(b.cov), S = Sa.average(Sb);
  return global_map_detail::meanTerm(a.mean - b.mean, S) + global_map_detail::shapeTerm(S, Sa, Sb);
}

double fusionHalfWidth(const std::vector<Ellipsoid>& ellipsoids, const GlobalMapParams& params) {
  return global_map_detail::fusionHalfWidth(global_map_detail::largestEigenvalues(ellipsoids, params.threads));
}

std::vector<Ellipsoid> fuseAcrossGroups(const std::vector<Ellipsoid>& ellipsoids, const std::vector<int>& group_of,
                                        const GlobalMapParams& params) {
  global_map_detail::FusionBuffers buffers;
  return global_map_detail::fuseAcrossGroups(global_map_detail::addressesOf(ellipsoids), group_of,
                                             global_map_detail::largestEigenvalues(ellipsoids, params.threads), params,
                                             &buffers);
}

}  // namespace vdmap
