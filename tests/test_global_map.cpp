// The global map (SPEC section 6): grouping, mean-shift merging, moment matching, occlusion
// removal, determinism across thread counts, parameter checks.
#include <map>
#include <random>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "mapping/global_map/global_map.h"
#include "mapping/io/camera_config.h"
#include "mapping/io/tum_sequence.h"
#include "mapping/keyframe/mapper.h"
#include "tests/box_room_keyframes.h"

namespace vdmap {
namespace {

const PinholeCamera kCamera = cameraPreset("tum-default");

int addKeyframe(KeyframeGraph* graph, const Transform& T_W_K, const Transform& T_W_placed) {
  return test::addBoxRoomKeyframe(graph, kCamera, T_W_K, T_W_placed);
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

TEST(GlobalMap, MomentMatchingEqualsTheStatisticsOfTheUnion) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Eigen::Vector3d> all;
  std::vector<Ellipsoid> parts;
  for (int part = 0; part < 3; ++part) {
    std::vector<Eigen::Vector3d> pts;
    for (int i = 0; i < 20 + 7 * part; ++i) pts.push_back(Eigen::Vector3d(g(rng), 2 * g(rng), 0.1 * g(rng)) + Eigen::Vector3d(part, 0, 3));
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

// The obviously-correct occlusion removal (SPEC 6 step 3), the oracle of occludingEllipsoids:
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

TEST(GlobalMap, EmptyGraphAndBadParameters) {
  KeyframeGraph graph;
  const GlobalMap map = buildGlobalMap(graph, {});
  EXPECT_EQ(map.sigma_e_prime, 0u);
  Keyframe empty{0, 0, 0.0, Transform::Identity(), {}, {}, {}, KeyframeContainer(kCamera, 5), 0};
  graph.add(std::move(empty));  // a keyframe with no kept ellipsoids
  EXPECT_EQ(buildGlobalMap(graph, {}).sigma_e_prime, 0u);
  GlobalMapParams p;
  p.merge_distance_m = -1;
  EXPECT_THROW(buildGlobalMap(graph, p), std::invalid_argument);
  p = {};
  p.occlusion_angle_deg = 181;
  EXPECT_THROW(buildGlobalMap(graph, p), std::invalid_argument);
}

// 7-Scenes RedKitchen, every 2nd of the first 120 frames (a few keyframes; the test stays short).
// The paper's Sigma_e'/Sigma_e on its three sequences is 0.23-0.47 (SPEC 10) and the whole 500
// frames here give 0.22: a few keyframes overlap less, so less is merged and occluded; the
// band 0.15-0.8 catches both failure modes (nothing merged/occluded, or most of the map gone).
TEST(GlobalMapRealData, KitchenRatioInRangeAndSameWithOneAndTwoThreads) {
  VDMAP_REQUIRE_SHARED_DATA(dir, "7scenes-redkitchen");
  SequenceOptions options;
  options.frames = {0, 120};
  const TumSequence seq = TumSequence::open(dir, options);
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
