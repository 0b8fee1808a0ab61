// The point queries' ground truth (mapping/eval/occupancy_truth.h): the per-frame labels on
// hand-made depth images, and the point sets on an analytic room (a box seen from inside, its
// exact depth computed by ray-box intersection) checked against facts of that geometry and the
// brute-force mesh distance.
#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "mapping/eval/mesh_accuracy.h"
#include "mapping/eval/occupancy_truth.h"

namespace vdmap {
namespace {

PinholeCamera smallCamera() {
  PinholeCamera cam;
  cam.width = 64, cam.height = 48;
  cam.fx = cam.fy = 50.0;
  cam.cx = 31.5, cam.cy = 23.5;
  cam.depth_scale = 1000.0;
  return cam;
}

cv::Mat constantDepth(const PinholeCamera& cam, double metres) {
  return cv::Mat(cam.height, cam.width, CV_16UC1, cv::Scalar(std::lround(metres * cam.depth_scale)));
}

// The room: the box [lo, hi], its six faces (two triangles each).
const Eigen::Vector3d kLo(-2.0, -1.5, -1.0), kHi(2.0, 1.5, 3.0);

ColoredTriangleMesh roomMesh() {
  ColoredTriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.positions.emplace_back(static_cast<float>(i & 1 ? kHi.x() : kLo.x()),
                                static_cast<float>(i & 2 ? kHi.y() : kLo.y()),
                                static_cast<float>(i & 4 ? kHi.z() : kLo.z()));
    mesh.colors.push_back({128, 128, 128});
  }
  // Each face as a quad of corner indices, split in two (the winding does not matter here).
  const std::uint32_t quads[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                     {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  for (const auto& q : quads) {
    mesh.triangles.push_back({q[0], q[1], q[2]});
    mesh.triangles.push_back({q[0], q[2], q[3]});
  }
  return mesh;
}

// Exact depth (z, mm steps) of the room's walls from a camera at `centre` looking down +z.
cv::Mat roomDepth(const PinholeCamera& cam, const Eigen::Vector3d& centre) {
  cv::Mat depth(cam.height, cam.width, CV_16UC1);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d = cam.backProject(u, v, 1.0);  // z = 1: t is the depth
      double t = std::numeric_limits<double>::infinity();
      for (int k = 0; k < 3; ++k)
        if (d[k] != 0) t = std::min(t, ((d[k] > 0 ? kHi[k] : kLo[k]) - centre[k]) / d[k]);
      depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(std::lround(t * cam.depth_scale));
    }
  return depth;
}

Transform at(const Eigen::Vector3d& centre) {
  Transform T = Transform::Identity();
  T.translation() = centre;
  return T;
}

OccupancyTruth roomTruth(const OccupancyTruthParams& params) {
  const PinholeCamera cam = smallCamera();
  OccupancyTruth truth(cam, params);
  for (const Eigen::Vector3d& c : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.5, 0.2, 0.3)})
    truth.addFrame(roomDepth(cam, c), at(c));
  return truth;
}

OccupancyTruthParams fewPoints() {
  OccupancyTruthParams p;
  p.occupied = 2000, p.free = 2000, p.free_near = 1000, p.unknown = 2000;
  return p;
}

TEST(OccupancyTruth, LabelsOfOneFrameAlongTheRay) {
  const PinholeCamera cam = smallCamera();
  OccupancyTruth truth(cam);
  truth.addFrame(constantDepth(cam, 2.0), Transform::Identity());
  EXPECT_EQ(truth.sight(0, {0, 0, 1.0}), FrameSight::kFree);
  EXPECT_EQ(truth.sight(0, {0, 0, 1.975}), FrameSight::kFree);
  EXPECT_EQ(truth.sight(0, {0, 0, 1.99}), FrameSight::kNone);  // within 2 cm of the surface, not on it
  EXPECT_EQ(truth.sight(0, {0, 0, 1.996}), FrameSight::kSurface);
  EXPECT_EQ(truth.sight(0, {0, 0, 2.004}), FrameSight::kSurface);
  EXPECT_EQ(truth.sight(0, {0, 0, 2.5}), FrameSight::kNone);   // behind the surface
  EXPECT_EQ(truth.sight(0, {10, 0, 1.0}), FrameSight::kNone);  // outside the image
  EXPECT_EQ(truth.sight(0, {0, 0, -1.0}), FrameSight::kNone);  // behind the camera
  const OccupancyTruth::Seen s = truth.seen({0, 0, 1.0});
  EXPECT_TRUE(s.free);
  EXPECT_FALSE(s.surface);
}

TEST(OccupancyTruth, NoFreeAtADepthEdgeOrBesideAMissingDepth) {
  const PinholeCamera cam = smallCamera();
  cv::Mat depth = constantDepth(cam, 2.0);
  depth.colRange(0, 32).setTo(1000);    // the left half is a near surface at 1 m
  depth.at<std::uint16_t>(10, 50) = 0;  // one pixel without depth
  OccupancyTruth truth(cam);
  truth.addFrame(depth, Transform::Identity());
  const auto point = [&](double u, double v, double z) { return cam.backProject(u, v, z); };
  EXPECT_EQ(truth.sight(0, point(40, 20, 1.5)), FrameSight::kFree);
  EXPECT_EQ(truth.sight(0, point(32, 20, 1.5)), FrameSight::kNone);  // its left neighbour is at 1 m
  EXPECT_EQ(truth.sight(0, point(31, 20, 1.5)), FrameSight::kNone);  // behind the near surface
  EXPECT_EQ(truth.sight(0, point(50, 10, 1.0)), FrameSight::kNone);  // no depth at the pixel
  EXPECT_EQ(truth.sight(0, point(51, 11, 1.0)), FrameSight::kNone);  // next to it
  EXPECT_EQ(truth.sight(0, point(53, 13, 1.0)), FrameSight::kFree);
}

TEST(OccupancyTruth, SetsMatchTheRoomsGeometry) {
  const OccupancyTruthParams params = fewPoints();
  const OccupancyTruth truth = roomTruth(params);
  const ColoredTriangleMesh mesh = roomMesh();
  const OccupancyTruthSets sets = truth.sample(mesh);
  ASSERT_EQ(sets.occupied.size(), params.occupied);
  ASSERT_EQ(sets.free.size(), params.free);
  ASSERT_EQ(sets.free_near.size(), params.free_near);
  ASSERT_EQ(sets.unknown.size(), params.unknown);
  const auto toFloat = [](const std::vector<Eigen::Vector3d>& v) {
    std::vector<Eigen::Vector3f> out;
    for (const auto& p : v) out.push_back(p.cast<float>());
    return out;
  };
  const auto inside = [](const Eigen::Vector3d& p) {
    return (p.array() > kLo.array()).all() && (p.array() < kHi.array()).all();
  };
  // O: within the offset of a wall, on the camera's side (inside the room) exactly when the
  // offset is positive.
  const std::vector<double> d_occ = distancesToMeshBruteForce(toFloat(sets.occupied), mesh);
  for (std::size_t i = 0; i < sets.occupied.size(); ++i) {
    const double s = sets.occupied_offset_m[i];
    ASSERT_LE(std::abs(s), params.occupied_offset_m);
    ASSERT_LE(d_occ[i], std::abs(s) + 1e-5) << i;  // less only near a corner
    if (std::abs(s) > 1e-5) {
      ASSERT_EQ(inside(sets.occupied[i]), s > 0) << i;
    }
  }
  // F: inside the room, clear of the walls, at the distance given (the brute-force one).
  const std::vector<double> d_free = distancesToMeshBruteForce(toFloat(sets.free), mesh);
  for (std::size_t i = 0; i < sets.free.size(); ++i) {
    ASSERT_TRUE(inside(sets.free[i]));
    ASSERT_GT(d_free[i], params.clearance_m);
    ASSERT_NEAR(sets.free_distance_m[i], d_free[i], 1e-6);
    ASSERT_GE(sets.free_seen_distance_m[i], d_free[i] - 1e-6);  // a part of the mesh is no nearer
    ASSERT_TRUE(truth.seen(sets.free[i]).free);
  }
  const std::vector<double> d_near = distancesToMeshBruteForce(toFloat(sets.free_near), mesh);
  for (std::size_t i = 0; i < sets.free_near.size(); ++i) {
    ASSERT_TRUE(inside(sets.free_near[i]));
    ASSERT_GE(d_near[i], params.near_min_m - 1e-6);
    ASSERT_LE(d_near[i], params.near_max_m + 1e-6);
  }
  // U: in the room (the mesh's box) but outside both cameras' views: behind them or beside the image.
  const PinholeCamera cam = truth.camera();
  std::size_t behind = 0;
  for (const Eigen::Vector3d& p : sets.unknown) {
    ASSERT_TRUE(inside(p));
    for (const Eigen::Vector3d& c : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.5, 0.2, 0.3)}) {
      const Eigen::Vector3d q = p - c;
      if (q.z() <= 0) {
        ++behind;
        continue;
      }
      const Eigen::Vector2d uv = cam.project(q);
      ASSERT_FALSE(cam.inImage(uv.x(), uv.y())) << p.transpose();
    }
  }
  EXPECT_GT(behind, 0u);
  // The walls behind both cameras are never seen: their triangles are not in the seen part, so
  // a free point near the back wall (z = -1) is farther from the seen part than from the mesh.
  EXPECT_GT(sets.seen_triangles, 0u);
  EXPECT_LT(sets.seen_triangles, mesh.triangles.size());
}

TEST(OccupancyTruth, SetsDependOnTheSeedAloneNotOnThreads) {
  OccupancyTruthParams one = fewPoints(), two = fewPoints();
  one.threads = 1, two.threads = 2;
  const ColoredTriangleMesh mesh = roomMesh();
  const OccupancyTruthSets a = roomTruth(one).sample(mesh), b = roomTruth(two).sample(mesh);
  EXPECT_EQ(a.occupied, b.occupied);
  EXPECT_EQ(a.free, b.free);
  EXPECT_EQ(a.free_near, b.free_near);
  EXPECT_EQ(a.unknown, b.unknown);
  EXPECT_EQ(a.free_distance_m, b.free_distance_m);
  OccupancyTruthParams other = fewPoints();
  other.seed = 37;
  const OccupancyTruthSets c = roomTruth(other).sample(mesh);
  EXPECT_NE(a.free, c.free);
}

TEST(OccupancyTruth, RefusesAWrongDepthImage) {
  const PinholeCamera cam = smallCamera();
  OccupancyTruth truth(cam);
  EXPECT_THROW(truth.addFrame(cv::Mat(48, 64, CV_32FC1), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(truth.addFrame(cv::Mat(10, 64, CV_16UC1), Transform::Identity()), std::invalid_argument);
}

}  // namespace
}  // namespace vdmap
