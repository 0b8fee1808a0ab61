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
  for (const char* key : {"renderer", "upload_ms", "frame_ms_median", "frame_ms_min"}) EXPECT_TRUE(j.contains(key)) << key;
}

TEST(RenderBench, EllipsoidsRefusesBadInput) {
  expectOneLineError(runVdmap("bench --ellipsoids 0"), "--ellipsoids");
  expectOneLineError(runVdmap("bench --ellipsoids 10 --frames 3"), "--ellipsoids excludes --frames");
  expectOneLineError(runVdmap("bench --ellipsoids 10 --size 0x5"), "--size");
}

}  // namespace
}  // namespace vdmap
