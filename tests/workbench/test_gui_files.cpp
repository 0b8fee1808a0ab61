// Opening files in the workbench without a window (app/workbench/file_actions.cpp): a map file opens
// as a static map with what it lacks disabled, drops queue until the frame opens them, and the
// opened paths go to the recent list.
#include <gtest/gtest.h>

#include "app/view/render_source.h"
#include "app/view/render_view.h"
#include "app/view/settings.h"
#include "app/view/view_file.h"
#include "app/workbench/workbench.h"
#include "mapping/files/map_export.h"
#include "mapping/files/octomap_export.h"
#include "mapping/files/ply_writer.h"
#include "mapping/io/camera_config.h"
#include "tests/support/box_room_keyframes.h"
#include "tests/support/test_util.h"

namespace vdmap::app::gui {
namespace {
namespace fs = std::filesystem;

// A `vdmap map` folder of two box-room keyframes (with a trajectory and an OctoMap).
struct MapFolder {
  test::TempDir dir;
  KeyframeGraph graph;
  GlobalMap map;
  fs::path folder = dir / "map";
  MapFolder() {
    test::addTwoBoxRoomViews(&graph, cameraPreset("tum-default"));
    map = buildGlobalMap(graph, GlobalMapParams{});
    MapExportOptions options;
    options.octomap_resolution_m = 0.1;
    for (int i = 0; i < 5; ++i)
      options.trajectory.push_back({graph.keyframe(0).timestamp + 0.1 * i, graph.keyframe(1).T_W_K});
    exportMap(folder, graph, map, options);
  }
};

TEST(GuiFiles, AMapFolderOpensWithThresholdsDisabled) {
  const MapFolder m;
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.files().openPath(m.folder.string())) << bench.ui().status.text;
  ASSERT_NE(bench.staticMap(), nullptr);
  EXPECT_EQ(bench.staticMap()->kind, MapFileKind::kMapFolder);
  EXPECT_TRUE(bench.savedSession());  // nothing to play or re-map
  EXPECT_EQ(bench.files().whyPlayerOff(), kStaticMapWhy);
  const auto mapping = bench.mapping();
  const auto global = bench.global();
  ASSERT_TRUE(mapping && global);
  EXPECT_EQ(mapping->keyframes.size(), 2u);
  EXPECT_TRUE(mapping->keyframes[1].T_W_K.isApprox(m.graph.keyframe(1).T_W_K, 1e-6));
  EXPECT_EQ(mapping->edges.size(), 1u);
  ASSERT_EQ(mapping->trajectory.size(), 5u);
  EXPECT_TRUE(mapping->framePose(4).isApprox(m.graph.keyframe(1).T_W_K, 1e-5));  // drawn where the file put it
  EXPECT_EQ(global->map.ellipsoids.size(), m.map.ellipsoids.size());
  EXPECT_EQ(global->map.sigma_e_prime, m.map.ellipsoids.size());
  for (const Parameter& p : parameterTable()) EXPECT_FALSE(bench.parameters().pending(p)) << p.key;

  // Nothing rebuilds it: Reset to defaults (which applies the thresholds) leaves it and says
  // nothing; thresholds sent to the worker anyway are refused with the reason; the map stays.
  bench.ui().settings.recent = {"/a", "/b"};
  bench.parameters().resetToDefaults();
  bench.worker()->waitIdle();
  EXPECT_EQ(bench.player().status().error, "");
  EXPECT_EQ(bench.ui().settings.recent, (std::vector<std::string>{"/a", "/b"}));  // a history, kept
  GlobalMapParams other;
  other.merge_distance_m = 0.01;
  bench.worker()->setThresholds(other);
  bench.worker()->waitIdle();
  EXPECT_EQ(bench.global(), global);
  EXPECT_EQ(bench.player().status().error, kStaticMapWhy);
  // Play, a pose edit and the container do nothing; a selection is published without a local map.
  bench.player().play();
  bench.poses().selectKeyframe(1);
  bench.worker()->waitIdle();
  EXPECT_EQ(bench.mapping(), mapping);
  ASSERT_TRUE(bench.selection());
  EXPECT_EQ(bench.selection()->keyframe, 1);
  EXPECT_TRUE(bench.selection()->local.empty());
  bench.key(KeyAction::kContainer);
  EXPECT_FALSE(bench.ui().show_container);
  bench.ui().pose_translation_m.x += 1.f;
  bench.poses().applyEdit();
  bench.worker()->waitIdle();
  EXPECT_EQ(bench.mapping(), mapping);
}

TEST(GuiFiles, OpenPathOpensEveryKindAndRemembersItNewestFirst) {
  const MapFolder m;
  writePointPly(m.dir / "points.ply", m.map.ellipsoids);
  test::writeTinySequence(m.dir / "seq", 3);
  Workbench bench{Settings{}};
  const std::vector<fs::path> paths = {m.dir / "seq", m.folder / "global.bt", m.dir / "points.ply",
                                       m.folder / "global_ellipsoids.ply", m.folder};
  for (const fs::path& p : paths) {
    ASSERT_TRUE(bench.files().openPath(p.string())) << p << ": " << bench.ui().status.text;
    EXPECT_EQ(bench.sequence() != nullptr, p == m.dir / "seq") << p;
    EXPECT_EQ(bench.staticMap() != nullptr, p != m.dir / "seq") << p;
  }
  EXPECT_EQ(bench.staticMap()->kind, MapFileKind::kMapFolder);
  std::vector<std::string> expected;
  for (auto it = paths.rbegin(); it != paths.rend(); ++it) expected.push_back(it->lexically_normal().string());
  EXPECT_EQ(bench.ui().settings.recent, expected);
  // A failure keeps what is open and is not remembered.
  const int session = bench.sessionSerial();
  EXPECT_FALSE(bench.files().openPath((m.dir / "nope.ply").string()));
  EXPECT_EQ(bench.ui().status.kind, StatusLine::Kind::kError);
  EXPECT_NE(bench.ui().status.text.find("nope.ply"), std::string::npos);
  EXPECT_EQ(bench.sessionSerial(), session);
  EXPECT_EQ(bench.ui().settings.recent, expected);
  // Opening one again moves it to the front.
  ASSERT_TRUE(bench.files().openPath((m.dir / "seq").string()));
  EXPECT_EQ(bench.ui().settings.recent.front(), (m.dir / "seq").string());
  EXPECT_EQ(bench.ui().settings.recent.size(), paths.size());
}

// What the command line opens (vdmap gui PATH goes through open, openSession or openMapFile,
// not openPath) is in Recent too.
TEST(GuiFiles, WhatTheCommandLineOpensIsRecent) {
  const MapFolder m;
  test::writeTinySequence(m.dir / "seq", 3);
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.files().open({.folder = (m.dir / "seq").string()})) << bench.ui().status.text;
  EXPECT_EQ(bench.ui().settings.recent, (std::vector<std::string>{(m.dir / "seq").string()}));
  ASSERT_TRUE(bench.files().openMapFile((m.folder / "global.bt").string())) << bench.ui().status.text;
  EXPECT_EQ(bench.ui().settings.recent.front(), (m.folder / "global.bt").string());
  EXPECT_EQ(bench.ui().settings.recent.size(), 2u);
}

// An OctoMap without colours is drawn by height: the colour mode says so (and the legend shows
// the height ramp); opening something else gives rgb back.
TEST(GuiFiles, AnOctomapWithoutColoursIsShownByHeight) {
  const MapFolder m;
  test::writeTinySequence(m.dir / "seq", 3);
  Workbench bench{Settings{}};
  bench.enableSettingsAutosave((m.dir / "settings.json").string(), Settings{});
  ASSERT_TRUE(bench.files().openPath((m.folder / "global.bt").string())) << bench.ui().status.text;
  EXPECT_TRUE(bench.staticMap()->height_colors);
  EXPECT_EQ(bench.ui().settings.color, render::ColorMode::kHeight) << "colour mode rgb over height colours";
  bench.saveSettings();  // the user's choice is saved, not the file's stand-in
  EXPECT_EQ(loadSettings(m.dir / "settings.json", nullptr).color, render::ColorMode::kRgb);
  ASSERT_TRUE(bench.files().openPath((m.dir / "seq").string())) << bench.ui().status.text;
  EXPECT_EQ(bench.ui().settings.color, render::ColorMode::kRgb);
  // A map file with its own colours keeps the mode, as does a mode chosen by the user.
  ASSERT_TRUE(bench.files().openPath(m.folder.string())) << bench.ui().status.text;
  EXPECT_FALSE(bench.staticMap()->height_colors);
  EXPECT_EQ(bench.ui().settings.color, render::ColorMode::kRgb);
  bench.ui().settings.color = render::ColorMode::kCount;
  ASSERT_TRUE(bench.files().openPath((m.folder / "global.bt").string())) << bench.ui().status.text;
  EXPECT_EQ(bench.ui().settings.color, render::ColorMode::kCount);
}

TEST(GuiFiles, RecentKeepsTenPathsAndRoundTripsThroughTheSettingsFile) {
  Settings s;
  for (int i = 0; i < 14; ++i) addRecent(s, "/p/" + std::to_string(i));
  addRecent(s, "/p/12");
  ASSERT_EQ(s.recent.size(), kRecentFiles);
  EXPECT_EQ(s.recent.front(), "/p/12");
  EXPECT_EQ(s.recent[1], "/p/13");
  EXPECT_EQ(s.recent.back(), "/p/4");  // 12 moved to the front: nothing dropped by it
  test::TempDir dir;
  saveSettings(dir / "settings.json", s);
  std::string warning;
  EXPECT_EQ(loadSettings(dir / "settings.json", &warning).recent, s.recent);
  EXPECT_EQ(warning, "");
  test::writeText(dir / "bad.json", R"({"recent": [1, 2]})");
  EXPECT_TRUE(loadSettings(dir / "bad.json", &warning).recent.empty());
  EXPECT_NE(warning.find("recent"), std::string::npos) << warning;
}

TEST(GuiFiles, DropsWaitForTheFrameAndAViewFileIsApplied) {
  const MapFolder m;
  Workbench bench{Settings{}};
  bench.files().drop(m.folder.string());
  EXPECT_FALSE(bench.isOpen());  // queued, not opened while a frame is drawn
  EXPECT_EQ(bench.files().openDropped(), 1);
  ASSERT_NE(bench.staticMap(), nullptr);
  EXPECT_EQ(bench.files().openDropped(), 0);

  // A view file: its camera, not a new session.
  render::ViewSpec spec = bench.view().spec();
  spec.look_at = render::LookAt{{1.f, 2.f, 3.f}, {0.5f, 0.f, 1.f}, {0.f, 0.f, 1.f}, 50.f};
  writeViewFile(m.dir / "v.json", spec, GlobalMapParams{}, m.folder.string());
  const int session = bench.sessionSerial();
  bench.files().drop((m.dir / "v.json").string());
  EXPECT_EQ(bench.files().openDropped(), 1);
  EXPECT_EQ(bench.sessionSerial(), session);
  const render::ViewSpec shown = bench.view().spec();
  ASSERT_TRUE(shown.look_at);
  EXPECT_NEAR(glm::distance(shown.look_at->eye, glm::vec3(1.f, 2.f, 3.f)), 0.f, 1e-5f);
  EXPECT_NEAR(glm::distance(shown.look_at->target, glm::vec3(0.5f, 0.f, 1.f)), 0.f, 1e-5f);
}

// The headless twin: `vdmap render` of a map folder estimates the same data up axis as the window
// (from the same cameras: the trajectory, else the keyframes, and the floor of the same map).
TEST(GuiFiles, RenderAndTheWindowAgreeOnAMapFoldersUpAxis) {
  const MapFolder m;
  fs::remove(m.folder / "trajectory.txt");
  for (const bool trajectory : {false, true}) {
    if (trajectory) {
      const KeyframeGraph& g = m.graph;
      writeTumTrajectory(m.folder / "trajectory.txt",
                         {{0.0, g.keyframe(0).T_W_K}, {0.5, g.keyframe(0).T_W_K}, {1.0, g.keyframe(1).T_W_K}},
                         "frames");
    }
    Workbench bench{Settings{}};
    ASSERT_TRUE(bench.files().openPath(m.folder.string())) << bench.ui().status.text;
    RenderSource source({}, m.folder.string(), "");
    const glm::vec3 window = bench.view().upVector(), render = source.up(render::UpAxis::kData, GlobalMapParams{});
    EXPECT_LT(glm::distance(window, render), 1e-6f) << trajectory;
    EXPECT_GT(glm::distance(window, glm::vec3(0.f, 0.f, 1.f)), 0.1f) << "the cameras were not used";
  }
}

}  // namespace
}  // namespace vdmap::app::gui
