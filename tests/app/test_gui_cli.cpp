// The workbench end to end under Xvfb: `vdmap` on the built-in scene through the scripted path
// (--play-to-end --screenshot --stats-json --exit), a second run with another merge_distance,
// and the failure paths. Skips when xvfb-run is not installed.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <regex>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "mapping/eval/mesh_accuracy.h"
#include "mapping/synth/builtin_scene.h"
#include "tests/support/test_util.h"

namespace vdmap::test {
namespace {

RunResult runInXvfb(const TempDir& home, const std::string& args, BuiltinCache cache = BuiltinCache::kShared) {
  return runVdmapInXvfb(home.path(), args, "3840x2160", cache);
}

nlohmann::json readJson(const fs::path& file) { return nlohmann::json::parse(readFile(file)); }

// The share of pixels in the middle of the window (between the side panels) that differ from
// the 3-D view's background colour.
double mapCoverage(const fs::path& png) {
  const cv::Mat bgr = test::readImage(png);
  if (bgr.empty()) return -1;
  const cv::Rect middle(bgr.cols * 3 / 10, bgr.rows / 10, bgr.cols * 4 / 10, bgr.rows * 8 / 10);
  const cv::Vec3b background = bgr.at<cv::Vec3b>(bgr.rows - 2, bgr.cols / 2);  // bottom centre: empty floor of the view
  int differing = 0;
  for (int y = middle.y; y < middle.y + middle.height; ++y)
    for (int x = middle.x; x < middle.x + middle.width; ++x)
      differing += cv::norm(bgr.at<cv::Vec3b>(y, x), background, cv::NORM_L1) > 30;
  return static_cast<double>(differing) / middle.area();
}

TEST(GuiCli, BuiltinScenePlayedToTheEndShowsAMapAndMergeDistanceChangesSigmaEPrime) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const std::string common = "--frames 0:30 --play-to-end --exit";
  const RunResult a = runInXvfb(home, common + " --screenshot '" + (home / "a.png").string() + "' --stats-json '" +
                                          (home / "a.json").string() + "'");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const nlohmann::json sa = readJson(home / "a.json");
  EXPECT_EQ(sa["frames_mapped"], 30);
  EXPECT_GE(sa["keyframes"].get<int>(), 2);  // merging needs a group of two keyframes
  EXPECT_GT(sa["sigma_e_prime"].get<int>(), 1000);
  EXPECT_DOUBLE_EQ(sa["merge_distance_m"].get<double>(), 0.25);
  const double coverage = mapCoverage(home / "a.png");
  EXPECT_GT(coverage, 0.05) << "the 3-D view looks empty";

  const RunResult b =
      runInXvfb(home, common + " --set merge_distance=0.01 --stats-json '" + (home / "b.json").string() + "'");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const nlohmann::json sb = readJson(home / "b.json");
  EXPECT_DOUBLE_EQ(sb["merge_distance_m"].get<double>(), 0.01);
  EXPECT_EQ(sb["sigma_e"], sa["sigma_e"]);  // same frames, same filter
  // Merging happens among ellipsoids that fall into one container cell; a 1 cm kernel splits
  // what 25 cm joins, so more ellipsoids stay.
  EXPECT_GT(sb["sigma_e_prime"].get<int>(), sa["sigma_e_prime"].get<int>());
  EXPECT_FALSE(fs::exists(home / "config" / "vdmap" / "settings.json"));  // scripted runs leave settings alone
}

// The layout at a window size: panels inside the window, the map's projected bounding box inside
// the 3-D viewport (between the panels), no label cut.
void expectLayoutFits(const nlohmann::json& stats, int width, int height) {
  const nlohmann::json& layout = stats["layout"];
  ASSERT_EQ(layout["window"], nlohmann::json({width, height})) << layout.dump();
  for (const auto& [name, r] : layout["panels"].items()) {
    const double x = r[0], y = r[1], w = r[2], h = r[3];
    EXPECT_TRUE(x >= 0 && y >= 0 && x + w <= width + 0.5 && y + h <= height + 0.5) << name << " " << r.dump();
    EXPECT_GT(w, 200) << name;
  }
  const nlohmann::json& v = layout["viewport"];
  const double vx = v[0], vy = v[1], vw = v[2], vh = v[3];
  EXPECT_GE(vx, layout["panels"]["Sequence"][2].get<double>() - 0.5) << "the view starts under the left panel";
  EXPECT_LE(vx + vw, layout["panels"]["Map"][0].get<double>() + 0.5) << "the view ends under the right panel";
  ASSERT_TRUE(layout.contains("map_bbox_px")) << layout.dump();
  const nlohmann::json& b = layout["map_bbox_px"];
  EXPECT_TRUE(b[0] >= vx && b[1] >= vy && b[2] <= vx + vw && b[3] <= vy + vh)
      << "map " << b.dump() << " view " << v.dump();
  EXPECT_GT(b[2].get<double>() - b[0].get<double>(), 0.4 * vw) << "the map fills the view";
  EXPECT_EQ(layout["labels_cut"], 0);
}

TEST(GuiCli, PanelsDockAndTheMapFitsTheViewFrom1280x720To3840x2160) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  for (const auto& [w, h] : {std::pair{1280, 720}, std::pair{1920, 1080}, std::pair{3840, 2160}}) {
    const std::string size = std::to_string(w) + "x" + std::to_string(h);
    const fs::path png = home / (size + ".png"), json = home / (size + ".json");
    // The largest window draws its many pixels with llvmpipe: fewer frames keep the test short.
    const std::string frames = w > 2000 ? "0:10" : "0:30";
    // Every section open and a keyframe in the inspector: each label of the panels is drawn and checked.
    const RunResult r =
        runInXvfb(home, "--frames " + frames + " --play-to-end --exit --expand-sections --keyframe 1 --window-size " +
                            size + " --screenshot '" + png.string() + "' --stats-json '" + json.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const cv::Mat image = test::readImage(png);
    EXPECT_EQ(image.cols, w);
    EXPECT_EQ(image.rows, h);
    SCOPED_TRACE(size);
    expectLayoutFits(readJson(json), w, h);
  }
}

TEST(GuiCli, AnIdleWindowCostsNoCpuAndKeyTapsWithinOneFrameAreAllHandled) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeTinySequence(home / "seq", 6);
  // Three Right taps arrive together (one UI frame): each maps one frame. H opens the help (in the
  // smallest window, whose 3-D view is narrowest).
  const RunResult r = runInXvfb(home, "gui '" + (home / "seq").string() +
                                          "' --exit --window-size 1280x720 --press right,right,right,h "
                                          "--measure-idle 3 --stats-json '" +
                                          (home / "s.json").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json stats = readJson(home / "s.json");
  EXPECT_EQ(stats["frames_mapped"], 3);
  EXPECT_EQ(stats["show_help"], true);
  // The help lies over the 3-D view, not over the panels.
  const nlohmann::json& help = stats["layout"]["help"];
  const nlohmann::json& view = stats["layout"]["viewport"];
  const double hx = help[0], hy = help[1], hw = help[2], hh = help[3];
  const double vx = view[0], vy = view[1], vw = view[2], vh = view[3];
  EXPECT_GT(hw * hh, 0) << help.dump();
  EXPECT_TRUE(hx >= vx && hy >= vy && hx + hw <= vx + vw && hy + hh <= vy + vh)
      << "help " << help.dump() << " view " << view.dump();
  // Process CPU over 3 s with the window open and nothing happening (the worker idle too).
  EXPECT_LE(stats["idle_cpu_s"].get<double>(), 0.15);
}

// Pixels of `bgr` inside `r` (x, y, w, h) within `tolerance` (L1) of RGB colour `rgb`.
int pixelsNear(const cv::Mat& bgr, const nlohmann::json& r, cv::Vec3b rgb, int tolerance = 30) {
  const cv::Rect rect(r[0].get<int>(), r[1].get<int>(), r[2].get<int>(), r[3].get<int>());
  const cv::Vec3b color(rgb[2], rgb[1], rgb[0]);
  int n = 0;
  for (int y = rect.y; y < rect.y + rect.height && y < bgr.rows; ++y)
    for (int x = rect.x; x < rect.x + rect.width && x < bgr.cols; ++x)
      n += cv::norm(bgr.at<cv::Vec3b>(y, x), color, cv::NORM_L1) <= tolerance;
  return n;
}

// --edit then D: the stats count what the edit removed and the 3-D view draws it red
// (kDiffRemoved), which it does not without D.
TEST(GuiCli, DShowsWhatAScriptedThresholdEditRemoved) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeTinySequence(home / "seq", 10);
  const auto run = [&](const std::string& name, const std::string& keys) {
    const fs::path png = home / (name + ".png"), json = home / (name + ".json");
    const RunResult r =
        runInXvfb(home, "gui '" + (home / "seq").string() +
                            "' --set keyframe_every=3 min_points=3 --play-to-end --exit "
                            "--window-size 1280x720 --edit min_points=60 " +
                            keys + " --view-screenshot '" + png.string() + "' --stats-json '" + json.string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const cv::Mat image = test::readImage(png);
    int red = 0;  // shaded kDiffRemoved: red well above green and blue
    for (auto p = image.begin<cv::Vec3b>(); p != image.end<cv::Vec3b>(); ++p)
      red += (*p)[2] > 60 && (*p)[2] > 3 * std::max((*p)[0], (*p)[1]);
    return std::pair(readJson(json), red);
  };
  const auto [stats, red] = run("d", "--press d");
  const nlohmann::json& diff = stats["edit_diff"];
  EXPECT_EQ(diff["edit"], "min points 3 -> 60") << stats.dump();
  EXPECT_GT(diff["removed"].get<int>(), 0);
  EXPECT_EQ(diff["shown"], true);
  const auto [plain_stats, plain_red] = run("plain", "");
  EXPECT_EQ(plain_stats["edit_diff"]["shown"], false);
  EXPECT_EQ(plain_stats["edit_diff"]["removed"], diff["removed"]);
  EXPECT_GT(red, plain_red + 1000) << "removed: red";  // ~15700 against ~200 (frustum lines)
}

// A tracked sequence that closes loops: the loop markers above the scrubber (left panel) and B
// showing the map before the last optimisation, whose banner the 3-D view shows in the loop colour.
TEST(GuiCli, TrackedLoopClosuresAreMarkedAndBShowsTheMapBeforeTheLastOptimisation) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeBoxRoomSequence(home / "seq", 70);
  const std::string common =
      "gui '" + (home / "seq").string() + "' --poses track --play-to-end --exit --window-size 1280x720";
  const fs::path png = home / "b.png", json = home / "b.json";
  const RunResult r =
      runInXvfb(home, common + " --press b --screenshot '" + png.string() + "' --stats-json '" + json.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json stats = readJson(json);
  EXPECT_EQ(stats["frames_mapped"], 70);
  EXPECT_GE(stats["loop_closures"].get<int>(), 1);
  EXPECT_EQ(stats["has_groundtruth"], true);
  EXPECT_EQ(stats["poses"], "track");
  EXPECT_EQ(stats["show_before_optimisation"], true);
  EXPECT_EQ(stats["map_before_optimisation"], true);
  EXPECT_EQ(stats["layout"]["labels_cut"], 0);
  const cv::Mat image = test::readImage(png);
  const cv::Vec3b loop_color(255, 120, 20);  // render::kLoopEdgeColor
  EXPECT_GT(pixelsNear(image, stats["layout"]["panels"]["Sequence"], loop_color), 20)
      << "loop markers above the scrubber";
  EXPECT_GT(pixelsNear(image, stats["layout"]["viewport"], loop_color), 50)
      << "the banner and loop edges in the 3-D view";
}

// --- Tracking error figures and latency stages (global map / worker stream): a tracked run with
// ground truth reports ATE and RPE (app/workbench/figures.h) in its stats.
TEST(GuiCli, TrackedRunReportsAteAndRpe) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeBoxRoomSequence(home / "seq", 40);
  const fs::path json = home / "t.json";
  const RunResult r = runInXvfb(home, "gui '" + (home / "seq").string() +
                                          "' --poses track --play-to-end --exit "
                                          "--window-size 1280x720 --stats-json '" +
                                          json.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json stats = readJson(json);
  for (const char* key : {"ate_rmse_m", "rpe_frame_m", "rpe_frame_deg", "rpe_second_m"}) {
    ASSERT_TRUE(stats.contains(key)) << key;
    EXPECT_TRUE(std::isfinite(stats[key].get<double>())) << key;
    EXPECT_GE(stats[key].get<double>(), 0.0) << key;
  }
  EXPECT_LT(stats["ate_rmse_m"].get<double>(), 0.05);
  EXPECT_GT(stats["rpe_frame_m"].get<double>(), 0.0);
}

// A session saved from a tracked run reopens with its tracking error: the ground truth comes
// from the session's sequence folder, matched by timestamp.
TEST(GuiCli, ATrackedSessionReopensWithItsTrackingError) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeBoxRoomSequence(home / "seq", 40);
  const fs::path session = home / "s.vdmap", json = home / "t.json";
  const RunResult m = runVdmap("map '" + (home / "seq").string() + "' --poses track --out '" + (home / "out").string() +
                               "' --save '" + session.string() + "'");
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const RunResult r = runInXvfb(
      home, "gui '" + session.string() + "' --exit --window-size 1280x720 --stats-json '" + json.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json stats = readJson(json);
  EXPECT_TRUE(stats["has_groundtruth"].get<bool>());
  EXPECT_EQ(stats["poses"], "track");
  ASSERT_TRUE(stats.contains("ate_rmse_m"));
  EXPECT_EQ(stats["trajectory_matched"].get<int>(), stats["frames_mapped"].get<int>());
  EXPECT_LT(stats["ate_rmse_m"].get<double>(), 0.05);
}

// --measure-latency splits each edit into stages from the snapshot's stamps and names the
// parameter edited and what the global map's stage cache kept (the second edit goes back).
TEST(GuiCli, LatencyStagesNameEachEditsParameterAndCache) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeBoxRoomSequence(home / "seq", 6);
  const fs::path json = home / "l.json";
  const RunResult r = runInXvfb(home, "gui '" + (home / "seq").string() +
                                          "' --poses gt --play-to-end --exit "
                                          "--measure-latency 4 --stats-json '" +
                                          json.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json stats = readJson(json);
  ASSERT_EQ(stats["slider_to_map_ms"].size(), 4u);
  const nlohmann::json& stages = stats["slider_to_map_stages_ms"];
  ASSERT_EQ(stages.size(), 4u);
  const char* expected[] = {"merge_distance", "merge_distance", "fusion_max_distance", "fusion_max_distance"};
  for (std::size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(stages[i]["parameter"], expected[i]);
    double sum = 0;
    for (const char* stage : {"queue", "build", "after_build", "to_ui", "frame"}) {
      ASSERT_TRUE(stages[i].contains(stage)) << stage;
      EXPECT_GE(stages[i][stage].get<double>(), 0.0) << stage;
      sum += stages[i][stage].get<double>();
    }
    // The stages come from the snapshot's stamps and the frame's own clock reads, the latency from
    // the script's: a few per cent and ms apart under a sanitizer, never a stage counted twice.
    EXPECT_LE(sum, 1.05 * stats["slider_to_map_ms"][i].get<double>() + 2.0)
        << "the stages lie within the edit's latency";
    EXPECT_GE(stages[i]["build"].get<double>() + 1e-3, stages[i]["t_g"].get<double>()) << "the build holds t_g";
  }
  // A fusion edit keeps every merge group and the occlusion removal; a merge-distance edit none.
  EXPECT_EQ(stages[0]["reused"][1], 0);
  EXPECT_EQ(stages[2]["reused"][1], stages[2]["reused"][2]);
  EXPECT_EQ(stages[2]["reused"][3], true);
}
// --- end tracking error figures and latency stages

// The picture a newcomer is left with: on first start (empty cache and settings) the built-in
// scene renders, opens and the window then waits for input; in the last frame before it waits
// no label is cut (tables still sizing their columns clip them to a letter). Likewise after
// opening a saved session, whose figures table appears with its map.
TEST(GuiCli, TheFirstStartsLastFrameBeforeWaitingCutsNoLabel) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const fs::path json = home / "first.json";
  const RunResult r =
      runInXvfb(home, "--frames 0:10 --exit --measure-idle 1 --stats-json '" + json.string() + "'", BuiltinCache::kOwn);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(readJson(json)["labels_cut_before_wait"], 0);
  // Then played, in the smallest window (each mapped frame is a picture between waits).
  const RunResult p = runInXvfb(home, "--frames 0:10 --play-to-end --window-size 1280x720 --exit --measure-idle 1 "
                                      "--stats-json '" +
                                          json.string() + "'");
  ASSERT_EQ(p.exit_code, 0) << p.err;
  EXPECT_EQ(readJson(json)["labels_cut_before_wait"], 0) << "while playing";

  writeTinySequence(home / "seq", 3);
  const std::string session = (home / "s.vdmap").string();
  ASSERT_EQ(
      runVdmap("map '" + (home / "seq").string() + "' --out '" + (home / "out").string() + "' --save '" + session + "'")
          .exit_code,
      0);
  const RunResult s =
      runInXvfb(home, "gui '" + session + "' --exit --measure-idle 1 --stats-json '" + json.string() + "'");
  ASSERT_EQ(s.exit_code, 0) << s.err;
  EXPECT_EQ(readJson(json)["labels_cut_before_wait"], 0);
}

// Closing the window while the first start renders the built-in scene (300 frames) stops the
// render within a frame: the run exits 0 at once, says so, and caches nothing (neither the
// sequence nor its temporary folder), so the next start renders it whole.
TEST(GuiCli, ClosingDuringTheFirstRenderExitsAtOnce) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  // Frames are drawn at the start and then after each batch of 8 rendered: the 5th comes after 16.
  const RunResult r = runInXvfb(home, "--close-after-frames 5", BuiltinCache::kOwn);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(
      r.err, m,
      std::regex(R"(closed while rendering the built-in scene \((\d+) of (\d+) frames done\): nothing kept)")))
      << r.err;
  EXPECT_LT(std::stoi(m[1]), std::stoi(m[2]));
  EXPECT_EQ(std::stoi(m[2]), 300);
  if (fs::exists(home / "cache" / "vdmap"))
    for (const auto& entry : fs::directory_iterator(home / "cache" / "vdmap"))
      ADD_FAILURE() << "left behind: " << entry.path();
}

// A sequence mapped with its ground-truth poses has ground truth: the figures say so, and which
// poses the map was made with.
TEST(GuiCli, GroundTruthPosesReportHasGroundtruthTrue) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeBoxRoomSequence(home / "seq", 6);
  const fs::path json = home / "g.json";
  const RunResult r = runInXvfb(home, "gui '" + (home / "seq").string() +
                                          "' --poses gt --play-to-end --exit --stats-json '" + json.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json stats = readJson(json);
  EXPECT_EQ(stats["frames_mapped"], 6);
  EXPECT_EQ(stats["has_groundtruth"], true);
  EXPECT_EQ(stats["poses"], "gt");
}

TEST(GuiCli, ASequenceThatFailsToLoadIsReportedNotACrash) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const RunResult r = runInXvfb(home, "gui '" + (home / "nowhere").string() + "' --exit");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;
}

TEST(GuiCli, ASavedSessionOpensAsSeqLikeWithMap) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeTinySequence(home / "seq", 3);
  const std::string session = (home / "s.vdmap").string();
  ASSERT_EQ(
      runVdmap("map '" + (home / "seq").string() + "' --out '" + (home / "out").string() + "' --save '" + session + "'")
          .exit_code,
      0);
  const RunResult r = runInXvfb(home, "gui '" + session + "' --exit --stats-json '" + (home / "s.json").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GE(readJson(home / "s.json")["keyframes"].get<int>(), 1);
}

TEST(GuiCli, BadSetAndNoDisplayAreClearErrors) {
  TempDir home;
  writeTinySequence(home / "seq", 3);
  const RunResult bad = runVdmap("gui '" + (home / "seq").string() + "' --set merge_distance=-2 --exit");
  EXPECT_EQ(bad.exit_code, 1) << bad.err;
  EXPECT_NE(bad.err.find("merge_distance"), std::string::npos) << bad.err;
  const RunResult no_display = runVdmap("gui '" + (home / "seq").string() + "' --exit", "DISPLAY= WAYLAND_DISPLAY=");
  EXPECT_EQ(no_display.exit_code, 1) << no_display.err;
  EXPECT_NE(no_display.err.find("window"), std::string::npos) << no_display.err;
}

TEST(GuiCli, NoDisplayFailsBeforeRenderingTheBuiltinScene) {
  TempDir home;
  fs::create_directories(home / "cache");
  const RunResult r = runVdmap("", "DISPLAY= WAYLAND_DISPLAY= XDG_CONFIG_HOME='" + (home / "config").string() +
                                       "' XDG_CACHE_HOME='" + (home / "cache").string() + "'");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("window"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;  // one line
  EXPECT_TRUE(fs::is_empty(home / "cache")) << "the built-in scene was rendered before the display was checked";
}

// A failed scripted run writes neither the screenshot nor the stats (a bad session once
// exited 1 but wrote a screenshot of the error dialog and its stats).
TEST(GuiCli, AFailedScriptedRunWritesNeitherFile) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  writeTinySequence(home / "seq", 3);
  const std::string session = (home / "s.vdmap").string();
  ASSERT_EQ(
      runVdmap("map '" + (home / "seq").string() + "' --out '" + (home / "out").string() + "' --save '" + session + "'")
          .exit_code,
      0);
  std::string bytes = readFile(session);
  bytes[bytes.size() / 2] ^= 1;  // a checksum mismatch
  writeText(home / "bad.vdmap", bytes);
  const RunResult r =
      runInXvfb(home, "gui '" + (home / "bad.vdmap").string() + "' --exit --screenshot '" + (home / "p.png").string() +
                          "' --stats-json '" + (home / "j.json").string() + "'");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("checksum mismatch"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(home / "p.png"));
  EXPECT_FALSE(fs::exists(home / "j.json"));
}

// Which settings apply (docs/workbench.md "Which settings apply"): --settings FILE, else the
// defaults for a scripted run; each run says which in one note.
const char* kTunedSettings = R"({"thresholds": {"filter_sigma_factor": 1, "merge_distance": 0.73}})";

bool saysSettings(const RunResult& r, const std::string& source) {
  return r.err.find("vdmap: note: settings: " + source + "\n") != std::string::npos ||
         r.err.find("vdmap gui: note: settings: " + source + "\n") != std::string::npos;
}

TEST(GuiCli, AScriptedRunUsesTheSettingsFileItIsGivenAndSaysSo) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const fs::path tuned = home / "tuned.json";
  writeText(tuned, kTunedSettings);
  const auto run = [&](const std::string& name, const std::string& extra) {
    const RunResult r =
        runInXvfb(home, "--frames 0:30 --play-to-end --exit --stats-json '" + (home / name).string() + "' " + extra);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r;
  };
  const RunResult defaults = run("d.json", "");
  const RunResult file = run("f.json", "--settings '" + tuned.string() + "'");
  const RunResult set = run("s.json", "--set filter_sigma_factor=1 --set merge_distance=0.73");
  EXPECT_TRUE(saysSettings(defaults, "defaults")) << defaults.err;
  EXPECT_TRUE(saysSettings(file, tuned.string())) << file.err;
  const nlohmann::json d = readJson(home / "d.json"), f = readJson(home / "f.json"), s = readJson(home / "s.json");
  // k = 1 keeps fewer ellipsoids, h = 0.73 m merges more of them: the file's map, not the defaults'.
  EXPECT_LT(f["sigma_e"].get<int>(), d["sigma_e"].get<int>());
  EXPECT_NE(f["sigma_e_prime"], d["sigma_e_prime"]);
  EXPECT_DOUBLE_EQ(f["merge_distance_m"].get<double>(), 0.73);
  EXPECT_EQ(f["sigma_e"], s["sigma_e"]);  // the same map as the same values given with --set
  EXPECT_EQ(f["sigma_e_prime"], s["sigma_e_prime"]);
  EXPECT_FALSE(fs::exists(home / "config" / "vdmap" / "settings.json"));

  // A saved session keeps its own thresholds; --settings goes over them, and says so.
  writeTinySequence(home / "seq", 3);
  const std::string session = (home / "s.vdmap").string();
  ASSERT_EQ(
      runVdmap("map '" + (home / "seq").string() + "' --out '" + (home / "out").string() + "' --save '" + session + "'")
          .exit_code,
      0);
  const RunResult own =
      runInXvfb(home, "gui '" + session + "' --exit --stats-json '" + (home / "o.json").string() + "'");
  const RunResult over = runInXvfb(home, "gui '" + session + "' --exit --settings '" + tuned.string() +
                                             "' --stats-json '" + (home / "v.json").string() + "'");
  ASSERT_EQ(own.exit_code, 0) << own.err;
  ASSERT_EQ(over.exit_code, 0) << over.err;
  EXPECT_TRUE(saysSettings(own, "the session's thresholds")) << own.err;
  EXPECT_TRUE(saysSettings(over, tuned.string() + " over the session's thresholds")) << over.err;
  EXPECT_DOUBLE_EQ(readJson(home / "o.json")["merge_distance_m"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(readJson(home / "v.json")["merge_distance_m"].get<double>(), 0.73);
}

TEST(GuiCli, AScriptedRunIgnoresTheUsersSettingsAndSaysDefaults) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const std::string args = "--frames 0:30 --play-to-end --exit --stats-json ";
  const RunResult plain = runInXvfb(home, args + "'" + (home / "p.json").string() + "'");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  // Now the user has tuned thresholds (runInXvfb points XDG_CONFIG_HOME into `home`).
  const fs::path user_file = home / "config" / "vdmap" / "settings.json";
  fs::create_directories(user_file.parent_path());
  writeText(user_file, kTunedSettings);
  const RunResult tuned = runInXvfb(home, args + "'" + (home / "t.json").string() + "'");
  ASSERT_EQ(tuned.exit_code, 0) << tuned.err;
  EXPECT_TRUE(saysSettings(tuned, "defaults")) << tuned.err;
  const nlohmann::json p = readJson(home / "p.json"), t = readJson(home / "t.json");
  EXPECT_EQ(t["sigma_e"], p["sigma_e"]);
  EXPECT_EQ(t["sigma_e_prime"], p["sigma_e_prime"]);
  EXPECT_DOUBLE_EQ(t["merge_distance_m"].get<double>(), 0.25);
  EXPECT_EQ(readFile(user_file), kTunedSettings);  // neither read nor written
}

// A --settings file that is malformed or out of range: one line naming it, before the display
// is looked at.
TEST(GuiCli, AMalformedSettingsFileIsOneErrorNamingIt) {
  TempDir home;
  writeTinySequence(home / "seq", 3);
  const fs::path bad = home / "bad.json";
  for (const std::string& text :
       {std::string(R"({"thresholds": {"merge_distance": -1}})"), std::string("{\"thresholds\": ")}) {
    writeText(bad, text);
    for (const std::string& verb : {"gui '" + (home / "seq").string() + "'", std::string("--frames 0:3")}) {
      const RunResult r = runVdmap(verb + " --exit --settings '" + bad.string() + "'", "DISPLAY= WAYLAND_DISPLAY=");
      EXPECT_EQ(r.exit_code, 1) << r.err;
      EXPECT_NE(r.err.find("error: " + bad.string() + ": "), std::string::npos) << r.err;
      EXPECT_EQ(r.err.find("display"), std::string::npos) << r.err;
      EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    }
  }
}

// Without a display, a missing sequence or session is named (it named the display), in one line.
TEST(GuiCli, AMissingInputIsNamedBeforeTheDisplay) {
  TempDir home;
  for (const std::string& input :
       {std::string("'") + (home / "nope").string() + "'", "--map '" + (home / "nope.vdmap").string() + "'"}) {
    const RunResult r = runVdmap("gui " + input + " --exit", "DISPLAY= WAYLAND_DISPLAY=");
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find("nope"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("display"), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

// ---- Opening files: map folders, PLYs and OctoMaps as `gui PATH` and dropped ----

// Pixels of an image that differ from its most common colour (the view's background) by more
// than 30 (L1 over BGR): what the map drew.
int drawnPixels(const fs::path& png) {
  const cv::Mat bgr = test::readImage(png);
  if (bgr.empty()) return -1;
  std::map<int, int> counts;
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b c = bgr.at<cv::Vec3b>(y, x);
      ++counts[c[0] << 16 | c[1] << 8 | c[2]];
    }
  const int mode =
      std::max_element(counts.begin(), counts.end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
  const cv::Vec3b background(static_cast<uchar>(mode >> 16), static_cast<uchar>(mode >> 8 & 255),
                             static_cast<uchar>(mode & 255));
  int drawn = 0;
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) drawn += cv::norm(bgr.at<cv::Vec3b>(y, x), background, cv::NORM_L1) > 30;
  return drawn;
}

// A `vdmap map` folder of a tiny sequence with its OctoMap; the counts its stats.json gives.
struct MappedFolder {
  fs::path seq, out;
  int ellipsoids = 0, occupied_leaves = 0, keyframes = 0;
  explicit MappedFolder(const TempDir& home) : seq(home / "seq"), out(home / "out") {
    writeTinySequence(seq, 6);
    const RunResult r = runVdmap("map '" + seq.string() + "' --out '" + out.string() + "' --octomap 0.02");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json stats = readJson(out / "stats.json");
    ellipsoids = stats["sigma_e_prime"];
    occupied_leaves = stats["octomap"]["occupied_leaves"];
    keyframes = stats["keyframes"];
  }
};

TEST(GuiCli, OpensAFolderAPlyAndABt) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const MappedFolder m(home);
  ASSERT_GT(m.ellipsoids, 100);
  ASSERT_GT(m.occupied_leaves, 10);
  struct Case {
    fs::path path;
    int ellipsoids, keyframes;
  };
  for (const Case& c :
       {Case{m.out, m.ellipsoids, m.keyframes}, Case{m.out / "global_points.ply", m.ellipsoids, 0},
        Case{m.out / "global_ellipsoids.ply", m.ellipsoids, 0}, Case{m.out / "global.bt", m.occupied_leaves, 0}}) {
    SCOPED_TRACE(c.path.string());
    const fs::path stats = home / "s.json", view = home / "v.png";
    fs::remove(view);
    const RunResult r = runInXvfb(home, "gui '" + c.path.string() + "' --exit --window-size 1280x720 --stats-json '" +
                                            stats.string() + "' --view-screenshot '" + view.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json s = readJson(stats);
    EXPECT_EQ(s["error"], "");
    EXPECT_EQ(s["sigma_e_prime"], c.ellipsoids);
    EXPECT_EQ(s["keyframes"], c.keyframes);
    EXPECT_GT(drawnPixels(view), 1000) << "the 3-D view looks empty";
  }
}

TEST(GuiCli, ADroppedPathOpens) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const MappedFolder m(home);
  const fs::path stats = home / "d.json", view = home / "d.png";
  // The sequence opens (mapped to 3 frames), then the OctoMap dropped on the window replaces it.
  const RunResult r =
      runInXvfb(home, "gui '" + m.seq.string() + "' --exit --drop '" + (m.out / "global.bt").string() +
                          "' --stats-json '" + stats.string() + "' --view-screenshot '" + view.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json s = readJson(stats);
  EXPECT_EQ(s["sigma_e_prime"], m.occupied_leaves);
  EXPECT_EQ(s["keyframes"], 0);
  EXPECT_GT(drawnPixels(view), 1000);
  // A dropped file that cannot be opened fails the scripted run with its name.
  const RunResult bad =
      runInXvfb(home, "gui '" + m.seq.string() + "' --exit --drop '" + (home / "nope.bt").string() + "'");
  EXPECT_EQ(bad.exit_code, 1) << bad.err;
  EXPECT_NE(bad.err.find("nope.bt"), std::string::npos) << bad.err;
}

// A view file dropped on the window is applied as a view: its camera is the one saved after.
TEST(GuiCli, ADroppedViewFileIsApplied) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const MappedFolder m(home);
  const std::string map = "gui '" + m.out.string() + "' --exit --window-size 1280x720 ";
  const fs::path a = home / "a.json", b = home / "b.json", c = home / "c.json";
  // The default view, saved; the same moved up and sideways, written as another view file.
  ASSERT_EQ(runInXvfb(home, map + "--save-view '" + b.string() + "'").exit_code, 0);
  nlohmann::json va = readJson(b);
  ASSERT_TRUE(va["camera"].is_object()) << va.dump();
  va["camera"]["eye"][0] = va["camera"]["eye"][0].get<double>() + 0.4;
  va["camera"]["eye"][1] = va["camera"]["eye"][1].get<double>() + 0.3;
  writeText(a, va.dump(2));
  const RunResult r = runInXvfb(home, map + "--drop '" + a.string() + "' --save-view '" + c.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json vc = readJson(c);
  for (const char* key : {"eye", "target"})
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(vc["camera"][key][i].get<double>(), va["camera"][key][i].get<double>(), 1e-4) << key << i;
}

}  // namespace
}  // namespace vdmap::test

// Progressive drawing (docs/performance.md "Workbench"): a scripted orbit draws the fast pass of
// exactly --fast-budget ellipsoids per frame, and once the camera rests the loop wakes itself to
// show the full-quality frame (the run waits for it; its pixels are the cache's, which
// test_view_cache compares with a fresh draw).
namespace vdmap::test {
namespace {
// Writing a file wants a modifier: S alone (typed into a text field that lost the keyboard)
// writes nothing; Ctrl+S saves the view.
TEST(GuiCli, SavingTheViewWantsCtrl) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const RunResult plain = runInXvfb(home, "--frames 0:10 --play-to-end --exit --press s");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.out.find("view saved to"), std::string::npos) << plain.out;
  const RunResult ctrl = runInXvfb(home, "--frames 0:10 --play-to-end --exit --press ctrl+s");
  ASSERT_EQ(ctrl.exit_code, 0) << ctrl.err;
  std::smatch saved;
  ASSERT_TRUE(std::regex_search(ctrl.out, saved, std::regex("view saved to (\\S+);"))) << ctrl.out;
  EXPECT_TRUE(fs::exists(saved[1].str()));
  fs::remove(saved[1].str());
}

TEST(GuiCli, AfterMovingStopsTheFullQualityFrameIsShown) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const RunResult r =
      runInXvfb(home, "--frames 0:30 --play-to-end --exit --measure-orbit 6 --fast-budget 500 --stats-json '" +
                          (home / "s.json").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json stats = readJson(home / "s.json");
  ASSERT_GT(stats["sigma_e_prime"].get<int>(), 500);
  EXPECT_EQ(stats["fast_instances"], 500);
  EXPECT_GE(stats["orbit_fast_ms"].size(), 5u) << stats["orbit_fast_ms"].dump();
  EXPECT_EQ(stats["view_full_quality"], true);
  EXPECT_GT(stats["settle_ms"].get<double>(), 0.0) << "the full frame followed the fast ones";
}

// The built-in scene's first 30 frames with the map alone in the view (no lines), and that
// view's image (empty on failure).
const std::string kSurfaceViewArgs = "--frames 0:30 --play-to-end --exit --window-size 1280x720 "
                                     "--set show_frustums=false --set show_graph=false --set show_trajectory=false";
cv::Mat surfaceView(const TempDir& home) {
  const fs::path png = home / "view.png";
  if (runInXvfb(home, kSurfaceViewArgs + " --view-screenshot '" + png.string() + "'").exit_code != 0) return {};
  return test::readImage(png);
}

// The pixels of a view screenshot on a coarse grid over its middle half where a surface is drawn
// all around them (not the background, not a line), top rows first.
std::vector<cv::Point> surfacePixels(const cv::Mat& view) {
  if (view.empty()) return {};
  const cv::Vec3b background = view.at<cv::Vec3b>(2, view.cols - 3);
  const auto surface = [&](int x, int y) {
    for (int dy = -3; dy <= 3; ++dy)
      for (int dx = -3; dx <= 3; ++dx)
        if (cv::norm(view.at<cv::Vec3b>(y + dy, x + dx), background, cv::NORM_L1) <= 30) return false;
    return true;
  };
  std::vector<cv::Point> found;
  for (int y = view.rows / 4; y < view.rows * 3 / 4; y += 17)
    for (int x = view.cols / 4; x < view.cols * 3 / 4; x += 17)
      if (surface(x, y)) found.push_back({x, y});
  return found;
}

// Measuring: the points --measure finds under two pixels of the view (the depth of the drawn
// scene, as Ctrl+click) lie on the built-in scene's surfaces, within 1 cm (the ellipsoids are
// drawn at 2 sigma around the surface), and the distance is |b - a|. The pixels are taken where
// the first run's view image shows a surface all around them (not the background, not a line).
TEST(GuiCli, MeasuredPointsLieOnTheBuiltinMesh) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const std::vector<cv::Point> found = surfacePixels(surfaceView(home));
  ASSERT_GE(found.size(), 2u) << "the view shows no surface";
  const std::string common = kSurfaceViewArgs;
  const cv::Point a = found.front(), b = found.back();
  const fs::path json = home / "m.json";
  const RunResult r =
      runInXvfb(home, common + " --measure " + std::to_string(a.x) + "," + std::to_string(a.y) + "," +
                          std::to_string(b.x) + "," + std::to_string(b.y) + " --stats-json '" + json.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json m = readJson(json)["measure"];
  ASSERT_TRUE(m.is_object()) << readJson(json).dump();
  const Eigen::Vector3f pa(m["a"][0], m["a"][1], m["a"][2]), pb(m["b"][0], m["b"][1], m["b"][2]);
  EXPECT_NEAR(m["distance_m"].get<double>(), (pb - pa).norm(), 1e-5);
  EXPECT_GT((pb - pa).norm(), 0.05f) << "two different places";
  const std::vector<double> d = distancesToMesh({pa, pb}, makeBuiltinScene().mesh);
  EXPECT_LT(d[0], 0.01) << pa.transpose();
  EXPECT_LT(d[1], 0.01) << pb.transpose();
}

// A pixel beyond the view is echoed short (it was printed as std::to_string does, 39 digits and
// six decimals for 1e38), and the scripted run fails with that one line.
TEST(GuiCli, AProbeBeyondTheViewEchoesItsPixelShort) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const RunResult r = runInXvfb(home, "--frames 0:3 --play-to-end --exit --probe 1e38,0");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("error: --probe: nothing drawn under pixel 1e+38,0 (and no query slice there)\n"),
            std::string::npos)
      << r.err;
}

// Point queries (docs/workbench.md "Queries"): --probe at a pixel where the view shows a surface
// finds the point 5 cm in front of it (so within 5 cm of a gate surface; occupied exactly when
// at distance 0), and with --query-slice the point lies on the slice's plane; the stats give the
// queries of the map shown and the slice's samples.
TEST(GuiCli, ProbeAndQuerySliceScripted) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const cv::Mat view = surfaceView(home);
  const std::vector<cv::Point> found = surfacePixels(view);
  ASSERT_FALSE(found.empty()) << "the view shows no surface";
  const std::string common = kSurfaceViewArgs;
  const cv::Point at = found[found.size() / 2];
  const std::string pixel = std::to_string(at.x) + "," + std::to_string(at.y);
  const fs::path json = home / "p.json";
  RunResult r = runInXvfb(home, common + " --probe " + pixel + " --stats-json '" + json.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json stats = readJson(json);
  const nlohmann::json probe = stats["probe"];
  ASSERT_TRUE(probe.is_object()) << stats.dump();
  EXPECT_EQ(probe["on_slice"], false);
  EXPECT_EQ(probe["generation"], stats["queries"]["generation"]);
  EXPECT_GT(stats["queries"]["keyframes"].get<int>(), 0);
  const double d = probe["distance_m"].get<double>();
  EXPECT_LE(d, 0.051) << "5 cm in front of the drawn surface, which lies inside a gate";
  EXPECT_EQ(probe["class"] == "occupied", d == 0.0) << probe.dump();

  const fs::path shot = home / "slice.png";
  r = runInXvfb(home, common + " --probe " + pixel +
                          " --query-slice z=1.0 --query-slice-color distance --stats-json '" + json.string() +
                          "' --view-screenshot '" + shot.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  stats = readJson(json);
  EXPECT_EQ(stats["probe"]["on_slice"], true) << stats["probe"].dump();
  EXPECT_NEAR(stats["probe"]["point"][2].get<double>(), 1.0, 1e-4);
  const nlohmann::json slice = stats["query_slice"];
  ASSERT_TRUE(slice.is_object()) << stats.dump();
  EXPECT_EQ(slice["color"], "distance");
  EXPECT_EQ(std::max(slice["width"].get<int>(), slice["height"].get<int>()), 256);
  EXPECT_GT(slice["free"].get<int>(), 0);
  EXPECT_GT(slice["occupied"].get<int>(), 0);
  cv::Mat diff;
  cv::absdiff(test::readImage(shot), view, diff);
  EXPECT_GT(cv::countNonZero(diff.reshape(1) > 30), 1000) << "the slice is drawn";
}

}  // namespace
}  // namespace vdmap::test

// --- picture stream: framing what is drawn ---
namespace vdmap::test {
namespace {

// Pixels on the border rows and columns of a view screenshot that differ from the dark
// background by more than 8 counts.
int borderPixelsOff(const fs::path& png) {
  const cv::Mat bgr = test::readImage(png);
  if (bgr.empty()) return -1;
  const cv::Vec3b bg(38, 33, 33);  // render::kDarkBackground in BGR bytes
  int off = 0;
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) {
      if (y != 0 && y != bgr.rows - 1 && x != 0 && x != bgr.cols - 1) continue;
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      off += std::abs(p[0] - bg[0]) > 8 || std::abs(p[1] - bg[1]) > 8 || std::abs(p[2] - bg[2]) > 8;
    }
  return off;
}

TEST(GuiCli, PressingFLeavesTheViewsBorderEmpty) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  for (const std::string size : {"1280x720", "900x1000"}) {
    const fs::path view = home / (size + ".png"), json = home / (size + ".json");
    const RunResult r =
        runInXvfb(home, "--frames 0:30 --play-to-end --press f --exit --window-size " + size + " --view-screenshot '" +
                            view.string() + "' --stats-json '" + json.string() + "'");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(borderPixelsOff(view), 0) << size << ": the frame cuts what is drawn";
    const nlohmann::json layout = readJson(json)["layout"];
    EXPECT_EQ(layout["map_strays"], 0) << size;
    const nlohmann::json& b = layout["map_bbox_px"];
    const nlohmann::json& v = layout["viewport"];
    EXPECT_TRUE(b[0] >= v[0] && b[1] >= v[1] && b[2] <= v[0].get<double>() + v[2].get<double>() &&
                b[3] <= v[1].get<double>() + v[3].get<double>())
        << "the drawn map's box " << b.dump() << " inside the view " << v.dump();
  }
}

// --- height slice ---
// A slice set with --set draws fewer ellipsoids (the mirror's count) and pixels, and a saved
// view carries it.
TEST(GuiCli, ASliceDrawsFewerEllipsoidsAndIsSavedInTheView) {
  VDMAP_REQUIRE_XVFB();
  TempDir home;
  const MappedFolder m(home);
  const std::string map = "gui '" + m.out.string() + "' --exit --window-size 1280x720 --set show_legend=false ";
  const auto run = [&](const std::string& name, const std::string& options) {
    const RunResult r = runInXvfb(home, map + options + " --stats-json '" + (home / (name + ".json")).string() +
                                            "' --view-screenshot '" + (home / (name + ".png")).string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return readJson(home / (name + ".json"));
  };
  const nlohmann::json all = run("all", "");
  const nlohmann::json sliced = run("sliced", "--set slice=true --set slice_lo=0 --set slice_hi=0.5 --save-view '" +
                                                  (home / "v.json").string() + "'");
  EXPECT_EQ(all["map_drawn"], m.ellipsoids);
  EXPECT_GT(sliced["map_drawn"].get<int>(), 0);
  EXPECT_LT(sliced["map_drawn"].get<int>(), 3 * m.ellipsoids / 4);
  EXPECT_LT(drawnPixels(home / "sliced.png"), drawnPixels(home / "all.png"));
  EXPECT_EQ(readJson(home / "v.json")["slice"], nlohmann::json::array({0.0, 0.5}));
  std::printf("slice 0..0.5 m: %d of %d ellipsoids, %d of %d pixels\n", sliced["map_drawn"].get<int>(), m.ellipsoids,
              drawnPixels(home / "sliced.png"), drawnPixels(home / "all.png"));
}

}  // namespace
}  // namespace vdmap::test
