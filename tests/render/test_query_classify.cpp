// QueryMap's classification (docs/method.md 13.1-13.3): the fast path against the plain oracle
// (tests/support/query_oracle.h) on the analytic box room and on a built-in-scene map, analytic answers
// about a wall, a moved object under the three conflict rules, corrected poses, determinism and
// the edge cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "mapping/global_map/global_map.h"
#include "mapping/local_map/local_map_integrator.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/query/detail/keyframe_views.h"
#include "mapping/query/query_map.h"
#include "mapping/sequence/frame_prefetcher.h"
#include "render/sequence_synth.h"
#include "tests/support/box_room_keyframes.h"
#include "tests/support/query_oracle.h"
#include "tests/support/render_scenes.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

// A quarter-size tum-default camera: the same field of view with 1/16 of the cells, so that the
// oracle's every-ellipsoid scans stay fast.
PinholeCamera smallCamera() {
  PinholeCamera c;
  c.width = 160, c.height = 120, c.fx = c.fy = 131.25, c.cx = 79.5, c.cy = 59.5;
  return c;
}

/// Three views of the box room: two of the +z wall (a merge group) and one of the -x wall.
void addBoxRoomViews(KeyframeGraph* graph, const PinholeCamera& camera) {
  test::addTwoBoxRoomViews(graph, camera);
  const Transform T = test::lookAt({0.2, 0.1, -0.3}, {-2, 0.3, -0.5});
  test::addBoxRoomKeyframe(graph, camera, T, T);
}

/// n/2 points uniform in [lo, hi] and n/2 at global means + N(0, 2 cm) (near surfaces, where the
/// classes meet).
std::vector<Eigen::Vector3d> randomPoints(const GlobalMap& global, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                          std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 2 == 0 || global.ellipsoids.empty()) {
      points.push_back(lo + (hi - lo).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng))));
    } else {
      const auto& e =
          global.ellipsoids[std::uniform_int_distribution<std::size_t>(0, global.ellipsoids.size() - 1)(rng)];
      points.push_back(e.mean + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
  }
  return points;
}

std::vector<Classification> classify(const QueryMap& map, const std::vector<Eigen::Vector3d>& points) {
  std::vector<Classification> out(points.size());
  map.classify(points, out);
  return out;
}

std::vector<Classification> classifyInKeyframe(const QueryMap& map, int id,
                                               const std::vector<Eigen::Vector3d>& points) {
  std::vector<Classification> out(points.size());
  map.classifyInKeyframe(id, points, out);
  return out;
}

bool same(const Classification& a, const Classification& b) {
  return a.state == b.state && a.keyframe == b.keyframe && a.ellipsoid == b.ellipsoid &&
         std::bit_cast<std::uint32_t>(a.p_occupied) == std::bit_cast<std::uint32_t>(b.p_occupied);
}

std::string describe(const Classification& c) {
  return std::string(occupancyName(c.state)) + " p=" + std::to_string(c.p_occupied) +
         " kf=" + std::to_string(c.keyframe) + " ell=" + std::to_string(c.ellipsoid);
}

/// Fast and oracle agree on every point: the same class, deciding keyframe and ellipsoid, and
/// p_occupied within 1e-6 (the two evaluate the same formulas in different orders).
void expectMatchesOracle(const std::vector<Classification>& fast, const std::vector<Classification>& oracle,
                         const std::vector<Eigen::Vector3d>& points, const std::string& what) {
  ASSERT_EQ(fast.size(), oracle.size());
  int mismatches = 0;
  for (std::size_t i = 0; i < fast.size(); ++i) {
    const Classification &f = fast[i], &o = oracle[i];
    const bool ok = f.state == o.state && f.keyframe == o.keyframe && f.ellipsoid == o.ellipsoid &&
                    std::abs(f.p_occupied - o.p_occupied) <= 1e-6f;
    if (!ok && ++mismatches <= 5)
      ADD_FAILURE() << what << ": point " << i << " (" << points[i].transpose() << "): fast " << describe(f)
                    << ", oracle " << describe(o);
  }
  EXPECT_EQ(mismatches, 0) << what;
}

struct Counts {
  int unknown = 0, free = 0, occupied = 0;
};
Counts count(const std::vector<Classification>& c) {
  Counts n;
  for (const auto& x : c)
    (x.state == Occupancy::kFree ? n.free : x.state == Occupancy::kOccupied ? n.occupied : n.unknown)++;
  return n;
}

/// Every conflict rule, and classifyInKeyframe of every keyframe, against the oracle.
void checkAgainstOracle(const KeyframeGraph& graph, const GlobalMap& global, const std::vector<Eigen::Vector3d>& points,
                        const std::string& what) {
  for (const ConflictRule rule : {ConflictRule::kOccupied, ConflictRule::kRecent, ConflictRule::kPrecise}) {
    QueryParams params;
    params.conflict = rule;
    // kRecent also with an order that is not the ids' (the last keyframe observed first).
    std::vector<std::vector<int>> ranks{{}};
    if (rule == ConflictRule::kRecent) {
      std::vector<int> r(graph.size());
      for (std::size_t i = 0; i < r.size(); ++i) r[i] = static_cast<int>((i * 7 + 3) % r.size());
      ranks.push_back(r);
    }
    for (const auto& rank : ranks) {
      const QueryMap map = QueryMap::build(graph, global, params, rank);
      const test::QueryOracle oracle(graph, global, params, rank);
      if (rule == ConflictRule::kOccupied) {  // the oracle's buckets are only a shortcut
        int differ = 0, gated = 0;
        for (std::size_t i = 0; i < points.size(); i += 19) {
          double m2 = 0, m2_scan = 0;
          const int e = oracle.gate(points[i], &m2);
          differ += e != oracle.gateByScan(points[i], &m2_scan) || (e >= 0 && m2 != m2_scan);
          gated += e >= 0;
        }
        EXPECT_EQ(differ, 0) << what;
        EXPECT_GT(gated, static_cast<int>(points.size() / 2000)) << what;
      }
      std::vector<Classification> expected(points.size());
      for (std::size_t i = 0; i < points.size(); ++i) expected[i] = oracle.classify(points[i]);
      const auto fast = classify(map, points);
      const Counts n = count(fast);
      std::printf("%s, rule %d, rank %s: %d free, %d occupied, %d unknown\n", what.c_str(), static_cast<int>(rule),
                  rank.empty() ? "ids" : "shuffled", n.free, n.occupied, n.unknown);
      // Not vacuous: every class is well represented.
      EXPECT_GT(n.free, static_cast<int>(points.size() / 20)) << what;
      EXPECT_GT(n.occupied, static_cast<int>(points.size() / 20)) << what;
      EXPECT_GT(n.unknown, static_cast<int>(points.size() / 50)) << what;
      expectMatchesOracle(fast, expected, points, what + " rule " + std::to_string(static_cast<int>(rule)));
      if (rule != ConflictRule::kOccupied) continue;
      // The visibility index lists every keyframe that has a verdict (a superset), and the
      // single-keyframe answers are the oracle's.
      const KeyframeViews views = KeyframeViews::build(graph, global, params, {});
      int missing = 0;
      for (int id = 0; id < static_cast<int>(graph.size()); ++id) {
        std::vector<Classification> one(points.size());
        for (std::size_t i = 0; i < points.size(); ++i) {
          one[i] = test::QueryOracle::fromVerdict(oracle.localMapVerdict(id, points[i]), id);
          if (oracle.verdict(id, points[i]).state == Occupancy::kUnknown) continue;  // the view's own
          const auto c = views.candidates(points[i]);
          if (std::find(c.begin(), c.end(), id) == c.end() && ++missing <= 5)
            ADD_FAILURE() << what << ": keyframe " << id << " sees " << points[i].transpose() << " but is no candidate";
        }
        expectMatchesOracle(classifyInKeyframe(map, id, points), one, points, what + " keyframe " + std::to_string(id));
        for (std::size_t i = 0; i < points.size(); i += 97)  // the view's verdict with its terms
          EXPECT_EQ(map.keyframeVerdict(id, points[i]).state, oracle.verdict(id, points[i]).state)
              << what << " keyframe " << id;
      }
      EXPECT_EQ(missing, 0) << what;
      EXPECT_THROW((void)map.keyframeVerdict(static_cast<int>(graph.size()), points[0]), std::invalid_argument);
    }
  }
}

TEST(QueryClassify, FastPathMatchesTheOracleOnTheBoxRoom) {
  KeyframeGraph graph;
  addBoxRoomViews(&graph, smallCamera());
  const GlobalMap global = buildGlobalMap(graph, {});
  const auto points = randomPoints(global, {-2.1, -1.6, -2.1}, {2.1, 1.6, 2.1}, 20000, 36);
  checkAgainstOracle(graph, global, points, "box room");
}

/// The views' stored mean (the oracle's too) is the container's float mean with its ray rounded
/// to 1/32768 of a grid cell: within half a step per axis of it on every cell of the box room.
TEST(QueryClassify, StoredMeansLieWithinARoundingOfTheCellsMeans) {
  KeyframeGraph graph;
  addBoxRoomViews(&graph, smallCamera());
  int cells = 0;
  for (std::size_t id = 0; id < graph.size(); ++id) {
    const KeyframeContainer& container = graph.keyframe(static_cast<int>(id)).container;
    for (const StoredCell& cell : container.cells()) {
      const Eigen::Vector3d mean = cell.mean.cast<double>(), stored = storedViewMean(container, cell);
      EXPECT_EQ(stored.z(), mean.z());
      const double half_step =
          container.cellSizePx() / std::min(container.camera().fx, container.camera().fy) / 65535.0 * mean.z();
      EXPECT_LE((stored - mean).norm(), std::sqrt(2.0) * half_step * (1 + 1e-9))
          << "keyframe " << id << " cell " << cell.grid_index;
      ++cells;
    }
  }
  EXPECT_GT(cells, 1000);
}

TEST(QueryClassify, FastPathMatchesTheOracleOnABuiltinSceneMap) {
  // One lap in 40 frames: large steps between frames, so several keyframes around the table.
  const Sequence seq = Sequence::open(test::builtinSequence(40));
  Mapper mapper(seq.camera());
  FramePrefetcher frames(seq);
  while (auto f = frames.next()) mapper.addFrame(*f);
  const KeyframeGraph& graph = mapper.graph();
  ASSERT_GE(graph.size(), 3u);
  const GlobalMap global = buildGlobalMap(graph, {});
  const auto points = randomPoints(global, {-2.6, -2.1, -0.1}, {2.6, 2.1, 2.7}, 20000, 37);
  checkAgainstOracle(graph, global, points, "built-in scene");
}

// One keyframe at the room's centre looking at the +z wall 2 m away (exact depth: the gate is a
// few mm thick about the wall).
TEST(QueryClassify, AnalyticWallFreeInFrontOccupiedOnItUnknownBehindAndOutside) {
  KeyframeGraph graph;
  const Transform T = test::lookAt({0, 0, 0}, {0, 0, 2});
  test::addBoxRoomKeyframe(&graph, smallCamera(), T, T);
  const GlobalMap global = buildGlobalMap(graph, {});
  const QueryMap map = QueryMap::build(graph, global, {});
  EXPECT_EQ(map.keyframes(), 1u);
  EXPECT_FALSE(map.empty());
  const std::vector<Eigen::Vector3d> front{{0, 0, 1.5}, {0.3, 0.2, 1.5}, {-0.4, -0.3, 1.0}, {0.1, 0.1, 0.3}};
  const std::vector<Eigen::Vector3d> wall{{0, 0, 2}, {0.31, 0.17, 2}, {-0.52, 0.4, 2}};
  const std::vector<Eigen::Vector3d> behind{{0, 0, 2.02}, {0.31, 0.17, 2.02}, {-0.52, 0.4, 2.05}};
  // Behind the camera, at its centre (z = 0), beside the frustum, far outside the room.
  const std::vector<Eigen::Vector3d> outside{{0, 0, -1.0}, {0, 0, 0}, {1.9, 0, 0.1}, {0, 0, 5}, {10, 10, 10}};
  for (const auto& c : classify(map, front)) {
    EXPECT_EQ(c.state, Occupancy::kFree) << describe(c);
    EXPECT_EQ(c.keyframe, 0);
    EXPECT_LT(c.p_occupied, 0.0014f);  // Phi(-3)
  }
  for (const auto& c : classify(map, wall)) {
    EXPECT_EQ(c.state, Occupancy::kOccupied) << describe(c);
    EXPECT_GE(c.ellipsoid, 0);
    EXPECT_GT(c.p_occupied, 0.5f);
  }
  for (const auto& set : {behind, outside})
    for (const auto& c : classify(map, set)) {
      EXPECT_EQ(c.state, Occupancy::kUnknown) << describe(c);
      EXPECT_EQ(c.p_occupied, 0.5f);
      EXPECT_EQ(c.keyframe, -1);
    }
  // The keyframe alone says the same.
  for (const auto& c : classifyInKeyframe(map, 0, front)) EXPECT_EQ(c.state, Occupancy::kFree);
  for (const auto& c : classifyInKeyframe(map, 0, wall)) EXPECT_EQ(c.state, Occupancy::kOccupied);
  for (const auto& c : classifyInKeyframe(map, 0, behind)) EXPECT_EQ(c.state, Occupancy::kUnknown);
  // The seen box holds the camera and the wall patch, not the far walls behind it.
  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  EXPECT_LE(lo.z(), 0.0);
  EXPECT_GE(hi.z(), 2.0);
  EXPECT_LT(hi.z(), 2.1);
}

// A frame integrated into the keyframe looked where the keyframe does not (the -x wall, at right
// angles to the keyframe's view): what lies in front of that frame's depth is free, from the
// keyframe alone too; behind it, or in a block where a pixel had no depth, it stays unknown; the
// frame's free space follows its keyframe's pose.
TEST(QueryClassify, WhatAnIntegratedFrameSawFreeIsFreeWhereNoKeyframeLooks) {
  const PinholeCamera camera = smallCamera();
  KeyframeGraph graph;
  const Transform T_W_K = test::lookAt({0, 0, 0}, {0, 0, 2});
  test::addBoxRoomKeyframe(&graph, camera, T_W_K, T_W_K);
  const Transform T_W_F = test::lookAt({0, 0, 0}, {-2, 0, 0});
  RgbdFrame frame = test::renderBoxRoom(camera, T_W_F);
  frame.depth.at<std::uint16_t>(camera.height / 2 + 20, camera.width / 2 + 20) =
      0;  // a hole to the frame's lower right
  graph.keyframe(0).frames_free.push_back(frameFreeSpace(frame, camera, DepthRange{}, T_W_K.inverse() * T_W_F));
  const GlobalMap global = buildGlobalMap(graph, {});
  const QueryMap map = QueryMap::build(graph, global, {});
  // In front of the -x wall (2 m from the frame), where the keyframe (looking along +z) has no verdict.
  const std::vector<Eigen::Vector3d> front{{-1.5, 0, 0}, {-1.0, 0.2, 0.3}, {-1.8, -0.3, -0.2}};
  const Eigen::Vector3d behind(-2.05, 0, 0);
  const Eigen::Vector3d hole =
      T_W_F * (1.5 * camera.backProject(camera.width / 2 + 20.5, camera.height / 2 + 20.5, 1.0));
  for (const Eigen::Vector3d& q : front) {
    EXPECT_EQ(map.keyframeVerdict(0, q).state, Occupancy::kUnknown) << "the keyframe's view sees " << q.transpose();
    Classification c;
    map.classify({&q, 1}, {&c, 1});
    EXPECT_EQ(c.state, Occupancy::kFree) << q.transpose() << ": " << describe(c);
    EXPECT_EQ(c.keyframe, 0);
    EXPECT_LT(c.p_occupied, 0.0014f);
    map.classifyInKeyframe(0, {&q, 1}, {&c, 1});
    EXPECT_EQ(c.state, Occupancy::kFree) << q.transpose();
  }
  for (const Eigen::Vector3d& q : {behind, hole}) {
    Classification c;
    map.classify({&q, 1}, {&c, 1});
    EXPECT_EQ(c.state, Occupancy::kUnknown) << q.transpose() << ": " << describe(c);
  }
  // The seen box now reaches the -x wall.
  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  EXPECT_LE(lo.x(), -2.0);
  // Moved with its keyframe: the keyframe turned by 180 degrees about y turns the frame to the +x side.
  graph.setKeyframePose(0, Transform(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY())) * T_W_K);
  const QueryMap moved = QueryMap::build(graph, buildGlobalMap(graph, {}), {});
  for (const Eigen::Vector3d& q : front) {
    const Eigen::Vector3d mirrored(-q.x(), q.y(), -q.z());
    Classification at_old, at_new;
    moved.classify({&q, 1}, {&at_old, 1});
    moved.classify({&mirrored, 1}, {&at_new, 1});
    EXPECT_EQ(at_old.state, Occupancy::kUnknown) << q.transpose();
    EXPECT_EQ(at_new.state, Occupancy::kFree) << mirrored.transpose();
  }
}

/// The box room from T_W_K with a square board 1 m in front of the camera (pixels of the middle
/// third), integrated into a new keyframe: an object that later views no longer see.
int addKeyframeWithBoard(KeyframeGraph* graph, const PinholeCamera& camera, const Transform& T_W_K) {
  Keyframe k{0, 0, 0.0, T_W_K, {}, {}, {}, KeyframeContainer(camera, 5), 0, {}};
  RgbdFrame frame = test::renderBoxRoom(camera, T_W_K);
  const auto board = static_cast<std::uint16_t>(std::lround(1.0 * camera.depth_scale));
  for (int v = camera.height / 3; v < 2 * camera.height / 3; ++v)
    for (int u = camera.width / 3; u < 2 * camera.width / 3; ++u) frame.depth.at<std::uint16_t>(v, u) = board;
  LocalMapIntegrator integrator;
  integrator.integrateFrame(frame, camera, T_W_K, &k.container, nullptr);
  return graph->add(std::move(k)).id;
}

TEST(QueryClassify, AMovedObjectIsOccupiedRecentOrPreciseByTheRule) {
  KeyframeGraph graph;
  const PinholeCamera camera = smallCamera();
  // Keyframe 0 sees the board in front of the +z wall; keyframe 1, later, sees the wall where the
  // board was.
  const Transform T0 = test::lookAt({0, 0, -0.5}, {0, 0, 2});
  addKeyframeWithBoard(&graph, camera, T0);
  const Transform T1 = test::lookAt({0.05, 0, 0}, {0.05, 0, 2});
  test::addBoxRoomKeyframe(&graph, camera, T1, T1);
  GlobalMapParams gp;
  // Occlusion removal (docs/method.md 6.3) may drop the board the later view sees through; this
  // test is about the query's rules, so the global map keeps every merged ellipsoid.
  gp.occlusion_removal = false;
  const GlobalMap global = buildGlobalMap(graph, gp);
  const std::vector<Eigen::Vector3d> board{{0, 0, 0.5}, {0.05, 0.03, 0.5}};
  for (const Eigen::Vector3d& q : board) {
    const test::QueryOracle oracle(graph, global, {});
    const test::OracleVerdict v0 = oracle.verdict(0, q), v1 = oracle.verdict(1, q);
    ASSERT_EQ(v0.state, Occupancy::kOccupied) << "keyframe 0 sees the board at " << q.transpose();
    ASSERT_EQ(v1.state, Occupancy::kFree) << "keyframe 1 sees through it";
    QueryParams params;
    const QueryMap occupied = QueryMap::build(graph, global, params);
    EXPECT_EQ(classify(occupied, {q})[0].state, Occupancy::kOccupied) << "the default keeps the board (a ghost, safe)";
    params.conflict = ConflictRule::kRecent;
    const Classification recent = classify(QueryMap::build(graph, global, params), {q})[0];
    EXPECT_EQ(recent.state, Occupancy::kFree) << "the later keyframe saw it gone";
    EXPECT_EQ(recent.keyframe, 1);
    // Keyframe 0 observed last (a rank): the board is back.
    const Classification recent0 = classify(QueryMap::build(graph, global, params, std::vector<int>{1, 0}), {q})[0];
    EXPECT_EQ(recent0.state, Occupancy::kOccupied);
    EXPECT_EQ(recent0.keyframe, 0);
    params.conflict = ConflictRule::kPrecise;
    const Classification precise = classify(QueryMap::build(graph, global, params), {q})[0];
    const int winner = v0.sigma_t < v1.sigma_t ? 0 : 1;
    EXPECT_EQ(precise.keyframe, winner) << "sigma_t " << v0.sigma_t << " vs " << v1.sigma_t;
    EXPECT_EQ(precise.state, winner == 0 ? Occupancy::kOccupied : Occupancy::kFree);
  }
}

TEST(QueryClassify, ARigidMotionOfEveryPoseMovesTheAnswers) {
  KeyframeGraph graph;
  addBoxRoomViews(&graph, smallCamera());
  const GlobalMap global = buildGlobalMap(graph, {});
  const QueryMap before = QueryMap::build(graph, global, {});
  const auto points = randomPoints(global, {-2.1, -1.6, -2.1}, {2.1, 1.6, 2.1}, 4000, 5);
  Transform G = Transform::Identity();
  G.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  G.translation() = Eigen::Vector3d(0.4, -1.1, 2.5);
  for (int id = 0; id < static_cast<int>(graph.size()); ++id) graph.setKeyframePose(id, G * graph.keyframe(id).T_W_K);
  const GlobalMap moved_global = buildGlobalMap(graph, {});
  ASSERT_EQ(moved_global.ellipsoids.size(), global.ellipsoids.size());
  const QueryMap after = QueryMap::build(graph, moved_global, {});
  std::vector<Eigen::Vector3d> moved;
  for (const auto& q : points) moved.push_back(G * q);
  const auto a = classify(before, points), b = classify(after, moved);
  int differ = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool ok = a[i].state == b[i].state && a[i].keyframe == b[i].keyframe && a[i].ellipsoid == b[i].ellipsoid &&
                    std::abs(a[i].p_occupied - b[i].p_occupied) < 1e-4f;
    if (!ok && ++differ <= 5)
      ADD_FAILURE() << points[i].transpose() << ": " << describe(a[i]) << " vs " << describe(b[i]);
  }
  EXPECT_EQ(differ, 0);
  const Counts n = count(a);
  EXPECT_GT(n.free, 100);
  EXPECT_GT(n.occupied, 100);
}

TEST(QueryClassify, MovingOneKeyframeMovesItsFreeSpace) {
  KeyframeGraph graph;
  const Transform T = test::lookAt({0, 0, 0}, {0, 0, 2});
  test::addBoxRoomKeyframe(&graph, smallCamera(), T, T);
  const QueryMap before = QueryMap::build(graph, buildGlobalMap(graph, {}), {});
  const Eigen::Vector3d shift(0.1, 0, 0);
  Transform T_moved = T;
  T_moved.translation() += shift;
  graph.setKeyframePose(0, T_moved);
  const QueryMap after = QueryMap::build(graph, buildGlobalMap(graph, {}), {});
  // Across the edge of the image at 1 m (x = 80.5 / 131.25 = 0.61 m; one frame fills no margin).
  std::vector<Eigen::Vector3d> points, shifted;
  for (int i = 0; i <= 240; ++i) {
    points.emplace_back(0.3 + i * 0.0025, 0.05, 1.0);
    shifted.push_back(points.back() + shift);
  }
  const auto a = classify(before, points), b = classify(after, points), c = classify(after, shifted);
  int only_before = 0, only_after = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    only_before += a[i].state == Occupancy::kFree && b[i].state != Occupancy::kFree;
    only_after += b[i].state == Occupancy::kFree && a[i].state != Occupancy::kFree;
    EXPECT_EQ(a[i].state, c[i].state) << "the free region moved with the keyframe, at " << points[i].transpose();
  }
  EXPECT_GT(only_after, 10);
  EXPECT_EQ(only_before, 0);
}

TEST(QueryClassify, OneAndTwoThreadsGiveBitIdenticalAnswers) {
  KeyframeGraph graph;
  addBoxRoomViews(&graph, smallCamera());
  const GlobalMap global = buildGlobalMap(graph, {});
  const auto points = randomPoints(global, {-2.1, -1.6, -2.1}, {2.1, 1.6, 2.1}, 20000, 11);
  for (const ConflictRule rule : {ConflictRule::kOccupied, ConflictRule::kRecent, ConflictRule::kPrecise}) {
    QueryParams p1, p2;
    p1.conflict = p2.conflict = rule;
    p1.threads = 1, p2.threads = 2;
    const QueryMap m1 = QueryMap::build(graph, global, p1), m2 = QueryMap::build(graph, global, p2);
    EXPECT_EQ(m1.memoryBytes(), m2.memoryBytes());
    const auto a = classify(m1, points), b = classify(m2, points), c = classify(m2, points);
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_TRUE(same(a[i], b[i])) << i << ": " << describe(a[i]) << " vs " << describe(b[i]);
      ASSERT_TRUE(same(b[i], c[i])) << i;
    }
    const auto k1 = classifyInKeyframe(m1, 1, points), k2 = classifyInKeyframe(m2, 1, points);
    for (std::size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(same(k1[i], k2[i])) << i;
  }
}

TEST(QueryClassify, MemoryIsTheSumOfItsParts) {
  KeyframeGraph graph;
  addBoxRoomViews(&graph, smallCamera());
  const QueryMap map = QueryMap::build(graph, buildGlobalMap(graph, {}), {});
  const QueryMap::MemoryParts parts = map.memoryParts();
  EXPECT_GT(parts.keyframe_views, 0u);
  EXPECT_GT(parts.surface, 0u);
  // Beyond the parts: the parameters and the parts' handles, far below a kilobyte.
  ASSERT_GE(map.memoryBytes(), parts.keyframe_views + parts.frames + parts.surface);
  EXPECT_LT(map.memoryBytes() - parts.keyframe_views - parts.frames - parts.surface, 1024u);
}

TEST(QueryClassify, AnEmptyMapIsUnknownEverywhere) {
  const std::vector<Eigen::Vector3d> points{{0, 0, 0}, {1, 2, 3}};
  KeyframeGraph graph;
  for (const QueryMap& map : {QueryMap(), QueryMap::build(graph, buildGlobalMap(graph, {}), {})}) {
    EXPECT_TRUE(map.empty());
    EXPECT_EQ(map.keyframes(), 0u);
    EXPECT_EQ(map.ellipsoids(), 0u);
    Eigen::Vector3d lo, hi;
    map.seenBounds(&lo, &hi);
    EXPECT_GT(lo.x(), hi.x());
    for (const auto& c : classify(map, points)) {
      EXPECT_EQ(c.state, Occupancy::kUnknown);
      EXPECT_EQ(c.p_occupied, 0.5f);
    }
    EXPECT_THROW(classifyInKeyframe(map, 0, points), std::invalid_argument);
  }
}

// A keyframe whose cells the filter all rejected sees nothing: no verdict anywhere, no seen box.
TEST(QueryClassify, AKeyframeWithoutKeptCellsSeesNothing) {
  KeyframeGraph graph;
  const Transform T = test::lookAt({0, 0, 0}, {0, 0, 2});
  test::addBoxRoomKeyframe(&graph, smallCamera(), T, T);
  GlobalMapParams gp;
  gp.filter.min_points = 1000000;
  const QueryMap map = QueryMap::build(graph, buildGlobalMap(graph, gp), {});
  EXPECT_EQ(map.keyframes(), 1u);
  EXPECT_EQ(map.ellipsoids(), 0u);
  EXPECT_FALSE(map.empty());
  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  EXPECT_GT(lo.x(), hi.x());
  const std::vector<Eigen::Vector3d> points{{0, 0, 1.5}, {0, 0, 2}};
  for (const auto& c : classify(map, points)) EXPECT_EQ(c.state, Occupancy::kUnknown);
  for (const auto& c : classifyInKeyframe(map, 0, points)) EXPECT_EQ(c.state, Occupancy::kUnknown);
}

TEST(QueryClassify, BadInputThrows) {
  KeyframeGraph graph;
  const Transform T = test::lookAt({0, 0, 0}, {0, 0, 2});
  test::addBoxRoomKeyframe(&graph, smallCamera(), T, T);
  const GlobalMap global = buildGlobalMap(graph, {});
  const QueryMap map = QueryMap::build(graph, global, {});
  std::vector<Eigen::Vector3d> points{{0, 0, 1}, {0, 0, 1}, {0, std::nan(""), 1}};
  try {
    classify(map, points);
    ADD_FAILURE() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 2"), std::string::npos) << e.what();
  }
  points[2] = {INFINITY, 0, 0};
  EXPECT_THROW(classifyInKeyframe(map, 0, points), std::invalid_argument);
  EXPECT_THROW(classifyInKeyframe(map, 1, points), std::invalid_argument);
  EXPECT_THROW(classifyInKeyframe(map, -1, points), std::invalid_argument);
  std::vector<Classification> short_out(1);
  EXPECT_THROW(map.classify(points, short_out), std::invalid_argument);
  for (void (*bad)(QueryParams&) :
       {+[](QueryParams& p) { p.gate_sigma = 0; }, +[](QueryParams& p) { p.gate_sigma = NAN; },
        +[](QueryParams& p) { p.min_sigma_m = -1; }, +[](QueryParams& p) { p.threads = -1; }}) {
    QueryParams p;
    bad(p);
    EXPECT_THROW(p.validate(), std::invalid_argument);
    EXPECT_THROW(QueryMap::build(graph, global, p), std::invalid_argument);
  }
  QueryParams{}.validate();
  // A global map of another graph, and a rank of the wrong size.
  KeyframeGraph other;
  EXPECT_THROW(QueryMap::build(other, global, {}), std::invalid_argument);
  EXPECT_THROW(QueryMap::build(graph, global, {}, std::vector<int>{0, 1}), std::invalid_argument);
  EXPECT_STREQ(occupancyName(Occupancy::kFree), "free");
  EXPECT_STREQ(occupancyName(Occupancy::kOccupied), "occupied");
  EXPECT_STREQ(occupancyName(Occupancy::kUnknown), "unknown");
}

}  // namespace
}  // namespace vdmap
