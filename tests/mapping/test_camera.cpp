#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "mapping/core/camera.h"
#include "mapping/core/colour_registration.h"
#include "mapping/core/rgbd_frame.h"
#include "mapping/io/camera_config.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

TEST(Camera, ProjectInvertsBackProject) {
  const PinholeCamera cam = cameraPreset("tum-fr1");
  for (double u : {0.0, 100.5, 639.0})
    for (double v : {0.0, 250.0, 479.0})
      for (double d : {0.3, 2.0, 7.5}) {
        const Eigen::Vector3d p = cam.backProject(u, v, d);
        EXPECT_DOUBLE_EQ(p.z(), d);
        const Eigen::Vector2d uv = cam.project(p);
        EXPECT_NEAR(uv.x(), u, 1e-9);
        EXPECT_NEAR(uv.y(), v, 1e-9);
      }
}

TEST(Camera, JacobianMatchesFiniteDifferences) {
  const PinholeCamera cam = cameraPreset("7scenes");
  const double u = 123.4, v = 321.0, d = 2.5, h = 1e-5;
  const Eigen::Matrix3d J = cam.backProjectJacobian(u, v, d);
  Eigen::Matrix3d numeric;
  numeric.col(0) = (cam.backProject(u + h, v, d) - cam.backProject(u - h, v, d)) / (2 * h);
  numeric.col(1) = (cam.backProject(u, v + h, d) - cam.backProject(u, v - h, d)) / (2 * h);
  numeric.col(2) = (cam.backProject(u, v, d + h) - cam.backProject(u, v, d - h)) / (2 * h);
  EXPECT_LT((J - numeric).cwiseAbs().maxCoeff(), 1e-8);
}

TEST(Camera, PresetsMatchSpec) {
  const PinholeCamera k = cameraPreset("7scenes");
  EXPECT_EQ(k.fx, 585.0);
  EXPECT_EQ(k.cx, 320.0);
  EXPECT_EQ(k.depth_scale, 1000.0);
  const PinholeCamera r = cameraPreset("replica");
  EXPECT_EQ(r.width, 1200);
  EXPECT_EQ(r.height, 680);
  EXPECT_EQ(r.depth_scale, 6553.5);
  EXPECT_EQ(cameraPreset("icl-nuim").fx, 481.2);
  EXPECT_EQ(cameraPresetNames().size(), 7u);
  EXPECT_THROW(cameraPreset("kinect9"), std::invalid_argument);
}

TEST(Camera, ValidateRejectsNonsense) {
  PinholeCamera cam;
  EXPECT_NO_THROW(cam.validate());
  cam.fx = 0;
  EXPECT_THROW(cam.validate(), std::invalid_argument);
  cam = {};
  cam.width = 0;
  EXPECT_THROW(cam.validate(), std::invalid_argument);
}

TEST(RgbdFrame, PointCloudBackProjectsValidPixelsOnly) {
  PinholeCamera cam{4, 3, 2.0, 2.0, 1.5, 1.0, 1000.0};
  RgbdFrame frame;
  frame.depth = cv::Mat(3, 4, CV_16UC1, cv::Scalar(2000));
  frame.depth.at<std::uint16_t>(0, 0) = 0;     // no measurement
  frame.depth.at<std::uint16_t>(1, 1) = 50;    // 5 cm: below the valid range
  frame.depth.at<std::uint16_t>(2, 3) = 9000;  // 9 m: beyond it
  frame.rgb = cv::Mat(3, 4, CV_8UC3, cv::Scalar(10, 20, 30));
  const ColoredPointCloud cloud = toPointCloud(frame, cam);
  ASSERT_EQ(cloud.size(), 9u);
  EXPECT_EQ(cloud.colors[0][1], 20);
  // Pixel (u=1, v=0) is the first kept one: x = (1 - 1.5) * 2 / 2, y = (0 - 1) * 2 / 2.
  EXPECT_FLOAT_EQ(cloud.points[0].x(), -0.5f);
  EXPECT_FLOAT_EQ(cloud.points[0].y(), -1.0f);
  EXPECT_FLOAT_EQ(cloud.points[0].z(), 2.0f);
}

TEST(CameraFile, ReadsYamlJsonAndPresetOverrides) {
  test::TempDir dir;
  test::writeText(dir / "a.yaml", "fx: 500\nfy: 501\ncx: 320\ncy: 240\ndepth_scale: 1000\nwidth: 640\nheight: 480\n");
  EXPECT_EQ(readCameraFile(dir / "a.yaml").fy, 501.0);
  test::writeText(dir / "b.json", R"({"camera": {"w": 1200, "h": 680, "fx": 600.0, "fy": 600.0,
      "cx": 599.5, "cy": 339.5, "scale": 6553.5}})");
  const PinholeCamera b = readCameraFile(dir / "b.json");
  EXPECT_EQ(b.width, 1200);
  EXPECT_EQ(b.depth_scale, 6553.5);
  test::writeText(dir / "c.yaml", "preset: 7scenes\nfx: 580\n");
  const PinholeCamera c = readCameraFile(dir / "c.yaml");
  EXPECT_EQ(c.fx, 580.0);
  EXPECT_EQ(c.depth_scale, 1000.0);
}

TEST(CameraFile, ColourCameraOfAPresetAFileOrNone) {
  test::TempDir dir;
  std::optional<ColourCamera> colour;
  // 7scenes carries its colour camera: 525 px, 2.56 cm beside the depth camera.
  test::writeText(dir / "a.yaml", "preset: 7scenes\n");
  readCameraFile(dir / "a.yaml", &colour);
  ASSERT_TRUE(colour.has_value());
  EXPECT_EQ(*colour, *cameraPresetColour("7scenes"));
  EXPECT_EQ(colour->fx, 525.0);
  EXPECT_NEAR(colour->T_colour_depth.translation().x(), -0.02556, 1e-5);
  EXPECT_TRUE(isValidTransform(colour->T_colour_depth));
  EXPECT_FALSE(cameraPresetColour("tum-fr1").has_value());
  test::writeText(dir / "b.yaml", "preset: 7scenes\ncolour: registered\n");
  readCameraFile(dir / "b.yaml", &colour);
  EXPECT_FALSE(colour.has_value());
  test::writeText(dir / "c.yaml", "preset: tum-fr1\ncolour: {fx: 500, fy: 501, cx: 300, cy: 200, "
                                  "T_colour_depth: [1, 0, 0, 0.05, 0, 1, 0, 0, 0, 0, 1, 0]}\n");
  readCameraFile(dir / "c.yaml", &colour);
  ASSERT_TRUE(colour.has_value());
  EXPECT_EQ(colour->fy, 501.0);
  EXPECT_EQ(colour->T_colour_depth.translation().x(), 0.05);
}

TEST(ColourRegistration, AColourCameraThatIsTheDepthCameraChangesNothing) {
  const PinholeCamera cam{64, 48, 60.0, 60.0, 31.5, 23.5, 1000.0};
  cv::Mat rgb(48, 64, CV_8UC3), depth(48, 64, CV_16UC1);
  cv::randu(rgb, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::randu(depth, cv::Scalar::all(0), cv::Scalar::all(4000));
  const cv::Mat registered = registerColour(rgb, depth, cam, {cam.fx, cam.fy, cam.cx, cam.cy, Transform::Identity()});
  EXPECT_EQ(cv::norm(registered, rgb, cv::NORM_INF), 0.0);
}

// A wall 2 m ahead, painted with a pattern of its own coordinates, seen by a depth camera and by
// a colour camera of another focal length 2.5 cm beside it (and turned 1 degree): registered, the
// colour at each depth pixel is the paint at that pixel's point (within bilinear interpolation),
// where the unregistered image is ~17 grey levels off on average.
TEST(ColourRegistration, GivesEachDepthPixelTheColourOfItsPoint) {
  const PinholeCamera depth_cam{160, 120, 146.0, 146.0, 79.5, 59.5, 1000.0};
  ColourCamera colour{131.0, 131.0, 80.0, 60.0, Transform::Identity()};
  colour.T_colour_depth.linear() = Eigen::AngleAxisd(M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  colour.T_colour_depth.translation() = Eigen::Vector3d(-0.025, 0.0, 0.0);
  const double wall = 2.0;
  auto paint = [](double x, double y) { return 128.0 + 100.0 * std::sin(6.0 * x) * std::cos(5.0 * y); };
  // The colour image: each colour pixel's ray hits the wall (z = 2 in the depth frame).
  cv::Mat rgb(120, 160, CV_8UC3);
  const Transform T_depth_colour = colour.T_colour_depth.inverse();
  for (int v = 0; v < rgb.rows; ++v)
    for (int u = 0; u < rgb.cols; ++u) {
      const Eigen::Vector3d origin = T_depth_colour.translation();
      const Eigen::Vector3d dir =
          T_depth_colour.linear() * Eigen::Vector3d((u - colour.cx) / colour.fx, (v - colour.cy) / colour.fy, 1);
      const Eigen::Vector3d p = origin + dir * ((wall - origin.z()) / dir.z());
      rgb.at<cv::Vec3b>(v, u) = cv::Vec3b::all(cv::saturate_cast<std::uint8_t>(paint(p.x(), p.y())));
    }
  const cv::Mat depth(120, 160, CV_16UC1, cv::Scalar(wall * 1000));
  const cv::Mat registered = registerColour(rgb, depth, depth_cam, colour);
  double registered_error = 0, raw_error = 0;
  int n = 0;
  for (int v = 10; v < 110; ++v)
    for (int u = 10; u < 150; ++u, ++n) {
      const Eigen::Vector3d p = depth_cam.backProject(u, v, wall);
      registered_error += std::abs(registered.at<cv::Vec3b>(v, u)[0] - paint(p.x(), p.y()));
      raw_error += std::abs(rgb.at<cv::Vec3b>(v, u)[0] - paint(p.x(), p.y()));
    }
  EXPECT_LT(registered_error / n, 2.0);
  EXPECT_GT(raw_error / n, 10.0);  // measured 17
}

// Bad camera files: tests/app/test_bad_input_matrix.cpp.

}  // namespace
}  // namespace vdmap
