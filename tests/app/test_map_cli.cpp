// vdmap map / vdmap bench end to end on a tiny generated sequence.
#include <algorithm>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "mapping/pipeline/parameters.h"
#include "tests/support/test_util.h"

namespace vdmap::test {
namespace {

TEST(MapCli, WritesEllipsoidPlyAndCounts) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 4);
  const fs::path out = tmp / "out" / "nested";
  const RunResult r =
      runVdmap("map '" + (tmp / "seq").string() + "' --keyframe-every 2 --octomap 0.05 --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("2 keyframes"), std::string::npos) << r.out;
  const std::string header = readFile(out / "local_maps.ply");
  EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(header.find("property uint count\nproperty int keyframe\nend_header\n"), std::string::npos);
  for (const char* file : {"keyframes.txt", "graph.txt", "global_points.ply", "global_ellipsoids.ply",
                           "global_gaussians.ply", "global.bt", "stats.json"})
    EXPECT_TRUE(fs::exists(out / file)) << file;
  for (const auto& entry : fs::directory_iterator(out))  // no temporary left behind
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  std::ifstream stats_file(out / "stats.json");
  const auto stats = nlohmann::json::parse(stats_file);
  for (const char* key : {"frames", "keyframes", "edges", "revisits", "sigma_e", "update_ms", "pipeline_ms",
                          "sigma_e_prime", "t_g_s", "t_g_us_per_ellipsoid", "global_stage_ms", "octomap"})
    EXPECT_TRUE(stats.contains(key)) << key;
  EXPECT_EQ(stats["keyframes"], 2);
}

// Frames without a ground-truth pose within 0.1 s are dropped (--poses gt); map says so in one
// line on stderr, loudly when most of the range goes, and stats.json counts them.
TEST(MapCli, DroppedFramesAreReportedAndCounted) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 5);
  // Poses for frames 0 and 1 only (t = 0, 1/30 s): frames 2-4 come after the last pose, and a
  // pose is interpolated between poses on both sides within 0.1 s.
  writeText(tmp / "seq" / "groundtruth.txt", "0.0 0 0 0 0 0 0 1\n0.033333 0.01 0 0 0 0 0 1\n");
  const RunResult r = runVdmap("map '" + (tmp / "seq").string() + "' --out '" + (tmp / "out").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_EQ(r.err.rfind("vdmap map: warning: MOST FRAMES DROPPED: 3 of the 5 frames of 0:5 dropped, 2 mapped: 3 "
                        "without a ground-truth pose within 0.1 s",
                        0),
            0u)
      << r.err;
  std::ifstream stats_file(tmp / "out" / "stats.json");
  const auto stats = nlohmann::json::parse(stats_file);
  EXPECT_EQ(stats["frames_listed"], 5);
  EXPECT_EQ(stats["frames_in_range"], 5);
  EXPECT_EQ(stats["frames_dropped_no_pose"], 3);
  EXPECT_EQ(stats["frames_dropped_no_rgb"], 0);
  EXPECT_EQ(stats["frames_mapped"], 2);
  EXPECT_EQ(stats["frames"], 2);

  // Every frame with a pose: no line, and the counts say nothing was dropped.
  writeTinySequence(tmp / "full", 3);
  const RunResult full =
      runVdmap("map '" + (tmp / "full").string() + "' --frames 1: --out '" + (tmp / "out2").string() + "'");
  ASSERT_EQ(full.exit_code, 0) << full.err;
  EXPECT_EQ(full.err, "");
  std::ifstream full_file(tmp / "out2" / "stats.json");
  const auto full_stats = nlohmann::json::parse(full_file);
  EXPECT_EQ(full_stats["frames_listed"], 3);
  EXPECT_EQ(full_stats["frames_in_range"], 2);
  EXPECT_EQ(full_stats["frames_dropped_no_pose"], 0);
  EXPECT_EQ(full_stats["frames_mapped"], 2);
}

// stats.json says how the folder was made: vdmap's version, the sequence, the camera and its
// source, the pose source and its refinement, and every mapping parameter with its value.
TEST(MapCli, StatsRecordTheProvenance) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 4);
  const RunResult r = runVdmap("map '" + (tmp / "seq").string() + "' --keyframe-every 2 --tau-group 0.3 --out '" +
                               (tmp / "out").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream stats_file(tmp / "out" / "stats.json");
  const auto stats = nlohmann::json::parse(stats_file);
  const std::string version = runVdmap("--version").out;  // "vdmap VERSION (git COMMIT)\n"
  ASSERT_GT(version.size(), 7u);
  EXPECT_EQ(stats["vdmap_version"], version.substr(6, version.size() - 7));
  EXPECT_EQ(stats["sequence"], fs::absolute(tmp / "seq").lexically_normal().string());
  EXPECT_EQ(stats["frame_range"], "0:4");
  EXPECT_EQ(stats["camera"], "file camera.yaml");
  EXPECT_EQ(stats["camera_source"], "file");
  EXPECT_EQ(stats["camera_intrinsics"], nlohmann::json({{"width", 64},
                                                        {"height", 48},
                                                        {"fx", 50.0},
                                                        {"fy", 50.0},
                                                        {"cx", 31.5},
                                                        {"cy", 23.5},
                                                        {"depth_scale", 5000.0}}));
  EXPECT_EQ(stats["poses"], "gt");
  EXPECT_EQ(stats["refine"], "none");
  // Every parameter of the table, the given ones with their values.
  ASSERT_TRUE(stats["parameters"].is_object());
  EXPECT_EQ(stats["parameters"].size(), parameters().size());
  for (const Parameter& p : parameters()) EXPECT_TRUE(stats["parameters"].contains(std::string(p.key))) << p.key;
  EXPECT_EQ(stats["parameters"]["keyframe_every"], 2);
  EXPECT_EQ(stats["parameters"]["tau_group"], 0.3);
  EXPECT_EQ(stats["parameters"]["occlusion_removal"], true);

  const RunResult tracked = runVdmap("map '" + (tmp / "seq").string() +
                                     "' --poses track --refine pairwise --json --out '" + (tmp / "out").string() + "'");
  ASSERT_EQ(tracked.exit_code, 0) << tracked.err;
  const auto t = nlohmann::json::parse(tracked.out);
  EXPECT_EQ(t["poses"], "track");
  EXPECT_EQ(t["refine"], "pairwise");

  // A preset given with --camera, and one guessed from the folder (tum-default): the source says which.
  writeTinySequence(tmp / "vga", 2, 640, 480);
  fs::remove(tmp / "vga" / "camera.yaml");
  for (const auto& [option, kind] : {std::pair{"", "guessed"}, std::pair{"--camera tum-fr1", "preset"}}) {
    const RunResult r2 =
        runVdmap("map '" + (tmp / "vga").string() + "' " + option + " --json --out '" + (tmp / "out").string() + "'");
    ASSERT_EQ(r2.exit_code, 0) << r2.err;
    EXPECT_EQ(nlohmann::json::parse(r2.out)["camera_source"], kind) << option;
  }
}

// More threads than the machine has: the same map, and nothing on stderr (TBB warned that it
// ignores the extra workers); 256 is the most --threads takes (65537 crashed in TBB's allocator).
TEST(MapCli, ThreadsBeyondTheCoresPrintNothingAndAreBounded) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 3);
  const std::string seq = "map '" + (tmp / "seq").string() + "' --out '";
  const RunResult one = runVdmap(seq + (tmp / "one").string() + "' --threads 1");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  const unsigned more = std::max(2u, std::thread::hardware_concurrency() + 1);
  for (const unsigned threads : {more, 256u}) {
    const fs::path out = tmp / ("t" + std::to_string(threads));
    const RunResult r = runVdmap(seq + out.string() + "' --threads " + std::to_string(threads));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_EQ(r.err, "") << threads << " threads";
    EXPECT_EQ(readFile(out / "global_ellipsoids.ply"), readFile(tmp / "one" / "global_ellipsoids.ply"));
  }
  const RunResult too_many = runVdmap(seq + (tmp / "x").string() + "' --threads 65537");
  EXPECT_EQ(too_many.exit_code, 105) << too_many.err;
  EXPECT_NE(too_many.err.find("--threads: Value 65537 not in range 0 to 256"), std::string::npos) << too_many.err;
  EXPECT_FALSE(fs::exists(tmp / "x"));
}

// A camera guessed from the folder (its name, or the default) is said in one line on stderr: an
// ICL-NUIM copy in a folder named b0 mapped with tum-default's focal length without a word.
TEST(MapCli, SaysWhichCameraItGuessedAndWhy) {
  TempDir tmp;
  struct Case {
    const char* folder;
    std::string note;  // empty: the camera was given, nothing to say
    const char* option = "";
  };
  const std::vector<Case> cases = {
      {"b0", "no camera given, guessed preset tum-default (no camera file or hint in the folder): fx 525 fy 525"},
      {"icl_b1", "no camera given, guessed preset icl-nuim (folder name 'icl_b1'): fx 481.2 fy 480"},
      {"b2", "", " --camera tum-default"},
  };
  for (const Case& c : cases) {
    writeTinySequence(tmp / c.folder, 2, 640, 480);
    fs::remove(tmp / c.folder / "camera.yaml");
    const RunResult r =
        runVdmap("map '" + (tmp / c.folder).string() + "' --out '" + (tmp / c.folder).string() + "_out'" + c.option);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    if (c.note.empty()) {
      EXPECT_EQ(r.err, "") << c.folder;
      continue;
    }
    EXPECT_EQ(r.err.rfind("vdmap map: note: " + (tmp / c.folder).string() + ": " + c.note, 0), 0u) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

TEST(MapCli, BadCellSizeFailsWithoutOutput) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 2);
  // 0 is wrong by itself (CLI11's ValidationError, 105); 49 only for this 64x48 camera (exit 1).
  for (const char* s : {"0", "49"}) {
    const RunResult r =
        runVdmap("map '" + (tmp / "seq").string() + "' --cell-size " + s + " --out '" + (tmp / "out").string() + "'");
    EXPECT_EQ(r.exit_code, s[0] == '0' ? 105 : 1);
    EXPECT_NE(r.err.find(s[0] == '0' ? "cell_size must be >= 1 px" : "cell size 49 px"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(tmp / "out"));
  }
}

TEST(BenchCli, JsonHasTheContractKeys) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 3);
  const RunResult r =
      runVdmap("bench '" + (tmp / "seq").string() + "' --frames 2 --json --out '" + tmp.path().string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  for (const char* key :
       {"frames", "vd_update_ms", "octomap_010_ms", "octomap_005_ms", "octomap_002_ms", "ratio_octomap_010",
        "vd_pipeline_ms", "sigma_e", "sigma_e_prime", "t_g_s", "t_g_us_per_ellipsoid"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["frames"], 2);  // a plain N means 0:N
  EXPECT_EQ(j["frame_range"], "0:2");
  EXPECT_TRUE(fs::exists(tmp / "bench.json"));
  EXPECT_TRUE(fs::exists(tmp / "bench.md"));
}

// The text report keeps its two keyframe rules apart: the update row's --keyframe-every and the
// pipeline's keyframes, which the global map is built from (it said "keyframe every 1" and then
// "global map 1 keyframe" for 3 frames).
TEST(BenchCli, TextSaysWhoseKeyframesItCounts) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 3);
  const RunResult r =
      runVdmap("bench '" + (tmp / "seq").string() + "' --keyframe-every 1 --out '" + tmp.path().string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("keyframes       the update row starts one every frame; the pipeline made "), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("global map      of the pipeline's "), std::string::npos) << r.out;
  EXPECT_NE(readFile(tmp / "bench.md").find("Global map of the pipeline's "), std::string::npos);
}

// The long run: a row per frame, a global map every --global-every frames and after the last,
// and the summary's windows (frames [N/6, N/3) and the last N/6).
TEST(BenchCli, LongRunWritesOneRowPerFrameAndTheSummary) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 12);
  const RunResult r = runVdmap("bench '" + (tmp / "seq").string() + "' --long --global-every 5 --json --out '" +
                               tmp.path().string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frames"], 12);
  EXPECT_EQ(j["early_frames"], nlohmann::json({2, 4}));
  EXPECT_EQ(j["late_frames"], nlohmann::json({10, 12}));
  EXPECT_GT(j["rss_mb_end"].get<double>(), 0.0);
  // The live heap comes from glibc's mallinfo2, which reads 0 under AddressSanitizer's allocator.
  EXPECT_LE(j["heap_mb_end"].get<double>(), j["rss_mb_end"].get<double>());
  EXPECT_GT(j["global_ellipsoids_end"].get<long>(), 0);
  std::istringstream csv(readFile(tmp / "long.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "frame,cpu_ms,wall_ms,rss_mb,keyframes,global_ellipsoids,t_g_s,heap_mb");
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 12u);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    std::vector<std::string> f;
    std::stringstream row(rows[i]);
    for (std::string cell; std::getline(row, cell, ',');) f.push_back(cell);
    ASSERT_EQ(f.size(), 8u) << "row " << i << ": " << rows[i];
    const bool global = i == 4 || i == 9 || i == 11;
    EXPECT_EQ(!f[5].empty(), global) << "row " << i << ": " << rows[i];
  }
  EXPECT_EQ(
      runVdmap("bench '" + (tmp / "seq").string() + "' --long --global-every 0 --out '" + tmp.path().string() + "'")
          .exit_code,
      105);  // a value wrong by itself: CLI11's ValidationError
  EXPECT_EQ(j.value("poses", ""), "gt");
  EXPECT_FALSE(j.contains("loop_closures"));
}

// The long run with --poses track tracks the poses (it mapped with the ground truth, silently,
// before) and reports the tracking figures beside the cost per frame. Its --out folder is made as
// map's is (the run failed at its end, after all the work, when the folder did not exist).
TEST(BenchCli, LongRunWithTrackedPosesReportsTheTracking) {
  TempDir tmp;
  writeBoxRoomSequence(tmp / "seq", 12);
  const RunResult r =
      runVdmap("bench '" + (tmp / "seq").string() + "' --long --poses track --global-every 6 --json --out '" +
               (tmp / "new" / "long").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(tmp / "new" / "long" / "long.json"));
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["frames"], 12);
  EXPECT_EQ(j.value("poses", ""), "track");
  for (const char* key : {"frames_lost", "frames_weak", "frames_relocalised", "loop_closures", "pose_graph_ms"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j.value("frames_lost", -1), 0);
  EXPECT_LT(j.value("ate_rmse_m", 1.0), 0.01);  // the same walk as the map verb's tracking test
}

// Every number in a JSON text has at most `digits` significant digits (figures such as
// 0.37278400000000003 are noise, not precision).
void expectTidyNumbers(const std::string& json, int digits) {
  static const std::regex number(R"((-?)(\d+)\.(\d+)(?:[eE][-+]?\d+)?)");
  for (auto it = std::sregex_iterator(json.begin(), json.end(), number); it != std::sregex_iterator(); ++it) {
    std::string all = (*it)[2].str() + (*it)[3].str();
    all.erase(0, std::min(all.find_first_not_of('0'), all.size()));
    EXPECT_LE(static_cast<int>(all.size()), digits) << it->str();
  }
}

// Small things of a map run: counts in the singular, no bare " done." from liboctomap on stderr,
// figures without float noise, the effective frame range in stats.json.
TEST(MapCli, OneFrameOneKeyframeAndAQuietOctomapExport) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 3);
  const RunResult r =
      runVdmap("map '" + (tmp / "seq").string() + "' --frames 1 --octomap 0.05 --out '" + (tmp / "out").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("1 frame, 1 keyframe, 0 edges, 0 revisits;"), std::string::npos) << r.out;
  EXPECT_EQ(r.err, "") << "stderr is not a terminal: no progress, no library lines";
  const std::string stats = readFile(tmp / "out" / "stats.json");
  expectTidyNumbers(stats, 6);
  EXPECT_EQ(nlohmann::json::parse(stats)["frame_range"], "0:1");
}

// bench --out is created like map --out; a peer that did not run has null figures in `methods`
// as at the top level (it had 0.0), and the numbers carry no float noise; bench.md echoes the
// range that ran.
TEST(BenchCli, CreatesItsOutFolderAndSkippedPeersAreNull) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 3);
  const fs::path out = tmp / "new" / "bench";
  const RunResult r =
      runVdmap("bench '" + (tmp / "seq").string() + "' --no-octomap --no-open3d --json --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(readFile(out / "bench.json"));
  EXPECT_TRUE(j["octomap_010_ms"].is_null());
  EXPECT_TRUE(j["methods"]["octomap_010"]["ms_per_frame"].is_null()) << j["methods"]["octomap_010"];
  EXPECT_TRUE(j["methods"]["octomap_010"]["elements"].is_null());
  EXPECT_TRUE(j["ratio_octomap_010_pipeline"].is_null());
  EXPECT_FALSE(j["methods"]["ndt_om_010"]["ms_per_frame"].is_null());
  EXPECT_EQ(j["frame_range"], "0:3") << "the default 0:30, cut at the end of a shorter sequence";
  expectTidyNumbers(readFile(out / "bench.json"), 6);
  const std::string md = readFile(out / "bench.md");
  EXPECT_NE(md.find("frames 0:3;"), std::string::npos) << md;
  EXPECT_NE(md.find("Global map of the pipeline's "), std::string::npos) << md;
  EXPECT_EQ(md.find("1 keyframes"), std::string::npos) << md;
}

}  // namespace
}  // namespace vdmap::test
