// vdmap bench --query end to end on the built-in scene: a noisy render mapped, the same poses
// rendered exactly as the truth; the report names every method's speed and accuracy and vdmap's
// queries in detail, and a truth of other frames is refused.
#include <algorithm>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/test_util.h"

namespace vdmap {
namespace {

using test::readFile;
using test::RunResult;
using test::runVdmap;
using test::TempDir;

// Appended rather than "'" + p.string(): GCC 12 warns (-Wrestrict) on that concatenation falsely.
std::string q(const std::filesystem::path& p) {
  std::string quoted = "'";
  quoted += p.string();
  quoted += '\'';
  return quoted;
}

TEST(QueryBench, ReportsSpeedAndAccuracyOfEveryMap) {
  TempDir tmp;
  ASSERT_EQ(runVdmap("synth --builtin --builtin-frames 12 --out " + q(tmp / "seq")).exit_code, 0);
  ASSERT_EQ(runVdmap("synth --builtin --builtin-frames 12 --noise none --out " + q(tmp / "exact")).exit_code, 0);
  const RunResult r = runVdmap(
      "bench " + q(tmp / "seq") + " --query --mesh " + q(tmp / "seq" / "mesh.ply") + " --truth " + q(tmp / "exact") +
      " --query-points 2000 --truth-points 300 --views 1 --octomap-every 3 --json --out " + q(tmp / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out).at("query");
  EXPECT_EQ(j["frames"], 12);
  EXPECT_EQ(j["octomap_frames"], 4);
  for (const char* key : {"vdmap", "octomap_005", "octomap_002"}) {
    EXPECT_GT(j["speed"][key]["classify_per_s"].get<double>(), 0.0) << key;
    // Each method's memory beside its speed.
    EXPECT_GT(j["speed"][key]["memory_bytes"].get<std::size_t>(), 0u) << key;
    const auto& a = j["accuracy"][key];
    // Every set is scored: the shares of each add up to one.
    for (const char* set : {"O", "F", "F_near", "U"})
      EXPECT_NEAR(a[set]["occupied"].get<double>() + a[set]["free"].get<double>() + a[set]["unknown"].get<double>(),
                  1.0, 1e-4)
          << key << " " << set;
    // Any of these maps tells most of the room's free and occupied points from the unknown.
    EXPECT_GT(a["balanced_accuracy"].get<double>(), 0.6) << key;
    EXPECT_GT(a["memory_mb"].get<double>(), 0.0) << key;
  }
  EXPECT_GT(j["speed"]["vdmap"]["view_ms"].get<double>(), 0.0);
  EXPECT_GT(j["speed"]["vdmap"]["kept_cell_bytes"].get<std::size_t>(), 0u);
  EXPECT_GT(j["speed"]["octomap_002"]["memory_ratio_to_vdmap"].get<double>(), 0.0);
  EXPECT_GT(j["speed"]["octomap_002"]["distance_index_bytes"].get<std::size_t>(), 0u);
  // vdmap alone: every conflict rule's classes, the distance halves, rays, memory by part.
  const auto& v = j.at("vdmap");
  for (const char* rule : {"occupied", "recent", "precise"}) {
    const auto& r = v.at("classify_by_rule").at(rule);
    EXPECT_GT(r.at("classify_per_s").get<double>(), 0.0) << rule;
    EXPECT_NEAR(r.at("occupied").get<double>() + r.at("free").get<double>() + r.at("unknown").get<double>(), 1.0, 1e-4)
        << rule;
  }
  EXPECT_GT(v.at("distance_near_per_s").get<double>(), 0.0);
  EXPECT_GT(v.at("distance_uniform_per_s").get<double>(), 0.0);
  EXPECT_EQ(v.at("rays"), 640 * 480);
  EXPECT_EQ(v.at("view_rays_differ"), 0) << "castView answers as castRays on its pixel rays";
  const auto& bytes = v.at("memory_bytes");
  EXPECT_EQ(bytes.at("total"), j["speed"]["vdmap"]["memory_bytes"]);
  EXPECT_GT(bytes.at("keyframe_views").get<std::size_t>(), 0u);
  EXPECT_GT(bytes.at("surface").get<std::size_t>(), 0u);
  EXPECT_GT(bytes.at("frames").get<std::size_t>(), 0u);
  EXPECT_GE(bytes.at("total").get<std::size_t>(), bytes.at("keyframe_views").get<std::size_t>() +
                                                      bytes.at("frames").get<std::size_t>() +
                                                      bytes.at("surface").get<std::size_t>());
  // The held-out points of the frames' own depth: every method's shares add up to one, and the
  // causes of vdmap's surface points not called occupied add up to those points.
  const auto& held = j.at("held_out");
  for (const char* key : {"vdmap", "octomap_005", "octomap_002"})
    for (const char* set : {"surface", "front_2cm", "front_5cm", "half_way"}) {
      const auto& h = held.at(key).at(set);
      EXPECT_EQ(h.at("points"), 12 * 200) << key << " " << set;
      EXPECT_NEAR(h.at("occupied").get<double>() + h.at("free").get<double>() + h.at("unknown").get<double>(), 1.0,
                  1e-4)
          << key << " " << set;
    }
  EXPECT_GT(held["vdmap"]["surface"]["occupied"].get<double>(), 0.9);
  EXPECT_GT(held["vdmap"]["half_way"]["free"].get<double>(), 0.5);
  std::size_t misses = 0;
  for (const auto& [cause, n] : held.at("vdmap_surface_misses").items()) misses += n.get<std::size_t>();
  EXPECT_NEAR(static_cast<double>(misses) / 2400.0, 1.0 - held["vdmap"]["surface"]["occupied"].get<double>(), 1e-3);
  EXPECT_EQ(j["accuracy"]["sets"]["occupied"], 300);
  EXPECT_EQ(j["accuracy"]["sets"]["free_near"], 150);
  const std::string md = readFile(tmp / "out" / "bench.md");
  for (const char* figure :
       {"bal.acc", "conflict rule", "near surfaces", "castRays", "keyframe views", "surface index"})
    EXPECT_NE(md.find(figure), std::string::npos) << figure;
}

TEST(QueryBench, RefusesATruthOfOtherFrames) {
  TempDir tmp;
  ASSERT_EQ(runVdmap("synth --builtin --builtin-frames 6 --out " + q(tmp / "seq")).exit_code, 0);
  ASSERT_EQ(runVdmap("synth --builtin --builtin-frames 5 --noise none --out " + q(tmp / "exact")).exit_code, 0);
  const RunResult r = runVdmap("bench " + q(tmp / "seq") + " --query --mesh " + q(tmp / "seq" / "mesh.ply") +
                               " --truth " + q(tmp / "exact") + " --out " + q(tmp / "out"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--truth"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(tmp / "out" / "bench.json"));
}

// --no-octomap: vdmap alone, no OctoMap built or named.
TEST(QueryBench, WithoutOctomapReportsVdmapAlone) {
  TempDir tmp;
  ASSERT_EQ(runVdmap("synth --builtin --builtin-frames 3 --out " + q(tmp / "seq")).exit_code, 0);
  const RunResult r = runVdmap("bench " + q(tmp / "seq") +
                               " --query --no-octomap --query-points 200 --views 1 --json --out " + q(tmp / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out).at("query");
  EXPECT_EQ(j["octomap_frames"], 0);
  EXPECT_GT(j["speed"]["vdmap"]["classify_per_s"].get<double>(), 0.0);
  EXPECT_FALSE(j["speed"].contains("octomap_002"));
  const std::string md = readFile(tmp / "out" / "bench.md");
  EXPECT_NE(md.find("no OctoMap (--no-octomap)"), std::string::npos) << md;
  EXPECT_EQ(md.find("OctoMap 0.02 m"), std::string::npos) << md;
}

}  // namespace
}  // namespace vdmap
