// vdmap map / vdmap bench end to end on a tiny generated sequence.
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/test_util.h"

namespace vdmap::test {
namespace {

TEST(MapCli, WritesEllipsoidPlyAndCounts) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 4);
  const fs::path out = tmp / "out" / "nested";
  const RunResult r = runVdmap("map '" + (tmp / "seq").string() + "' --keyframe-every 2 --octomap 0.05 --out '" +
                               out.string() + "'");
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

TEST(MapCli, BadCellSizeFailsWithoutOutput) {
  TempDir tmp;
  writeTinySequence(tmp / "seq", 2);
  for (const char* s : {"0", "49"}) {  // the tiny sequence is 64x48
    const RunResult r = runVdmap("map '" + (tmp / "seq").string() + "' --cell-size " + s +
                                 " --out '" + (tmp / "out").string() + "'");
    EXPECT_EQ(r.exit_code, 1);
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
  for (const char* key : {"frames", "vd_update_ms", "octomap_010_ms", "octomap_005_ms",
                          "octomap_002_ms", "ratio_octomap_010", "vd_pipeline_ms", "sigma_e", "sigma_e_prime",
                          "t_g_s", "t_g_us_per_ellipsoid"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["frames"], 2);  // a plain N means 0:N
  EXPECT_TRUE(fs::exists(tmp / "bench.json"));
  EXPECT_TRUE(fs::exists(tmp / "bench.md"));
}

}  // namespace
}  // namespace vdmap::test
