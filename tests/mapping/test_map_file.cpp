// Map files (mapping/files/map_file.h): what detectMapFile tells apart, and loadStaticMap's reading
// of a `vdmap map` folder, PLYs and OctoMaps written by vdmap's own exports.
#include <algorithm>
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include "mapping/core/error.h"
#include "mapping/files/map_export.h"
#include "mapping/files/map_file.h"
#include "mapping/files/octomap_export.h"
#include "mapping/files/ply_writer.h"
#include "mapping/io/camera_config.h"
#include "tests/support/box_room_keyframes.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;

// Two keyframes looking at a wall of the box room, and their global map (as test_export.cpp).
struct TwoViewMap {
  KeyframeGraph graph;
  GlobalMap map;
  TwoViewMap() {
    test::addTwoBoxRoomViews(&graph, cameraPreset("tum-default"));
    map = buildGlobalMap(graph, GlobalMapParams{});
  }
};

TEST(MapFile, DetectsEachKind) {
  const TwoViewMap scene;
  test::TempDir tmp;
  test::writeTinySequence(tmp / "seq", 2);
  MapExportOptions options;
  options.octomap_resolution_m = 0.1;
  exportMap(tmp / "map", scene.graph, scene.map, options);
  test::writeText(tmp / "s.vdmap", "");
  writePointPly(tmp / "points.ply", scene.map.ellipsoids);
  test::writeText(tmp / "view.json", "{\n  \"vdmap_view\": 1\n}\n");
  test::writeText(tmp / "other.json", "{\"thresholds\": {}}\n");
  test::writeText(tmp / "notes.txt", "hello\n");
  fs::create_directories(tmp / "empty");

  EXPECT_EQ(detectMapFile(tmp / "seq"), MapFileKind::kSequence);
  EXPECT_EQ(detectMapFile(tmp / "map"), MapFileKind::kMapFolder);
  EXPECT_EQ(detectMapFile(tmp / "s.vdmap"), MapFileKind::kSession);
  EXPECT_EQ(detectMapFile(tmp / "map" / "global_ellipsoids.ply"), MapFileKind::kEllipsoidPly);
  EXPECT_EQ(detectMapFile(tmp / "map" / "global_points.ply"), MapFileKind::kPointPly);
  EXPECT_EQ(detectMapFile(tmp / "points.ply"), MapFileKind::kPointPly);
  EXPECT_EQ(detectMapFile(tmp / "map" / "global.bt"), MapFileKind::kOctomap);
  EXPECT_EQ(detectMapFile(tmp / "view.json"), MapFileKind::kViewFile);
  for (const char* bad : {"other.json", "notes.txt", "empty", "missing.ply"}) {
    try {
      detectMapFile(tmp / bad);
      ADD_FAILURE() << bad << " was given a kind";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find((tmp / bad).string()), std::string::npos) << e.what();
    }
  }
  // A sequence, session or view file is no static map.
  EXPECT_THROW(loadStaticMap(tmp / "seq"), InputError);
  EXPECT_THROW(loadStaticMap(tmp / "view.json"), InputError);
}

TEST(MapFile, AFolderListsFoldersFirstWithWhatEachOpensAs) {
  const TwoViewMap scene;
  test::TempDir tmp;
  test::writeTinySequence(tmp / "b_seq", 2);
  exportMap(tmp / "C_map", scene.graph, scene.map, {});
  fs::create_directories(tmp / "a_plain");
  writePointPly(tmp / "a.ply", scene.map.ellipsoids);
  test::writeText(tmp / "Z.txt", "notes\n");
  test::writeText(tmp / ".hidden.ply", "");
  const std::vector<FolderEntry> entries = listFolder(tmp.path());
  std::vector<std::string> names, kinds;
  for (const FolderEntry& e : entries) {
    names.push_back(e.path.filename().string() + (e.folder ? "/" : ""));
    kinds.push_back(e.kind ? mapFileKindName(*e.kind) : "-");
  }
  EXPECT_EQ(names, (std::vector<std::string>{"a_plain/", "b_seq/", "C_map/", "a.ply", "Z.txt"}));
  EXPECT_EQ(kinds, (std::vector<std::string>{"-", "sequence", "map folder", "point PLY", "-"}));
  EXPECT_THROW(listFolder(tmp / "missing"), InputError);
}

TEST(MapFile, AMapFolderReadsItsEllipsoidsKeyframesAndGraph) {
  const TwoViewMap scene;
  test::TempDir tmp;
  MapExportOptions options;
  options.trajectory = {
      {1.0, Transform::Identity()}, {2.0, scene.graph.keyframe(1).T_W_K}, {3.0, Transform::Identity()}};
  exportMap(tmp / "map", scene.graph, scene.map, options);
  const StaticMap map = loadStaticMap(tmp / "map");
  EXPECT_EQ(map.kind, MapFileKind::kMapFolder);
  ASSERT_EQ(map.ellipsoids.size(), scene.map.ellipsoids.size());
  EXPECT_EQ(map.source_elements, scene.map.ellipsoids.size());
  for (std::size_t i = 0; i < map.ellipsoids.size(); ++i) {
    ASSERT_EQ(map.ellipsoids[i].mean.cast<float>(), scene.map.ellipsoids[i].mean.cast<float>());
    ASSERT_EQ(map.ellipsoids[i].keyframe, scene.map.ellipsoids[i].keyframe);
  }
  ASSERT_EQ(map.keyframes.size(), 2u);
  EXPECT_TRUE(map.keyframes[1].T_W_C.isApprox(scene.graph.keyframe(1).T_W_K, 1e-6));
  ASSERT_EQ(map.edges.size(), 1u);
  EXPECT_EQ(map.edges[0].a, 0);
  EXPECT_EQ(map.edges[0].b, 1);
  EXPECT_DOUBLE_EQ(map.edges[0].weight, 0.6);
  EXPECT_EQ(map.trajectory.size(), 3u);
  EXPECT_NE(map.stats_json.find("\"sigma_e_prime\""), std::string::npos);
}

TEST(MapFile, ReadsOccupiedOctomapLeaves) {
  const TwoViewMap scene;
  test::TempDir tmp;
  const OctomapExportReport report = writeOctomapBt(tmp / "a.bt", scene.graph, scene.map.ellipsoids, 0.05);
  ASSERT_GT(report.occupied_leaves, 10u);
  const StaticMap map = loadStaticMap(tmp / "a.bt");
  EXPECT_EQ(map.kind, MapFileKind::kOctomap);
  EXPECT_EQ(map.ellipsoids.size(), report.occupied_leaves);
  EXPECT_EQ(map.source_elements, report.occupied_leaves);
  EXPECT_DOUBLE_EQ(map.sigma_m, 0.05);
  // Every leaf: an occupied voxel of the tree at its centre, Sigma = size^2/12 I (a uniform cube).
  octomap::OcTree tree((tmp / "a.bt").string());
  for (const Ellipsoid& e : map.ellipsoids) {
    const octomap::OcTreeNode* node = tree.search(e.mean.x(), e.mean.y(), e.mean.z());
    ASSERT_TRUE(node && tree.isNodeOccupied(node)) << e.mean.transpose();
    const double size2 = e.cov(0, 0) * 12.0;
    const double steps = std::log2(std::sqrt(size2) / 0.05);  // pruned leaves are 2^k voxels wide
    ASSERT_NEAR(steps, std::round(steps), 1e-9);
    ASSERT_EQ(e.cov, Eigen::Matrix3d::Identity() * e.cov(0, 0));
  }
  // The means of the map fall in the leaves read (the export occupies every mean's voxel). Leaf
  // centres are floats: a mean on a voxel face (the box room's wall at z = 2 m) is within 1e-5 m.
  std::size_t inside = 0;
  for (const Ellipsoid& m : scene.map.ellipsoids)
    inside += std::any_of(map.ellipsoids.begin(), map.ellipsoids.end(), [&](const Ellipsoid& e) {
      return ((m.mean - e.mean).cwiseAbs().array() <= std::sqrt(e.cov(0, 0) * 12.0) / 2 + 1e-5).all();
    });
  EXPECT_EQ(inside, scene.map.ellipsoids.size());
}

// .ot files (liboctomap's full format): an OcTree's occupied leaves coloured by height, a
// ColorOcTree's with their own colours; free leaves are left out.
TEST(MapFile, ReadsOtFilesOfBothTreeTypes) {
  test::TempDir tmp;
  const std::vector<octomap::point3d> occupied = {{0.05f, 0.05f, 0.05f}, {1.05f, 0.05f, 0.55f}, {0.55f, 0.95f, 1.25f}};
  octomap::OcTree plain(0.1);
  octomap::ColorOcTree coloured(0.1);
  for (const octomap::point3d& p : occupied) {
    plain.updateNode(p, true);
    coloured.updateNode(p, true);
    coloured.setNodeColor(p.x(), p.y(), p.z(), 200, 10, 30);
  }
  plain.updateNode(octomap::point3d(-1.f, -1.f, -1.f), false);  // a free leaf
  coloured.updateNode(octomap::point3d(-1.f, -1.f, -1.f), false);
  {
    std::ofstream a(tmp / "plain.ot", std::ios::binary), b(tmp / "colour.ot", std::ios::binary);
    plain.write(a);
    coloured.write(b);
  }
  for (const char* name : {"plain.ot", "colour.ot"}) {
    SCOPED_TRACE(name);
    const StaticMap map = loadStaticMap(tmp / name);
    EXPECT_EQ(map.kind, MapFileKind::kOctomap);
    ASSERT_EQ(map.ellipsoids.size(), occupied.size());
    for (const Ellipsoid& e : map.ellipsoids) {
      EXPECT_NEAR(e.cov(0, 0), 0.01 / 12, 1e-9);
      const bool found = std::any_of(occupied.begin(), occupied.end(), [&](const octomap::point3d& p) {
        return (e.mean - Eigen::Vector3d(p.x(), p.y(), p.z())).norm() < 1e-6;
      });
      EXPECT_TRUE(found) << e.mean.transpose();
      if (std::string(name) == "colour.ot") {
        EXPECT_EQ(e.color, Eigen::Vector3f(200, 10, 30));
      }
    }
  }
  const std::string bytes = test::readFile(tmp / "colour.ot");
  test::writeText(tmp / "cut.ot", bytes.substr(0, bytes.size() - 3));
  EXPECT_THROW(loadStaticMap(tmp / "cut.ot"), InputError);
  test::writeText(tmp / "other.ot", "# Octomap OcTree file\nid CountingOcTree\nsize 1\nres 0.1\ndata\n");
  EXPECT_THROW(loadStaticMap(tmp / "other.ot"), InputError);
}

TEST(MapFile, ACorruptOctomapIsRefusedNamingIt) {
  const TwoViewMap scene;
  test::TempDir tmp;
  writeOctomapBt(tmp / "a.bt", scene.graph, scene.map.ellipsoids, 0.1);
  const std::string bytes = test::readFile(tmp / "a.bt");
  test::writeText(tmp / "truncated.bt", bytes.substr(0, bytes.size() - 7));
  test::writeText(tmp / "longer.bt", bytes + "xyz");
  test::writeText(tmp / "text.bt", "hello\n");
  test::writeText(tmp / "noheader.bt", "# Octomap OcTree binary file\nid OcTree\nres 0.1\n");
  for (const char* name : {"truncated.bt", "longer.bt", "text.bt", "noheader.bt"}) {
    try {
      loadStaticMap(tmp / name);
      ADD_FAILURE() << name << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find((tmp / name).string()), std::string::npos) << e.what();
    }
  }
}

TEST(MapFile, APointPlyBecomesIsotropicEllipsoids) {
  // A 20 x 30 grid of points 4 cm apart: the median spacing is 4 cm, sigma 2 cm.
  std::vector<Ellipsoid> grid;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 30; ++j) {
      Ellipsoid e;
      e.mean = {0.04 * i, 0.04 * j, 1.0};
      e.color = {10.f * static_cast<float>(i), 200, 30};
      grid.push_back(e);
    }
  test::TempDir tmp;
  writePointPly(tmp / "grid.ply", grid);
  const StaticMap map = loadStaticMap(tmp / "grid.ply");
  EXPECT_EQ(map.kind, MapFileKind::kPointPly);
  ASSERT_EQ(map.ellipsoids.size(), grid.size());
  EXPECT_NEAR(map.sigma_m, 0.02, 1e-6);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const Ellipsoid& e = map.ellipsoids[i];
    ASSERT_TRUE(e.mean.isApprox(grid[i].mean, 1e-6));
    ASSERT_EQ(e.cov, Eigen::Matrix3d::Identity() * (map.sigma_m * map.sigma_m));
    ASSERT_EQ(e.color, grid[i].color);
  }
}

TEST(MapFile, MedianSpacingOfScatteredPoints) {
  // Points along a line at spacings 1, 2, 3, ... cm: nearest distances 1, 1, 2, 3, ..., median known.
  std::vector<Eigen::Vector3d> points;
  double x = 0;
  for (int i = 1; i <= 9; ++i) {
    points.push_back({x, 0, 0});
    x += 0.01 * i;
  }
  // nearest: 0.01, 0.01, 0.02, 0.03, 0.04, 0.05, 0.06, 0.07, 0.08 -> median (index 4) 0.04
  EXPECT_NEAR(medianNearestNeighbourSpacing(points), 0.04, 1e-12);
  EXPECT_EQ(medianNearestNeighbourSpacing({{1, 2, 3}}), 0.0);
  EXPECT_EQ(medianNearestNeighbourSpacing({{1, 2, 3}, {1, 2, 3}}), 0.0);
}

}  // namespace
}  // namespace vdmap
