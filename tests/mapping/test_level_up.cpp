// The up direction of a map from its geometry alone (mapping/global_map/level_up.h): a scanned
// room turned every way (the 7-Scenes kitchen's map files: tests/render/test_view_framing.cpp).
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "mapping/global_map/level_up.h"

namespace vdmap {
namespace {

double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

// Points every 3 cm over the rectangle corner + s a + t b (s, t in [0, 1]), with 2 mm of noise.
void addRect(std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& corner, const Eigen::Vector3d& a,
             const Eigen::Vector3d& b, std::mt19937& rng) {
  std::normal_distribution<double> noise(0.0, 0.002);
  const int na = static_cast<int>(a.norm() / 0.03), nb = static_cast<int>(b.norm() / 0.03);
  for (int i = 0; i <= na; ++i)
    for (int j = 0; j <= nb; ++j)
      points.push_back(corner + a * (i / static_cast<double>(na)) + b * (j / static_cast<double>(nb)) +
                       Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
}

// A kitchen as a hand-held camera scans it, z up: the floor in front of the counters, a back
// wall and a side wall (upper halves, above the counters), a counter along each (top at 0.9 m,
// front 0.6 m out), a wall cabinet's underside and front, and a table in the room.
std::vector<Eigen::Vector3d> scannedKitchen() {
  std::mt19937 rng(3);
  std::vector<Eigen::Vector3d> p;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  addRect(p, {0.6, 0.6, 0}, 3.4 * x, 2.4 * y, rng);     // floor
  addRect(p, {0, 0, 0.9}, 4.0 * x, 1.5 * z, rng);       // back wall above the counter
  addRect(p, {0, 0, 0.9}, 3.0 * y, 1.5 * z, rng);       // side wall above the counter
  addRect(p, {0, 0, 0.9}, 4.0 * x, 0.6 * y, rng);       // back counter top
  addRect(p, {0, 0.6, 0.1}, 4.0 * x, 0.8 * z, rng);     // its front
  addRect(p, {0, 0.6, 0.9}, 0.6 * x, 2.4 * y, rng);     // side counter top
  addRect(p, {0.6, 0.6, 0.1}, 2.4 * y, 0.8 * z, rng);   // its front
  addRect(p, {1.0, 0, 1.6}, 2.0 * x, 0.35 * y, rng);    // wall cabinet underside
  addRect(p, {1.0, 0.35, 1.6}, 2.0 * x, 0.7 * z, rng);  // its front
  addRect(p, {2.0, 1.8, 0.75}, 1.2 * x, 0.8 * y, rng);  // table top
  return p;
}

std::vector<Ellipsoid> asEllipsoids(const std::vector<Eigen::Vector3d>& points, const Eigen::Matrix3d& R) {
  std::vector<Ellipsoid> map;
  for (const Eigen::Vector3d& p : points) {
    Ellipsoid e;
    e.mean = R * p;
    e.cov = Eigen::Matrix3d::Identity() * 1e-6;
    map.push_back(e);
  }
  return map;
}

// Turned every way (20 random rotations, fixed seed), the room's up is found within 2 degrees:
// the floor's and tables' normals fit to a few tenths of a degree over 3 cm samples with 2 mm
// of noise.
TEST(LevelUp, FindsARoomsUpTurnedEveryWay) {
  const std::vector<Eigen::Vector3d> room = scannedKitchen();
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  double worst = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d R = trial == 0
                                  ? Eigen::Matrix3d::Identity()
                                  : Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    const std::optional<LevelUp> found = levelUp(asEllipsoids(room, R));
    ASSERT_TRUE(found) << trial;
    const double error = angleDeg(found->up, R * Eigen::Vector3d::UnitZ());
    worst = std::max(worst, error);
    EXPECT_LT(error, 2.0) << "trial " << trial;
  }
  std::printf("worst up error over 20 turns: %.3f degrees\n", worst);
}

TEST(LevelUp, TooFewFlatPatchesGiveNothing) {
  EXPECT_FALSE(levelUp({}));
  std::vector<Eigen::Vector3d> specks;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int i = 0; i < 200; ++i) specks.emplace_back(u(rng), u(rng), u(rng));  // nothing within 12 cm of most
  EXPECT_FALSE(levelUp(asEllipsoids(specks, Eigen::Matrix3d::Identity())));
}

}  // namespace
}  // namespace vdmap
