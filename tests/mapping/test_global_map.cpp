// The global map (docs/method.md 6): grouping, mean-shift merging, moment matching, occlusion
// removal, determinism across thread counts, parameter checks.
#include <map>
#include <numeric>
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "mapping/global_map/global_map.h"
#include "mapping/io/camera_config.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/sequence/sequence.h"
#include "tests/support/box_room_keyframes.h"

namespace vdmap {
namespace {

const PinholeCamera kGlobalMapCamera = cameraPreset("tum-default");

int addKeyframe(KeyframeGraph* graph, const Transform& T_W_K, const Transform& T_W_placed) {
  return test::addBoxRoomKeyframe(graph, kGlobalMapCamera, T_W_K, T_W_placed);
}

Transform facingWall(double z) { return test::lookAt({0, 0, z}, {0, 0, 2}); }

TEST(GlobalMap, TwoKeyframesOnOnePlaneMergeToAboutHalf) {
  KeyframeGraph graph;
  addKeyframe(&graph, facingWall(0.0), facingWall(0.0));
  addKeyframe(&graph, test::lookAt({0.01, 0, 0.01}, {0.01, 0, 2}), test::lookAt({0.01, 0, 0.01}, {0.01, 0, 2}));
  graph.edges().strengthen(0, 1, 0.8);
  GlobalMapParams params;
  params.occlusion_removal = false;
  const GlobalMap map = buildGlobalMap(graph, params);
  ASSERT_EQ(map.groups.size(), 1u);
  const double ratio = static_cast<double>(map.sigma_e_prime) / static_cast<double>(map.sigma_e);
  EXPECT_GT(ratio, 0.45);
  EXPECT_LT(ratio, 0.6);
  // Noise-free ray-cast depth quantised to 1/5000 m: means lie on the wall z = 2 within that.
  for (const Ellipsoid& e : map.ellipsoids) ASSERT_NEAR(e.mean.z(), 2.0, 2e-4);
}

TEST(GlobalMap, MeansFartherApartThanTheMergeDistanceNeverMerge) {
  KeyframeGraph graph;
  addKeyframe(&graph, facingWall(0.0), facingWall(0.0));
  addKeyframe(&graph, facingWall(0.0), facingWall(-0.3));  // its wall appears 0.3 m farther
  graph.edges().strengthen(0, 1, 0.8);
  GlobalMapParams params;
  params.occlusion_removal = false;
  const GlobalMap map = buildGlobalMap(graph, params);  // h = 0.25 m < 0.3 m
  EXPECT_EQ(map.sigma_e_prime, map.sigma_e);
  params.merge_distance_m = 0.35;
  EXPECT_LT(buildGlobalMap(graph, params).sigma_e_prime, map.sigma_e_prime) << "a wider kernel merges";
}

TEST(GlobalMap, MeanShiftSeparatesClustersFartherThanH) {
  const std::vector<Eigen::Vector3d> means = {{0, 0, 1}, {0.05, 0, 1}, {0, 0, 1.6}, {0.02, 0, 1.62}};
  const std::vector<int> label = meanShiftClusters(means, {10, 30, 5, 5}, 0.25);
  EXPECT_EQ(label, (std::vector<int>{0, 0, 1, 1}));
  EXPECT_EQ(meanShiftClusters(means, {1, 1, 1, 1}, 1.0), (std::vector<int>{0, 0, 0, 0}));
}

// meanShiftClusters skips the iteration when all means lie within h of each other; it must label
// exactly as the iteration does, near that boundary, across it, and for h = 0 (equal means).
TEST(GlobalMap, MeanShiftShortcutLabelsAsTheIteration) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> size(1, 9), count(1, 50);
  int shortcuts = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double h = 0.25,
                 spread = trial % 3 == 0 ? 0.05 : (trial % 3 == 1 ? 0.09 : 0.3);  // all within h; around it; apart
    std::vector<Eigen::Vector3d> means(static_cast<std::size_t>(size(rng)));
    std::vector<double> weights;
    const Eigen::Vector3d centre(u(rng), u(rng), 2.0 + u(rng));
    for (Eigen::Vector3d& m : means) {
      m = centre + spread * Eigen::Vector3d(u(rng), u(rng), u(rng));
      weights.push_back(count(rng));
    }
    const std::vector<int> label = meanShiftClusters(means, weights, h);
    ASSERT_EQ(label, meanShiftClustersByIteration(means, weights, h)) << "trial " << trial;
    if (std::count(label.begin(), label.end(), 0) == static_cast<long>(label.size())) ++shortcuts;
  }
  EXPECT_GT(shortcuts, 1000) << "the one-cluster case is common and checked";
  // Two means exactly h apart are within the kernel for the iteration; with h = 0, equal means
  // each start their own cluster (distance 0 is not below h/2).
  const std::vector<Eigen::Vector3d> pair = {{0, 0, 1}, {0.25, 0, 1}}, same = {{0, 0, 1}, {0, 0, 1}};
  EXPECT_EQ(meanShiftClusters(pair, {1, 1}, 0.25), meanShiftClustersByIteration(pair, {1, 1}, 0.25));
  EXPECT_EQ(meanShiftClusters(same, {1, 1}, 0.0), meanShiftClustersByIteration(same, {1, 1}, 0.0));
  EXPECT_EQ(meanShiftClusters(same, {1, 1}, 0.0), (std::vector<int>{0, 1}));
}

TEST(GlobalMap, MomentMatchingEqualsTheStatisticsOfTheUnion) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Eigen::Vector3d> all;
  std::vector<Ellipsoid> parts;
  for (int part = 0; part < 3; ++part) {
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 20 + 7 * part; ++i)
      pts.push_back(Eigen::Vector3d(g(rng), 2 * g(rng), 0.1 * g(rng)) + Eigen::Vector3d(part, 0, 3));
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const auto& p : pts) mean += p;
    mean /= pts.size();
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (const auto& p : pts) S += (p - mean) * (p - mean).transpose();
    Ellipsoid e;
    e.mean = mean;
    e.cov = S / (pts.size() - 1.0);
    e.count = static_cast<std::uint32_t>(pts.size());
    e.color = Eigen::Vector3f(10.0f * part, 0, 0);
    parts.push_back(e);
    all.insert(all.end(), pts.begin(), pts.end());
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : all) mean += p;
  mean /= all.size();
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  for (const auto& p : all) S += (p - mean) * (p - mean).transpose();
  const Ellipsoid m = momentMatch({&parts[0], &parts[1], &parts[2]});
  EXPECT_EQ(m.count, all.size());
  EXPECT_LT((m.mean - mean).norm(), 1e-12);
  EXPECT_LT((m.cov - S / (all.size() - 1.0)).norm() / S.norm(), 1e-12);
  EXPECT_NEAR(m.color.x(), (0 * 20 + 10 * 27 + 20 * 34) / 81.0, 1e-4);
}

// Keyframe 0 sees the wall from 2 m (coarse cells) and is placed 1 cm too near: its surface
// floats just in front of the wall. Keyframe 1 sees it from 0.3 m (fine cells), correctly.
KeyframeGraph coarseViewInFrontOfCloseView() {
  KeyframeGraph graph;
  Transform placed = facingWall(0.0);
  placed.translation().z() -= 0.01;
  addKeyframe(&graph, facingWall(0.0), placed);
  addKeyframe(&graph, facingWall(1.7), facingWall(1.7));
  graph.edges().strengthen(0, 1, 0.05);  // neighbours, but below tau_group: no merging
  return graph;
}

TEST(GlobalMap, OcclusionRemovalKeepsTheCloseViewAndDropsCoarseEllipsoidsInFront) {
  const KeyframeGraph graph = coarseViewInFrontOfCloseView();
  GlobalMapParams params;
  const GlobalMap on = buildGlobalMap(graph, params);
  params.occlusion_removal = false;
  const GlobalMap off = buildGlobalMap(graph, params);
  EXPECT_EQ(off.sigma_e_prime, off.sigma_e);
  // Count, per keyframe, the ellipsoids inside keyframe 1's view (|x|, |y| within its footprint).
  auto count = [](const GlobalMap& m, int keyframe) {
    int n = 0;
    for (const Ellipsoid& e : m.ellipsoids)
      if (e.keyframe == keyframe && std::abs(e.mean.x()) < 0.1 && std::abs(e.mean.y()) < 0.07) ++n;
    return n;
  };
  ASSERT_GT(count(off, 0), 20);
  EXPECT_LT(count(on, 0), count(off, 0) / 5) << "coarse ellipsoids in front of the precise ones go";
  EXPECT_GT(count(on, 1), count(off, 1) * 95 / 100) << "the precise view stays";
}

// The obviously-correct occlusion removal (docs/method.md 6.3), the oracle of occludingEllipsoids:
// for every viewpoint K, every pair of its group's ellipsoids in one of K's cells, with no
// sorting and no skipping. The numerics are the fast path's (same regularised covariance, same
// expressions), so the two agree exactly.
std::vector<bool> occludingEllipsoidsReference(const KeyframeGraph& graph, const std::vector<Ellipsoid>& ellipsoids,
                                               const GlobalMapParams& params) {
  const double cos_angle = std::cos(params.occlusion_angle_deg * M_PI / 180.0);
  std::vector<Eigen::Matrix3d> information;
  std::vector<double> lambda_max;
  for (const Ellipsoid& e : ellipsoids) {
    const Eigen::Matrix3d cov = e.cov + 1e-10 * Eigen::Matrix3d::Identity();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(cov);
    lambda_max.push_back(eig.eigenvalues()(2));
    information.push_back(cov.inverse());
  }
  std::vector<bool> removed(ellipsoids.size(), false);
  for (const Keyframe& K : graph.keyframes()) {
    auto inGroup = [&](int id) {
      const Keyframe& o = graph.keyframe(id);
      return id == K.id || graph.edges().hasEdge(K.id, id) ||
             ((o.T_W_K.translation() - K.T_W_K.translation()).norm() <= params.occlusion_distance_m &&
              o.T_W_K.linear().col(2).dot(K.T_W_K.linear().col(2)) >= cos_angle - 1e-12);
    };
    const Transform T_K_W = K.T_W_K.inverse();
    const Eigen::Vector3d c = K.T_W_K.translation();
    std::map<int, std::vector<std::size_t>> cells;
    std::vector<double> z(ellipsoids.size());
    for (std::size_t i = 0; i < ellipsoids.size(); ++i) {
      if (!inGroup(ellipsoids[i].keyframe)) continue;
      const Eigen::Vector3d p = T_K_W * ellipsoids[i].mean;
      z[i] = p.z();
      if (p.z() <= 0.0) continue;
      const Eigen::Vector2d uv = K.container.camera().project(p);
      const int cell = K.container.gridIndexOfPixel(uv.x(), uv.y());
      if (cell >= 0) cells[cell].push_back(i);
    }
    for (const auto& [cell, members] : cells)
      for (std::size_t a : members)
        for (std::size_t b : members) {
          if (!(z[a] < z[b]) || !(lambda_max[b] < lambda_max[a])) continue;
          const Eigen::Vector3d mu = ellipsoids[a].mean - c;
          const Eigen::Vector3d d = (ellipsoids[b].mean - c).normalized();
          const Eigen::Matrix3d& P = information[a];
          const Eigen::Vector3d P_mu = P * mu;
          const double dPmu = d.dot(P_mu);
          if (mu.dot(P_mu) - dPmu * dPmu / d.dot(P * d) <= 4.0) removed[a] = true;
        }
  }
  return removed;
}

// Occlusion removal checked against the reference on two scenes: the coarse view in front, and
// four keyframes turning in the box room (neighbours and near keyframes both form the groups).
TEST(GlobalMap, OcclusionRemovalEqualsTheReference) {
  KeyframeGraph wall = coarseViewInFrontOfCloseView();
  KeyframeGraph turning;
  for (int i = 0; i < 4; ++i) {
    const Transform T = test::lookAt({0.1 * i, 0, 0}, {2 * std::sin(0.3 * i), 0.3, 2 * std::cos(0.3 * i)});
    addKeyframe(&turning, T, T);
  }
  turning.edges().strengthen(0, 2, 0.05);
  for (const KeyframeGraph* graph : {&wall, &turning}) {
    GlobalMapParams params;
    params.occlusion_removal = false;
    const std::vector<Ellipsoid> merged = buildGlobalMap(*graph, params).ellipsoids;
    const std::vector<bool> removed = occludingEllipsoids(*graph, merged, params);
    const std::vector<bool> expected = occludingEllipsoidsReference(*graph, merged, params);
    ASSERT_EQ(removed.size(), expected.size());
    for (std::size_t i = 0; i < removed.size(); ++i) ASSERT_EQ(removed[i], expected[i]) << "ellipsoid " << i;
    EXPECT_GT(std::count(removed.begin(), removed.end(), true), 10) << "the scene occludes something";
    EXPECT_LT(std::count(removed.begin(), removed.end(), true), static_cast<long>(merged.size()));
  }
}

// The same ellipsoids bit for bit, in the same order (buildGlobalMap's promise for any thread count).
void expectSameMap(const GlobalMap& a, const GlobalMap& b) {
  ASSERT_EQ(a.ellipsoids.size(), b.ellipsoids.size());
  for (std::size_t i = 0; i < a.ellipsoids.size(); ++i) {
    const Ellipsoid &x = a.ellipsoids[i], &y = b.ellipsoids[i];
    ASSERT_EQ(x.mean, y.mean) << i;
    ASSERT_EQ(x.cov, y.cov) << i;
    ASSERT_EQ(x.count, y.count) << i;
    ASSERT_EQ(x.color, y.color) << i;
    ASSERT_EQ(x.keyframe, y.keyframe) << i;
  }
}

TEST(GlobalMap, SameResultWithOneAndTwoThreads) {
  KeyframeGraph graph;
  for (int i = 0; i < 4; ++i) {
    const double a = i * 0.4;
    addKeyframe(&graph, test::lookAt({0, 0, 0}, {2 * std::sin(a), 0, 2 * std::cos(a)}),
                test::lookAt({0, 0, 0}, {2 * std::sin(a), 0, 2 * std::cos(a)}));
  }
  graph.edges().strengthen(0, 1, 0.5);
  graph.edges().strengthen(1, 2, 0.4);
  graph.edges().strengthen(2, 3, 0.3);
  GlobalMapParams params;
  params.threads = 1;
  const GlobalMap a = buildGlobalMap(graph, params);
  params.threads = 2;
  expectSameMap(a, buildGlobalMap(graph, params));
}

// Fusion across groups (docs/method.md 7) written out plainly, the oracle of fuseAcrossGroups: every pair
// of ellipsoids of different groups, no spatial hash, no pre-filter, the same greedy choice.
std::vector<Ellipsoid> fuseAcrossGroupsReference(const std::vector<Ellipsoid>& e, const std::vector<int>& group,
                                                 const GlobalMapParams& params) {
  const double max_distance = params.fusion_max_distance, half = fusionHalfWidth(e, params);
  const std::size_t n = e.size();
  std::vector<double> lambda_max(n);
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(e[i].cov + 1e-10 * Eigen::Matrix3d::Identity(), Eigen::EigenvaluesOnly);
    lambda_max[i] = eig.eigenvalues()(2);
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return lambda_max[a] < lambda_max[b]; });
  std::vector<std::size_t> seed_of(n, n);
  for (std::size_t s : order) {
    if (seed_of[s] < n) continue;
    seed_of[s] = s;
    std::map<int, std::pair<double, std::size_t>> nearest;  // per other group: (distance, index)
    for (std::size_t j = 0; j < n; ++j) {
      if (seed_of[j] < n || group[j] == group[s] || (e[j].mean - e[s].mean).cwiseAbs().maxCoeff() > half) continue;
      const double d = bhattacharyyaDistance(e[s], e[j]);
      if (d > max_distance) continue;
      const auto it = nearest.find(group[j]);
      if (it == nearest.end() || std::make_pair(d, j) < it->second) nearest[group[j]] = {d, j};
    }
    for (const auto& [g, best] : nearest) seed_of[best.second] = s;
  }
  std::vector<Ellipsoid> out;
  for (std::size_t i = 0; i < n; ++i) {
    if (seed_of[i] != i) continue;
    std::vector<const Ellipsoid*> cluster = {&e[i]};
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && seed_of[j] == i) cluster.push_back(&e[j]);
    out.push_back(cluster.size() == 1 ? e[i] : momentMatch(cluster));
  }
  return out;
}

// A flat patch (a wall cell): spread `half_width_m` in x and y, `thickness_m` along z, then rotated.
Ellipsoid patch(const Eigen::Vector3d& mean, double half_width_m, double thickness_m,
                const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity(), std::uint32_t count = 20) {
  Ellipsoid e;
  e.mean = mean;
  const Eigen::Vector3d sigma(half_width_m / std::sqrt(3.0), half_width_m / std::sqrt(3.0), thickness_m);
  e.cov = R * sigma.array().square().matrix().asDiagonal() * R.transpose();
  e.count = count;
  e.color = Eigen::Vector3f(100, 100, 100);
  return e;
}

TEST(GlobalMap, FusionJoinsCopiesOfOneWallButNotACornerOrOneGroup) {
  GlobalMapParams params;
  const Eigen::Matrix3d wall_x = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  // Two groups' cells of one wall, offset by less than a cell: one ellipsoid, the union's moments.
  const std::vector<Ellipsoid> copies = {patch({0, 0, 2}, 0.005, 0.001), patch({0.004, 0.002, 2.0005}, 0.005, 0.001)};
  const std::vector<Ellipsoid> fused = fuseAcrossGroups(copies, {0, 1}, params);
  ASSERT_EQ(fused.size(), 1u);
  EXPECT_EQ(fused[0].count, 40u);
  EXPECT_NEAR(fused[0].mean.x(), 0.002, 1e-12);
  EXPECT_EQ(fuseAcrossGroups(copies, {3, 3}, params).size(), 2u) << "one group's cells stay apart";
  // The same offset between flat patches of two perpendicular walls (a corner): shapes differ.
  const std::vector<Ellipsoid> corner = {patch({0, 0, 2}, 0.005, 0.0005),
                                         patch({0.004, 0.002, 2.0005}, 0.005, 0.0005, wall_x)};
  EXPECT_EQ(fuseAcrossGroups(corner, {0, 1}, params).size(), 2u);
  // Two cells apart on the wall: neighbours, not copies.
  const std::vector<Ellipsoid> neighbours = {patch({0, 0, 2}, 0.005, 0.001), patch({0.02, 0, 2}, 0.005, 0.001)};
  EXPECT_EQ(fuseAcrossGroups(neighbours, {0, 1}, params).size(), 2u);
  // Three groups' copies: the most precise takes one of each other group, the nearest.
  const std::vector<Ellipsoid> three = {patch({0.001, 0, 2}, 0.006, 0.001), patch({0, 0, 2}, 0.004, 0.001),
                                        patch({0.003, 0, 2}, 0.006, 0.001), patch({-0.002, 0, 2}, 0.006, 0.001)};
  const std::vector<Ellipsoid> one = fuseAcrossGroups(three, {0, 1, 2, 2}, params);
  ASSERT_EQ(one.size(), 2u);
  EXPECT_EQ(one[0].count, 60u) << "seed (index 1) with index 0 and the nearer of group 2 (index 3)";
  EXPECT_EQ(one[1].mean, three[2].mean) << "group 2's farther copy stays";
  params.fusion_max_distance = 0;
  EXPECT_EQ(fuseAcrossGroups(copies, {0, 1}, params).size(), 2u);
}

// Many groups seeing the same walls at different grid offsets, sizes and depths, plus a
// perpendicular wall: the spatial hash finds what the all-pairs oracle finds, for 1 and 2 threads.
// A workspace reused across builds (the workbench's) gives every build the map a fresh build
// gives, whatever changed in between: poses, the filter, a container's cells, the keyframes, the
// stages switched on, the thread count.
TEST(GlobalMap, AWorkspaceReusedAcrossBuildsGivesTheMapOfAFreshBuild) {
  KeyframeGraph graph;
  for (int i = 0; i < 3; ++i) {
    const Transform T = test::lookAt({0.05 * i, 0, 0}, {2 * std::sin(0.2 * i), 0.2, 2 * std::cos(0.2 * i)});
    addKeyframe(&graph, T, T);
  }
  graph.edges().strengthen(0, 1, 0.5);
  GlobalMapWorkspace workspace;
  GlobalMapParams params;
  auto check = [&](const char* what) {
    const GlobalMap fresh = buildGlobalMap(graph, params);
    const GlobalMap reused = buildGlobalMap(graph, params, &workspace);
    SCOPED_TRACE(what);
    expectSameMap(fresh, reused);
    EXPECT_EQ(fresh.kept, reused.kept);
    EXPECT_EQ(fresh.merged, reused.merged);
    EXPECT_GT(fresh.sigma_e_prime, 0u);
  };
  check("first build");
  check("the same again");
  graph.setKeyframePose(2, test::lookAt({0.2, 0.05, 0}, {0.4, 0.2, 2}));
  check("a pose moved");
  params.filter.filter_sigma_factor = 1.5;
  check("a tighter filter");
  // A kept cell of keyframe 1 gets a wide spread: the filter must reject it now.
  const std::vector<bool> before = buildGlobalMap(graph, params, &workspace).kept[1];
  const std::size_t cell = static_cast<std::size_t>(std::find(before.begin(), before.end(), true) - before.begin());
  ASSERT_LT(cell, before.size());
  KeyframeContainer& box = graph.keyframe(1).container;
  box.findOrCreate(box.cells()[cell].grid_index).scatter = {1e3f, 0, 0, 1e3f, 0, 1e3f};
  EXPECT_FALSE(buildGlobalMap(graph, params, &workspace).kept[1][cell]) << "the kept cells follow the container";
  check("a cell changed");
  addKeyframe(&graph, facingWall(0.0), facingWall(0.0));
  check("a keyframe added");
  params.fuse_across_groups = false;
  check("without fusion");
  params.occlusion_removal = false;
  check("without occlusion removal");
  params = {};
  params.threads = 1;
  check("one thread");
}

TEST(GlobalMap, FusionEqualsTheReference) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.004, 0.004), size(0.003, 0.012);
  const Eigen::Matrix3d wall_x = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  std::vector<Ellipsoid> ellipsoids;
  std::vector<int> group;
  for (int g = 0; g < 5; ++g)
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 12; ++j) {
        const double w = size(rng);
        ellipsoids.push_back(patch({0.01 * i + jitter(rng), 0.01 * j + jitter(rng), 2 + 0.1 * jitter(rng)}, w, 0.001));
        group.push_back(g);
        ellipsoids.push_back(patch({0.12 + 0.1 * jitter(rng), 0.01 * j + jitter(rng), 2 - 0.01 * i}, w, 0.001, wall_x));
        group.push_back(g);
      }
  GlobalMapParams params;
  for (double max_distance : {0.5, 1.0, 3.0}) {
    params.fusion_max_distance = max_distance;
    const std::vector<Ellipsoid> expected = fuseAcrossGroupsReference(ellipsoids, group, params);
    EXPECT_LT(expected.size(), ellipsoids.size() * 2 / 3) << "most copies fuse at " << max_distance;
    EXPECT_GT(expected.size(), ellipsoids.size() / 10) << "at most one per group";
    for (int threads : {1, 2}) {
      params.threads = threads;
      const std::vector<Ellipsoid> fused = fuseAcrossGroups(ellipsoids, group, params);
      ASSERT_EQ(fused.size(), expected.size()) << max_distance;
      for (std::size_t i = 0; i < fused.size(); ++i) {
        ASSERT_EQ(fused[i].mean, expected[i].mean) << i;
        ASSERT_EQ(fused[i].cov, expected[i].cov) << i;
        ASSERT_EQ(fused[i].count, expected[i].count) << i;
      }
    }
  }
}

// Two keyframes of one wall that are not graph neighbours (two merge groups): without fusion the
// map keeps both copies, with it about half, and the means stay on the wall.
TEST(GlobalMap, FusionHalvesTwoUnlinkedViewsOfOneWall) {
  KeyframeGraph graph;
  addKeyframe(&graph, facingWall(0.0), facingWall(0.0));
  addKeyframe(&graph, test::lookAt({0.01, 0, 0.01}, {0.01, 0, 2}), test::lookAt({0.01, 0, 0.01}, {0.01, 0, 2}));
  GlobalMapParams params;
  params.occlusion_removal = false;
  const GlobalMap fused = buildGlobalMap(graph, params);
  params.fuse_across_groups = false;
  const GlobalMap apart = buildGlobalMap(graph, params);
  ASSERT_EQ(fused.groups.size(), 2u);
  EXPECT_EQ(apart.sigma_e_prime, apart.sigma_e);
  EXPECT_EQ(apart.merged_across_groups, 0u);
  EXPECT_EQ(fused.sigma_e_prime + fused.merged_across_groups, fused.sigma_e);
  const double ratio = static_cast<double>(fused.sigma_e_prime) / static_cast<double>(fused.sigma_e);
  EXPECT_GT(ratio, 0.45);
  EXPECT_LT(ratio, 0.65);
  for (const Ellipsoid& e : fused.ellipsoids) ASSERT_NEAR(e.mean.z(), 2.0, 2e-4);
}

TEST(GlobalMap, EmptyGraphAndBadParameters) {
  KeyframeGraph graph;
  const GlobalMap map = buildGlobalMap(graph, {});
  EXPECT_EQ(map.sigma_e_prime, 0u);
  Keyframe empty{0, 0, 0.0, Transform::Identity(), {}, {}, {}, KeyframeContainer(kGlobalMapCamera, 5), 0, {}};
  graph.add(std::move(empty));  // a keyframe with no kept ellipsoids
  EXPECT_EQ(buildGlobalMap(graph, {}).sigma_e_prime, 0u);
  GlobalMapParams p;
  p.merge_distance_m = -1;
  EXPECT_THROW(buildGlobalMap(graph, p), std::invalid_argument);
  p = {};
  p.occlusion_angle_deg = 181;
  EXPECT_THROW(buildGlobalMap(graph, p), std::invalid_argument);
  p = {};
  p.fusion_max_distance = -0.1;
  EXPECT_THROW(buildGlobalMap(graph, p), std::invalid_argument);
}

// 7-Scenes RedKitchen, every 2nd of the first 120 frames (a few keyframes; the test stays short).
// The paper's Sigma_e'/Sigma_e on its three sequences is 0.23-0.47 (docs/results.md) and the whole 500
// frames here give 0.22: a few keyframes overlap less, so less is merged and occluded; the
// band 0.15-0.8 catches both failure modes (nothing merged/occluded, or most of the map gone).
TEST(GlobalMapRealData, KitchenRatioInRangeAndSameWithOneAndTwoThreads) {
  VDMAP_REQUIRE_SHARED_DATA(dir, "7scenes-redkitchen");
  SequenceOptions options;
  options.frames = {0, 120};
  const Sequence seq = Sequence::open(dir, options);
  Mapper mapper(seq.camera());
  for (std::size_t i = 0; i < seq.size(); i += 2) mapper.addFrame(seq.load(i));
  const KeyframeGraph& graph = mapper.graph();
  ASSERT_GE(graph.size(), 3u);
  GlobalMapParams params;
  params.threads = 1;
  const GlobalMap a = buildGlobalMap(graph, params);
  params.threads = 2;
  const GlobalMap b = buildGlobalMap(graph, params);
  const double ratio = static_cast<double>(a.sigma_e_prime) / static_cast<double>(a.sigma_e);
  std::printf("%zu keyframes: sigma_e %zu -> merged %zu -> sigma_e' %zu (%.3f)\n", graph.size(), a.sigma_e, a.merged,
              a.sigma_e_prime, ratio);
  EXPECT_GT(ratio, 0.15);
  EXPECT_LT(ratio, 0.8);
  EXPECT_LT(a.merged, a.sigma_e) << "neighbouring keyframes merge";
  EXPECT_LT(a.sigma_e_prime, a.merged) << "occlusion removal removes something";
  expectSameMap(a, b);
}

}  // namespace
}  // namespace vdmap
