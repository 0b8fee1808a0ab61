// The data sets' own layouts read as the TUM folder of the same frames: same stamps, poses,
// camera and pixels (the map is then the same, tests/app/test_sequence_kinds.cpp); and each
// layout's bad input is one line naming the file.
#include <gtest/gtest.h>

#include "mapping/core/error.h"
#include "mapping/sequence/sequence.h"
#include "tests/support/layouts.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;

// The frames of `layout` equal those of `tum`: stamps, poses (to the rounding of a matrix read
// back through a quaternion), camera and every pixel.
void expectSameFrames(const fs::path& tum, const fs::path& layout, SequenceKind kind, int frames) {
  SequenceOptions options;
  options.frames = {0, frames};
  const Sequence a = Sequence::open(tum, options);
  const Sequence b = Sequence::open(layout, options);
  EXPECT_EQ(b.kind(), kind) << sequenceKindName(b.kind());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(b.listedDepthFrames(), frames);
  EXPECT_TRUE(a.camera() == b.camera()) << b.cameraSource();
  EXPECT_EQ(a.colourCamera().has_value(), b.colourCamera().has_value());
  for (std::size_t i = 0; i < a.size(); ++i) {
    const FrameEntry& x = a.entries()[i];
    const FrameEntry& y = b.entries()[i];
    EXPECT_EQ(x.index, y.index);
    EXPECT_NEAR(x.t_depth, y.t_depth, 1e-6);  // TUM lists keep microseconds
    EXPECT_TRUE(y.has_pose);
    EXPECT_LT((x.T_W_C.matrix() - y.T_W_C.matrix()).cwiseAbs().maxCoeff(), 1e-12) << "frame " << i << "\n"
                                                                                  << x.T_W_C.matrix() << "\n"
                                                                                  << y.T_W_C.matrix();
    const RgbdFrame fx = a.load(i), fy = b.load(i);
    EXPECT_EQ(cv::norm(fx.depth, fy.depth, cv::NORM_INF), 0) << "depth of frame " << i;
    EXPECT_EQ(cv::norm(fx.rgb, fy.rgb, cv::NORM_INF), 0) << "colour of frame " << i;
  }
}

TEST(SequenceLayouts, SevenScenesReadsAsTheTumFolder) {
  VDMAP_REQUIRE_SHARED_DATA(tum, "7scenes-redkitchen");
  const test::TempDir dir;
  test::writeDataSetLayout(SequenceKind::kSevenScenes, tum, dir.path() / "seq-01", {.frames = 8});
  expectSameFrames(tum, dir.path() / "seq-01", SequenceKind::kSevenScenes, 8);
  // The original's colour is PNG.
  test::writeDataSetLayout(SequenceKind::kSevenScenes, tum, dir.path() / "seq-02", {.frames = 3, .colour_png = true});
  expectSameFrames(tum, dir.path() / "seq-02", SequenceKind::kSevenScenes, 3);
}

TEST(SequenceLayouts, ReplicaReadsAsTheTumFolder) {
  VDMAP_REQUIRE_SHARED_DATA(tum, "replica-office0");
  const test::TempDir dir;
  test::writeDataSetLayout(SequenceKind::kReplica, tum, dir.path() / "office0", {.frames = 4});
  expectSameFrames(tum, dir.path() / "office0", SequenceKind::kReplica, 4);
}

TEST(SequenceLayouts, ScanNetReadsAsTheTumFolderWithItsColourCamera) {
  VDMAP_REQUIRE_SHARED_DATA(tum, "7scenes-redkitchen");
  const test::TempDir dir;
  test::writeDataSetLayout(SequenceKind::kScanNet, tum, dir.path() / "scene0000_00", {.frames = 5});
  expectSameFrames(tum, dir.path() / "scene0000_00", SequenceKind::kScanNet, 5);
  EXPECT_TRUE(Sequence::open(dir.path() / "scene0000_00").colourCamera().has_value());
}

// Built in code, so it always runs: a 7-Scenes folder of the tiny sequence's frames.
fs::path tinySevenScenes(const fs::path& dir) {
  test::writeTinySequence(dir / "tum", 3);
  test::writeDataSetLayout(SequenceKind::kSevenScenes, dir / "tum", dir / "seq");
  return dir / "seq";
}

std::string openError(const fs::path& path, SequenceOptions options = {}) {
  try {
    Sequence::open(path, options);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(opened)";
}

TEST(SequenceLayouts, RecognisedByContentWithTheReason) {
  const test::TempDir dir;
  const fs::path seq = tinySevenScenes(dir.path());
  const auto kind = recogniseSequence(seq);
  ASSERT_TRUE(kind);
  EXPECT_EQ(kind->first, SequenceKind::kSevenScenes);
  EXPECT_EQ(kind->second, "holds frame-NNNNNN.depth.png files");
  EXPECT_EQ(recogniseSequence(dir.path() / "tum")->first, SequenceKind::kTumFolder);
  fs::create_directories(dir.path() / "empty");
  EXPECT_FALSE(recogniseSequence(dir.path() / "empty"));
  EXPECT_NE(openError(dir.path() / "empty").find("is not a sequence vdmap reads: expected a TUM RGB-D folder"),
            std::string::npos);
  test::writeText(dir.path() / "notes.txt", "hello");
  EXPECT_NE(openError(dir.path() / "notes.txt").find("is neither a sequence folder nor a recording"),
            std::string::npos);
}

TEST(SequenceLayouts, BadPoseFilesNameTheFile) {
  const test::TempDir dir;
  const fs::path seq = tinySevenScenes(dir.path());
  const fs::path pose = seq / "frame-000001.pose.txt";
  test::writeText(pose, "1 0 0 0\n0 1 0 0\n0 0 1 0\n");
  EXPECT_EQ(openError(seq), pose.string() + ": holds 12 numbers; expected 16, a 4x4 camera-to-world matrix row by row");
  test::writeText(pose, "1 0 0 0\n0 1 0 0\n0 0 1 x\n0 0 0 1\n");
  EXPECT_NE(openError(seq).find(pose.string() + ": expected a number, found 'x'"), std::string::npos);
  test::writeText(pose, "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_EQ(openError(seq), pose.string() + ": the 4x4 camera-to-world matrix does not hold a rotation");
  // ScanNet's lost frames (-inf) are frames without a pose: dropped under --poses gt, kept for tracking.
  test::writeText(pose, "-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n-inf -inf -inf -inf\n");
  const Sequence gt = Sequence::open(seq);
  EXPECT_EQ(gt.size(), 2u);
  EXPECT_EQ(gt.dropped().no_pose, 1);
  SequenceOptions track;
  track.poses = SequenceOptions::Poses::kOptional;
  const Sequence tracked = Sequence::open(seq, track);
  EXPECT_EQ(tracked.size(), 3u);
  EXPECT_FALSE(tracked.entries()[1].has_pose);
}

TEST(SequenceLayouts, PosesAreOptionalWhenNoneAreRecorded) {
  const test::TempDir dir;
  const fs::path seq = tinySevenScenes(dir.path());
  for (int i = 0; i < 3; ++i) fs::remove(seq / ("frame-00000" + std::to_string(i) + ".pose.txt"));
  EXPECT_NE(openError(seq).find("--poses gt needs ground-truth poses"), std::string::npos);
  SequenceOptions automatic;
  automatic.poses = SequenceOptions::Poses::kAuto;
  const Sequence s = Sequence::open(seq, automatic);
  EXPECT_FALSE(s.hasGroundTruth());
  EXPECT_EQ(s.size(), 3u);
}

}  // namespace
}  // namespace vdmap
