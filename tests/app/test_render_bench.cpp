// The modes of `vdmap bench` that time the renderer and the 3-D view, end to end through the
// built binary: each names its figures (text and JSON) and refuses bad input in one line. No
// time is asserted: the figures are whatever this machine measures.
#include <algorithm>
#include <filesystem>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/test_util.h"

namespace vdmap {
namespace {

using test::RunResult;
using test::runVdmap;
using test::TempDir;

std::string quoted(const std::filesystem::path& p) { return std::string("'").append(p.string()).append("'"); }

// stderr holds exactly one line that names `what`.
void expectOneLineError(const RunResult& r, const std::string& what) {
  EXPECT_NE(r.exit_code, 0);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
}

TEST(RenderBench, EllipsoidsNamesTheUploadAndTheMedianFrame) {
  RunResult r = runVdmap("bench --ellipsoids 200 --size 64x48");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* figure : {"renderer", "200 instanced", "64x48", "upload", "median of 5 frames"})
    EXPECT_NE(r.out.find(figure), std::string::npos) << figure << " in\n" << r.out;
  r = runVdmap("bench --ellipsoids 200 --size 64x48 --points-below 0 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out).at("ellipsoids");
  EXPECT_EQ(j.at("count"), 200);
  EXPECT_EQ(j.at("points_below_px"), 0.0);
  for (const char* key : {"renderer", "upload_ms", "frame_ms_median", "frame_ms_min"})
    EXPECT_TRUE(j.contains(key)) << key;
}

TEST(RenderBench, EllipsoidsRefusesBadInput) {
  expectOneLineError(runVdmap("bench --ellipsoids 0"), "--ellipsoids");
  expectOneLineError(runVdmap("bench --ellipsoids 10 --frames 3"), "--ellipsoids excludes --frames");
  expectOneLineError(runVdmap("bench --ellipsoids 10 --size 0x5"), "--size");
}

// A session of the built-in room's first 4 frames, made once for the tests that time a map.
class RenderBenchOnASession : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    ASSERT_EQ(runVdmap("synth --builtin --builtin-frames 4 --out " + quoted(*dir_ / "seq")).exit_code, 0);
    const RunResult r = runVdmap("map " + quoted(*dir_ / "seq") + " --out " + quoted(*dir_ / "map") + " --save " +
                                 quoted(*dir_ / "s.vdmap"));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { delete dir_; }
  static std::string session() { return quoted(*dir_ / "s.vdmap"); }
  static TempDir* dir_;
};
TempDir* RenderBenchOnASession::dir_ = nullptr;

TEST_F(RenderBenchOnASession, ViewNamesEveryPassOfTheOrbit) {
  TempDir tmp;
  const std::string view = "bench " + session() + " --view --steps 2 --fast-budget 100 --size 64x48";
  RunResult r = runVdmap(view + " --png " + quoted(tmp / "v"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* figure :
       {"map upload", "LOD order", "full:", "mesh selection", "fast:", "budget 100", "settle", "cached frame"})
    EXPECT_NE(r.out.find(figure), std::string::npos) << figure << " in\n" << r.out;
  EXPECT_TRUE(std::filesystem::exists(tmp / "v_full.png"));
  EXPECT_TRUE(std::filesystem::exists(tmp / "v_fast_100.png"));
  r = runVdmap(view + " --replicate 2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out).at("view");
  EXPECT_EQ(j.at("replicate"), 2);
  EXPECT_EQ(j.at("width"), 64);
  EXPECT_GT(j.at("ellipsoids").get<int>(), 0);
  for (const char* key : {"ms", "cpu_ms", "select_ms", "mesh_instances", "splat_instances"})
    EXPECT_TRUE(j.at("full").contains(key)) << key;
  ASSERT_EQ(j.at("fast").size(), 1u);
  EXPECT_EQ(j.at("fast")[0].at("budget"), 100);
  for (const char* key : {"upload_ms", "lod_order_ms", "settle_ms", "cached_ms"}) EXPECT_TRUE(j.contains(key)) << key;
}

TEST_F(RenderBenchOnASession, ViewRefusesWhatIsNoMap) {
  TempDir tmp;
  test::writeText(tmp / "notes.txt", "not a map\n");
  expectOneLineError(runVdmap("bench " + quoted(tmp / "notes.txt") + " --view"),
                     "vdmap bench: error: " + (tmp / "notes.txt").string() + ": ");
  expectOneLineError(runVdmap("bench --view"), "SEQ");
  expectOneLineError(runVdmap("bench " + session() + " --steps 3"), "--steps requires --view");
  expectOneLineError(runVdmap("bench " + session() + " --view --frames 3"), "--view excludes --frames");
}

TEST_F(RenderBenchOnASession, SuiteOfASessionNamesEveryStage) {
  const RunResult r = runVdmap("bench --suite " + session() + " --runs 1 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out).at("suite");
  EXPECT_EQ(j.at("views"), 20);
  EXPECT_EQ(j.at("differ"), 0) << "the goldens were written by the same process";
  EXPECT_EQ(j.at("maps_loaded"), 1);
  for (const char* key : {"decoded_s", "lazy_s"}) EXPECT_TRUE(j.at("session_load").contains(key)) << key;
  for (const char* run : {"update", "compare"})
    for (const char* key :
         {"validate_s", "load_s", "context_s", "build_s", "render_s_per_view", "check_s_per_view", "total_s"})
      EXPECT_TRUE(j.at(run).contains(key)) << run << " " << key;
}

TEST_F(RenderBenchOnASession, SuiteFileIsTimedAsItIs) {
  TempDir tmp;
  test::writeText(tmp / "views.yaml", "version: 1\nmaps: {room: " + quoted(*dir_ / "s.vdmap") +
                                          "}\nviews:\n  - {name: a, map: room, size: 64x48}\n"
                                          "  - {name: b, map: room, size: 64x48, orbit: \"30,20\"}\n");
  ASSERT_EQ(runVdmap("render --suite " + quoted(tmp / "views.yaml") + " --update").exit_code, 0);
  const RunResult r = runVdmap("bench --suite " + quoted(tmp / "views.yaml") + " --runs 2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* figure :
       {"compare  validate", "context", "per view: render", "medians of 2 runs", "2 views, 0 differ", "maps loaded 1"})
    EXPECT_NE(r.out.find(figure), std::string::npos) << figure << " in\n" << r.out;
  EXPECT_EQ(r.out.find("update"), std::string::npos) << "a given suite's goldens are not rewritten";
}

TEST_F(RenderBenchOnASession, SuiteRefusesWhatIsNoSuite) {
  TempDir tmp;
  test::writeText(tmp / "notes.txt", "not a suite\n");
  expectOneLineError(runVdmap("bench --suite " + quoted(tmp / "notes.txt")), (tmp / "notes.txt").string() + ": ");
  // A suite whose goldens were never made is refused before anything is timed.
  test::writeText(tmp / "views.yaml",
                  "version: 1\nmaps: {room: " + quoted(*dir_ / "s.vdmap") + "}\nviews:\n  - {name: a, map: room}\n");
  expectOneLineError(runVdmap("bench --suite " + quoted(tmp / "views.yaml")), "golden");
  expectOneLineError(runVdmap("bench --suite " + session() + " " + session()), "--suite excludes SEQ");
  expectOneLineError(runVdmap("bench " + session() + " --runs 2"), "--runs requires --suite");
}

}  // namespace
}  // namespace vdmap
