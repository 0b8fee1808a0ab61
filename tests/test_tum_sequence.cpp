#include <fstream>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "mapping/core/error.h"
#include "mapping/io/frame_prefetcher.h"
#include "mapping/io/tum_sequence.h"
#include "tests/test_util.h"

namespace vdmap {
namespace {

using test::TempDir;
using test::writeText;

// Expects TumSequence::open (or load of frame 0) to throw an InputError whose one-line message
// contains every fragment (the file, the line, what was expected).
void expectOpenError(const std::filesystem::path& dir, std::initializer_list<std::string> fragments,
                     bool load_first = false) {
  try {
    const TumSequence seq = TumSequence::open(dir);
    if (load_first) seq.load(0);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << "error must be one line: " << what;
    for (const std::string& f : fragments) EXPECT_NE(what.find(f), std::string::npos) << what << " lacks " << f;
  }
}

TEST(TumSequence, OpensTinySequence) {
  TempDir dir;
  test::writeTinySequence(dir.path(), 3);
  const TumSequence seq = TumSequence::open(dir.path());
  ASSERT_EQ(seq.size(), 3u);
  EXPECT_EQ(seq.cameraSource(), "file camera.yaml");
  EXPECT_EQ(seq.camera().width, 64);
  const RgbdFrame f = seq.load(2);
  EXPECT_EQ(f.depth.type(), CV_16UC1);
  EXPECT_EQ(f.rgb.type(), CV_8UC3);
  EXPECT_NEAR(f.T_W_C.translation().x(), 0.02, 1e-12);
}

TEST(TumSequence, AssociatesNearestRgbAndInterpolatesPose) {
  TempDir dir;
  test::writeTinySequence(dir.path(), 3);
  // rgb shifted by 10 ms (within 0.02 s); ground truth only at 0 and 0.1 s with a 90 degree yaw.
  writeText(dir / "rgb.txt", "0.010 rgb/000000.png\n0.043 rgb/000001.png\n0.076 rgb/000002.png\n");
  writeText(dir / "groundtruth.txt", "0.0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0.7071067811865476 0 0.7071067811865476\n");
  const TumSequence seq = TumSequence::open(dir.path());
  ASSERT_EQ(seq.size(), 3u);
  EXPECT_NEAR(seq.entries()[1].t_rgb, 0.043, 1e-12);
  const Transform& T = seq.entries()[1].T_W_C;  // about a third of the way from 0 to 0.1 s
  const double s = seq.entries()[1].t_depth / 0.1;
  EXPECT_NEAR(s, 1.0 / 3.0, 1e-4);
  EXPECT_NEAR(T.translation().x(), s, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(T.linear()).angle(), s * M_PI / 2.0, 1e-9);
}

TEST(TumSequence, DropsFramesWithoutRgbOrPoseAndCountsThem) {
  TempDir dir;
  test::writeTinySequence(dir.path(), 3);
  writeText(dir / "rgb.txt", "0.0 rgb/000000.png\n0.0333 rgb/000001.png\n");  // none near 0.0667
  writeText(dir / "groundtruth.txt", "0.0 0 0 0 0 0 0 1\n0.04 0 0 0 0 0 0 1\n");  // ends before 0.0667
  const TumSequence seq = TumSequence::open(dir.path());
  EXPECT_EQ(seq.size(), 2u);
  EXPECT_EQ(seq.dropped().no_rgb, 1);
  writeText(dir / "rgb.txt", "0.0 rgb/000000.png\n0.0333 rgb/000001.png\n0.0667 rgb/000002.png\n");
  const TumSequence seq2 = TumSequence::open(dir.path());
  EXPECT_EQ(seq2.size(), 2u);
  EXPECT_EQ(seq2.dropped().no_pose, 1);
}

TEST(TumSequence, FrameRangeSelectsDepthListIndices) {
  TempDir dir;
  test::writeTinySequence(dir.path(), 5);
  SequenceOptions options;
  options.frames = parseFrameRange("1:3");
  const TumSequence seq = TumSequence::open(dir.path(), options);
  ASSERT_EQ(seq.size(), 2u);
  EXPECT_EQ(seq.entries()[0].index, 1);
  EXPECT_EQ(seq.dropped().outside_range, 3);
  EXPECT_EQ(parseFrameRange("4:").last, -1);
  EXPECT_EQ(parseFrameRange(":4").first, 0);
  EXPECT_THROW(parseFrameRange("3:1"), std::invalid_argument);
  EXPECT_THROW(parseFrameRange("a:b"), std::invalid_argument);
  options.frames = parseFrameRange("7:");
  EXPECT_THROW(TumSequence::open(dir.path(), options), InputError);
}

TEST(TumSequence, PrefetcherYieldsEveryFrameInOrder) {
  TempDir dir;
  test::writeTinySequence(dir.path(), 6);
  const TumSequence seq = TumSequence::open(dir.path());
  FramePrefetcher prefetch(seq, 2);
  int expected = 0;
  while (auto frame = prefetch.next()) EXPECT_EQ(frame->index, expected++);
  EXPECT_EQ(expected, 6);
}

TEST(TumSequence, PrefetcherRethrowsDecodeErrors) {
  TempDir dir;
  test::writeTinySequence(dir.path(), 3);
  writeText(dir / "depth" / "000001.png", "not a png");
  const TumSequence seq = TumSequence::open(dir.path());
  FramePrefetcher prefetch(seq);
  EXPECT_TRUE(prefetch.next().has_value());
  EXPECT_THROW(prefetch.next(), InputError);
}

// ---- Bad input: each gets a one-line error naming the file (and line) and what was expected.

TEST(TumSequenceBadInput, MissingFolder) {
  expectOpenError("/nonexistent/vdmap-seq", {"/nonexistent/vdmap-seq", "no such sequence folder"});
}

TEST(TumSequenceBadInput, MissingListFiles) {
  for (const char* file : {"rgb.txt", "depth.txt", "groundtruth.txt"}) {
    TempDir dir;
    test::writeTinySequence(dir.path());
    std::filesystem::remove(dir / file);
    expectOpenError(dir.path(), {file, "cannot open"});
  }
}

TEST(TumSequenceBadInput, MalformedLine) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  writeText(dir / "depth.txt", "# header\n0.0 depth/000000.png\n0.0333 depth/000001.png extra\n");
  expectOpenError(dir.path(), {"depth.txt:3", "expected 'timestamp path'"});
  writeText(dir / "depth.txt", "0.0 depth/000000.png\nabc depth/000001.png\n");
  expectOpenError(dir.path(), {"depth.txt:2", "expected a number", "'abc'"});
}

TEST(TumSequenceBadInput, NonMonotonicTimestamp) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  writeText(dir / "rgb.txt", "0.0 rgb/000000.png\n0.0667 rgb/000002.png\n0.0333 rgb/000001.png\n");
  expectOpenError(dir.path(), {"rgb.txt:3", "timestamps must increase"});
}

TEST(TumSequenceBadInput, ImagePathDoesNotExist) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  std::filesystem::remove(dir / "rgb" / "000001.png");
  expectOpenError(dir.path(), {"rgb.txt:3", "rgb/000001.png", "does not exist"});
}

TEST(TumSequenceBadInput, CorruptPng) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  writeText(dir / "depth" / "000000.png", "\x89PNG\r\n garbage");
  expectOpenError(dir.path(), {"depth/000000.png", "cannot decode depth image"}, true);
  test::writeTinySequence(dir.path());
  writeText(dir / "rgb" / "000000.png", "garbage");
  expectOpenError(dir.path(), {"rgb/000000.png", "cannot decode colour image"}, true);
}

TEST(TumSequenceBadInput, DepthOfWrongTypeOrSize) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  cv::imwrite((dir / "depth" / "000000.png").string(), cv::Mat(48, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  expectOpenError(dir.path(), {"depth/000000.png", "must be 16-bit single-channel", "8-bit 3-channel"}, true);
  cv::imwrite((dir / "depth" / "000000.png").string(), cv::Mat(24, 32, CV_16UC1, cv::Scalar(1000)));
  expectOpenError(dir.path(), {"depth/000000.png", "is 32x24 but the camera is 64x48"}, true);
}

TEST(TumSequenceBadInput, ZeroNormQuaternion) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  writeText(dir / "groundtruth.txt", "0.0 0 0 0 0 0 0 1\n0.0333 0 0 0 0 0 0 0\n");
  expectOpenError(dir.path(), {"groundtruth.txt:2", "zero norm"});
}

TEST(TumSequenceBadInput, NanInPose) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  writeText(dir / "groundtruth.txt", "# c\n0.0 0 nan 0 0 0 0 1\n");
  expectOpenError(dir.path(), {"groundtruth.txt:2", "ty is not finite"});
}

TEST(TumSequenceBadInput, EmptySequence) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  writeText(dir / "depth.txt", "# nothing here\n");
  expectOpenError(dir.path(), {"depth.txt", "lists no frames"});
  test::writeTinySequence(dir.path());
  writeText(dir / "groundtruth.txt", "100.0 0 0 0 0 0 0 1\n");  // no frame has a pose
  expectOpenError(dir.path(), {"no usable frames", "3 without a ground-truth pose"});
}

TEST(TumSequenceBadInput, CameraFileWithMissingKey) {
  TempDir dir;
  test::writeTinySequence(dir.path());
  writeText(dir / "camera.yaml", "fx: 50\nfy: 50\ncx: 31.5\ndepth_scale: 5000\nwidth: 64\nheight: 48\n");
  expectOpenError(dir.path(), {"camera.yaml", "missing key 'cy'"});
}

// ---- Real data (skipped when ../shared/data is absent).

TEST(TumSequenceRealData, SevenScenesHas500PosedFramesAnd7ScenesCamera) {
  VDMAP_REQUIRE_SHARED_DATA(folder, "7scenes-redkitchen");
  const TumSequence seq = TumSequence::open(folder);
  EXPECT_EQ(seq.size(), 500u);
  EXPECT_EQ(seq.camera().fx, 585.0);
  EXPECT_EQ(seq.camera().depth_scale, 1000.0);
  const RgbdFrame f = seq.load(0);
  EXPECT_EQ(f.depth.cols, 640);
}

TEST(TumSequenceRealData, IclNuimAndReplicaPickTheirCameras) {
  VDMAP_REQUIRE_SHARED_DATA(icl, "icl-nuim-livingroom-5");
  VDMAP_REQUIRE_SHARED_DATA(replica, "replica-office0");
  const TumSequence a = TumSequence::open(icl);
  EXPECT_EQ(a.size(), 5u);
  EXPECT_EQ(a.camera().fx, 481.2);
  const TumSequence b = TumSequence::open(replica);
  EXPECT_EQ(b.size(), 4u);
  EXPECT_EQ(b.camera().width, 1200);
  EXPECT_EQ(b.camera().depth_scale, 6553.5);
  EXPECT_EQ(b.load(3).depth.rows, 680);
  SequenceOptions forced;
  forced.camera_preset = "tum-fr1";
  EXPECT_EQ(TumSequence::open(icl, forced).camera().fx, 517.306);
}

}  // namespace
}  // namespace vdmap
