// Map exports (SPEC section 7) through exportMap: every file written into one folder, each PLY
// reads back to the values written, and a folder that cannot be written fails cleanly.
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "mapping/export/map_export.h"
#include "mapping/export/octomap_export.h"
#include "mapping/export/ply_writer.h"
#include "mapping/io/camera_config.h"
#include "mapping/io/ply_reader.h"
#include "tests/box_room_keyframes.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;

const PinholeCamera kCamera = cameraPreset("tum-default");

// Two neighbouring keyframes looking at the same wall of the box room, and their global map.
struct TwoViews {
  KeyframeGraph graph;
  GlobalMapParams params;
  GlobalMap map;
  TwoViews() {
    test::addBoxRoomKeyframe(&graph, kCamera, test::lookAt({0, 0, 0}, {0, 0, 2}), test::lookAt({0, 0, 0}, {0, 0, 2}));
    const Transform T = test::lookAt({0.3, 0, 0.2}, {0.5, 0.2, 2});
    test::addBoxRoomKeyframe(&graph, kCamera, T, T);
    graph.edges().strengthen(0, 1, 0.6);
    map = buildGlobalMap(graph, params);
  }
};

std::vector<std::string> filesIn(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(Export, WritesEveryFileAndTheEllipsoidPlyReadsBack) {
  const TwoViews scene;
  ASSERT_GT(scene.map.ellipsoids.size(), 100u);
  test::TempDir tmp;
  MapExportOptions options;
  options.run_stats = {{"frames", 2}};
  const nlohmann::json stats = exportMap(tmp / "out", scene.graph, scene.map, options);
  EXPECT_EQ(filesIn(tmp / "out"), (std::vector<std::string>{"global_ellipsoids.ply", "global_gaussians.ply",
                                                             "global_points.ply", "graph.txt", "keyframes.txt",
                                                             "local_maps.ply", "stats.json"}));
  EXPECT_EQ(stats["frames"], 2);
  EXPECT_EQ(stats["sigma_e_prime"], scene.map.sigma_e_prime);

  const std::vector<EllipsoidRecord> back = readPlyEllipsoids(tmp / "out" / "global_ellipsoids.ply");
  ASSERT_EQ(back.size(), scene.map.ellipsoids.size());
  for (std::size_t i = 0; i < back.size(); ++i) {
    const Ellipsoid& e = scene.map.ellipsoids[i];
    // Stored as float: equal to the double rounded to float, exactly.
    ASSERT_EQ(back[i].mean, e.mean.cast<float>());
    ASSERT_EQ(back[i].cov, e.cov.cast<float>());
    ASSERT_EQ(back[i].count, e.count);
    ASSERT_EQ(back[i].keyframe, e.keyframe);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(back[i].rgb[k], static_cast<int>(std::lround(e.color(k))));
  }

  // local_maps.ply: every keyframe's ellipsoids as the filter selects them, in the world frame.
  std::vector<Ellipsoid> local;
  for (const Keyframe& k : scene.graph.keyframes())
    for (const Ellipsoid& e : keptEllipsoids(k.container, scene.params.filter, k.T_W_K, k.id)) local.push_back(e);
  EXPECT_EQ(local.size(), scene.map.sigma_e);
  const std::vector<EllipsoidRecord> local_back = readPlyEllipsoids(tmp / "out" / "local_maps.ply");
  ASSERT_EQ(local_back.size(), local.size());
  for (std::size_t i = 0; i < local.size(); ++i) {
    ASSERT_EQ(local_back[i].mean, local[i].mean.cast<float>());
    ASSERT_EQ(local_back[i].keyframe, local[i].keyframe);
  }
}

TEST(Export, PointPlyReadsBack) {
  const TwoViews scene;
  test::TempDir tmp;
  writePointPly(tmp / "p.ply", scene.map.ellipsoids);
  const PlyVertexTable t = readPlyVertices(tmp / "p.ply");
  ASSERT_EQ(t.names, (std::vector<std::string>{"x", "y", "z", "red", "green", "blue"}));
  ASSERT_EQ(t.count, scene.map.ellipsoids.size());
  for (std::size_t i = 0; i < t.count; ++i) {
    const Ellipsoid& e = scene.map.ellipsoids[i];
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(t.at(i, k), static_cast<float>(e.mean(k)));
      ASSERT_EQ(t.at(i, 3 + k), std::lround(e.color(k)));
    }
  }
}

// 3DGS rebuilds Sigma = R S S^T R^T from the normalised quaternion and S = diag(exp(scale)).
TEST(Export, GaussianScaleAndRotationReproduceTheCovariance) {
  const TwoViews scene;
  std::vector<Ellipsoid> ellipsoids = scene.map.ellipsoids;
  Ellipsoid skew;  // a long, tilted, non-axis-aligned one as well, and a flat one
  skew.mean = {1, 2, 3};
  const Eigen::Matrix3d R0 = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  skew.cov = R0 * Eigen::Vector3d(0.04, 1e-4, 1e-6).asDiagonal() * R0.transpose();
  skew.color = {255, 0, 128};
  ellipsoids.push_back(skew);
  test::TempDir tmp;
  writeGaussianPly(tmp / "g.ply", ellipsoids);
  const PlyVertexTable t = readPlyVertices(tmp / "g.ply");
  ASSERT_EQ(t.count, ellipsoids.size());
  const int x = t.column("x"), f_dc = t.column("f_dc_0"), opacity = t.column("opacity"), scale = t.column("scale_0"),
            rot = t.column("rot_0"), nx = t.column("nx");
  ASSERT_EQ(t.column("rot_3"), rot + 3);
  for (std::size_t i = 0; i < t.count; ++i) {
    const Ellipsoid& e = ellipsoids[i];
    const Eigen::Quaterniond q = Eigen::Quaterniond(t.at(i, rot), t.at(i, rot + 1), t.at(i, rot + 2), t.at(i, rot + 3));
    ASSERT_NEAR(q.norm(), 1.0, 1e-6);
    const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
    Eigen::Vector3d sigma2;
    for (int k = 0; k < 3; ++k) sigma2(k) = std::exp(2.0 * t.at(i, scale + k));
    const Eigen::Matrix3d cov = R * sigma2.asDiagonal() * R.transpose();
    // Float storage: ~1e-7 relative on the axes and the angles, so 1e-5 of the largest
    // eigenvalue; plus the clamp of a degenerate axis at kGaussianMinSigma.
    const double tol = 1e-5 * e.cov.norm() + kGaussianMinSigma * kGaussianMinSigma;
    ASSERT_LT((cov - e.cov).cwiseAbs().maxCoeff(), tol) << i << "\n" << cov << "\n" << e.cov;
    const Eigen::Vector3d normal(t.at(i, nx), t.at(i, nx + 1), t.at(i, nx + 2));
    ASSERT_NEAR(normal.norm(), 1.0, 1e-6);
    ASSERT_LE(normal.dot(e.cov * normal), sigma2.minCoeff() * (1 + 1e-4) + tol) << "normal: the flattest axis";
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(t.at(i, x + k), static_cast<float>(e.mean(k)));
      ASSERT_NEAR(t.at(i, f_dc + k), (e.color(k) / 255.0 - 0.5) / 0.28209479, 1e-6);
    }
    ASSERT_NEAR(1.0 / (1.0 + std::exp(-t.at(i, opacity))), 0.9, 1e-6);
  }
}

TEST(Export, OctomapOpensWithLiboctomapAndItsOccupiedVoxelsContainTheMeans) {
  const TwoViews scene;
  test::TempDir tmp;
  MapExportOptions options;
  options.octomap_resolution_m = 0.05;
  std::vector<std::size_t> progress;  // one call per keyframe scan, counting up to the total
  options.octomap_progress = [&](std::size_t done, std::size_t total) {
    EXPECT_EQ(total, scene.graph.size());
    progress.push_back(done);
  };
  const nlohmann::json stats = exportMap(tmp / "out", scene.graph, scene.map, options);
  EXPECT_EQ(progress, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(stats["octomap"]["points"], 7 * scene.map.ellipsoids.size());
  EXPECT_EQ(stats["octomap"]["means_occupied"], 1.0);
  octomap::OcTree tree((tmp / "out" / "global.bt").string());
  ASSERT_EQ(tree.getResolution(), 0.05);
  ASSERT_GT(tree.getNumLeafNodes(), 0u);
  std::size_t occupied = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) occupied += tree.isNodeOccupied(*it);
  EXPECT_EQ(stats["octomap"]["occupied_leaves"], occupied);
  for (const Ellipsoid& e : scene.map.ellipsoids) {
    const octomap::OcTreeNode* node = tree.search(e.mean.x(), e.mean.y(), e.mean.z());
    ASSERT_TRUE(node && tree.isNodeOccupied(node)) << e.mean.transpose();
  }
  // The camera centres are free: the rays carved them.
  for (const Keyframe& k : scene.graph.keyframes()) {
    const Eigen::Vector3d c = k.T_W_K.translation();
    const octomap::OcTreeNode* node = tree.search(c.x(), c.y(), c.z());
    ASSERT_TRUE(node && !tree.isNodeOccupied(node));
  }
  MapExportOptions negative;
  negative.octomap_resolution_m = -1.0;
  EXPECT_THROW(exportMap(tmp / "bad", scene.graph, scene.map, negative), std::invalid_argument);
  EXPECT_FALSE(fs::exists(tmp / "bad"));
}

TEST(Export, EllipsoidSamplePointsAreTheSigmaPoints) {
  Ellipsoid e;
  e.mean = {1, 2, 3};
  e.cov = Eigen::Vector3d(0.01, 0.04, 0.0).asDiagonal();
  const std::vector<Eigen::Vector3d> p = ellipsoidSamplePoints(e);
  ASSERT_EQ(p.size(), 7u);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& x : p) mean += x / 7.0;
  for (const auto& x : p) scatter += (x - e.mean) * (x - e.mean).transpose();
  EXPECT_LT((mean - e.mean).norm(), 1e-12);
  EXPECT_LT((scatter / 2.0 - e.cov).norm(), 1e-12) << "+-1 sigma along each axis: scatter = 2 Sigma";
}

TEST(Export, AFolderThatCannotBeWrittenFailsClearlyAndWritesNothing) {
  const TwoViews scene;
  test::TempDir tmp;
  test::writeText(tmp / "file", "not a folder\n");
  for (const fs::path& dir : {tmp / "file", tmp / "file" / "sub"}) {
    try {
      exportMap(dir, scene.graph, scene.map);
      ADD_FAILURE() << "no error for " << dir;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(dir.string()), std::string::npos) << e.what();
    }
    EXPECT_THROW(checkExportFolder(dir), std::runtime_error);
  }
  // A file that cannot be replaced (a folder of its name is in the way): no file of this export
  // appears, earlier files stay as they were.
  fs::create_directories(tmp / "out" / "stats.json" / "x");
  test::writeText(tmp / "out" / "graph.txt", "old\n");
  EXPECT_THROW(exportMap(tmp / "out", scene.graph, scene.map), std::runtime_error);
  EXPECT_EQ(filesIn(tmp / "out"), (std::vector<std::string>{"graph.txt", "stats.json"}));
  EXPECT_EQ(test::readFile(tmp / "out" / "graph.txt"), "old\n");
}

}  // namespace
}  // namespace vdmap
