// Every kind of sequence maps as the TUM folder of the same frames (the same keyframes and
// ellipsoids, up to float rounding), and `vdmap info` says which kind it found and why.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>

#include <nlohmann/json.hpp>

#include "mapping/files/ply_reader.h"
#include "tests/support/layouts.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;
using test::runVdmap;

// The share of `x`'s ellipsoids with one in `y` whose mean is within `tolerance_m`: maps equal
// up to float rounding (a pose read through another route differs in its last bits, which can
// tip a cell or a filter threshold here and there).
double matchedShare(const std::vector<EllipsoidRecord>& x, const std::vector<EllipsoidRecord>& y, float tolerance_m) {
  constexpr float kCell = 1e-4f;
  auto key = [&](const Eigen::Vector3f& p) {
    return std::array<long, 3>{std::lround(p.x() / kCell), std::lround(p.y() / kCell), std::lround(p.z() / kCell)};
  };
  std::map<std::array<long, 3>, std::vector<Eigen::Vector3f>> grid;
  for (const EllipsoidRecord& e : y) grid[key(e.mean)].push_back(e.mean);
  std::size_t matched = 0;
  for (const EllipsoidRecord& e : x) {
    const auto k = key(e.mean);
    bool found = false;
    for (long dx = -1; dx <= 1 && !found; ++dx)
      for (long dy = -1; dy <= 1 && !found; ++dy)
        for (long dz = -1; dz <= 1 && !found; ++dz) {
          auto it = grid.find({k[0] + dx, k[1] + dy, k[2] + dz});
          if (it == grid.end()) continue;
          for (const Eigen::Vector3f& m : it->second)
            found = found || (m - e.mean).cwiseAbs().maxCoeff() <= tolerance_m;
        }
    matched += found;
  }
  return x.empty() ? 1.0 : static_cast<double>(matched) / static_cast<double>(x.size());
}

// `vdmap map` of `seq` (frames 0:N) into `out`; its stats.json.
nlohmann::json mapStats(const fs::path& seq, int frames, const fs::path& out) {
  const test::RunResult r = runVdmap("map '" + seq.string() + "' --frames 0:" + std::to_string(frames) +
                                     " --json --out '" + out.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

void expectSameMap(SequenceKind kind, const char* data, int frames, const std::string& kind_name) {
  VDMAP_REQUIRE_SHARED_DATA(tum, data);
  const test::TempDir dir;
  test::writeDataSetLayout(kind, tum, dir / "layout", {.frames = frames});
  const test::RunResult info = runVdmap("info '" + (dir / "layout").string() + "' --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["kind"], kind_name);
  const nlohmann::json a = mapStats(tum, frames, dir / "tum_map");
  const nlohmann::json b = mapStats(dir / "layout", frames, dir / "layout_map");
  ASSERT_FALSE(a.is_null() || b.is_null());
  EXPECT_EQ(a["keyframes"], b["keyframes"]) << kind_name;
  const auto x = readPlyEllipsoids(dir / "tum_map" / "global_ellipsoids.ply");
  const auto y = readPlyEllipsoids(dir / "layout_map" / "global_ellipsoids.ply");
  ASSERT_GT(x.size(), 1000u);
  EXPECT_NEAR(static_cast<double>(y.size()), static_cast<double>(x.size()), 1e-3 * x.size()) << kind_name;
  EXPECT_GE(matchedShare(x, y, 1e-5f), 0.999) << kind_name;
  EXPECT_GE(matchedShare(y, x, 1e-5f), 0.999) << kind_name;
}

TEST(SequenceKinds, SevenScenesMapsAsTheTumFolder) {
  expectSameMap(SequenceKind::kSevenScenes, "7scenes-redkitchen", 30, "7-Scenes sequence folder");
}

TEST(SequenceKinds, ReplicaMapsAsTheTumFolder) {
  expectSameMap(SequenceKind::kReplica, "replica-office0", 4, "Replica scene as NICE-SLAM renders it");
}

TEST(SequenceKinds, ScanNetMapsAsTheTumFolder) {
  expectSameMap(SequenceKind::kScanNet, "7scenes-redkitchen", 30, "ScanNet export");
}

// A recording of every 5th of the folder's frames 0-149, mapped with its tf poses, gives the map
// of a folder of the same frames: the same keyframes, ellipsoids equal to float rounding.
void expectRecordingMapsAsTheFolder(const char* recording, float max_mean_difference_m) {
  VDMAP_REQUIRE_SHARED_DATA(tum, "7scenes-redkitchen");
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  const test::TempDir dir;
  test::writeTumSubset(tum, dir / "7scenes-every-5th", 0, 150, 5);
  auto map = [&](const fs::path& seq, const std::string& out) {
    const test::RunResult r =
        runVdmap("map '" + seq.string() + "' --camera 7scenes --json --out '" + (dir / out).string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
  };
  const nlohmann::json a = map(dir / "7scenes-every-5th", "folder_map");
  const nlohmann::json b = map(bags / recording, "recording_map");
  ASSERT_FALSE(a.is_null() || b.is_null());
  EXPECT_EQ(a["frames_mapped"], 30);
  EXPECT_EQ(a["keyframes"], b["keyframes"]);
  const auto x = readPlyEllipsoids(dir / "folder_map" / "global_ellipsoids.ply");
  const auto y = readPlyEllipsoids(dir / "recording_map" / "global_ellipsoids.ply");
  ASSERT_GT(x.size(), 1000u);
  EXPECT_NEAR(static_cast<double>(y.size()), static_cast<double>(x.size()), 1e-3 * x.size()) << recording;
  EXPECT_GE(matchedShare(x, y, max_mean_difference_m), 0.999) << recording;
  EXPECT_GE(matchedShare(y, x, max_mean_difference_m), 0.999) << recording;
}

TEST(SequenceKinds, Ros1BagMapsAsTheFolderOfItsFrames) {
  expectRecordingMapsAsTheFolder("7scenes-redkitchen-tum-layout.bag", 1e-5);
}

TEST(SequenceKinds, McapMapsAsTheFolderOfItsFrames) {
  expectRecordingMapsAsTheFolder("7scenes-redkitchen-realsense-layout.mcap", 1e-5);
}

TEST(SequenceKinds, InfoSaysTheKindAndWhy) {
  const test::TempDir dir;
  test::writeTinySequence(dir / "tum", 3);
  test::writeDataSetLayout(SequenceKind::kSevenScenes, dir / "tum", dir / "seq");
  const test::RunResult r = runVdmap("info '" + (dir / "seq").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("kind       7-Scenes sequence folder (it holds frame-NNNNNN.depth.png files)"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("all with poses, from frame-NNNNNN.pose.txt"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace vdmap
