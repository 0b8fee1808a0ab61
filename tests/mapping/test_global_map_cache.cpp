// The global map's stage cache (GlobalMapWorkspace): a build with a workspace re-runs only the
// stages after what changed (GlobalMap::reuse), and its map is always the fresh build's, bit for bit.
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "mapping/global_map/global_map.h"
#include "mapping/io/camera_config.h"
#include "mapping/pipeline/parameters.h"
#include "tests/support/box_room_keyframes.h"

namespace vdmap {
namespace {

const PinholeCamera kCacheCamera = cameraPreset("tum-default");

// Six keyframes around the box room, three pairs linked with weights 0.5, 0.3 and 0.15: with the
// default tau_group (0.1) three merge groups, with tau_group 0.2 the last pair splits in two.
KeyframeGraph sixKeyframes() {
  KeyframeGraph graph;
  for (int i = 0; i < 6; ++i) {
    const double a = 0.35 * i;
    const Transform T = test::lookAt({0.03 * i, 0, 0}, {2 * std::sin(a), 0.1, 2 * std::cos(a)});
    test::addBoxRoomKeyframe(&graph, kCacheCamera, T, T);
  }
  graph.edges().strengthen(0, 1, 0.5);
  graph.edges().strengthen(2, 3, 0.3);
  graph.edges().strengthen(4, 5, 0.15);
  return graph;
}

// FNV-1a over every field of the map's ellipsoids (as bench_global_map's mapHash).
std::uint64_t hashOf(const GlobalMap& map) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&h](const void* data, std::size_t bytes) {
    for (std::size_t i = 0; i < bytes; ++i) h = (h ^ static_cast<const unsigned char*>(data)[i]) * 1099511628211ull;
  };
  for (const Ellipsoid& e : map.ellipsoids) {
    add(e.mean.data(), sizeof(double) * 3);
    add(e.cov.data(), sizeof(double) * 9);
    add(e.color.data(), sizeof(float) * 3);
    add(&e.count, sizeof e.count);
    add(&e.keyframe, sizeof e.keyframe);
    add(&e.grid_index, sizeof e.grid_index);
  }
  return h;
}

void expectFreshMap(const KeyframeGraph& graph, const GlobalMapParams& params, const GlobalMap& cached) {
  const GlobalMap fresh = buildGlobalMap(graph, params);
  ASSERT_GT(fresh.ellipsoids.size(), 0u);
  EXPECT_EQ(hashOf(fresh), hashOf(cached));
  EXPECT_EQ(fresh.ellipsoids.size(), cached.ellipsoids.size());
  EXPECT_EQ(fresh.sigma_e, cached.sigma_e);
  EXPECT_EQ(fresh.merged, cached.merged);
  EXPECT_EQ(fresh.merged_across_groups, cached.merged_across_groups);
  EXPECT_EQ(fresh.kept, cached.kept);
  EXPECT_EQ(fresh.groups.size(), cached.groups.size());
}

// Another value of a live parameter, within its range, that changes what it controls.
double otherValue(const Parameter& p, double now) {
  if (p.kind == ParameterSpec::Kind::kBool || p.kind == ParameterSpec::Kind::kChoice) return now == 0 ? 1 : 0;
  if (p.key == std::string("tau_group")) return 0.2;
  if (p.key == std::string("min_points")) return now + 4;
  return now * 0.7;
}

TEST(GlobalMapCache, EveryParameterChangeGivesTheFreshBuildsMapBitForBit) {
  const KeyframeGraph graph = sixKeyframes();
  GlobalMapWorkspace workspace;
  ParameterValues values;
  expectFreshMap(graph, values.global, buildGlobalMap(graph, values.global, &workspace));
  int live = 0;
  for (const Parameter& p : parameters()) {
    if (!p.live) continue;
    ++live;
    SCOPED_TRACE(p.key);
    const double was = p.get(values);
    p.set(values, otherValue(p, was));
    ASSERT_NE(p.get(values), was);
    expectFreshMap(graph, values.global, buildGlobalMap(graph, values.global, &workspace));
    p.set(values, was);
    expectFreshMap(graph, values.global, buildGlobalMap(graph, values.global, &workspace));
  }
  EXPECT_EQ(live, 10);
}

TEST(GlobalMapCache, TheSameBuildAgainReusesEveryStage) {
  const KeyframeGraph graph = sixKeyframes();
  GlobalMapWorkspace workspace;
  const GlobalMapParams params;
  const GlobalMap first = buildGlobalMap(graph, params, &workspace);
  EXPECT_FALSE(first.reuse.groups);
  EXPECT_EQ(first.reuse.merged_groups, 0u);
  EXPECT_FALSE(first.reuse.occlusion);
  EXPECT_FALSE(first.reuse.fusion);
  const GlobalMap again = buildGlobalMap(graph, params, &workspace);
  EXPECT_TRUE(again.reuse.groups);
  EXPECT_EQ(again.reuse.merged_groups, again.groups.size());
  EXPECT_TRUE(again.reuse.occlusion);
  EXPECT_TRUE(again.reuse.fusion);
  EXPECT_EQ(hashOf(first), hashOf(again));
  // Without a workspace nothing is reused.
  const GlobalMap fresh = buildGlobalMap(graph, params);
  EXPECT_EQ(fresh.reuse.merged_groups, 0u);
  EXPECT_FALSE(fresh.reuse.fusion);
}

TEST(GlobalMapCache, FusionChangeRerunsOnlyFusion) {
  const KeyframeGraph graph = sixKeyframes();
  GlobalMapWorkspace workspace;
  GlobalMapParams params;
  buildGlobalMap(graph, params, &workspace);
  params.fusion_max_distance = 0.5;
  const GlobalMap map = buildGlobalMap(graph, params, &workspace);
  EXPECT_TRUE(map.reuse.groups);
  EXPECT_EQ(map.reuse.merged_groups, 3u);
  EXPECT_TRUE(map.reuse.occlusion);
  EXPECT_FALSE(map.reuse.fusion);
  expectFreshMap(graph, params, map);
}

TEST(GlobalMapCache, OcclusionChangeKeepsGroupsAndMerge) {
  const KeyframeGraph graph = sixKeyframes();
  GlobalMapWorkspace workspace;
  GlobalMapParams params;
  buildGlobalMap(graph, params, &workspace);
  params.occlusion_angle_deg = 20;
  const GlobalMap map = buildGlobalMap(graph, params, &workspace);
  EXPECT_TRUE(map.reuse.groups);
  EXPECT_EQ(map.reuse.merged_groups, 3u);
  EXPECT_FALSE(map.reuse.occlusion);
  EXPECT_FALSE(map.reuse.fusion);
  expectFreshMap(graph, params, map);
  // Its distance while it is off changes nothing: occlusion removal and fusion are kept too.
  params.occlusion_removal = false;
  buildGlobalMap(graph, params, &workspace);
  params.occlusion_distance_m = 0.3;
  const GlobalMap off = buildGlobalMap(graph, params, &workspace);
  EXPECT_TRUE(off.reuse.occlusion);
  EXPECT_TRUE(off.reuse.fusion);
  expectFreshMap(graph, params, off);
}

TEST(GlobalMapCache, TauGroupReusesUnchangedGroups) {
  const KeyframeGraph graph = sixKeyframes();
  GlobalMapWorkspace workspace;
  GlobalMapParams params;
  ASSERT_EQ(buildGlobalMap(graph, params, &workspace).groups.size(), 3u);
  params.tau_group = 0.2;  // {4, 5} splits into {4} and {5}
  const GlobalMap map = buildGlobalMap(graph, params, &workspace);
  ASSERT_EQ(map.groups.size(), 4u);
  EXPECT_FALSE(map.reuse.groups);
  EXPECT_EQ(map.reuse.merged_groups, 2u);
  EXPECT_FALSE(map.reuse.occlusion);
  expectFreshMap(graph, params, map);
  params.tau_group = 0.1;
  const GlobalMap back = buildGlobalMap(graph, params, &workspace);
  EXPECT_EQ(back.reuse.merged_groups, 2u);
  expectFreshMap(graph, params, back);
}

TEST(GlobalMapCache, APoseChangeReMergesOnlyTheGroupsItTouches) {
  KeyframeGraph graph = sixKeyframes();
  GlobalMapWorkspace workspace;
  const GlobalMapParams params;
  buildGlobalMap(graph, params, &workspace);
  Transform moved = graph.keyframe(5).T_W_K;
  moved.translation().x() += 0.01;
  graph.setKeyframePose(5, moved);
  const GlobalMap map = buildGlobalMap(graph, params, &workspace);
  EXPECT_EQ(map.reuse.merged_groups, 2u);
  EXPECT_FALSE(map.reuse.occlusion);
  EXPECT_FALSE(map.reuse.fusion);
  expectFreshMap(graph, params, map);
}

TEST(GlobalMapCache, OneAndTwoThreadsAgree) {
  const KeyframeGraph graph = sixKeyframes();
  GlobalMapWorkspace one, two;
  GlobalMapParams p1, p2;
  p1.threads = 1;
  p2.threads = 2;
  auto both = [&](const char* what) {
    SCOPED_TRACE(what);
    const GlobalMap a = buildGlobalMap(graph, p1, &one), b = buildGlobalMap(graph, p2, &two);
    EXPECT_EQ(hashOf(a), hashOf(b));
    EXPECT_EQ(a.reuse.merged_groups, b.reuse.merged_groups);
    EXPECT_EQ(a.reuse.occlusion, b.reuse.occlusion);
    expectFreshMap(graph, p1, a);
  };
  both("first");
  p1.merge_distance_m = p2.merge_distance_m = 0.1;
  both("merge distance");
  p1.fusion_max_distance = p2.fusion_max_distance = 2.0;
  both("fusion distance");
  p1.tau_group = p2.tau_group = 0.2;
  both("tau_group");
}

}  // namespace
}  // namespace vdmap
