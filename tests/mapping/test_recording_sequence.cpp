// A ROS 1 bag and an MCAP of 7-Scenes frames (../shared/data/bags, written by independent tools)
// read as the TUM folder's frames: same stamps, depth to the millimetre, colour, and the tf poses
// equal to groundtruth.txt; the RealSense recording with its Depth Units and no poses.
#include <gtest/gtest.h>

#include <algorithm>

#include "mapping/core/error.h"
#include "mapping/io/image_codec.h"
#include "mapping/sequence/sequence.h"
#include "tests/support/ros1_bag_writer.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;

// The recordings hold every 5th of the folder's frames 0-149, stamped 1.6e9 s later (the bag).
void expectFolderFrames(const Sequence& rec, double stamp_offset, int max_colour_difference) {
  VDMAP_REQUIRE_SHARED_DATA(tum, "7scenes-redkitchen");
  SequenceOptions folder_options;
  folder_options.frames = {0, 150};
  const Sequence folder = Sequence::open(tum, folder_options);
  ASSERT_EQ(rec.size(), 30u);
  EXPECT_TRUE(rec.hasGroundTruth());
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const FrameEntry& r = rec.entries()[i];
    const FrameEntry& f = folder.entries()[5 * i];
    EXPECT_EQ(r.index, static_cast<int>(i));
    EXPECT_NEAR(r.t_depth - stamp_offset, f.t_depth, 1e-6) << "frame " << i;
    ASSERT_TRUE(r.has_pose);
    EXPECT_LT((r.T_W_C.matrix() - f.T_W_C.matrix()).cwiseAbs().maxCoeff(), 1e-6) << "pose of frame " << i;
    if (i % 10 != 0) continue;  // pixels of a few frames
    const RgbdFrame a = rec.load(i), b = folder.load(5 * i);
    cv::Mat metres_a, metres_b;
    a.depth.convertTo(metres_a, CV_64F, 1.0 / rec.camera().depth_scale);
    b.depth.convertTo(metres_b, CV_64F, 1.0 / folder.camera().depth_scale);
    EXPECT_LT(cv::norm(metres_a, metres_b, cv::NORM_INF), 1e-9) << "depth of frame " << i;
    EXPECT_LE(cv::norm(a.rgb, b.rgb, cv::NORM_INF), max_colour_difference) << "colour of frame " << i;
  }
}

TEST(RecordingSequence, Ros1BagReadsAsTheFolderWithTfPoses) {
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  SequenceOptions options;
  options.camera_preset = "7scenes";  // camera_info says 585 px for colour too: the preset knows better
  const Sequence bag = Sequence::open(bags / "7scenes-redkitchen-tum-layout.bag", options);
  EXPECT_EQ(bag.kind(), SequenceKind::kRos1Bag);
  EXPECT_EQ(bag.posesSource(), "tf world -> openni_rgb_optical_frame");
  EXPECT_EQ(bag.camera().depth_scale, 5000.0);  // 32FC1 metres
  // rgb8 pixels were decoded from the folder's JPEGs by another decoder.
  expectFolderFrames(bag, 1.6e9, 2);
}

TEST(RecordingSequence, McapReadsAsTheFolderWithTfAndTfStaticPoses) {
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  SequenceOptions options;
  options.camera_preset = "7scenes";
  const Sequence mcap = Sequence::open(bags / "7scenes-redkitchen-realsense-layout.mcap", options);
  EXPECT_EQ(mcap.kind(), SequenceKind::kMcap);
  EXPECT_EQ(mcap.camera().depth_scale, 1000.0);  // 16UC1 millimetres
  expectFolderFrames(mcap, mcap.entries().front().t_depth, 0);
}

TEST(RecordingSequence, RealSenseBagUsesItsDepthUnitsAndHasNoPoses) {
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  SequenceOptions options;
  options.poses = SequenceOptions::Poses::kAuto;
  // Its one colour frame is 0.10 s before the first depth frame: no pair within 0.02 s.
  const fs::path bag = bags / "realsense-d400-single-depth-color.bag";
  try {
    Sequence::open(bag, options);
    ADD_FAILURE() << "expected no usable frames";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 without an rgb frame within 0.02 s"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--rgb-window S pairs colour further away"), std::string::npos) << e.what();
  }
  options.max_rgb_dt_s = 0.2;
  const Sequence rs = Sequence::open(bag, options);
  EXPECT_EQ(rs.kind(), SequenceKind::kRos1Bag);
  EXPECT_FALSE(rs.hasGroundTruth());
  EXPECT_EQ(rs.camera().width, 640);
  EXPECT_NEAR(rs.camera().depth_scale, 1000.0, 1.0);  // Depth Units 0.001 m
  ASSERT_GE(rs.size(), 1u);
  const RgbdFrame frame = rs.load(0);
  EXPECT_EQ(frame.depth.size(), cv::Size(640, 480));
  EXPECT_GT(cv::countNonZero(frame.depth), 1000);
  // The colour camera (613 px) is not the depth camera (390 px): registered with the recorded
  // extrinsics, 14 mm along x.
  ASSERT_TRUE(rs.colourCamera().has_value());
  EXPECT_NEAR(rs.colourCamera()->T_colour_depth.translation().norm(), 0.0143, 0.001);
  EXPECT_EQ(frame.rgb.size(), cv::Size(640, 480));
}

}  // namespace
}  // namespace vdmap

namespace vdmap {
namespace {

// A recording cut short maps the frames before the cut and says where it ended.
TEST(RecordingSequence, ATruncatedRecordingGivesTheFramesBeforeTheCut) {
  VDMAP_REQUIRE_SHARED_DATA(bags, "bags");
  const test::TempDir dir;
  for (const char* name : {"7scenes-redkitchen-realsense-layout.mcap", "7scenes-redkitchen-tum-layout.bag"}) {
    const std::string bytes = test::readFile(bags / name);
    const fs::path cut = dir / (std::string("cut-") + name);
    test::writeText(cut, bytes.substr(0, bytes.size() * 6 / 10));
    SequenceOptions options;
    options.camera_preset = "7scenes";
    const Sequence seq = Sequence::open(cut, options);
    EXPECT_GT(seq.size(), 5u) << name;
    EXPECT_LT(seq.size(), 30u) << name;
    const auto damaged = std::find_if(seq.notes().begin(), seq.notes().end(),
                                      [](const std::string& n) { return n.rfind("damaged: ", 0) == 0; });
    ASSERT_NE(damaged, seq.notes().end()) << name;
    EXPECT_NE(damaged->find(cut.string()), std::string::npos) << *damaged;
    EXPECT_EQ(seq.load(seq.size() - 1).depth.size(), cv::Size(640, 480));
  }
}

// compressed_depth_image_transport's messages: a 12-byte header (format, quantisation A and B)
// and a PNG. For 32FC1 the PNG holds A / depth + B (truncated to 16 bits; 0 = none), read back as
// A / (v - B); for 16UC1 it holds the millimetres.
std::vector<std::uint8_t> compressedDepthMessage(double stamp, const std::string& format, const cv::Mat& values,
                                                 float a, float b) {
  std::vector<std::uint8_t> data(12, 0);
  std::memcpy(data.data() + 4, &a, 4);
  std::memcpy(data.data() + 8, &b, 4);
  const std::string png = encodePng(values);
  data.insert(data.end(), png.begin(), png.end());
  const auto sec = static_cast<std::uint32_t>(stamp);
  const auto nsec = static_cast<std::uint32_t>(std::llround((stamp - sec) * 1e9));
  return test::Ros1Bytes().header(sec, nsec, "camera").text(format).blob(data).bytes;
}

// The tiny recording with its depth as compressedDepth of `format`, each frame's values `values`.
fs::path writeCompressedDepth(const fs::path& dir, const std::string& format, const cv::Mat& values, float a, float b) {
  test::TinyRecording recording(3, static_cast<std::uint32_t>(values.cols), static_cast<std::uint32_t>(values.rows));
  recording.connections[0].type = "sensor_msgs/CompressedImage";
  const std::vector<std::size_t> depth = recording.on("/camera/depth/image");
  for (std::size_t k = 0; k < depth.size(); ++k)
    recording.messages[depth[k]].bytes =
        compressedDepthMessage(100.0 + 0.1 * static_cast<double>(k), format, values, a, b);
  const fs::path file = dir / (format.substr(0, 5) + ".bag");
  test::writeText(file, recording.write());
  return file;
}

TEST(RecordingSequence, CompressedDepthOf16UC1And32FC1) {
  const test::TempDir dir;
  // 16UC1: millimetres as they are.
  const cv::Mat mm(24, 32, CV_16UC1, cv::Scalar(1500));
  const Sequence a = Sequence::open(writeCompressedDepth(dir.path(), "16UC1; compressedDepth", mm, 0, 0));
  EXPECT_EQ(a.camera().depth_scale, 1000.0);
  EXPECT_EQ(cv::norm(a.load(0).depth, mm, cv::NORM_INF), 0.0);
  // 32FC1 with the transport's defaults (depth_max 10 m, quantization 100): 1.5 m in the left
  // half, 4 m in the right, none in the top row.
  const float qa = 100.0f * 101.0f, qb = 1.0f - qa / 10.0f;
  cv::Mat inverse(24, 32, CV_16UC1);
  for (int v = 0; v < 24; ++v)
    for (int u = 0; u < 32; ++u)
      inverse.at<std::uint16_t>(v, u) = v == 0 ? 0 : static_cast<std::uint16_t>(qa / (u < 16 ? 1.5f : 4.0f) + qb);
  const Sequence b = Sequence::open(writeCompressedDepth(dir.path(), "32FC1; compressedDepth png", inverse, qa, qb));
  EXPECT_EQ(b.camera().depth_scale, 5000.0);
  const cv::Mat depth = b.load(0).depth;
  EXPECT_EQ(depth.at<std::uint16_t>(0, 3), 0);
  EXPECT_NEAR(depth.at<std::uint16_t>(5, 3) / 5000.0, 1.5, 1e-3);
  EXPECT_NEAR(depth.at<std::uint16_t>(5, 30) / 5000.0, 4.0, 2e-3);
  // The transport's other codec is refused by name, not read as a PNG.
  try {
    Sequence::open(writeCompressedDepth(dir.path(), "16UC1; compressedDepth rvl", mm, 0, 0));
    ADD_FAILURE() << "an RVL compressedDepth topic was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("has encoding '16UC1; compressedDepth rvl'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vdmap
