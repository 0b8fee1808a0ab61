// The held-out points of vdmap bench --query: four points on each sampled pixel's ray at the
// distances the report names, none at a depth edge.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "app/bench/query_heldout.h"
#include "mapping/core/rgbd_frame.h"

namespace vdmap::app {
namespace {

TEST(QueryHeldOut, PointsLieOnThePixelRaysAwayFromDepthEdges) {
  PinholeCamera cam;
  cam.width = 64, cam.height = 48, cam.fx = cam.fy = 50, cam.cx = 32, cam.cy = 24, cam.depth_scale = 1000;
  RgbdFrame frame;
  frame.depth = cv::Mat(48, 64, CV_16UC1, cv::Scalar(2000));  // a wall at 2 m ...
  frame.depth.colRange(32, 64).setTo(3000);                   // ... with a step to 3 m at u = 32
  frame.T_W_C.translation() = Eigen::Vector3d(1, 2, 3);
  HeldOutPoints p;
  addHeldOut(frame, cam, 0.1, 8.0, 0, 300, &p);
  ASSERT_EQ(p.surface.size(), 300u);
  ASSERT_EQ(p.half_way.size(), 300u);
  const Eigen::Vector3d c = frame.T_W_C.translation();
  for (std::size_t i = 0; i < p.surface.size(); ++i) {
    const Eigen::Vector3d s = p.surface[i] - c;
    EXPECT_TRUE(std::abs(s.z() - 2.0) < 1e-9 || std::abs(s.z() - 3.0) < 1e-9) << s.transpose();
    const double u = cam.fx * s.x() / s.z() + cam.cx;
    EXPECT_TRUE(u < 30.5 || u > 32.5) << "pixel " << u << " is next to the step";
    EXPECT_NEAR((p.surface[i] - p.front_2cm[i]).norm(), 0.02, 1e-9);
    EXPECT_NEAR((p.surface[i] - p.front_5cm[i]).norm(), 0.05, 1e-9);
    EXPECT_NEAR((p.half_way[i] - c).norm(), 0.5 * s.norm(), 1e-9);
    EXPECT_NEAR((p.front_5cm[i] - c).normalized().dot(s.normalized()), 1.0, 1e-12);
  }
  HeldOutPoints again;
  addHeldOut(frame, cam, 0.1, 8.0, 0, 300, &again);
  EXPECT_EQ(again.surface, p.surface) << "seeded by the frame index";
  HeldOutPoints none;
  addHeldOut(frame, cam, 3.5, 8.0, 0, 10, &none);
  EXPECT_TRUE(none.surface.empty()) << "no depth within the range";
}

}  // namespace
}  // namespace vdmap::app
