// The workbench without a window: settings persistence, the mapping session (play, step, seek,
// live thresholds, pose correction) and the UI actions, driven exactly as the ImGui code does.
#include <atomic>
#include <chrono>
#include <fstream>
#include <future>
#include <random>
#include <regex>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Eigenvalues>
#include <glm/gtc/matrix_transform.hpp>

#include "app/view/settings.h"
#include "app/view/view_file.h"
#include "app/window/tg_parts.h"
#include "app/workbench/workbench.h"
#include "render/colormap.h"
#include "render/lod_order.h"
#include "render/map_mirror.h"
#include "render/map_scene.h"
#include "render/scene_lines.h"
#include "render/view_draw.h"
#include "tests/support/test_util.h"

namespace vdmap::app::gui {
namespace {
namespace fs = std::filesystem;

// Ten frames of a textured plane, a keyframe every three frames (so the test does not depend on
// ORB matching of random texture).
struct TinyBench {
  test::TempDir dir;
  Workbench bench{settings()};
  TinyBench() {
    test::writeTinySequence(dir / "seq", 10);
    EXPECT_TRUE(bench.files().open({.folder = (dir / "seq").string()})) << bench.ui().status.text;
  }
  static Settings settings() {
    Settings s;
    s.mapper.keyframe_every = 3;
    return s;
  }
  MappingWorker& worker() { return *bench.worker(); }
  // Maps every frame and frames the view in a 900 x 500 viewport, following the map.
  void mapAndFrame() {
    worker().play();
    worker().waitIdle();
    bench.ui().view_width = 900, bench.ui().view_height = 500;
    bench.sync();
  }
};

// Selects keyframe `id` as the keyframe list does and returns the session's selection once the
// worker has published it.
std::shared_ptr<const SelectionSnapshot> selectAndWait(Workbench& bench, int id) {
  bench.poses().selectKeyframe(id);
  bench.worker()->waitIdle();
  return bench.worker()->selection();
}

// Keyframe `id`'s ellipsoids kept by the current global map's thresholds, filtered in its own
// frame and moved to the world here (the reference for SelectionSnapshot::local).
std::vector<Ellipsoid> keptInWorld(MappingWorker& worker, int id) {
  std::vector<Ellipsoid> out;
  worker.withMapper([&](const Mapper& mapper, const GlobalSnapshot& global) {
    const Keyframe& k = mapper.graph().keyframe(id);
    out = keptEllipsoids(k.container, global.params.filter, Transform::Identity(), id);
    for (Ellipsoid& e : out) {
      e.mean = k.T_W_K * e.mean;
      e.cov = k.T_W_K.linear() * e.cov * k.T_W_K.linear().transpose();
    }
    return std::string();
  });
  worker.waitIdle();
  return out;
}

void expectSameEllipsoids(const std::vector<Ellipsoid>& actual, const std::vector<Ellipsoid>& expected) {
  ASSERT_EQ(actual.size(), expected.size());
  for (std::size_t i = 0; i < actual.size(); ++i) {
    EXPECT_EQ(actual[i].keyframe, expected[i].keyframe) << i;
    EXPECT_EQ(actual[i].grid_index, expected[i].grid_index) << i;
    EXPECT_TRUE(actual[i].mean.isApprox(expected[i].mean, 1e-12)) << i;
    EXPECT_TRUE(actual[i].cov.isApprox(expected[i].cov, 1e-12)) << i;
  }
}

TEST(GuiSettings, RoundTripAndDefaultsForMissingKeys) {
  test::TempDir dir;
  Settings s;
  s.thresholds.merge_distance_m = 0.4;
  s.thresholds.filter.model = SensorModel::kBelter2018;
  s.color = render::ColorMode::kCount;
  s.show_graph = false;
  s.last_sequence = "/data/seq";
  saveSettings(dir / "a" / "settings.json", s);
  std::string warning;
  const Settings r = loadSettings(dir / "a" / "settings.json", &warning);
  EXPECT_TRUE(warning.empty()) << warning;
  EXPECT_DOUBLE_EQ(r.thresholds.merge_distance_m, 0.4);
  EXPECT_EQ(r.thresholds.filter.model, SensorModel::kBelter2018);
  EXPECT_EQ(r.color, render::ColorMode::kCount);
  EXPECT_FALSE(r.show_graph);
  EXPECT_EQ(r.last_sequence, "/data/seq");

  test::writeText(dir / "partial.json", R"({"thresholds": {"min_points": 9}})");
  const Settings p = loadSettings(dir / "partial.json", &warning);
  EXPECT_EQ(p.thresholds.filter.min_points, 9);
  EXPECT_DOUBLE_EQ(p.thresholds.merge_distance_m, Settings{}.thresholds.merge_distance_m);
  EXPECT_TRUE(loadSettings(dir / "missing.json", &warning).last_sequence.empty());
  EXPECT_TRUE(warning.empty());
}

TEST(GuiSettings, TheProbeAndTheQuerySliceAreKept) {
  test::TempDir dir;
  Settings s;
  s.probe = true;
  s.probe_offset_m = 0.12f;
  s.query_slice = true;
  s.query_slice_spec = {.axis = render::QuerySliceAxis::kY,
                        .offset_m = -0.375,
                        .color = render::QuerySliceColor::kDistance,
                        .max_distance_m = 0.8};
  saveSettings(dir / "settings.json", s);
  std::string warning;
  const Settings r = loadSettings(dir / "settings.json", &warning);
  EXPECT_TRUE(warning.empty()) << warning;
  EXPECT_TRUE(r.probe);
  EXPECT_FLOAT_EQ(r.probe_offset_m, 0.12f);
  EXPECT_TRUE(r.query_slice);
  EXPECT_EQ(r.query_slice_spec, s.query_slice_spec);
  // --set takes them as the file does; a bad plane is named.
  Settings t;
  applySetting(t, "query_slice_at=up=1.5");
  EXPECT_EQ(t.query_slice_spec.axis, render::QuerySliceAxis::kUp);
  EXPECT_DOUBLE_EQ(t.query_slice_spec.offset_m, 1.5);
  try {
    applySetting(t, "query_slice_at=w=1");
    ADD_FAILURE() << "taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("query_slice_at"), std::string::npos) << e.what();
  }
}

// How the mesh is made: kept in the file, taken by --set, a value out of range named in one line.
TEST(GuiSettings, TheMeshParametersAreKept) {
  test::TempDir dir;
  Settings s;
  s.mesh.max_slope_deg = 35;
  s.mesh.edge_sigma = 1.5;
  s.mesh.stride = 3;
  s.mesh.fuse = false;
  saveSettings(dir / "settings.json", s);
  std::string warning;
  const Settings r = loadSettings(dir / "settings.json", &warning);
  EXPECT_TRUE(warning.empty()) << warning;
  EXPECT_EQ(r.mesh, s.mesh);
  EXPECT_TRUE(sameSettings(r, s));
  EXPECT_FALSE(sameSettings(r, Settings{})) << "the mesh keys count as settings";
  Settings t;
  applySetting(t, "mesh_stride=4");
  applySetting(t, "mesh_fuse=false");
  EXPECT_EQ(t.mesh.stride, 4);
  EXPECT_FALSE(t.mesh.fuse);
  for (const auto& [kv, named] : std::vector<std::pair<std::string, std::string>>{
           {"mesh_max_slope=95", "view.mesh_max_slope must be in [0, 89.9] degrees"},
           {"mesh_edge_sigma=-1", "view.mesh_edge_sigma must be in [0, 100]"},
           {"mesh_stride=0", "view.mesh_stride must be in 1..16"},
           {"mesh_fuse=3", "view.mesh_fuse: expected true or false"}}) {
    try {
      applySetting(t, kv);
      ADD_FAILURE() << kv << " taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(named), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line: " << e.what();
    }
  }
  test::writeText(dir / "bad.json", R"({"view": {"mesh_stride": 99}})");
  const Settings bad = loadSettings(dir / "bad.json", &warning);
  EXPECT_NE(warning.find("view.mesh_stride"), std::string::npos) << warning;
  EXPECT_EQ(bad.mesh, MeshParams{});
}

TEST(GuiSettings, CorruptFileGivesDefaultsWithAWarning) {
  test::TempDir dir;
  for (const char* text : {"{not json", R"({"thresholds": {"merge_distance": "far"}})",
                           R"({"thresholds": {"merge_distance": -1}})", R"({"view": {"color": "pink"}})", "[1, 2]"}) {
    test::writeText(dir / "settings.json", text);
    std::string warning;
    const Settings s = loadSettings(dir / "settings.json", &warning);
    EXPECT_NE(warning.find("settings.json"), std::string::npos) << text;
    EXPECT_NE(warning.find("default"), std::string::npos) << warning;
    EXPECT_DOUBLE_EQ(s.thresholds.merge_distance_m, Settings{}.thresholds.merge_distance_m);
    EXPECT_EQ(s.color, render::ColorMode::kRgb);
  }
}

TEST(GuiSettings, SetKeyValue) {
  Settings s;
  applySetting(s, "merge_distance=0.5");
  applySetting(s, "occlusion_removal=false");
  applySetting(s, "sensor_model=belter2018");
  applySetting(s, "cell_size=8");
  applySetting(s, "color=uncertainty");
  applySetting(s, "show_ellipsoids=false");
  EXPECT_EQ(s.color, render::ColorMode::kUncertainty);
  EXPECT_FALSE(s.show_ellipsoids);
  EXPECT_DOUBLE_EQ(s.thresholds.merge_distance_m, 0.5);
  EXPECT_FALSE(s.thresholds.occlusion_removal);
  EXPECT_EQ(s.thresholds.filter.model, SensorModel::kBelter2018);
  EXPECT_EQ(s.mapper.local_map.cell_size_px, 8);
  EXPECT_THROW(applySetting(s, "merge_distance"), std::invalid_argument);
  EXPECT_THROW(applySetting(s, "colour=3"), std::invalid_argument);
  EXPECT_THROW(applySetting(s, "min_points=lots"), std::invalid_argument);
  EXPECT_THROW(applySetting(s, "tau_group=2"), std::invalid_argument);
  EXPECT_DOUBLE_EQ(s.thresholds.merge_distance_m, 0.5);  // a failed --set changes nothing
}

TEST(GuiSettings, EveryKeyInTheSetHelpIsAKeySetTakes) {
  const std::string list = settingKeyList();
  // Keys are the words followed by ',', ';' or the end ("view:" is a section name).
  static const std::regex key_pattern(R"((\w+)(?=,|;|$))");
  std::vector<std::string> keys;
  for (std::sregex_iterator it(list.begin(), list.end(), key_pattern), end; it != end; ++it) keys.push_back((*it)[1]);
  EXPECT_GE(keys.size(), 18u) << list;
  for (const std::string& key : keys) {
    Settings s;
    try {
      applySetting(s, key + "=[]");  // a known key rejects the value, an unknown one the key
      ADD_FAILURE() << key << "=[] was taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).find("unknown key"), std::string::npos) << e.what();
    }
  }
}

TEST(GuiSettings, RerunParamsDifferOnlyInTheRerunKeys) {
  EXPECT_FALSE(rerunParamsDiffer(Settings{}, Settings{}));
  for (const char* key_value : {"cell_size=8", "tau=0.5", "orb_features=500"}) {
    Settings s;
    applySetting(s, key_value);
    EXPECT_TRUE(rerunParamsDiffer(s, Settings{})) << key_value;
  }
  Settings live;
  applySetting(live, "merge_distance=0.5");
  applySetting(live, "color=count");
  EXPECT_FALSE(rerunParamsDiffer(live, Settings{}));
}

TEST(GuiSettings, EveryColourModeNameSelectsItsMode) {
  for (std::size_t i = 0; i < render::kColorModeNames.size(); ++i) {
    Settings s;
    applySetting(s, std::string("color=") + render::kColorModeNames[i]);
    EXPECT_EQ(s.color, static_cast<render::ColorMode>(i));
    EXPECT_STREQ(render::colorModeName(s.color), render::kColorModeNames[i]);
  }
}

TEST(GuiAppendLog, ViewsKeepTheirItemsWhileTheLogGrowsAndClears) {
  AppendLog<int> log;
  std::vector<int> reference;  // the obviously-correct copy
  std::vector<std::pair<SharedSpan<int>, std::vector<int>>> views;
  for (int i = 0; i < 1000; ++i) {  // several buffer growths
    log.push_back(i * 7);
    reference.push_back(i * 7);
    if (i % 97 == 0) views.emplace_back(log.view(), reference);
  }
  log.clear();
  log.push_back(-1);
  for (const auto& [view, expected] : views) EXPECT_EQ(std::vector<int>(view.begin(), view.end()), expected);
  EXPECT_EQ(log.size(), 1u);
  EXPECT_EQ(log.view().back(), -1);
  EXPECT_TRUE(AppendLog<int>().view().empty());
}

TEST(GuiWorkbench, BadSequenceShowsTheErrorAndKeepsTheOpenOne) {
  TinyBench t;
  Workbench& bench = t.bench;
  EXPECT_FALSE(bench.files().open({.folder = (t.dir / "nowhere").string()}));
  EXPECT_NE(bench.ui().status.text.find("nowhere"), std::string::npos) << bench.ui().status.text;
  ASSERT_NE(bench.worker(), nullptr);  // the sequence opened before is still there
  EXPECT_EQ(bench.worker()->sequence()->folder(), t.dir / "seq");
  Workbench empty{Settings{}};
  EXPECT_FALSE(empty.files().open({.folder = (t.dir / "nowhere").string()}));
  EXPECT_EQ(empty.worker(), nullptr);
}

TEST(GuiSession, StepStepToKeyframePlayAndSeekBack) {
  TinyBench t;
  MappingWorker& s = t.worker();
  s.step();
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 1);
  EXPECT_EQ(s.mapping()->keyframes.size(), 1u);
  ASSERT_NE(s.global(), nullptr);  // built once the worker is idle
  s.stepToKeyframe();              // frame 3 starts keyframe 1
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 4);
  EXPECT_EQ(s.mapping()->keyframes.size(), 2u);
  EXPECT_EQ(s.mapping()->keyframes[1].frame, 3);
  s.play();
  s.waitIdle();
  const auto end = s.mapping();
  EXPECT_EQ(end->frames_mapped, 10);
  EXPECT_EQ(end->times.size(), 10u);
  EXPECT_EQ(end->trajectory.size(), 10u);
  EXPECT_FALSE(end->rgb.empty());
  EXPECT_EQ(s.global()->frames_mapped, 10);
  const std::size_t sigma_e_prime = s.global()->map.sigma_e_prime;
  EXPECT_GT(sigma_e_prime, 0u);
  s.seek(4);  // backwards: re-mapped from the start up to frame 4
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 5);
  EXPECT_EQ(s.mapping()->keyframes.size(), 2u);
  s.seek(9);
  s.waitIdle();
  EXPECT_EQ(s.global()->map.sigma_e_prime, sigma_e_prime);  // same frames, same map
  EXPECT_TRUE(s.status().error.empty());
}

// With --frames A:B the scrubber counts from A: keyframe ticks (and loop markers) stand at the
// frame's position in the selection, not at its depth-list index.
TEST(GuiSession, KeyframesAreAtTheirScrubberPositionWithAFrameRange) {
  test::TempDir dir;
  test::writeTinySequence(dir / "seq", 10);
  Workbench bench{TinyBench::settings()};
  ASSERT_TRUE(bench.files().open({(dir / "seq").string(), "", "4:10", ""})) << bench.ui().status.text;
  bench.worker()->play();
  bench.worker()->waitIdle();
  const auto mapping = bench.worker()->mapping();
  EXPECT_EQ(mapping->frames_total, 6);
  ASSERT_EQ(mapping->keyframes.size(), 2u);
  EXPECT_EQ(mapping->keyframes[0].frame, 0);  // depth frame 4
  EXPECT_EQ(mapping->keyframes[1].frame, 3);  // depth frame 7
}

// The ellipsoids of `a` that no ellipsoid of `b` matches (same keyframe, same mean), compared
// pair by pair: the reference for MapDiff.
std::size_t countNotIn(const std::vector<Ellipsoid>& a, const std::vector<Ellipsoid>& b) {
  std::size_t n = 0;
  for (const Ellipsoid& e : a)
    n += std::none_of(b.begin(), b.end(),
                      [&](const Ellipsoid& f) { return f.keyframe == e.keyframe && f.mean == e.mean; });
  return n;
}

// How many ellipsoids of `map` have colour `c`.
std::size_t countColoured(const std::vector<Ellipsoid>& map, const Eigen::Vector3f& c) {
  return std::count_if(map.begin(), map.end(), [&](const Ellipsoid& e) { return e.color == c; });
}

// A threshold edit's diff counts what the edit removed or merged away and what it added, as a
// set difference of the two maps says; D draws it: kept grey, added green, removed red.
TEST(GuiSession, EditDiffShowsWhatAThresholdEditChanged) {
  TinyBench t;
  Workbench& bench = t.bench;
  bench.ui().params.global.filter.min_points = 3;  // keeps what the edits below remove
  bench.parameters().applyThresholds();
  t.mapAndFrame();
  EXPECT_EQ(bench.view().diff(), nullptr);  // no edit yet (the one above had no map before it)
  const auto before = t.worker().global();
  ASSERT_TRUE(bench.parameters().edit(*findParameter("min_points"), 60));
  t.worker().waitIdle();
  bench.sync();
  const MapDiff* diff = bench.view().diff();
  ASSERT_NE(diff, nullptr);
  const auto after = t.worker().global();
  EXPECT_EQ(diff->before, before);
  EXPECT_EQ(diff->after, after);
  const std::vector<Ellipsoid>&old_map = before->map.ellipsoids, &new_map = after->map.ellipsoids;
  const std::size_t removed = countNotIn(old_map, new_map), added = countNotIn(new_map, old_map);
  EXPECT_GT(removed, 0u);  // the cells of keyframes that integrated fewer frames
  EXPECT_EQ(diff->removed.size(), removed);
  EXPECT_EQ(diff->added_count, added);
  EXPECT_EQ(diff->text(),
            "min points 3 -> 60: " + std::to_string(removed) + " removed or merged, " + std::to_string(added) + " new");

  // The view draws the map until D shows the diff, and again after a second D.
  EXPECT_EQ(bench.view().shownDiff(), nullptr);
  EXPECT_EQ(bench.view().shownMap().ellipsoids->size(), new_map.size());
  bench.key(KeyAction::kEditDiff);
  ASSERT_EQ(bench.view().shownDiff(), diff);
  const auto shown = bench.view().shownMap().ellipsoids;
  ASSERT_EQ(shown->size(), new_map.size() + removed);
  EXPECT_EQ(countColoured(*shown, kDiffAdded), added);
  EXPECT_EQ(countColoured(*shown, kDiffRemoved), removed);
  EXPECT_EQ(countColoured(*shown, kDiffKept), new_map.size() - added);

  // The next edit is compared with the map of the one before, and the view shows its diff.
  const int serial = bench.view().shownMap().serial;
  ASSERT_TRUE(bench.parameters().edit(*findParameter("min_points"), 3));
  t.worker().waitIdle();
  bench.sync();
  diff = bench.view().diff();
  ASSERT_NE(diff, nullptr);
  EXPECT_EQ(diff->before, after);
  EXPECT_EQ(diff->removed.size(), countNotIn(new_map, t.worker().global()->map.ellipsoids));
  EXPECT_EQ(diff->added_count, countNotIn(t.worker().global()->map.ellipsoids, new_map));
  EXPECT_EQ(diff->edit, "min points 60 -> 3");
  EXPECT_EQ(diff->added_count, removed);  // brought back
  EXPECT_NE(bench.view().shownMap().serial, serial);
  EXPECT_EQ(bench.view().shownMap().ellipsoids->size(), diff->after->map.ellipsoids.size() + diff->removed.size());
  bench.key(KeyAction::kEditDiff);
  EXPECT_EQ(bench.view().shownMap().ellipsoids->size(), diff->after->map.ellipsoids.size());

  // A refused edit changes nothing; the next one is compared with the map shown.
  const auto shown_map = t.worker().global();
  EXPECT_FALSE(bench.parameters().edit(*findParameter("merge_distance"), -1));
  ASSERT_TRUE(bench.parameters().edit(*findParameter("min_points"), 60));
  t.worker().waitIdle();
  bench.sync();
  ASSERT_NE(bench.view().diff(), nullptr);
  EXPECT_EQ(bench.view().diff()->before, shown_map);
  EXPECT_EQ(bench.view().diff()->edit, "min points 3 -> 60");
}

TEST(GuiSession, LiveThresholdChangeSwapsInANewGlobalMap) {
  TinyBench t;
  Workbench& bench = t.bench;
  bench.ui().params.global.filter.min_points = 3;
  bench.parameters().applyThresholds();
  t.worker().play();
  t.worker().waitIdle();
  const auto before = t.worker().global();
  // Cells of a 5 px grid over 3 frames of a plane hold ~75 points; 60 keeps only those of
  // keyframes that integrated three frames.
  bench.ui().params.global.filter.min_points = 60;
  bench.parameters().applyThresholds();
  t.worker().waitIdle();
  const auto after = t.worker().global();
  EXPECT_GT(after->generation, before->generation);
  EXPECT_EQ(after->params.filter.min_points, 60);
  EXPECT_LT(after->map.sigma_e, before->map.sigma_e);
  EXPECT_LT(after->map.sigma_e_prime, before->map.sigma_e_prime);
  // Each map comes with its fast-pass order, made by the worker rather than the UI thread.
  for (const auto& snap : {before, after}) EXPECT_EQ(snap->lod_order, render::lodOrder(snap->map.ellipsoids));
  std::size_t local = 0;  // the selection, keyframe by keyframe, covers Sigma_e
  for (int id = 0; id < static_cast<int>(after->map.kept.size()); ++id) local += selectAndWait(bench, id)->local.size();
  EXPECT_EQ(local, after->map.sigma_e);

  bench.ui().params.global.merge_distance_m = -1;  // refused, shown, map kept
  bench.parameters().applyThresholds();
  EXPECT_NE(bench.ui().status.text.find("merge"), std::string::npos) << bench.ui().status.text;
  t.worker().waitIdle();
  EXPECT_EQ(t.worker().global()->generation, after->generation);

  bench.parameters().resetToDefaults();
  t.worker().waitIdle();
  EXPECT_EQ(t.worker().global()->params.filter.min_points, FilterParams{}.min_points);
  EXPECT_TRUE(bench.ui().reset_layout);
}

// The "of which" row under t_g: every stage of the build, fusion included, and the rest, adding
// up to t_g.
TEST(Figures, TgPartsSumToTg) {
  GlobalMap m;
  m.t_g_s = 0.209;
  m.groups_ms = 2, m.merge_ms = 90, m.occlusion_ms = 30, m.fusion_ms = 83;
  const TgParts p = tgParts(m);
  EXPECT_DOUBLE_EQ(p.fusion_ms, 83);
  EXPECT_NEAR(p.other_ms, 4, 1e-9);

  TinyBench t;  // a real build's parts
  t.worker().play();
  t.worker().waitIdle();
  const GlobalMap& built = t.worker().global()->map;
  const TgParts q = tgParts(built);
  EXPECT_EQ(q.fusion_ms, built.fusion_ms);
  EXPECT_GE(q.other_ms, 0);
  EXPECT_NEAR(q.groups_ms + q.merge_ms + q.occlusion_ms + q.fusion_ms + q.other_ms, 1e3 * built.t_g_s, 1e-9);
}

TEST(GuiSession, DraggingAKeyframePoseMovesItsEllipsoids) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.worker().play();
  t.worker().waitIdle();
  auto mean_of = [&](int keyframe) {  // selected without touching the edited pose in ui()
    t.worker().selectKeyframe(keyframe);
    t.worker().waitIdle();
    const auto selection = t.worker().selection();
    EXPECT_EQ(selection->keyframe, keyframe);
    EXPECT_EQ(selection->generation, t.worker().global()->generation);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const Ellipsoid& e : selection->local) sum += e.mean;
    return Eigen::Vector3d(sum / std::max<std::size_t>(selection->local.size(), 1));
  };
  const Eigen::Vector3d before0 = mean_of(0), before1 = mean_of(1);
  bench.poses().selectKeyframe(1);
  EXPECT_NEAR(bench.ui().pose_translation_m.x, 0.03f, 1e-5f);  // frame 3 of the tiny walk
  bench.ui().pose_translation_m.z += 0.2f;
  bench.poses().applyEdit();
  t.worker().waitIdle();
  EXPECT_NEAR(t.worker().mapping()->keyframes[1].T_W_K.translation().z(), 0.2, 1e-6);
  EXPECT_NEAR((mean_of(1) - before1).z(), 0.2, 1e-4);
  EXPECT_NEAR((mean_of(0) - before0).norm(), 0.0, 1e-9);
  // Pitch 100 degrees reads back from the rotation as another triple (roll and yaw 180); the fields
  // keep what was typed while the snapshot holds the sent pose, so a drag does not jump.
  bench.ui().pose_rotation_deg.y = 100.f;
  bench.poses().applyEdit();
  t.worker().waitIdle();
  const glm::vec3 typed = bench.ui().pose_rotation_deg;
  bench.poses().syncFields();
  EXPECT_EQ(bench.ui().pose_rotation_deg, typed);
  // While an edit waits behind other work, the snapshot still holds the pose before it: a drag
  // must not be pulled back to that pose every frame.
  std::promise<void> release;
  const std::shared_future<void> released = release.get_future().share();
  t.worker().withMapper([released](const Mapper&, const GlobalSnapshot&) {
    released.wait();  // holds the worker
    return std::string();
  });
  bench.ui().pose_translation_m.x += 0.1f;
  bench.poses().applyEdit();
  const glm::vec3 dragged = bench.ui().pose_translation_m;
  bench.poses().syncFields();
  EXPECT_EQ(bench.ui().pose_translation_m, dragged);
  release.set_value();
  t.worker().waitIdle();
  bench.poses().syncFields();
  EXPECT_EQ(bench.ui().pose_translation_m, dragged);
  // A trajectory file that names no keyframe: the error is reported, the poses stay.
  test::writeText(t.dir / "wrong.txt", "5.0 0 0 0 0 0 0 1\n");
  bench.ui().trajectory_text = (t.dir / "wrong.txt").string();
  bench.files().loadTrajectory();
  t.worker().waitIdle();
  EXPECT_NE(t.worker().status().error.find("wrong.txt"), std::string::npos) << t.worker().status().error;
  // The sequence's own ground truth puts keyframe 1 back.
  bench.ui().trajectory_text = (t.dir / "seq" / "groundtruth.txt").string();
  bench.files().loadTrajectory();
  t.worker().waitIdle();
  EXPECT_TRUE(t.worker().status().error.empty()) << t.worker().status().error;
  EXPECT_NE(t.worker().status().message.find("replaced"), std::string::npos);
  EXPECT_NEAR((mean_of(1) - before1).norm(), 0.0, 1e-4);
  // The pose fields follow the reloaded pose, so a further drag starts from it, not from the edit.
  EXPECT_NEAR(bench.ui().pose_translation_m.z, 0.2f, 1e-5f);
  bench.poses().syncFields();
  EXPECT_NEAR(bench.ui().pose_translation_m.z, 0.f, 1e-5f);
  EXPECT_NEAR(bench.ui().pose_translation_m.x, 0.03f, 1e-5f);
}

TEST(GuiSession, TheSelectionHoldsTheSelectedKeyframesLocalMapAndFollowsRebuilds) {
  TinyBench t;
  Workbench& bench = t.bench;
  MappingWorker& s = t.worker();
  s.selectKeyframe(2);  // not mapped yet (as `vdmap gui --keyframe 2` does): filled once it is
  s.waitIdle();
  EXPECT_TRUE(s.selection()->local.empty());
  s.play();
  s.waitIdle();
  EXPECT_EQ(s.selection()->keyframe, 2);
  EXPECT_FALSE(s.selection()->local.empty());
  expectSameEllipsoids(s.selection()->local, keptInWorld(s, 2));

  const auto one = selectAndWait(bench, 1);
  EXPECT_EQ(one->keyframe, 1);
  EXPECT_EQ(one->generation, s.global()->generation);
  EXPECT_FALSE(one->local.empty());
  expectSameEllipsoids(one->local, keptInWorld(s, 1));

  bench.ui().params.global.filter.min_points = 60;  // see LiveThresholdChangeSwapsInANewGlobalMap
  bench.parameters().applyThresholds();
  s.waitIdle();
  const auto after = s.selection();
  EXPECT_EQ(after->keyframe, 1);
  EXPECT_EQ(after->generation, s.global()->generation);
  EXPECT_GT(after->generation, one->generation);
  EXPECT_LT(after->local.size(), one->local.size());
  expectSameEllipsoids(after->local, keptInWorld(s, 1));

  EXPECT_TRUE(selectAndWait(bench, -1)->local.empty());
  EXPECT_EQ(s.selection()->keyframe, -1);
}

TEST(GuiWorkbench, ExportSaveAndReopenTheSession) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.worker().play();
  t.worker().waitIdle();
  const auto global = t.worker().global();
  bench.ui().export_text = (t.dir / "export").string();
  bench.files().exportMap();
  bench.ui().session_text = (t.dir / "map.vdmap").string();
  bench.files().saveSession();
  t.worker().waitIdle();
  EXPECT_TRUE(t.worker().status().error.empty()) << t.worker().status().error;
  for (const char* file :
       {"local_maps.ply", "keyframes.txt", "graph.txt", "global_points.ply", "global_ellipsoids.ply", "stats.json"})
    EXPECT_TRUE(std::filesystem::exists(t.dir / "export" / file)) << file;

  Workbench reopened{Settings{}};
  ASSERT_TRUE(reopened.files().openPath((t.dir / "map.vdmap").string())) << reopened.ui().status.text;
  EXPECT_EQ(reopened.ui().status.kind, StatusLine::Kind::kSuccess) << "a session to the sequence's end is no warning";
  MappingWorker& s = *reopened.worker();
  EXPECT_EQ(s.sequence(), nullptr);
  s.play();  // nothing to play: the map stays as saved
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 10);
  EXPECT_EQ(s.mapping()->keyframes.size(), t.worker().mapping()->keyframes.size());
  EXPECT_EQ(s.global()->map.sigma_e_prime, global->map.sigma_e_prime);  // the same map, rebuilt
  const auto selection = selectAndWait(reopened, 1);
  EXPECT_EQ(selection->keyframe, 1);
  expectSameEllipsoids(selection->local, selectAndWait(bench, 1)->local);

  test::writeText(t.dir / "bad.vdmap", "not a session");
  EXPECT_FALSE(reopened.files().openPath((t.dir / "bad.vdmap").string()));
  EXPECT_NE(reopened.ui().status.text.find("bad.vdmap"), std::string::npos) << reopened.ui().status.text;
  EXPECT_NE(reopened.worker(), nullptr);  // the open session stays
}

// The Export writes what `vdmap map` writes: trajectory.txt (the same, byte for byte, for the same
// frames and parameters) and the same provenance in stats.json; part-way, the range played.
TEST(GuiWorkbench, ExportWritesTheTrajectoryAndProvenanceOfMap) {
  TinyBench t;
  t.worker().seek(4);  // frames 0..4
  t.worker().waitIdle();
  t.bench.ui().export_text = (t.dir / "part").string();
  t.bench.files().exportMap();
  t.worker().waitIdle();
  ASSERT_TRUE(t.worker().status().error.empty()) << t.worker().status().error;
  const auto part = nlohmann::json::parse(test::readFile(t.dir / "part" / "stats.json"));
  EXPECT_EQ(part["frame_range"], "0:5");
  EXPECT_EQ(part["frames"], 5);

  t.worker().play();
  t.worker().waitIdle();
  t.bench.ui().export_text = (t.dir / "gui").string();
  t.bench.files().exportMap();
  t.worker().waitIdle();
  ASSERT_TRUE(t.worker().status().error.empty()) << t.worker().status().error;
  const test::RunResult r = test::runVdmap("map '" + (t.dir / "seq").string() + "' --keyframe-every 3 --out '" +
                                           (t.dir / "cli").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_TRUE(std::filesystem::exists(t.dir / "gui" / "trajectory.txt"));
  EXPECT_EQ(test::readFile(t.dir / "gui" / "trajectory.txt"), test::readFile(t.dir / "cli" / "trajectory.txt"));
  const auto gui = nlohmann::json::parse(test::readFile(t.dir / "gui" / "stats.json"));
  const auto cli = nlohmann::json::parse(test::readFile(t.dir / "cli" / "stats.json"));
  for (const char* key : {"vdmap_version", "sequence", "frame_range", "camera", "camera_source", "camera_intrinsics",
                          "poses", "refine", "parameters", "frames", "frames_listed", "frames_in_range",
                          "frames_dropped_no_rgb", "frames_dropped_no_pose"}) {
    ASSERT_TRUE(gui.contains(key)) << key;
    EXPECT_EQ(gui[key], cli[key]) << key;
  }
}

// A session mapped to its sequence's end, whose folder is still there, says so (the Sequence
// panel shows it) rather than that it has no sequence; one that continues has nothing to say.
TEST(GuiWorkbench, ASessionMappedToTheEndSaysSo) {
  TinyBench t;
  t.worker().seek(4);
  t.worker().waitIdle();
  t.bench.ui().session_text = (t.dir / "half.vdmap").string();
  t.bench.files().saveSession();
  t.worker().waitIdle();
  t.worker().play();
  t.worker().waitIdle();
  t.bench.ui().session_text = (t.dir / "all.vdmap").string();
  t.bench.files().saveSession();
  t.worker().waitIdle();
  ASSERT_TRUE(t.worker().status().error.empty()) << t.worker().status().error;

  Workbench reopened{Settings{}};
  ASSERT_TRUE(reopened.files().openPath((t.dir / "all.vdmap").string())) << reopened.ui().status.text;
  EXPECT_TRUE(reopened.savedSession());
  const std::string seq = fs::absolute(t.dir / "seq").lexically_normal().string();
  EXPECT_EQ(reopened.files().whyPlayerOff(), "mapped to the end of " + seq + " (10 of 10 frames): nothing to continue");
  ASSERT_TRUE(reopened.files().openPath((t.dir / "half.vdmap").string())) << reopened.ui().status.text;
  EXPECT_FALSE(reopened.savedSession());
  EXPECT_EQ(reopened.files().whyPlayerOff(), "");
}

// An opened session whose sequence is still there continues in the player from the
// session's state, to the same map as one run over all frames; seeking back goes no further
// back than the session.
TEST(GuiWorkbench, AnOpenedSessionContinuesInThePlayer) {
  TinyBench t;
  t.worker().seek(4);  // frames 0..4
  t.worker().waitIdle();
  t.bench.ui().session_text = (t.dir / "half.vdmap").string();
  t.bench.files().saveSession();
  t.worker().waitIdle();
  ASSERT_TRUE(t.worker().status().error.empty()) << t.worker().status().error;
  t.worker().play();
  t.worker().waitIdle();

  Workbench reopened{Settings{}};
  ASSERT_TRUE(reopened.files().openPath((t.dir / "half.vdmap").string())) << reopened.ui().status.text;
  EXPECT_EQ(reopened.ui().status.kind, StatusLine::Kind::kSuccess) << reopened.ui().status.text;
  MappingWorker& s = *reopened.worker();
  ASSERT_NE(s.sequence(), nullptr);
  EXPECT_EQ(s.mapping()->frames_mapped, 5);
  EXPECT_EQ(s.mapping()->frames_total, 10);
  EXPECT_EQ(s.mapping()->trajectory.size(), 5u);  // every saved frame's pose, not the keyframes'
  s.play();
  s.waitIdle();
  ASSERT_TRUE(s.status().error.empty()) << s.status().error;
  const auto whole = t.worker().mapping(), continued = s.mapping();
  EXPECT_EQ(continued->frames_mapped, 10);
  const std::vector<Transform> whole_path = whole->trajectoryWorld(), continued_path = continued->trajectoryWorld();
  ASSERT_EQ(continued_path.size(), whole_path.size());
  for (std::size_t i = 0; i < whole_path.size(); ++i)
    EXPECT_TRUE(continued_path[i].isApprox(whole_path[i], 1e-9)) << "frame " << i;
  ASSERT_EQ(continued->keyframes.size(), whole->keyframes.size());
  for (std::size_t i = 0; i < whole->keyframes.size(); ++i) {
    EXPECT_EQ(continued->keyframes[i].frame, whole->keyframes[i].frame);
    EXPECT_EQ(continued->keyframes[i].ellipsoids, whole->keyframes[i].ellipsoids);
    EXPECT_EQ(continued->keyframes[i].frames_integrated, whole->keyframes[i].frames_integrated);
  }
  EXPECT_EQ(s.global()->map.sigma_e_prime, t.worker().global()->map.sigma_e_prime);
  s.seek(1);  // before the session's end: back to the session as saved, then mapping on
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 5);
  s.play();
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 10);
  EXPECT_EQ(s.mapping()->keyframes.size(), whole->keyframes.size());
}

TEST(GuiWorkbench, PickingFindsTheNearestProjectedMean) {
  std::vector<Ellipsoid> es(3);
  es[0].mean = {0, 0, 4};    // straight ahead, listed first
  es[1].mean = {0, 0, 2};    // in front of it on the same ray: the nearer one wins
  es[2].mean = {0.5, 0, 2};  // to the right
  render::ViewCamera view;   // identity pose, 640x480, f = 525
  EXPECT_EQ(pickEllipsoid(es, view, view.cx, view.cy), 1);
  EXPECT_EQ(pickEllipsoid(es, view, view.cx + 525.f * 0.25f, view.cy + 2.f), 2);
  EXPECT_EQ(pickEllipsoid(es, view, 10.f, 10.f), -1);
  view.T_C_W = glm::translate(glm::mat4(1.f), glm::vec3(0, 0, -10));  // everything behind
  EXPECT_EQ(pickEllipsoid(es, view, view.cx, view.cy), -1);
}

TEST(GuiWorkbench, EulerAnglesRoundTrip) {
  const glm::vec3 deg(10.f, -20.f, 135.f);
  const glm::vec3 back = rotationToEulerDeg(eulerDegToRotation(deg));
  EXPECT_TRUE(eulerDegToRotation(back).isApprox(eulerDegToRotation(deg), 1e-6));
  // The round trip alone holds for any eulerDegToRotation (even one returning identity); pin
  // the convention: yaw about z turns x into y, roll about x turns y into z.
  EXPECT_TRUE(
      (eulerDegToRotation({0.f, 0.f, 90.f}) * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-6));
  EXPECT_TRUE(
      (eulerDegToRotation({90.f, 0.f, 0.f}) * Eigen::Vector3d::UnitY()).isApprox(Eigen::Vector3d::UnitZ(), 1e-6));
}

TEST(GuiWorkbench, PitchStaysWithin90DegreesAndTheRotationIsKept) {
  for (const float pitch : {100.f, -135.f, 90.f, -90.f, 45.f, 179.f}) {
    const Eigen::Matrix3d R = eulerDegToRotation({30.f, pitch, -60.f});
    const glm::vec3 back = rotationToEulerDeg(R);
    EXPECT_LE(std::abs(back.y), 90.f) << pitch;
    EXPECT_LE(std::abs(back.x), 180.f) << pitch;
    EXPECT_LE(std::abs(back.z), 180.f) << pitch;
    EXPECT_TRUE(eulerDegToRotation(back).isApprox(R, 1e-5)) << pitch;
  }
}

TEST(GuiSession, TheTrajectoryFollowsAKeyframesPoseEdit) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.worker().play();
  t.worker().waitIdle();
  const auto before = t.worker().mapping();
  bench.poses().selectKeyframe(1);
  bench.ui().pose_translation_m.z += 0.2f;
  bench.poses().applyEdit();
  t.worker().waitIdle();
  const auto after = t.worker().mapping();
  ASSERT_EQ(after->trajectory.size(), 10u);
  int moved = 0;
  for (std::size_t i = 0; i < after->trajectory.size(); ++i) {
    const Eigen::Vector3d d = after->framePose(i).translation() - before->framePose(i).translation();
    if (after->trajectory[i].keyframe == 1) {
      EXPECT_NEAR(d.z(), 0.2, 1e-6) << i;
      ++moved;
    } else {
      EXPECT_NEAR(d.norm(), 0.0, 1e-9) << i;
    }
  }
  EXPECT_EQ(moved, 3);  // frames 3, 4, 5 went into keyframe 1
  // Before any edit the trajectory is the sequence's ground truth.
  EXPECT_NEAR(before->framePose(4).translation().x(), 0.04, 1e-9);
}

TEST(GuiWorkbench, APendingParameterIsNotUsedUntilApplied) {
  TinyBench t;
  Workbench& bench = t.bench;
  const Parameter& cell = *findParameter("cell_size");
  ASSERT_TRUE(bench.parameters().edit(cell, 8));
  EXPECT_TRUE(bench.parameters().pending(cell));
  EXPECT_EQ(bench.parameters().inUse(cell), 5);
  t.worker().play();
  t.worker().waitIdle();
  EXPECT_EQ(t.worker().mapping()->mapper.local_map.cell_size_px, 5) << "a pending value was used";
  EXPECT_TRUE(bench.parameters().pending(cell));
  EXPECT_EQ(bench.ui().settings.mapper.local_map.cell_size_px, 5) << "not applied: not the user's setting yet";
  const std::size_t cells_at_5 = t.worker().mapping()->keyframes[0].ellipsoids;
  bench.parameters().rerun();
  t.worker().waitIdle();
  EXPECT_EQ(t.worker().mapping()->mapper.local_map.cell_size_px, 8);
  EXPECT_LT(t.worker().mapping()->keyframes[0].ellipsoids, cells_at_5);
  EXPECT_FALSE(bench.parameters().pending(cell));
  EXPECT_EQ(bench.ui().settings.mapper.local_map.cell_size_px, 8);
  // A live threshold applies at once; it is pending only until its map arrives.
  const Parameter& min_points = *findParameter("min_points");
  ASSERT_TRUE(bench.parameters().edit(min_points, 60));
  t.worker().waitIdle();
  EXPECT_EQ(t.worker().global()->params.filter.min_points, 60);
  EXPECT_FALSE(bench.parameters().pending(min_points));
  // A refused value changes nothing.
  EXPECT_FALSE(bench.parameters().edit(min_points, -1));
  EXPECT_EQ(bench.ui().params.global.filter.min_points, 60);
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kError);
  EXPECT_NE(bench.ui().status.text.find("min_points must be >= 0"), std::string::npos) << bench.ui().status.text;
}

TEST(GuiWorkbench, ASavedSessionShowsItsOwnParametersAndLeavesTheUsersSettingsAlone) {
  TinyBench t;
  ASSERT_TRUE(t.bench.parameters().edit(*findParameter("merge_distance"), 0.4));
  t.worker().play();
  t.worker().waitIdle();
  t.bench.ui().session_text = (t.dir / "s.vdmap").string();
  t.bench.files().saveSession();
  t.worker().waitIdle();
  Settings user;
  user.thresholds.filter.min_points = 9;
  Workbench other{user};
  ASSERT_TRUE(other.files().openPath((t.dir / "s.vdmap").string())) << other.ui().status.text;
  EXPECT_TRUE(other.savedSession());
  EXPECT_DOUBLE_EQ(other.ui().params.global.merge_distance_m, 0.4);  // the session's, not the user's 0.25
  EXPECT_EQ(other.ui().params.global.filter.min_points, 6);
  EXPECT_EQ(other.ui().params.mapper.keyframe_every, 3);
  EXPECT_TRUE(other.parameters().edit(*findParameter("tau_group"), 0.5));
  other.worker()->waitIdle();
  EXPECT_DOUBLE_EQ(other.worker()->global()->params.tau_group, 0.5);
  EXPECT_DOUBLE_EQ(other.ui().settings.thresholds.tau_group, Settings{}.thresholds.tau_group)
      << "the user's settings changed";
  EXPECT_EQ(other.ui().settings.thresholds.filter.min_points, 9);
  EXPECT_FALSE(other.parameters().pending(*findParameter("cell_size")));
  other.parameters().rerun();  // nothing to re-map
  other.worker()->waitIdle();
  EXPECT_EQ(other.worker()->mapping()->frames_mapped, 10);
  // Paths in messages are absolute.
  EXPECT_NE(t.worker().status().message.find((t.dir / "s.vdmap").string()), std::string::npos);
  EXPECT_EQ(other.ui().status.text, "opened " + (t.dir / "s.vdmap").string());
}

TEST(GuiSettings, OnlyWhatTheUserChangedIsSavedAndACorruptFileIsKept) {
  test::TempDir dir;
  const fs::path file = dir / "settings.json";
  Settings saved;
  saved.thresholds.filter.min_points = 9;
  saveSettings(file, saved);
  std::string warning;
  Settings start = loadSettings(file, &warning);
  applySetting(start, "merge_distance=0.5");  // --set: this run only
  Settings end = start;
  end.color = render::ColorMode::kCount;  // changed in the window
  end.window_width = 1000;
  saveChangedSettings(file, start, end);
  const Settings reread = loadSettings(file, &warning);
  EXPECT_TRUE(warning.empty()) << warning;
  EXPECT_DOUBLE_EQ(reread.thresholds.merge_distance_m, Settings{}.thresholds.merge_distance_m) << "--set was saved";
  EXPECT_EQ(reread.thresholds.filter.min_points, 9);
  EXPECT_EQ(reread.color, render::ColorMode::kCount);
  EXPECT_EQ(reread.window_width, 1000);

  test::writeText(file, "{not json");
  EXPECT_THROW(saveChangedSettings(file, start, end), std::runtime_error);
  EXPECT_EQ(test::readFile(file), "{not json") << "a corrupt settings file was replaced";
  fs::remove(file);
  saveChangedSettings(file, start, start);
  EXPECT_FALSE(fs::exists(file)) << "nothing changed, nothing written";
}

TEST(GuiWorkbench, KeysDriveThePlayerAndTheViewFollowsTheMapUntilMoved) {
  TinyBench t;
  Workbench& bench = t.bench;
  MappingWorker& s = t.worker();
  bench.key(KeyAction::kStepForward);
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 1);
  bench.key(KeyAction::kNextKeyframe);
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 4);
  bench.key(KeyAction::kStepBack);
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 3);
  bench.key(KeyAction::kHelp);
  EXPECT_TRUE(bench.ui().show_help);
  bench.key(KeyAction::kEscape);
  EXPECT_FALSE(bench.ui().show_help);
  bench.key(KeyAction::kPlayPause);
  s.waitIdle();
  EXPECT_EQ(s.mapping()->frames_mapped, 10);

  bench.sync();  // frames the map
  EXPECT_TRUE(bench.ui().follow_map);
  const render::OrbitCamera framed = bench.ui().camera;
  bench.view().orbit(0.3f, 0.f);
  EXPECT_FALSE(bench.ui().follow_map);
  const render::OrbitCamera moved = bench.ui().camera;
  ASSERT_TRUE(bench.parameters().edit(*findParameter("min_points"), 3));  // a new map
  s.waitIdle();
  bench.sync();
  EXPECT_EQ(bench.ui().camera.yaw, moved.yaw) << "the view moved after the user moved it";
  EXPECT_EQ(bench.ui().camera.distance_m, moved.distance_m);
  bench.key(KeyAction::kFrameMap);  // F: the same direction, framed, following again
  EXPECT_TRUE(bench.ui().follow_map);
  EXPECT_EQ(bench.ui().camera.yaw, moved.yaw);
  bench.key(KeyAction::kResetView);  // R: the default direction
  EXPECT_EQ(bench.ui().camera.yaw, framed.yaw);
}

// The player as the window drives it, through the Workbench alone: play, pause, the fps limit
// and the scrubber's seek, with the snapshots the panels read.
TEST(GuiWorkbench, PlayPauseFpsAndSeekGoThroughTheWorkbench) {
  Workbench closed{Settings{}};
  EXPECT_FALSE(closed.isOpen());
  EXPECT_EQ(closed.sessionSerial(), 0);
  closed.player().play();
  closed.player().seek(3);
  closed.player().setFps(7.f);  // nothing to play: only the setting changes
  EXPECT_FALSE(closed.player().status().playing);
  EXPECT_EQ(closed.player().status().target, 0);
  EXPECT_EQ(closed.mapping(), nullptr);
  EXPECT_EQ(closed.global(), nullptr);
  EXPECT_EQ(closed.selection(), nullptr);
  EXPECT_EQ(closed.sequence(), nullptr);
  EXPECT_FLOAT_EQ(closed.ui().settings.play_fps, 7.f);

  TinyBench t;
  Workbench& bench = t.bench;
  ASSERT_TRUE(bench.isOpen());
  EXPECT_EQ(bench.sessionSerial(), 1);
  ASSERT_NE(bench.sequence(), nullptr);
  EXPECT_EQ(bench.sequence()->folder(), t.dir / "seq");
  bench.player().setFps(12.f);
  EXPECT_FLOAT_EQ(bench.player().status().fps, 12.f) << "the fps limit did not reach the player";
  EXPECT_FLOAT_EQ(bench.ui().settings.play_fps, 12.f);
  bench.player().setFps(0.f);
  EXPECT_FLOAT_EQ(bench.player().status().fps, 0.f);
  bench.player().play();
  EXPECT_EQ(bench.player().status().target, 10);
  t.worker().waitIdle();
  EXPECT_EQ(bench.mapping()->frames_mapped, 10);
  ASSERT_NE(bench.global(), nullptr);
  EXPECT_EQ(bench.global()->frames_mapped, 10);
  EXPECT_FALSE(bench.player().status().playing) << "the player stops at the end";

  bench.player().seek(4);  // backwards: re-mapped from the first frame up to frame 4
  EXPECT_EQ(bench.player().status().target, 5);
  t.worker().waitIdle();
  EXPECT_EQ(bench.mapping()->frames_mapped, 5);
  EXPECT_EQ(bench.global()->frames_mapped, 5);
  bench.player().seek(7);  // forwards: maps up to frame 7
  t.worker().waitIdle();
  EXPECT_EQ(bench.mapping()->frames_mapped, 8);
  EXPECT_TRUE(bench.player().status().error.empty()) << bench.player().status().error;

  // The limit is a setting: a sequence opened later plays at it. Slow enough that play, then
  // pause, finds the player still playing.
  bench.player().setFps(2.f);
  ASSERT_TRUE(bench.files().open({.folder = (t.dir / "seq").string()})) << bench.ui().status.text;
  EXPECT_EQ(bench.sessionSerial(), 2);
  EXPECT_FLOAT_EQ(bench.player().status().fps, 2.f);
  bench.player().play();
  EXPECT_TRUE(bench.player().status().playing);
  EXPECT_EQ(bench.player().status().target, 10);
  bench.player().pause();
  EXPECT_FALSE(bench.player().status().playing);
  t.worker().waitIdle();
  EXPECT_LT(bench.mapping()->frames_mapped, 10) << "paused, yet mapped to the end";
  bench.parameters().resetToDefaults();
  EXPECT_FLOAT_EQ(bench.player().status().fps, Settings{}.play_fps);
}

// The scripted run's --keyframe selects a keyframe before it is mapped; the inspector shows it once
// it is (selectKeyframe would drop an id not mapped yet).
TEST(GuiWorkbench, APreselectedKeyframeIsShownOnceItIsMapped) {
  TinyBench t;
  Workbench& bench = t.bench;
  bench.poses().selectKeyframe(2);
  EXPECT_EQ(bench.ui().selected_keyframe, -1) << "not mapped yet: no selection";
  bench.poses().preselectKeyframe(2);
  EXPECT_EQ(bench.ui().selected_keyframe, 2);
  bench.player().play();
  t.worker().waitIdle();
  const auto selection = bench.selection();
  ASSERT_NE(selection, nullptr);
  EXPECT_EQ(selection->keyframe, 2);
  EXPECT_FALSE(selection->local.empty());
}

// The window wakes its event loop with the on-change hook: it is called for the open session's
// news and handed to every session opened later.
TEST(GuiWorkbench, TheOnChangeHookFollowsEverySessionOpened) {
  std::atomic<int> calls{0};  // outlives the worker, which may call the hook until it stops
  TinyBench t;
  Workbench& bench = t.bench;
  bench.setOnChange([&calls] { ++calls; });
  bench.key(KeyAction::kStepForward);
  t.worker().waitIdle();
  EXPECT_GT(calls.load(), 0);
  ASSERT_TRUE(bench.files().open({.folder = (t.dir / "seq").string()})) << bench.ui().status.text;
  t.worker().waitIdle();
  calls = 0;
  bench.key(KeyAction::kStepForward);
  t.worker().waitIdle();
  EXPECT_GT(calls.load(), 0) << "the new session does not call the hook";
  bench.setOnChange(nullptr);
  t.worker().waitIdle();
  calls = 0;
  bench.key(KeyAction::kStepForward);
  t.worker().waitIdle();
  EXPECT_EQ(calls.load(), 0) << "the hook was removed";
}

// The key table of docs/workbench.md is the help overlay's list, row for row, so neither drifts.
TEST(GuiWorkbench, TheWorkbenchDocsListEveryKeyOfTheHelpOverlay) {
  const std::string readme = test::readFile(fs::path(VDMAP_SOURCE_DIR) / "docs" / "workbench.md");
  std::string table = "| key | action |\n|---|---|\n";
  for (const auto& [keys, what] : keyHelp()) table += "| " + std::string(keys) + " | " + what + " |\n";
  EXPECT_NE(readme.find(table), std::string::npos) << "docs/workbench.md should hold this table:\n" << table;
}

TEST(GuiWorkbench, APickIsMarkedAndClearedWhenTheMapChanges) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.worker().play();
  t.worker().waitIdle();
  bench.sync();
  const auto global = t.worker().global();
  const ViewportView v = bench.view().viewport(640, 480);
  const Eigen::Vector3d& m = global->map.ellipsoids[global->map.ellipsoids.size() / 2].mean;
  const glm::vec4 p = v.camera.T_C_W * glm::vec4(m.x(), m.y(), m.z(), 1.f);
  bench.view().pick(v.camera.fx * p.x / p.z + v.camera.cx, v.camera.fy * p.y / p.z + v.camera.cy, 640, 480);
  ASSERT_TRUE(bench.ui().picked);
  EXPECT_EQ(bench.ui().selected_keyframe, bench.ui().picked->keyframe);
  bench.sync();
  EXPECT_TRUE(bench.ui().picked) << "the same map: the pick stays";
  ASSERT_TRUE(bench.parameters().edit(*findParameter("merge_distance"), 0.1));
  t.worker().waitIdle();
  bench.sync();
  EXPECT_FALSE(bench.ui().picked) << "a new map: the old pick may not exist in it";
}

TEST(GuiWorkbench, UndoPutsBackThePoseFromBeforeTheEdit) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.worker().play();
  t.worker().waitIdle();
  bench.poses().selectKeyframe(2);
  const glm::vec3 start = bench.ui().pose_translation_m;
  EXPECT_FALSE(bench.poses().canUndoEdit());
  bench.poses().beginEdit();  // a drag starts
  for (int i = 0; i < 5; ++i) {
    bench.ui().pose_translation_m.y += 0.05f;
    bench.poses().applyEdit();
  }
  t.worker().waitIdle();
  EXPECT_NEAR(t.worker().mapping()->keyframes[2].T_W_K.translation().y(), start.y + 0.25, 1e-6);
  EXPECT_TRUE(bench.poses().undoEdit());
  t.worker().waitIdle();
  EXPECT_NEAR(t.worker().mapping()->keyframes[2].T_W_K.translation().y(), start.y, 1e-6);
  EXPECT_NEAR(bench.ui().pose_translation_m.y, start.y, 1e-6);
  EXPECT_FALSE(bench.poses().undoEdit());
}

TEST(GuiView, ViewFromKeyframeKeepsTheImagesAspectAndIntrinsics) {
  EXPECT_EQ(render::letterbox(1000, 500, 640, 480), (render::PixelRect{166, 0, 667, 500}));
  EXPECT_EQ(render::letterbox(600, 900, 640, 480), (render::PixelRect{0, 225, 600, 450}));
  TinyBench t;
  t.worker().play();
  t.worker().waitIdle();
  t.bench.ui().view_from_keyframe = 1;
  const ViewportView v = t.bench.view().viewport(1000, 500);
  const PinholeCamera& c = t.worker().mapping()->camera;
  EXPECT_EQ(v.image.height, 500);
  EXPECT_NEAR(static_cast<double>(v.image.width) / v.image.height, static_cast<double>(c.width) / c.height, 0.01);
  // The image scaled alike along both axes (to the rounding of the letterbox to whole pixels).
  EXPECT_NEAR(v.camera.fx / v.camera.fy, c.fx / c.fy, 2e-3) << "stretched";
  EXPECT_NEAR(v.camera.fy, c.fy * 500.0 / c.height, 1e-3);
}

// A threshold change is a new map of the same frames: a view that follows the map keeps its
// camera (eye, target, up) and its estimated up axis, so before and after compare.
TEST(GuiView, AThresholdChangeLeavesTheCameraWhereItIs) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.mapAndFrame();
  UiState& ui = bench.ui();
  ASSERT_TRUE(ui.follow_map);
  const render::OrbitCamera before = ui.camera;
  const glm::vec3 up_before = bench.view().heightFrame().up;
  const auto map_before = t.worker().global();
  // Cells of a 5 px grid over 3 frames of a plane hold ~75 points: 60 drops most of the map.
  ASSERT_TRUE(bench.parameters().edit(*findParameter("min_points"), 60));
  t.worker().waitIdle();
  bench.sync();
  const auto map_after = t.worker().global();
  ASSERT_GT(map_after->generation, map_before->generation);
  ASSERT_LT(map_after->map.ellipsoids.size(), map_before->map.ellipsoids.size()) << "the map must change";
  EXPECT_EQ(ui.camera.eye(), before.eye());
  EXPECT_EQ(ui.camera.target, before.target);
  EXPECT_EQ(ui.camera.up, before.up);
  EXPECT_EQ(bench.view().heightFrame().up, up_before);
  EXPECT_TRUE(ui.follow_map);
}

// ViewController::spec describes what is shown (global with its camera, keyframe:K at the letterbox's size,
// container:K at 2W x 2H) and applySpec shows it again: the camera, the view options and the
// selection come back as they were.
TEST(GuiView, ViewSpecRoundTripsThroughApplyViewSpec) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.mapAndFrame();
  UiState& ui = bench.ui();
  bench.view().orbit(0.4f, -0.1f);
  bench.view().zoom(2.f);
  bench.view().pan(30.f, -12.f);
  ui.settings.color = render::ColorMode::kUncertainty;
  ui.settings.ellipsoid_sigma = 1.5f;
  ui.settings.show_graph = false;
  ui.settings.show_mesh = true;
  ui.settings.mesh_style = render::MeshStyle::kWireframe;
  ui.settings.up_axis = render::UpAxis::kPlusY;
  bench.poses().selectKeyframe(1);
  const render::OrbitCamera camera = ui.camera;
  const render::ViewSpec global = bench.view().spec();
  EXPECT_EQ(global.kind, render::ViewKind::kGlobal);
  EXPECT_EQ(global.width, 900);
  EXPECT_EQ(global.height, 500);
  ASSERT_TRUE(global.look_at.has_value());
  EXPECT_EQ(global.color, render::ColorMode::kUncertainty);
  EXPECT_FALSE(global.layers.graph);
  EXPECT_TRUE(global.layers.mesh);
  EXPECT_EQ(global.mesh_style, render::MeshStyle::kWireframe);
  EXPECT_EQ(global.selected_keyframe, 1);

  // Elsewhere, with other options: applying the spec brings the view back.
  const Settings defaults;
  ui.settings.color = defaults.color;
  ui.settings.ellipsoid_sigma = defaults.ellipsoid_sigma;
  ui.settings.show_graph = defaults.show_graph;
  ui.settings.show_mesh = defaults.show_mesh;
  ui.settings.mesh_style = defaults.mesh_style;
  ui.settings.up_axis = defaults.up_axis;
  bench.key(KeyAction::kResetView);
  bench.poses().selectKeyframe(-1);
  ASSERT_NE(bench.view().spec(), global);
  ASSERT_TRUE(bench.view().applySpec(global));
  EXPECT_FALSE(ui.follow_map);
  const glm::vec3 eye = ui.camera.eye(), eye0 = camera.eye();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(eye[i], eye0[i], 1e-4f) << i;
    EXPECT_NEAR(ui.camera.target[i], camera.target[i], 1e-5f) << i;
  }
  render::ViewSpec again = bench.view().spec();
  ASSERT_TRUE(again.look_at.has_value());
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(again.look_at->eye[i], global.look_at->eye[i], 1e-4f);
  again.look_at = global.look_at;
  EXPECT_EQ(again, global);

  // keyframe:1 at the letterbox of the 900 x 500 viewport.
  bench.key(KeyAction::kViewFromKeyframe);
  const render::ViewSpec keyframe = bench.view().spec();
  const PinholeCamera& c = t.worker().mapping()->camera;
  const render::PixelRect box = render::letterbox(900, 500, c.width, c.height);
  EXPECT_EQ(keyframe.kind, render::ViewKind::kKeyframe);
  EXPECT_EQ(keyframe.keyframe, 1);
  EXPECT_EQ(keyframe.width, box.width);
  EXPECT_EQ(keyframe.height, box.height);
  EXPECT_FALSE(keyframe.look_at.has_value());
  // container:1, 2W x 2H, while the container window is open.
  bench.key(KeyAction::kContainer);
  const render::ViewSpec container = bench.view().spec();
  EXPECT_EQ(container.kind, render::ViewKind::kContainer);
  EXPECT_EQ(container.keyframe, 1);
  EXPECT_EQ(container.width, 2 * c.width);
  EXPECT_EQ(container.height, 2 * c.height);

  bench.key(KeyAction::kEscape);
  ASSERT_TRUE(bench.view().applySpec(keyframe));
  EXPECT_EQ(ui.view_from_keyframe, 1);
  EXPECT_EQ(bench.view().spec(), keyframe);
  ASSERT_TRUE(bench.view().applySpec(container));
  EXPECT_TRUE(ui.show_container);
  EXPECT_EQ(bench.view().spec(), container);
  // A keyframe this session lacks: the global view, and an error saying so.
  render::ViewSpec missing = keyframe;
  missing.keyframe = 99;
  EXPECT_FALSE(bench.view().applySpec(missing));
  EXPECT_EQ(bench.view().spec().kind, render::ViewKind::kGlobal);
  EXPECT_NE(ui.status.text.find("99"), std::string::npos) << ui.status.text;
}

// S writes the view shown as a view file (into the View section's file field) that reads back
// as the same view, and the status line names the file and the render command.
TEST(GuiView, SKeySavesTheViewFile) {
  TinyBench t;
  Workbench& bench = t.bench;
  t.worker().play();
  t.worker().waitIdle();
  bench.sync();
  bench.view().orbit(0.2f, 0.1f);
  const fs::path file = t.dir / "views" / "v.json";
  fs::create_directories(file.parent_path());
  bench.ui().view_file_text = file.string();
  bench.key(KeyAction::kSaveView);
  ASSERT_TRUE(fs::exists(file)) << bench.ui().status.text;
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kSuccess);
  EXPECT_NE(bench.ui().status.text.find(file.string()), std::string::npos) << bench.ui().status.text;
  EXPECT_NE(bench.ui().status.text.find("vdmap render " + (t.dir / "seq").string() +
                                        " --poses gt --set keyframe_every=3 --view-file"),
            std::string::npos)
      << bench.ui().status.text;
  GlobalMapParams thresholds;
  thresholds.merge_distance_m = -1;
  const render::ViewSpec read = readViewFile(file, &thresholds);
  const render::ViewSpec shown = bench.view().spec();
  ASSERT_TRUE(read.look_at && shown.look_at);
  for (int i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(read.look_at->eye[i], shown.look_at->eye[i]);
  EXPECT_EQ(read, shown);
  EXPECT_EQ(thresholds.merge_distance_m, bench.ui().params.global.merge_distance_m);
  // Nothing written where no file can be: an error on the status line.
  bench.ui().view_file_text = (t.dir / "no" / "such" / "v.json").string();
  bench.key(KeyAction::kSaveView);
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kError);
}

TEST(GuiView, FramingFitsTheBoxInNarrowAndWideViewports) {
  const glm::vec3 lo(-2.f, -1.f, 0.f), hi(3.f, 1.5f, 2.f);
  for (const auto& [w, h] : {std::pair{300, 900}, std::pair{1600, 400}, std::pair{800, 800}}) {
    const render::OrbitCamera cam =
        render::OrbitCamera::framing(lo, hi, {0.f, 0.f, 1.f}, static_cast<float>(w) / static_cast<float>(h));
    const render::ViewCamera v = cam.view(w, h);
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 p((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
      const glm::vec4 q = v.T_C_W * glm::vec4(p, 1.f);
      const float u = v.fx * q.x / q.z + v.cx, y = v.fy * q.y / q.z + v.cy;
      EXPECT_TRUE(u >= 0 && u <= w && y >= 0 && y <= h) << w << "x" << h << " corner " << c << ": " << u << ", " << y;
    }
  }
}

// The floor, found without the workbench's estimate: planes through the ellipsoid means (3 cm;
// RANSAC, fixed seed) that every camera is at least 0.3 m above, with their normal within 45
// degrees of the cameras' mean image-up; of those holding 3% of the map or more, the lowest.
struct Floor {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero(), centroid = Eigen::Vector3d::Zero();
  std::size_t inliers = 0;
};
Floor findFloor(const std::vector<Ellipsoid>& map, const std::vector<Transform>& cameras) {
  Eigen::Vector3d prior = Eigen::Vector3d::Zero();
  for (const Transform& T : cameras) prior -= T.linear().col(1);
  prior.normalize();
  const auto planeThrough = [&](const Eigen::Vector3d& n, double offset) {
    Floor f;
    f.normal = n;
    for (const Ellipsoid& e : map)
      if (std::abs(n.dot(e.mean) - offset) < 0.03) {
        f.centroid += e.mean;
        ++f.inliers;
      }
    if (f.inliers > 0) f.centroid /= static_cast<double>(f.inliers);
    return f;
  };
  std::vector<Floor> candidates;
  std::mt19937 rng(7);
  for (int it = 0; it < 2000; ++it) {
    const Eigen::Vector3d& a = map[rng() % map.size()].mean;
    Eigen::Vector3d n = (map[rng() % map.size()].mean - a).cross(map[rng() % map.size()].mean - a);
    if (n.norm() < 1e-12) continue;
    n.normalize();
    if (n.dot(prior) < 0) n = -n;
    if (n.dot(prior) < std::cos(M_PI / 4)) continue;
    bool below_cameras = true;
    for (const Transform& T : cameras) below_cameras &= n.dot(T.translation() - a) > 0.3;
    if (!below_cameras) continue;
    const Floor f = planeThrough(n, n.dot(a));
    if (f.inliers * 100 >= 3 * map.size()) candidates.push_back(f);
  }
  if (candidates.empty()) return {};
  // The lowest planes (within 0.3 m of the lowest), and of those the largest: a plane tilted
  // through the floor's edge is low too, but holds less of it.
  double lowest = INFINITY;
  for (const Floor& f : candidates) lowest = std::min(lowest, prior.dot(f.centroid));
  Floor best;
  for (const Floor& f : candidates)
    if (prior.dot(f.centroid) < lowest + 0.3 && f.inliers > best.inliers) best = f;
  return best;
}

// Opens a real sequence, maps it, resets the view as the workbench does, and checks on the map
// that the floor is at the bottom of the 3-D view with its normal pointing up on screen, and
// that the cameras are in view.
void expectFloorAtTheBottom(const fs::path& folder, const std::string& frames) {
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.files().open({folder.string(), "", frames, ""})) << bench.ui().status.text;
  bench.worker()->play();
  bench.worker()->waitIdle();
  constexpr int kWidth = 602, kHeight = 685;  // the 3-D viewport of a 1280x720 window
  bench.ui().view_width = kWidth;
  bench.ui().view_height = kHeight;
  bench.sync();  // the first map: the default view about the estimated up axis
  const auto global = bench.worker()->global();
  const std::vector<Transform> cameras = bench.worker()->mapping()->trajectoryWorld();
  const Floor floor = findFloor(global->map.ellipsoids, cameras);
  ASSERT_GT(floor.inliers, 0u) << "no floor found";
  const glm::vec3 up = bench.view().upVector();
  const double angle_deg =
      std::acos(std::clamp(floor.normal.dot(Eigen::Vector3d(up.x, up.y, up.z)), -1.0, 1.0)) * 180 / M_PI;
  std::printf("%s: up (%.3f %.3f %.3f), floor normal (%.3f %.3f %.3f), %.1f deg apart; floor %zu of %zu ellipsoids\n",
              folder.filename().c_str(), up.x, up.y, up.z, floor.normal.x(), floor.normal.y(), floor.normal.z(),
              angle_deg, floor.inliers, global->map.ellipsoids.size());
  EXPECT_LT(angle_deg, 5.0);
  const render::ViewCamera v = bench.view().viewport(kWidth, kHeight).camera;
  const auto project = [&](const Eigen::Vector3d& p) {
    const glm::vec4 q = v.T_C_W * glm::vec4(p.x(), p.y(), p.z(), 1.f);
    return Eigen::Vector2d(v.fx * q.x / q.z + v.cx, v.fy * q.y / q.z + v.cy);
  };
  // The floor normal points up on screen (image v decreases along it).
  const Eigen::Vector2d d = project(floor.centroid + 0.3 * floor.normal) - project(floor.centroid);
  EXPECT_LT(d.y(), -2.0 * std::abs(d.x())) << "floor normal on screen: " << d.transpose();
  // Every keyframe's frustum and every camera of the trajectory lie in the view whole: they are few
  // beside the map's ellipsoids and off its surfaces, and framing them with the map's trimmed
  // outliers cut them at the viewport's edge.
  const auto mapping = bench.worker()->mapping();
  render::ColoredLines frustums;
  for (const KeyframeInfo& k : mapping->keyframes)
    render::addFrustum(frustums, mapping->camera, k.T_W_K, render::kKeyframeFrustumDepthM, {});
  for (const Transform& T : cameras)
    frustums.positions.emplace_back(T.translation().x(), T.translation().y(), T.translation().z());
  int outside = 0;
  for (const glm::vec3& p : frustums.positions) {
    const glm::vec4 q = v.T_C_W * glm::vec4(p, 1.f);
    const float u = v.fx * q.x / q.z + v.cx, w = v.fy * q.y / q.z + v.cy;
    outside += !(q.z > 0 && u >= 0 && u <= kWidth && w >= 0 && w <= kHeight);
  }
  EXPECT_EQ(outside, 0) << "camera and frustum points out of view, of " << frustums.positions.size();
  // The floor lies below the middle of the map on screen.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Ellipsoid& e : global->map.ellipsoids) centre += e.mean;
  centre /= static_cast<double>(global->map.ellipsoids.size());
  EXPECT_GT(project(floor.centroid).y(), project(centre).y());
}

TEST(GuiRealData, SevenScenesFloorIsAtTheBottomOfTheDefaultView) {
  VDMAP_REQUIRE_SHARED_DATA(dir, "7scenes-redkitchen");
  expectFloorAtTheBottom(dir, "0:100");
}

TEST(GuiRealData, ReplicaRenderFloorIsAtTheBottomOfTheDefaultView) {
  VDMAP_REQUIRE_SHARED_DATA(dir, "replica-office0");
  expectFloorAtTheBottom(dir, "");
}

}  // namespace
}  // namespace vdmap::app::gui

namespace vdmap::app::gui {
namespace {

// The turning box room (test_util's writeBoxRoomSequence: 6 degrees a frame on the spot, so frame
// 60 faces where frame 0 did) mapped with tracked poses one frame at a time until tracking
// re-observes a first keyframe from a last one and closes a loop (frame 64 here): the last
// optimisation is then that loop's.
struct TrackedLoopBench {
  test::TempDir dir;
  Workbench bench{Settings{}};
  TrackedLoopBench() {
    test::writeBoxRoomSequence(dir / "seq", kFrames);
    EXPECT_TRUE(bench.files().open({(dir / "seq").string(), "", "", "track"})) << bench.ui().status.text;
    while (worker().mapping()->loops.empty() && worker().mapping()->frames_mapped < kFrames) {
      worker().step();
      worker().waitIdle();
    }
    bench.sync();
  }
  static constexpr int kFrames = 90;
  MappingWorker& worker() { return *bench.worker(); }
};

double largestMove(std::span<const Transform> a, std::span<const Transform> b) {
  double largest = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    largest = std::max(largest, (a[i].translation() - b[i].translation()).norm());
  return largest;
}

TEST(GuiTracking, LoopClosuresAreEventsAndEdgesAndTheMapBeforeTheLastOptimisationCanBeShown) {
  TrackedLoopBench t;
  Workbench& bench = t.bench;
  const auto mapping = t.worker().mapping();
  ASSERT_GE(mapping->loops.size(), 1u) << "the turn past its start closes a loop";
  const LoopEvent& loop = mapping->loops.back();
  EXPECT_EQ(loop.position, mapping->frames_mapped - 1);  // closed by the frame just mapped
  EXPECT_EQ(loop.position, loop.loop.frame_index);       // the sequence starts at depth frame 0
  EXPECT_GT(loop.loop.from, loop.loop.to);
  ASSERT_EQ(mapping->keyframes_before.size(), mapping->keyframes.size());
  // The 3-D view: a loop edge per loop, the ground truth beside the tracked trajectory.
  const render::GraphScene after = bench.view().graphScene(*bench.worker()->mapping());
  ASSERT_EQ(after.loops.size(), mapping->loops.size());
  EXPECT_EQ(after.loops.back().a, mapping->loops.back().loop.from);
  EXPECT_EQ(after.loops.back().b, mapping->loops.back().loop.to);
  EXPECT_EQ(after.groundtruth.size(), after.trajectory.size());
  bench.ui().settings.show_groundtruth = false;
  EXPECT_TRUE(bench.view().graphScene(*bench.worker()->mapping()).groundtruth.empty());

  // Before the last optimisation: other keyframe poses and trajectory, and a global map rebuilt
  // with them; after it again: the same map as before, bit for bit (the mapper's poses were
  // swapped for the build and put back).
  const auto map_after = t.worker().global();
  ASSERT_FALSE(map_after->before_optimisation);
  ASSERT_TRUE(bench.poses().canShowBeforeOptimisation());
  ASSERT_TRUE(bench.poses().showBeforeOptimisation(true));
  t.worker().waitIdle();
  const render::GraphScene before = bench.view().graphScene(*bench.worker()->mapping());
  const double moved = largestMove(before.keyframes, after.keyframes);
  std::printf("loop closed at frame %d (K%d -> K%d, correction %.2f mm); keyframes before it moved up to %.2f mm\n",
              loop.position, loop.loop.from, loop.loop.to, 1e3 * loop.loop.correction_m, 1e3 * moved);
  EXPECT_NEAR(moved, loop.loop.correction_m, 1e-9);  // the correction is the largest keyframe move
  EXPECT_GT(moved, 0.005) << "6 degrees a frame drifts by centimetres over a turn";
  EXPECT_GT(largestMove(before.trajectory, after.trajectory), 1e-5);
  // The inspector's local map is at the pose the global map shows.
  const int from = loop.loop.from;
  const auto selection = selectAndWait(bench, from);
  EXPECT_TRUE(selection->T_W_K.isApprox(before.keyframes[static_cast<std::size_t>(from)], 1e-12));
  EXPECT_FALSE(selection->T_W_K.isApprox(after.keyframes[static_cast<std::size_t>(from)], 1e-6));
  const auto map_before = t.worker().global();
  ASSERT_TRUE(map_before->before_optimisation);
  ASSERT_EQ(map_before->frames_mapped, mapping->frames_mapped);
  double mean_moved = 0;
  const std::size_t n = std::min(map_before->map.ellipsoids.size(), map_after->map.ellipsoids.size());
  for (std::size_t i = 0; i < n; ++i)
    mean_moved = std::max(mean_moved, (map_before->map.ellipsoids[i].mean - map_after->map.ellipsoids[i].mean).norm());
  EXPECT_TRUE(map_before->map.ellipsoids.size() != map_after->map.ellipsoids.size() || mean_moved > 1e-6)
      << "the global map follows the keyframe poses";
  // Exports take the map as it is, whatever is shown.
  bool exported_before = true;
  t.worker().withMapper([&](const Mapper&, const GlobalSnapshot& global) {
    exported_before = global.before_optimisation;
    return std::string();
  });
  t.worker().waitIdle();
  EXPECT_FALSE(exported_before);
  bench.key(KeyAction::kBeforeOptimisation);  // B: after again
  t.worker().waitIdle();
  EXPECT_FALSE(bench.ui().show_before_optimisation);
  const auto map_again = t.worker().global();
  EXPECT_FALSE(map_again->before_optimisation);
  ASSERT_EQ(map_again->map.ellipsoids.size(), map_after->map.ellipsoids.size());
  for (std::size_t i = 0; i < map_again->map.ellipsoids.size(); ++i)
    ASSERT_EQ(map_again->map.ellipsoids[i].mean, map_after->map.ellipsoids[i].mean) << i;

  // Seeking back before the loops forgets them: the toggle goes off and is refused.
  ASSERT_TRUE(bench.poses().showBeforeOptimisation(true));
  t.worker().seek(5);
  t.worker().waitIdle();
  bench.sync();
  EXPECT_TRUE(t.worker().mapping()->loops.empty());
  EXPECT_FALSE(bench.ui().show_before_optimisation);
  EXPECT_FALSE(bench.poses().showBeforeOptimisation(true));
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kWarning);
}

// The tracked trajectory is the mapper's (not the sequence's ground truth); the ground truth is
// there iff the sequence has one and poses are tracked.
TEST(GuiTracking, TheGroundTruthTrajectoryIsShownIffTheSequenceHasOne) {
  test::TempDir dir;
  test::writeBoxRoomSequence(dir / "seq", 8);
  for (const char* poses : {"track", "gt"}) {
    Workbench bench{Settings{}};
    ASSERT_TRUE(bench.files().open({(dir / "seq").string(), "", "", poses})) << bench.ui().status.text;
    bench.worker()->play();
    bench.worker()->waitIdle();
    const auto mapping = bench.worker()->mapping();
    ASSERT_EQ(mapping->frames_mapped, 8);
    std::vector<StampedPose> estimated;
    bench.worker()->withMapper([&](const Mapper& mapper, const GlobalSnapshot&) {
      estimated = mapper.trajectory();
      return std::string();
    });
    bench.worker()->waitIdle();
    const std::vector<Transform> shown = mapping->trajectoryWorld();
    ASSERT_EQ(shown.size(), estimated.size()) << poses;
    for (std::size_t i = 0; i < shown.size(); ++i)
      EXPECT_TRUE(shown[i].isApprox(estimated[i].T_W_C, 1e-12)) << poses << " " << i;
    const bool tracked = std::string(poses) == "track";
    EXPECT_EQ(mapping->hasGroundTruth(), tracked) << poses;
    EXPECT_EQ(mapping->frames_with_groundtruth, 8) << poses;  // the sequence has it, whatever mapped it
    EXPECT_EQ(bench.view().graphScene(*bench.worker()->mapping()).groundtruth.size(), tracked ? shown.size() : 0u)
        << poses;
  }
  fs::remove(dir / "seq" / "groundtruth.txt");  // no ground truth: tracked by default, none shown
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.files().open({.folder = (dir / "seq").string()})) << bench.ui().status.text;
  bench.worker()->play();
  bench.worker()->waitIdle();
  EXPECT_EQ(bench.worker()->mapping()->mapper.poses, PoseSource::kTrack);
  EXPECT_EQ(bench.worker()->mapping()->frames_mapped, 8);
  EXPECT_FALSE(bench.worker()->mapping()->hasGroundTruth());
  EXPECT_EQ(bench.worker()->mapping()->frames_with_groundtruth, 0);
  EXPECT_TRUE(bench.view().graphScene(*bench.worker()->mapping()).groundtruth.empty());
  // No loop closed, but after the last frame the keyframe poses were refined from the local
  // maps (the status says so): B shows the map before that.
  const std::string message = bench.worker()->status().message;
  std::printf("status after the last tracked frame: %s\n", message.c_str());
  EXPECT_EQ(bench.poses().canShowBeforeOptimisation(), message.find("keyframe poses refined") != std::string::npos)
      << message;
  EXPECT_TRUE(bench.poses().canShowBeforeOptimisation());
  EXPECT_TRUE(bench.worker()->status().error.empty()) << bench.worker()->status().error;
}

// The refinement after the last tracked frame is the one setRefinement (vdmap gui --refine) names:
// the keyframe poses end as a Mapper refined that way on the same frames ends them; none leaves
// them as tracked, with nothing to show before.
TEST(GuiTracking, TheKeyframePosesAreRefinedAsTheCommandLineSays) {
  test::TempDir dir;
  test::writeBoxRoomSequence(dir / "seq", 8);
  fs::remove(dir / "seq" / "groundtruth.txt");
  const auto keyframePoses = [](const Mapper& mapper) {
    std::vector<Transform> poses;
    for (const Keyframe& k : mapper.graph().keyframes()) poses.push_back(k.T_W_K);
    return poses;
  };
  MapRefinementParams joint;
  joint.method = MapRefinementMethod::kJoint;
  for (const std::optional<MapRefinementParams>& refine :
       {std::optional(joint), std::optional<MapRefinementParams>()}) {
    const Sequence sequence = openSequence({.folder = (dir / "seq").string()});
    MapperParams params = Settings{}.mapper;
    params.poses = PoseSource::kTrack;
    Mapper reference(sequence.camera(), params);
    for (std::size_t i = 0; i < sequence.size(); ++i) reference.addFrame(sequence.load(i));
    const std::vector<Transform> tracked = keyframePoses(reference);
    ASSERT_GE(tracked.size(), 2u);
    if (refine) reference.refineKeyframePoses(*refine);

    Workbench bench{Settings{}};
    bench.files().setRefinement(refine);
    ASSERT_TRUE(bench.files().open({.folder = (dir / "seq").string()})) << bench.ui().status.text;
    bench.worker()->play();
    bench.worker()->waitIdle();
    const std::string message = bench.worker()->status().message;  // before withMapper's replaces it
    std::vector<Transform> shown;
    bench.worker()->withMapper([&](const Mapper& mapper, const GlobalSnapshot&) {
      shown = keyframePoses(mapper);
      return std::string();
    });
    bench.worker()->waitIdle();
    const std::vector<Transform> expected = keyframePoses(reference);
    ASSERT_EQ(shown.size(), expected.size());
    double moved = 0;
    for (std::size_t k = 0; k < shown.size(); ++k) {
      EXPECT_TRUE(shown[k].isApprox(expected[k], 1e-12)) << k;
      moved = std::max(moved, (shown[k].translation() - tracked[k].translation()).norm());
    }
    std::printf("%s: keyframes moved %.3f mm; status: %s\n", refine ? "joint" : "none", 1e3 * moved, message.c_str());
    EXPECT_EQ(moved > 0, refine.has_value());
    EXPECT_EQ(message.find("refined (joint)") != std::string::npos, refine.has_value()) << message;
    EXPECT_EQ(bench.poses().canShowBeforeOptimisation(), refine.has_value());
  }
}

TEST(GuiTracking, AfterTheRefinementTheBannerNamesIt) {
  Workbench bench{Settings{}};
  MappingSnapshot m;
  LoopEvent loop;
  loop.position = 40;
  loop.loop.correction_m = 0.012;
  m.loops = {loop};
  m.last_optimisation = {LastOptimisation::Kind::kLoop, 0, "", 0, 0};
  EXPECT_EQ(bench.poses().beforeOptimisationBanner(m), "") << "only while B shows the map before it";
  bench.ui().show_before_optimisation = true;
  EXPECT_NE(bench.poses().beforeOptimisationBanner(m).find("loop at frame 40"), std::string::npos)
      << bench.poses().beforeOptimisationBanner(m);
  // After the sequence's last frame the refinement is the last optimisation, not the loop.
  m.last_optimisation = {LastOptimisation::Kind::kRefinement, -1, "joint", 41, 0.0032};
  EXPECT_EQ(bench.poses().beforeOptimisationBanner(m),
            "BEFORE the final refinement (joint, 41 pairs, 3.20 mm; B: after)");
}

// ---- The view tools: pick scroll, drag speed, zoom at the cursor, pivot, framing the paths,
// view files, quick views, screenshots, settings autosave, loop-strip markers.

// The pixel of the 3-D view (640x480) where world point p shows.
glm::vec2 projectInView(const Workbench& bench, const glm::vec3& p) {
  const render::ViewCamera v = bench.view().viewport(640, 480).camera;
  const glm::vec4 q = v.T_C_W * glm::vec4(p, 1.f);
  return {v.fx * q.x / q.z + v.cx, v.fy * q.y / q.z + v.cy};
}

// TinyBench mapped to the end, its view 640x480.
struct MappedTinyBench : TinyBench {
  MappedTinyBench() {
    bench.ui().view_width = 640;
    bench.ui().view_height = 480;
    worker().play();
    worker().waitIdle();
    bench.sync();
  }
};

TEST(GuiViewTools, PickScrollsTheListOnce) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  const auto global = t.worker().global();
  const Eigen::Vector3d& m = global->map.ellipsoids[global->map.ellipsoids.size() / 2].mean;
  const glm::vec2 at = projectInView(bench, {m.x(), m.y(), m.z()});
  bench.view().pick(at.x, at.y, 640, 480);
  ASSERT_TRUE(bench.ui().picked);
  EXPECT_TRUE(bench.poses().takeScrollToSelected()) << "a pick scrolls the keyframe list to its keyframe";
  EXPECT_FALSE(bench.poses().takeScrollToSelected()) << "once: the user may scroll away";
  bench.poses().selectKeyframe(0);  // a click in the list itself does not scroll it
  EXPECT_FALSE(bench.poses().takeScrollToSelected());
}

TEST(GuiViewTools, PoseDragSpeedFollowsTheViewDistance) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  bench.poses().selectKeyframe(0);
  const float near = bench.view().poseDragSpeed();
  bench.view().zoom(-6.f);  // farther away: a pixel spans more
  const float far = bench.view().poseDragSpeed();
  EXPECT_GT(far, 1.5f * near);
  // A pixel of drag spans what a pixel of the view spans at the keyframe's depth.
  const render::ViewCamera v = bench.view().viewport(640, 480).camera;
  const Eigen::Vector3d k = t.worker().mapping()->keyframes[0].T_W_K.translation();
  const float depth = (v.T_C_W * glm::vec4(k.x(), k.y(), k.z(), 1.f)).z;
  EXPECT_NEAR(far, std::clamp(depth / v.fy, 1e-4f, 0.05f), 1e-6f);
  bench.view().zoom(-60.f);
  EXPECT_LE(bench.view().poseDragSpeed(), 0.05f) << "clamped";
}

TEST(GuiViewTools, ZoomAtKeepsThePointUnderTheCursor) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  const glm::vec3 p = bench.view().targetPlanePoint(100.f, 380.f, 640, 480) + glm::vec3(0.05f, -0.02f, 0.03f);
  const glm::vec2 before = projectInView(bench, p);
  const float distance = bench.ui().camera.distance_m;
  bench.view().zoomAt(2.f, p);
  const glm::vec2 after = projectInView(bench, p);
  EXPECT_NEAR(after.x, before.x, 0.5f);
  EXPECT_NEAR(after.y, before.y, 0.5f);
  EXPECT_LT(bench.ui().camera.distance_m, distance);
  EXPECT_FALSE(bench.ui().follow_map);
  // The target's plane point under a pixel projects back to that pixel.
  const glm::vec2 back = projectInView(bench, bench.view().targetPlanePoint(200.f, 100.f, 640, 480));
  EXPECT_NEAR(back.x, 200.f, 0.5f);
  EXPECT_NEAR(back.y, 100.f, 0.5f);
}

TEST(GuiViewTools, PivotHereKeepsTheEye) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  const glm::vec3 eye = bench.ui().camera.eye();
  const glm::vec3 p = bench.view().targetPlanePoint(500.f, 100.f, 640, 480);
  bench.view().pivotAt(p);
  EXPECT_LT(glm::length(bench.ui().camera.eye() - eye), 1e-4f);
  EXPECT_LT(glm::length(bench.ui().camera.target - p), 1e-4f);
  const glm::vec2 centre = projectInView(bench, p);
  EXPECT_NEAR(centre.x, 319.5f, 0.5f) << "the pivot is in the middle of the view";
  EXPECT_NEAR(centre.y, 239.5f, 0.5f);
}

TEST(GuiViewTools, FrameTrajectoriesFramesOnlyThePaths) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  bench.key(KeyAction::kFrameMap);
  const float map_distance = bench.ui().camera.distance_m;
  bench.key(KeyAction::kFrameTrajectories);
  EXPECT_FALSE(bench.ui().follow_map) << "a growing map does not take the view back";
  // Every camera of the path inside the view; the path (10 frames on a short line) is framed far
  // closer than the whole map.
  for (const Transform& T : t.worker().mapping()->trajectoryWorld()) {
    const glm::vec2 at = projectInView(bench, {T.translation().x(), T.translation().y(), T.translation().z()});
    EXPECT_GE(at.x, 0.f);
    EXPECT_LE(at.x, 640.f);
    EXPECT_GE(at.y, 0.f);
    EXPECT_LE(at.y, 480.f);
  }
  EXPECT_LT(bench.ui().camera.distance_m, 0.8f * map_distance);
}

// --- height slice ---
TEST(GuiViewTools, PickIgnoresSlicedAwayEllipsoids) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  const auto global = t.worker().global();
  const std::vector<Ellipsoid>& map = global->map.ellipsoids;
  const render::HeightFrame frame = bench.view().heightFrame();
  const auto height = [&](const Ellipsoid& e) { return frame.height({e.mean.x(), e.mean.y(), e.mean.z()}); };
  std::vector<float> h;
  for (const Ellipsoid& e : map) h.push_back(height(e));
  std::nth_element(h.begin(), h.begin() + static_cast<long>(h.size() / 2), h.end());
  const float median = h[h.size() / 2];
  // The highest ellipsoid, picked with the slice off.
  const Ellipsoid& top =
      *std::max_element(map.begin(), map.end(), [&](auto& a, auto& b) { return height(a) < height(b); });
  ASSERT_GT(height(top), median);
  const glm::vec2 at = projectInView(bench, {top.mean.x(), top.mean.y(), top.mean.z()});
  bench.view().pick(at.x, at.y, 640, 480);
  ASSERT_TRUE(bench.ui().picked);
  EXPECT_EQ(bench.view().shownMap().ellipsoids->size(), map.size()) << "no slice: the whole map is drawn";
  // The lower half: the mirror gets only what it keeps, and a pick never returns the rest.
  bench.ui().settings.slice = {true, -100.f, median};
  const ViewController::ShownMap shown = bench.view().shownMap();
  EXPECT_LT(shown.ellipsoids->size(), map.size());
  EXPECT_GT(shown.ellipsoids->size(), 0u);
  for (const Ellipsoid& e : *shown.ellipsoids) EXPECT_LE(height(e), median);
  bench.view().pick(at.x, at.y, 640, 480);
  if (bench.ui().picked) {
    EXPECT_LE(height(*bench.ui().picked), median) << "a sliced-away ellipsoid was picked";
  }
  EXPECT_EQ(bench.view().shownMap().serial, shown.serial) << "an unchanged slice keeps its selection (no re-upload)";
  // PgUp / PgDn move the slice by its thickness; the selection is new.
  bench.key(KeyAction::kSliceUp);
  EXPECT_NEAR(bench.ui().settings.slice.lo_m, median, 1e-4f);
  EXPECT_NEAR(bench.ui().settings.slice.hi_m, 2.f * median + 100.f, 1e-4f);
  EXPECT_NE(bench.view().shownMap().serial, shown.serial);
  bench.key(KeyAction::kSliceDown);
  EXPECT_NEAR(bench.ui().settings.slice.hi_m, median, 1e-4f);
  // The slice is in the view spec a saved view file carries.
  EXPECT_TRUE(bench.view().spec().slice.on);
  EXPECT_NEAR(bench.view().spec().slice.hi_m, median, 1e-4f);
}

TEST(GuiViewTools, HiddenMapDrawsNoEllipsoids) {
  Settings s;
  EXPECT_TRUE(render::mirrorStyle(viewSpecOf(s)).map);
  s.hide_map = true;  // draw: hidden
  const render::ViewSpec spec = viewSpecOf(s);
  EXPECT_EQ(spec.draw(), render::DrawMode::kNone);
  EXPECT_FALSE(render::mirrorStyle(spec).map) << "the mirror draws no ellipsoids";
  // A view file's "draw": "none" hides the map in the window too, and "hidden" is not saved.
  Workbench bench{Settings{}};
  bench.view().applySpec(spec);
  EXPECT_TRUE(bench.ui().settings.hide_map);
  EXPECT_EQ(bench.view().spec().draw(), render::DrawMode::kNone);
  EXPECT_TRUE(sameSettings(s, Settings{})) << "hidden lasts for the run only";
}

TEST(GuiViewTools, LoadViewRestoresTheSavedCamera) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  bench.view().orbit(0.4f, 0.1f);
  const glm::vec3 eye = bench.ui().camera.eye(), target = bench.ui().camera.target;
  const fs::path file = t.dir / "v.json";
  ASSERT_TRUE(bench.viewFiles().saveSafely(file.string())) << bench.ui().status.text;
  const GlobalMapParams saved_thresholds = bench.ui().params.global;
  bench.view().orbit(-1.f, 0.3f);
  bench.view().zoom(3.f);
  ASSERT_TRUE(bench.parameters().edit(*findParameter("merge_distance"), 0.2));
  t.worker().waitIdle();
  ASSERT_TRUE(bench.viewFiles().load(file.string(), false)) << bench.ui().status.text;
  EXPECT_LT(glm::length(bench.ui().camera.eye() - eye), 1e-5f);
  EXPECT_LT(glm::length(bench.ui().camera.target - target), 1e-5f);
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kSuccess) << bench.ui().status.text;
  EXPECT_EQ(bench.ui().params.global.merge_distance_m, 0.2) << "its thresholds only when asked";
  ASSERT_TRUE(bench.viewFiles().load(file.string(), true));
  EXPECT_EQ(bench.ui().params.global.merge_distance_m, saved_thresholds.merge_distance_m);
  // The view's size differs from the viewport's: the status line says so.
  bench.ui().view_width = 500;
  ASSERT_TRUE(bench.viewFiles().load(file.string(), false));
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kWarning);
  EXPECT_NE(bench.ui().status.text.find("640x480"), std::string::npos) << bench.ui().status.text;
  EXPECT_FALSE(bench.viewFiles().load((t.dir / "none.json").string(), false));
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kError);
}

TEST(GuiViewTools, SaveViewAutoNumbersTheDefaultNameAndAsksForATypedOne) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  const fs::path first = t.dir / "vdmap_view.json";
  ASSERT_TRUE(bench.viewFiles().saveSafely(first.string()));
  const auto written = fs::last_write_time(first);
  ASSERT_TRUE(bench.viewFiles().saveSafely(first.string()));
  EXPECT_TRUE(fs::exists(t.dir / "vdmap_view-2.json"));
  ASSERT_TRUE(bench.viewFiles().saveSafely(first.string()));
  EXPECT_TRUE(fs::exists(t.dir / "vdmap_view-3.json"));
  EXPECT_EQ(fs::last_write_time(first), written) << "never overwritten";
  const fs::path typed = t.dir / "mine.json";
  ASSERT_TRUE(bench.viewFiles().saveSafely(typed.string()));
  EXPECT_FALSE(bench.viewFiles().saveSafely(typed.string())) << "a typed name that exists asks first";
  EXPECT_EQ(bench.ui().confirm_view_replace, typed.string());
  EXPECT_TRUE(bench.viewFiles().saveSafely(typed.string(), true));
  EXPECT_TRUE(bench.ui().confirm_view_replace.empty());
}

TEST(GuiViewTools, QuickViewRecallsTheStoredCamera) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  EXPECT_FALSE(bench.viewFiles().recallQuickView(3)) << "nothing kept there yet";
  bench.view().orbit(0.7f, -0.2f);
  const glm::vec3 eye = bench.ui().camera.eye(), target = bench.ui().camera.target;
  bench.viewFiles().storeQuickView(3);
  bench.view().orbit(-1.5f, 0.4f);
  bench.view().pan(40.f, 10.f);
  ASSERT_TRUE(bench.viewFiles().recallQuickView(3));
  EXPECT_LT(glm::length(bench.ui().camera.eye() - eye), 1e-4f);
  EXPECT_LT(glm::length(bench.ui().camera.target - target), 1e-4f);
}

TEST(GuiViewTools, QuickViewsLastBeyondTheRun) {
  MappedTinyBench t;
  const fs::path settings = t.dir / "config" / "settings.json";
  t.bench.enableSettingsAutosave(settings.string(), t.bench.ui().settings);
  t.bench.view().orbit(0.7f, -0.2f);
  const glm::vec3 eye = t.bench.ui().camera.eye();
  t.bench.viewFiles().storeQuickView(4);
  // The next start, with the same settings folder.
  Workbench next{TinyBench::settings()};
  next.enableSettingsAutosave(settings.string(), next.ui().settings);
  ASSERT_TRUE(next.files().open({.folder = (t.dir / "seq").string()})) << next.ui().status.text;
  next.ui().view_width = 640;
  next.ui().view_height = 480;
  next.worker()->play();
  next.worker()->waitIdle();
  next.sync();
  ASSERT_TRUE(next.viewFiles().recallQuickView(4)) << next.ui().status.text;
  EXPECT_LT(glm::length(next.ui().camera.eye() - eye), 1e-4f);
  EXPECT_FALSE(next.viewFiles().recallQuickView(5));
}

TEST(GuiViewTools, MeasurePointsAlternateAndSnapToCentres) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  bench.view().addMeasurePoint({0.f, 0.f, 1.f});
  ASSERT_TRUE(bench.ui().measure_a);
  EXPECT_FALSE(bench.ui().measure_b);
  bench.view().addMeasurePoint({0.3f, 0.4f, 1.f});
  ASSERT_TRUE(bench.ui().measure_b);
  EXPECT_FLOAT_EQ(glm::length(*bench.ui().measure_b - *bench.ui().measure_a), 0.5f);
  bench.ui().measure_snap = true;
  const Eigen::Vector3d m = t.worker().global()->map.ellipsoids.front().mean;
  bench.view().addMeasurePoint(glm::vec3(m.x(), m.y(), m.z()) + glm::vec3(1e-4f));  // a third click: A again
  EXPECT_FALSE(bench.ui().measure_b);
  EXPECT_LT(glm::length(*bench.ui().measure_a - glm::vec3(m.x(), m.y(), m.z())), 1e-6f);
}

TEST(GuiViewTools, AMeasurementBelongsToTheMapItWasMadeOn) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  bench.view().addMeasurePoint({0.f, 0.f, 1.f});
  bench.view().addMeasurePoint({0.3f, 0.4f, 1.f});
  ASSERT_TRUE(bench.ui().measure_b);
  ASSERT_TRUE(bench.files().openPath((t.dir / "seq").string())) << bench.ui().status.text;
  EXPECT_FALSE(bench.ui().measure_a) << "the A-B line stayed on the newly opened map";
  EXPECT_FALSE(bench.ui().measure_b);
}

// The status line says what the last action did: a message from an earlier one goes with the
// next action, and what that action reports shows.
TEST(GuiViewTools, AStatusMessageGoesWithTheNextAction) {
  MappedTinyBench t;
  Workbench& bench = t.bench;
  bench.report(StatusLine::Kind::kInfo, "no surface under the cursor to measure at");
  bench.key(KeyAction::kFrameMap);
  EXPECT_EQ(bench.ui().status.text, "") << "the message stayed after a later action";
  bench.report(StatusLine::Kind::kError, "an error");
  bench.noteAction();  // a click
  EXPECT_EQ(bench.ui().status.text, "");
  bench.ui().view_file_text = (t.dir / "v.json").string();
  bench.key(KeyAction::kSaveView);  // an action that reports: its own message shows
  EXPECT_NE(bench.ui().status.text.find("v.json"), std::string::npos) << bench.ui().status.text;
}

TEST(GuiViewTools, ScreenshotNeverOverwritesADefaultName) {
  test::TempDir dir;
  const std::time_t when = 1764150000;
  const fs::path first = freeTimestampedName(dir.path(), when);
  EXPECT_TRUE(std::regex_match(first.filename().string(), std::regex(R"(vdmap-\d{8}-\d{6}\.png)"))) << first;
  std::ofstream(first) << "x";
  const fs::path second = freeTimestampedName(dir.path(), when);
  EXPECT_NE(second, first);
  EXPECT_EQ(second.filename().string(), first.stem().string() + "-2.png");
  std::ofstream(second) << "x";
  EXPECT_EQ(freeTimestampedName(dir.path(), when).filename().string(), first.stem().string() + "-3.png");
  // The default folder: $XDG_PICTURES_DIR/vdmap.
  const char* old = std::getenv("XDG_PICTURES_DIR");
  const std::string kept = old ? old : "";
  setenv("XDG_PICTURES_DIR", (dir / "pics").c_str(), 1);
  EXPECT_EQ(screenshotFolder(), dir / "pics" / "vdmap");
  const fs::path made = defaultScreenshotFile(when);
  EXPECT_EQ(made.parent_path(), dir / "pics" / "vdmap");
  EXPECT_TRUE(fs::is_directory(made.parent_path()));
  if (old) setenv("XDG_PICTURES_DIR", kept.c_str(), 1);
  else unsetenv("XDG_PICTURES_DIR");
}

TEST(GuiSettings, AutosaveIsDueOneSecondAfterTheLastChange) {
  using namespace std::chrono_literals;
  const SettingsAutosave::Clock::time_point t0{};
  Settings s;
  SettingsAutosave autosave(s);
  autosave.note(t0, s);
  EXPECT_FALSE(autosave.due(t0 + 5s)) << "nothing changed";
  EXPECT_FALSE(autosave.dueIn(t0));
  s.ellipsoid_sigma = 3.f;
  autosave.note(t0, s);
  EXPECT_FALSE(autosave.due(t0 + 900ms));
  s.ellipsoid_sigma = 3.5f;  // a slider still moving: the second starts again
  autosave.note(t0 + 900ms, s);
  EXPECT_FALSE(autosave.due(t0 + 1500ms));
  EXPECT_EQ(*autosave.dueIn(t0 + 1500ms), 400ms);
  autosave.note(t0 + 1500ms, s);  // unchanged: the delay runs on
  EXPECT_TRUE(autosave.due(t0 + 1900ms));
  EXPECT_EQ(autosave.noted().ellipsoid_sigma, 3.5f);
  autosave.saved();
  EXPECT_FALSE(autosave.due(t0 + 10s)) << "saved: nothing more to do";
  s.ellipsoid_sigma = 2.f;
  autosave.note(t0 + 11s, s);
  s.ellipsoid_sigma = 3.5f;  // changed back to what was saved within the second
  autosave.note(t0 + 11500ms, s);
  EXPECT_FALSE(autosave.due(t0 + 20s));
}

TEST(GuiSettings, TheWorkbenchAutosavesWhatChangedIntoTheFile) {
  using namespace std::chrono_literals;
  test::TempDir dir;
  const fs::path file = dir / "settings.json";
  Workbench bench{Settings{}};
  bench.enableSettingsAutosave(file.string(), Settings{});
  const SettingsAutosave::Clock::time_point t0{};
  EXPECT_TRUE(std::isinf(bench.autosaveSettings(t0)));
  bench.ui().settings.ellipsoid_sigma = 3.f;
  EXPECT_NEAR(bench.autosaveSettings(t0 + 100ms), 1.0, 1e-9);
  EXPECT_FALSE(fs::exists(file));
  EXPECT_TRUE(std::isinf(bench.autosaveSettings(t0 + 1100ms)));
  ASSERT_TRUE(fs::exists(file));
  EXPECT_EQ(loadSettings(file, nullptr).ellipsoid_sigma, 3.f);
}

// A value put back to what it was when the window opened, by hand or by Reset to defaults, is
// what the next start shows (it was left as written in between).
TEST(GuiSettings, AValuePutBackOrResetIsSaved) {
  using namespace std::chrono_literals;
  TinyBench t;
  const fs::path file = t.dir / "settings.json";
  Workbench& bench = t.bench;
  bench.enableSettingsAutosave(file.string(), bench.ui().settings);
  const SettingsAutosave::Clock::time_point t0{};
  bench.ui().settings.ellipsoid_sigma = 3.f;
  bench.autosaveSettings(t0);
  bench.autosaveSettings(t0 + 2s);
  ASSERT_EQ(loadSettings(file, nullptr).ellipsoid_sigma, 3.f);
  bench.ui().settings.ellipsoid_sigma = 2.f;  // back to the start's value
  bench.autosaveSettings(t0 + 3s);
  bench.autosaveSettings(t0 + 5s);
  EXPECT_EQ(loadSettings(file, nullptr).ellipsoid_sigma, 2.f);

  ASSERT_TRUE(bench.parameters().edit(*findParameter("filter_sigma_factor"), 0.5));
  ASSERT_TRUE(bench.parameters().edit(*findParameter("min_points"), 55));
  bench.ui().settings.ellipsoid_sigma = 8.f;
  bench.autosaveSettings(t0 + 6s);
  bench.autosaveSettings(t0 + 8s);
  Settings reread = loadSettings(file, nullptr);
  ASSERT_EQ(reread.thresholds.filter.min_points, 55);
  ASSERT_EQ(reread.ellipsoid_sigma, 8.f);
  bench.parameters().resetToDefaults();
  t.worker().waitIdle();
  bench.saveSettings();  // on exit, within the second
  reread = loadSettings(file, nullptr);
  const Settings defaults;
  EXPECT_EQ(reread.thresholds.filter.min_points, defaults.thresholds.filter.min_points);
  EXPECT_EQ(reread.thresholds.filter.filter_sigma_factor, defaults.thresholds.filter.filter_sigma_factor);
  EXPECT_EQ(reread.ellipsoid_sigma, defaults.ellipsoid_sigma);
  EXPECT_EQ(reread.mapper.keyframe_every, defaults.mapper.keyframe_every);
}

// Each parameter goes back to its default alone; its tooltip names the default.
TEST(GuiSettings, EachParameterResetsAloneAndItsTooltipGivesItsDefault) {
  TinyBench t;
  Workbench& bench = t.bench;
  const Parameter& k = *findParameter("filter_sigma_factor");
  const Parameter& n = *findParameter("min_points");
  ASSERT_TRUE(bench.parameters().edit(k, 0.5));
  ASSERT_TRUE(bench.parameters().edit(n, 55));
  ASSERT_TRUE(bench.parameters().resetParameter(n));
  EXPECT_EQ(bench.ui().params.global.filter.min_points, Settings{}.thresholds.filter.min_points);
  EXPECT_EQ(bench.ui().settings.thresholds.filter.min_points, Settings{}.thresholds.filter.min_points);
  EXPECT_EQ(bench.ui().params.global.filter.filter_sigma_factor, 0.5) << "the other parameter was reset too";
  EXPECT_NE(parameterHelp(n).find("default 6"), std::string::npos) << parameterHelp(n);
  EXPECT_NE(parameterHelp(k).find("default 3"), std::string::npos) << parameterHelp(k);
}

// A slider moved while nothing is open is what the next sequence opens with, and is saved.
TEST(GuiSettings, AParameterEditedWithNothingOpenIsKept) {
  test::TempDir dir;
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.parameters().edit(*findParameter("min_points"), 12));
  ASSERT_TRUE(bench.parameters().edit(*findParameter("keyframe_every"), 4));
  EXPECT_EQ(bench.ui().settings.thresholds.filter.min_points, 12);
  test::writeTinySequence(dir / "seq", 4);
  ASSERT_TRUE(bench.files().open({.folder = (dir / "seq").string()})) << bench.ui().status.text;
  EXPECT_EQ(bench.ui().params.global.filter.min_points, 12);
  EXPECT_EQ(bench.ui().params.mapper.keyframe_every, 4);
}

// Long paths break between their folders, never inside a name that fits on a line.
TEST(GuiWorkbench, LongPathsBreakBetweenFolders) {
  const auto chars = [](std::string_view s) { return static_cast<float>(s.size()); };
  EXPECT_EQ(breakLines("/home/user/data/rgbd_dataset_freiburg1_desk", 30, chars),
            "/home/user/data/\nrgbd_dataset_freiburg1_desk");
  EXPECT_EQ(breakLines("Saved to /x/y; the window", 12, chars), "Saved to /x/\ny; the\nwindow");
  EXPECT_EQ(breakLines("abcdefghij", 4, chars), "abcd\nefgh\nij") << "a name wider than a line";
  EXPECT_EQ(breakLines("short", 30, chars), "short");
  EXPECT_EQ(breakLines("", 30, chars), "");
}

// A double click is told by the presses' times, however slowly frames are drawn (a frame slower
// than the clicks saw the button held once and the file browser's double click did nothing).
TEST(GuiWorkbench, ADoubleClickIsToldByThePressTimes) {
  DoubleClick d;
  EXPECT_FALSE(d.press(10.0, 100, 100));
  EXPECT_TRUE(d.press(10.25, 102, 101)) << "two presses a quarter second apart";
  EXPECT_FALSE(d.press(10.4, 102, 101)) << "a third press starts again";
  EXPECT_FALSE(d.press(11.0, 102, 101)) << "0.6 s after the last";
  EXPECT_FALSE(d.press(11.2, 140, 101)) << "somewhere else";
  EXPECT_TRUE(d.press(11.3, 141, 100));
}

TEST(LoopStrip, NearbyMarkersMergeWithACount) {
  const std::vector<MarkerCluster> c = clusterMarkers({10.f, 12.f, 15.f, 40.f, 41.f, 90.f}, 8.f);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0].members, (std::vector<int>{0, 1, 2}));
  EXPECT_FLOAT_EQ(c[0].x, 12.5f);
  EXPECT_EQ(c[1].members, (std::vector<int>{3, 4}));
  EXPECT_EQ(c[2].members, (std::vector<int>{5}));
  EXPECT_FLOAT_EQ(c[2].x, 90.f);
  // A long run of markers 5 px apart does not merge into one: each cluster spans < min_px.
  std::vector<float> run;
  for (int i = 0; i < 10; ++i) run.push_back(5.f * static_cast<float>(i));
  EXPECT_EQ(clusterMarkers(run, 8.f).size(), 5u);
  EXPECT_TRUE(clusterMarkers({}, 8.f).empty());
}

// The render command the window prints draws what it shows: the frames played so far, how the
// sequence was opened, and the parameters that are not what `vdmap render` starts with.
TEST(GuiViewFiles, TheRenderCommandNamesTheFramesPlayedAndTheChangedParameters) {
  TinyBench t;
  for (int i = 0; i < 4; ++i) t.worker().step();
  t.worker().waitIdle();
  findParameter("merge_distance")->set(t.bench.ui().params, 0.125);
  const CommandSource source = t.bench.viewFiles().commandSource();
  EXPECT_EQ(source.path, (t.dir / "seq").string());
  EXPECT_EQ(source.flags, " --frames 0:4 --poses gt --set keyframe_every=3");
  EXPECT_EQ(source.thresholds, " --set merge_distance=0.125");
  const std::string command = renderCommand(render::ViewSpec{}, source, "v.json", "o.png");
  EXPECT_NE(command.find(" --view-file v.json --settings v.json --out o.png"), std::string::npos) << command;
  // At the end of the sequence, no --frames: the whole sequence as opened.
  t.worker().play();
  t.worker().waitIdle();
  EXPECT_EQ(t.bench.viewFiles().commandSource().flags, " --poses gt --set keyframe_every=3");
  // The mesh layer's mesh as the Mesh section makes it.
  t.bench.ui().settings.show_mesh = true;
  t.bench.ui().settings.mesh.stride = 3;
  t.bench.ui().settings.mesh.fuse = false;
  EXPECT_EQ(t.bench.viewFiles().commandSource().flags,
            " --poses gt --set keyframe_every=3 --mesh-stride 3 --mesh-no-fuse");
}

}  // namespace
}  // namespace vdmap::app::gui
