// The built-in scene's walk: the default stays the one the golden images and tests were made
// with, and further laps take new viewpoints (a long run for the loop-closure cost).
#include <cmath>

#include <gtest/gtest.h>

#include "mapping/synth/builtin_scene.h"

namespace vdmap {
namespace {

TEST(BuiltinScene, FirstLapIsTheDefaultWalk) {
  const BuiltinScene one = makeBuiltinScene();
  const BuiltinScene three = makeBuiltinScene({.laps = 3});
  ASSERT_EQ(one.trajectory.size(), 300u);
  ASSERT_EQ(three.trajectory.size(), 900u);
  for (std::size_t i = 0; i < one.trajectory.size(); ++i) {
    EXPECT_EQ(one.trajectory[i].t, three.trajectory[i].t);
    EXPECT_TRUE(one.trajectory[i].T_W_C.matrix() == three.trajectory[i].T_W_C.matrix()) << i;
  }
  // The default walk itself, written out independently of the lap table: an ellipse at eye
  // height looking at a point 0.9 rad ahead on a larger ellipse (the walk the goldens and the
  // built-in tests were made with), so a change to lap 0 cannot pass by changing both sides.
  for (std::size_t i = 0; i < one.trajectory.size(); ++i) {
    const double a = 2.0 * M_PI * static_cast<double>(i) / 300.0, b = a + 0.9;
    const Eigen::Vector3d eye(1.2 * std::cos(a), 0.95 * std::sin(a), 1.35 + 0.08 * std::sin(3 * a));
    const Eigen::Vector3d target(2.4 * std::cos(b), 1.9 * std::sin(b), 0.75 + 0.15 * std::sin(2 * a));
    const Transform& T = one.trajectory[i].T_W_C;
    EXPECT_EQ(one.trajectory[i].t, static_cast<double>(i) / 30.0);
    EXPECT_LT((T.translation() - eye).norm(), 1e-12) << i;
    EXPECT_LT((T.linear().col(2) - (target - eye).normalized()).norm(), 1e-12) << i;
  }
  // Timestamps keep increasing across laps (one sequence, 30 fps).
  for (std::size_t i = 1; i < three.trajectory.size(); ++i) EXPECT_GT(three.trajectory[i].t, three.trajectory[i - 1].t);
}

// Each further lap sees the room from elsewhere: no pose of lap 1 or 2 is within 10 cm and 20
// degrees of any pose of lap 0 (else those laps would only revisit lap 0's keyframes).
TEST(BuiltinScene, FurtherLapsTakeNewViewpoints) {
  const BuiltinScene scene = makeBuiltinScene({.frames = 100, .laps = 3});
  for (std::size_t i = 100; i < 300; ++i)
    for (std::size_t j = 0; j < 100; ++j) {
      const Transform& a = scene.trajectory[i].T_W_C;
      const Transform& b = scene.trajectory[j].T_W_C;
      const double dist = (a.translation() - b.translation()).norm();
      const double cos_angle = a.linear().col(2).dot(b.linear().col(2));
      EXPECT_FALSE(dist < 0.1 && cos_angle > std::cos(20.0 * M_PI / 180.0)) << i << " near " << j;
    }
}

TEST(BuiltinScene, RejectsAnEmptyWalk) {
  EXPECT_THROW(makeBuiltinScene({.frames = 1}), std::invalid_argument);
  EXPECT_THROW(makeBuiltinScene({.laps = 0}), std::invalid_argument);
}

}  // namespace
}  // namespace vdmap
