#include <gtest/gtest.h>

#include "mapping/core/camera.h"
#include "mapping/core/rgbd_frame.h"
#include "mapping/io/camera_config.h"
#include "tests/test_util.h"

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
  frame.depth.at<std::uint16_t>(0, 0) = 0;       // no measurement
  frame.depth.at<std::uint16_t>(1, 1) = 50;      // 5 cm: below the valid range
  frame.depth.at<std::uint16_t>(2, 3) = 9000;    // 9 m: beyond it
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

// Bad camera files: tests/test_bad_input_matrix.cpp.

}  // namespace
}  // namespace vdmap
