// Every kind of sequence maps as the TUM folder of the same frames (same map files, byte for
// byte), and `vdmap info` says which kind it found and why.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "mapping/files/ply_reader.h"
#include "tests/support/layouts.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;
using test::runVdmap;

// `vdmap map` of `seq` (frames 0:N) into `out`; the global map's bytes.
std::string mapBytes(const fs::path& seq, int frames, const fs::path& out) {
  const test::RunResult r = runVdmap("map '" + seq.string() + "' --frames 0:" + std::to_string(frames) + " --out '" +
                                     out.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return test::readFile(out / "global_ellipsoids.ply");
}

void expectSameMap(SequenceKind kind, const char* data, int frames, const std::string& kind_name) {
  VDMAP_REQUIRE_SHARED_DATA(tum, data);
  const test::TempDir dir;
  test::writeDataSetLayout(kind, tum, dir / "layout", {.frames = frames});
  const test::RunResult info = runVdmap("info '" + (dir / "layout").string() + "' --json");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["kind"], kind_name);
  const std::string a = mapBytes(tum, frames, dir / "tum_map");
  const std::string b = mapBytes(dir / "layout", frames, dir / "layout_map");
  ASSERT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << kind_name << ": the map differs from the TUM folder's (" << a.size() << " vs " << b.size()
                      << " bytes)";
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
void expectRecordingMapsAsTheFolder(const char* recording, double max_mean_difference_m) {
  VDMAP_REQUIRE_SHARED_DATA(tum, "7scenes-redkitchen");
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  const test::TempDir dir;
  test::writeTumSubset(tum, dir / "7scenes-every-5th", 0, 150, 5);
  auto map = [&](const fs::path& seq, const std::string& out) {
    const test::RunResult r = runVdmap("map '" + seq.string() + "' --camera 7scenes --json --out '" +
                                       (dir / out).string() + "'");
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
  ASSERT_EQ(x.size(), y.size());
  float worst = 0;
  for (std::size_t i = 0; i < x.size(); ++i) worst = std::max(worst, (x[i].mean - y[i].mean).cwiseAbs().maxCoeff());
  EXPECT_LE(worst, max_mean_difference_m) << recording;
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
  EXPECT_NE(r.out.find("kind       7-Scenes sequence folder (it holds frame-NNNNNN.depth.png files)"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("all with poses, from frame-NNNNNN.pose.txt"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace vdmap
