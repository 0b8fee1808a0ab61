// Every kind of sequence maps as the TUM folder of the same frames (the same keyframes and
// ellipsoids, up to float rounding), and `vdmap info` says which kind it found and why.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>

#include <nlohmann/json.hpp>

#include "mapping/files/ply_reader.h"
#include "tests/support/layouts.h"
#include "tests/support/ros1_bag_writer.h"
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
nlohmann::json mapStats(const fs::path& seq, int frames, const fs::path& out, const std::string& options = "") {
  const test::RunResult r = runVdmap("map '" + seq.string() + "' --frames 0:" + std::to_string(frames) + " " + options +
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

// The RealSense recorder's sample: its one colour frame is 0.10 s from the first depth frame.
// Refused in one line that names --rgb-window; with it, that frame maps (tracked: no poses).
TEST(SequenceKinds, RealSenseBagMapsWithAWiderColourWindow) {
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  const fs::path bag = bags / "realsense-d400-single-depth-color.bag";
  const test::TempDir dir;
  const test::RunResult refused = runVdmap("map '" + bag.string() + "' --out '" + (dir / "a").string() + "'");
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
  EXPECT_NE(refused.err.find("no usable frames"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--rgb-window"), std::string::npos) << refused.err;
  const nlohmann::json j = mapStats(bag, 2, dir / "b", "--rgb-window 0.2");
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["frames_mapped"], 1);
  EXPECT_EQ(j["poses"], "track");
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

// --- A recording's bad input, at the command line ---------------------------------------------

// `vdmap map` of `recording` written as rec.bag: its result, and whether the output folder holds
// anything.
struct MapRun {
  test::RunResult r;
  bool wrote = false;
};
MapRun mapRecording(const test::TinyRecording& recording, const std::string& options = "") {
  const test::TempDir dir;
  test::writeText(dir / "rec.bag", recording.write());
  MapRun run;
  run.r = runVdmap("map '" + (dir / "rec.bag").string() + "' " + options + " --out '" + (dir / "out").string() + "'");
  run.wrote = fs::exists(dir / "out") && !fs::is_empty(dir / "out");
  return run;
}

// Exit 1, one line naming the file and `what`, nothing written.
void expectRefused(const MapRun& run, const std::string& what) {
  EXPECT_EQ(run.r.exit_code, 1) << run.r.err;
  EXPECT_EQ(std::count(run.r.err.begin(), run.r.err.end(), '\n'), 1) << run.r.err;
  EXPECT_NE(run.r.err.find("rec.bag"), std::string::npos) << run.r.err;
  EXPECT_NE(run.r.err.find(what), std::string::npos) << run.r.err;
  EXPECT_FALSE(run.wrote);
}

TEST(RecordingBadInput, TheTinyRecordingMaps) {  // so that no case below fails by accident
  const MapRun run = mapRecording(test::TinyRecording());
  EXPECT_EQ(run.r.exit_code, 0) << run.r.err;
  EXPECT_TRUE(run.wrote);
}

TEST(RecordingBadInput, AnImageOfAnotherSizeThanItsCameraInfo) {
  test::TinyRecording recording;
  const std::size_t last = recording.on("/camera/depth/image").back();
  recording.messages[last].bytes =
      test::imageMessage(100.2, "camera", 16, 12, "16UC1", 32, std::vector<std::uint8_t>(16 * 12 * 2, 0));
  expectRefused(mapRecording(recording), "image is 16x12 but its camera is 32x24");
}

TEST(RecordingBadInput, HeaderStampsGoingBackwards) {
  test::TinyRecording recording;
  const std::vector<std::size_t> depth = recording.on("/camera/depth/image");
  recording.messages[depth[2]].bytes =
      test::imageMessage(100.05, "camera", 32, 24, "16UC1", 64, std::vector<std::uint8_t>(32 * 24 * 2, 0));
  expectRefused(mapRecording(recording), "header stamps go backwards");
}

TEST(RecordingBadInput, AColourEncodingVdmapDoesNotRead) {
  test::TinyRecording recording;
  const std::vector<std::size_t> rgb = recording.on("/camera/rgb/image_color");
  for (std::size_t k = 0; k < rgb.size(); ++k)
    recording.messages[rgb[k]].bytes = test::imageMessage(100.0 + 0.1 * static_cast<double>(k), "camera", 32, 24,
                                                          "yuv422", 64, std::vector<std::uint8_t>(32 * 24 * 2, 0));
  expectRefused(mapRecording(recording), "colour encoding 'yuv422' is not one vdmap reads");
}

TEST(RecordingBadInput, TfWithoutAPathBetweenThePoseFrames) {
  test::TinyRecording recording;
  expectRefused(mapRecording(recording, "--pose-frames world:elsewhere"), "tf has no frame 'elsewhere'");
  recording.messages.push_back({4, 100'000'000'000, test::tfMessage(100.0, "odom", "base", 0, 0, 0)});
  std::stable_sort(recording.messages.begin(), recording.messages.end(),
                   [](const auto& a, const auto& b) { return a.time_ns < b.time_ns; });
  expectRefused(mapRecording(recording, "--pose-frames odom:camera"), "tf has frames: ");
}

// Without camera_info the camera is a preset, named with the reason (as for folders); an image
// of another size than the preset's is refused saying so.
TEST(RecordingBadInput, NoCameraInfoMapsWithAStatedGuess) {
  auto without_info = [](test::TinyRecording recording) {
    std::erase_if(recording.messages, [](const test::BagMessage& m) { return m.conn == 2 || m.conn == 3; });
    return recording;
  };
  expectRefused(mapRecording(without_info(test::TinyRecording(3, 32, 24))),
                "32x24 images but the camera (preset tum-default (the recording has no camera_info; --camera PRESET "
                "sets it)) is 640x480");
  const test::TempDir dir;
  test::writeText(dir / "rec.bag", without_info(test::TinyRecording(3, 640, 480)).write());
  const test::RunResult info = runVdmap("info '" + (dir / "rec.bag").string() + "'");
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("preset tum-default (the recording has no camera_info"), std::string::npos) << info.out;
  const test::RunResult map =
      runVdmap("map '" + (dir / "rec.bag").string() + "' --out '" + (dir / "out").string() + "'");
  EXPECT_EQ(map.exit_code, 0) << map.err;
  EXPECT_TRUE(fs::exists(dir / "out" / "global_ellipsoids.ply"));
}

}  // namespace
}  // namespace vdmap
