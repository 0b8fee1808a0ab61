// The image files vdmap reads and writes itself (mapping/io/image_codec.h) against OpenCV's
// imgcodecs, the oracle: the decoders give the pixels imread gives, the encoders the bytes
// imencode writes with the same settings. The only test program that links OpenCV's codecs.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "mapping/core/colour_registration.h"
#include "mapping/core/error.h"
#include "mapping/io/compressed_image.h"
#include "mapping/io/image_codec.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/sequence/sequence.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

using test::TempDir;

std::string imencodeBytes(const std::string& ext, const cv::Mat& image, const std::vector<int>& params = {}) {
  std::vector<unsigned char> bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes, params));
  return std::string(bytes.begin(), bytes.end());
}

// Smooth gradients with noise: compressible like a render, not a trivial run of one value.
cv::Mat testImage(int rows, int cols, int type, int seed) {
  cv::Mat image(rows, cols, type);
  cv::theRNG().state = static_cast<std::uint64_t>(seed);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(type == CV_16UC1 ? 65535 : 255));
  cv::Mat smooth;
  cv::GaussianBlur(image, smooth, cv::Size(7, 7), 2.0);
  cv::Mat noise(rows, cols, type);
  cv::randu(noise, cv::Scalar::all(0), cv::Scalar::all(8));
  return smooth + noise;
}

TEST(ImageEncode, PngBytesAreImencodes) {
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(53, 37), cv::Size(320, 240)})
    for (const int type : {CV_8UC1, CV_8UC3, CV_16UC1}) {
      const cv::Mat image = testImage(size.height, size.width, type, size.area() + type);
      const std::string what =
          std::to_string(size.width) + "x" + std::to_string(size.height) + " type " + std::to_string(type);
      // imencode without parameters (the renders, the synthetic sequences) and with level 1
      // (a keyframe's pixels); imencode takes colour as BGR.
      EXPECT_EQ(encodePng(image, ChannelOrder::kBgr, PngCompression::kFast), imencodeBytes(".png", image)) << what;
      EXPECT_EQ(encodePng(image, ChannelOrder::kBgr, PngCompression::kLevel1),
                imencodeBytes(".png", image, {cv::IMWRITE_PNG_COMPRESSION, 1}))
          << what;
      if (type != CV_8UC3) continue;
      cv::Mat bgr;
      cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
      EXPECT_EQ(encodePng(image, ChannelOrder::kRgb), imencodeBytes(".png", bgr)) << what;
    }
}

TEST(ImageEncode, JpegBytesAreImencodes) {
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(53, 37), cv::Size(320, 240)})
    for (const int quality : {1, 50, 90, 95, 100}) {
      const cv::Mat image = testImage(size.height, size.width, CV_8UC3, quality);
      const std::string what =
          std::to_string(size.width) + "x" + std::to_string(size.height) + " q" + std::to_string(quality);
      EXPECT_EQ(encodeJpeg(image, quality, ChannelOrder::kBgr),
                imencodeBytes(".jpg", image, {cv::IMWRITE_JPEG_QUALITY, quality}))
          << what;
      cv::Mat bgr;
      cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
      EXPECT_EQ(encodeJpeg(image, quality), imencodeBytes(".jpg", bgr, {cv::IMWRITE_JPEG_QUALITY, quality})) << what;
    }
}

TEST(ImageEncode, WritesTheFormatItsNameSaysAndRefusesOthers) {
  TempDir dir;
  const cv::Mat image = testImage(24, 32, CV_8UC3, 3);
  writeImageFile(dir / "a.PNG", image);
  writeImageFile(dir / "b.jpeg", image);
  EXPECT_EQ(test::readFile(dir / "a.PNG"), encodePng(image));
  EXPECT_EQ(test::readFile(dir / "b.jpeg"), encodeJpeg(image, 95));
  EXPECT_EQ(cv::norm(readColorImage(dir / "a.PNG", image.size()), image, cv::NORM_INF), 0.0);
  EXPECT_THROW(writeImageFile(dir / "c.tif", image), InputError);
  EXPECT_THROW(writeImageFile(dir / "missing" / "d.png", image), InputError);
  EXPECT_THROW(encodeJpeg(image, 0), std::invalid_argument);
  EXPECT_THROW(encodePng(cv::Mat(4, 4, CV_32FC1)), std::invalid_argument);
}

// The decoder gives the pixels OpenCV's imread gave, for every layout a colour PNG can have and
// for 16-bit depth, so the switch changed no map; damaged files are the bad-input matrix's rows.
TEST(ImageDecode, GivesOpenCvsPixels) {
  TempDir dir;
  cv::Mat colour(37, 53, CV_8UC3), grey(37, 53, CV_8UC1), depth(37, 53, CV_16UC1);
  cv::randu(colour, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::randu(grey, 0, 255);
  cv::randu(depth, 0, 65535);
  cv::Mat rgba, colour16;
  cv::cvtColor(colour, rgba, cv::COLOR_BGR2BGRA);
  colour.convertTo(colour16, CV_16UC3, 257.0);
  const cv::Size size(53, 37);
  for (const auto& [name, image] : std::vector<std::pair<std::string, cv::Mat>>{{"colour.png", colour},
                                                                                {"grey.png", grey},
                                                                                {"rgba.png", rgba},
                                                                                {"colour16.png", colour16},
                                                                                {"colour.jpg", colour},
                                                                                {"grey.jpg", grey}}) {
    const std::filesystem::path file = dir / name;
    ASSERT_TRUE(cv::imwrite(file.string(), image));
    cv::Mat expected;
    cv::cvtColor(cv::imread(file.string(), cv::IMREAD_COLOR), expected, cv::COLOR_BGR2RGB);
    EXPECT_EQ(cv::norm(readColorImage(file, size), expected, cv::NORM_INF), 0.0) << name;
  }
  ASSERT_TRUE(cv::imwrite((dir / "depth.png").string(), depth));
  EXPECT_EQ(cv::norm(readDepthImage(dir / "depth.png", size), depth, cv::NORM_INF), 0.0);
  EXPECT_THROW(readDepthImage(dir / "depth.png", {52, 37}), InputError);
}

TEST(ImageDecode, GivesOpenCvsPixelsOnSevenScenes) {
  VDMAP_REQUIRE_SHARED_DATA(folder, "7scenes-redkitchen");
  const Sequence seq = Sequence::open(folder);
  for (const std::size_t i : {std::size_t{0}, seq.size() / 2, seq.size() - 1}) {
    const RgbdFrame frame = seq.load(i);
    cv::Mat expected;
    cv::cvtColor(cv::imread(seq.entries()[i].rgb_path.string(), cv::IMREAD_COLOR), expected, cv::COLOR_BGR2RGB);
    // 7-Scenes' colour is not registered to its depth: load() registers it.
    ASSERT_TRUE(seq.colourCamera().has_value());
    expected = registerColour(expected, frame.depth, seq.camera(), *seq.colourCamera());
    EXPECT_EQ(cv::norm(frame.rgb, expected, cv::NORM_INF), 0.0) << i;
    EXPECT_EQ(
        cv::norm(frame.depth, cv::imread(seq.entries()[i].depth_path.string(), cv::IMREAD_UNCHANGED), cv::NORM_INF),
        0.0)
        << i;
  }
}

// A keyframe holds the files a frame was read from (7-Scenes' JPEG and PNG are ~0.13 MB
// where re-compressing the pixels as PNG took ~0.5 MB) and gets back exactly the frame's pixels;
// pixels that came from no file are PNG-compressed, losslessly too.
TEST(CompressedImage, HoldsTheSourceFilesAndDecodesThemToTheFramesPixels) {
  TempDir dir;
  cv::Mat colour(37, 53, CV_8UC3), depth(37, 53, CV_16UC1);
  cv::randu(colour, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::randu(depth, 0, 65535);
  const cv::Size size(53, 37);
  ASSERT_TRUE(cv::imwrite((dir / "colour.jpg").string(), colour));
  ASSERT_TRUE(cv::imwrite((dir / "depth.png").string(), depth));
  std::string rgb_bytes, depth_bytes;
  const cv::Mat rgb = readColorImage(dir / "colour.jpg", size, &rgb_bytes);
  const cv::Mat d = readDepthImage(dir / "depth.png", size, &depth_bytes);
  EXPECT_EQ(rgb_bytes.size(), std::filesystem::file_size(dir / "colour.jpg"));
  const CompressedImage held_rgb(rgb, std::make_shared<const std::string>(rgb_bytes));
  const CompressedImage held_depth(d, std::make_shared<const std::string>(depth_bytes));
  EXPECT_EQ(held_rgb.compressedBytes(), rgb_bytes.size());
  EXPECT_EQ(held_depth.compressedBytes(), depth_bytes.size());
  EXPECT_EQ(cv::norm(held_rgb.decode(), rgb, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(held_depth.decode(), d, cv::NORM_INF), 0.0);
  EXPECT_EQ(held_rgb.decode().type(), CV_8UC3);
  const CompressedImage png(rgb);
  EXPECT_GT(png.compressedBytes(), 0u);
  EXPECT_EQ(cv::norm(png.decode(), rgb, cv::NORM_INF), 0.0);
  // The bytes a keyframe's pixels were always stored as: imencode of the pixels taken as BGR.
  EXPECT_EQ(std::string(png.encoded()), imencodeBytes(".png", rgb, {cv::IMWRITE_PNG_COMPRESSION, 1}));
  // A JPEG of resampled pixels decodes to the pixels OpenCV's decoder gives it (as keyframes
  // always have), and the bytes a session stores (encoded(), swappedRedBlue()) give them back.
  const CompressedImage jpeg(rgb, 90);
  EXPECT_EQ(std::string(jpeg.encoded()), imencodeBytes(".jpg", rgb, {cv::IMWRITE_JPEG_QUALITY, 90}));
  const std::vector<std::uint8_t> jpeg_bytes(jpeg.encoded().begin(), jpeg.encoded().end());
  EXPECT_EQ(cv::norm(jpeg.decode(), cv::imdecode(jpeg_bytes, cv::IMREAD_UNCHANGED), cv::NORM_INF), 0.0);
  for (const CompressedImage* image : {&png, &jpeg, &held_rgb}) {
    const CompressedImage copy = CompressedImage::fromEncoded(image->rows(), image->cols(), image->type(),
                                                              std::string(image->encoded()), image->swappedRedBlue());
    EXPECT_EQ(cv::norm(copy.decode(), image->decode(), cv::NORM_INF), 0.0);
  }
  // Through the sequence and the mapper: the keyframe keeps the loaded frame's files.
  test::writeTinySequence(dir / "seq", 2);
  const Sequence seq = Sequence::open(dir / "seq");
  const RgbdFrame frame = seq.load(0);
  ASSERT_TRUE(frame.rgb_file && frame.depth_file);
  Mapper mapper(seq.camera());
  mapper.addFrame(frame);
  const Keyframe& k = mapper.graph().keyframe(0);
  EXPECT_EQ(k.memory().images, frame.rgb_file->size() + frame.depth_file->size());
  EXPECT_EQ(cv::norm(k.rgb(), frame.rgb, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(k.depth(), frame.depth, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace vdmap
