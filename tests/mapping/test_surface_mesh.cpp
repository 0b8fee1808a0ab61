// The surface mesh (docs/method.md 14) of analytic scenes: the box room's walls, a depth step, fusion
// of overlapping keyframes, determinism, the reference without pruning, and the files it is written to.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "mapping/files/ply_writer.h"
#include "mapping/io/camera_config.h"
#include "mapping/mesh/detail/mesh_pieces.h"
#include "mapping/mesh/surface_mesh.h"
#include "tests/support/box_room_keyframes.h"

namespace vdmap {
namespace {

const PinholeCamera kCamera = cameraPreset("tum-default");

std::vector<std::vector<bool>> keptOf(const KeyframeGraph& graph) {
  std::vector<std::vector<bool>> kept;
  for (const Keyframe& k : graph.keyframes()) kept.push_back(keptCells(k.container, FilterParams{}));
  return kept;
}

// Distance of a point inside the box room [-2,2] x [-1.5,1.5] x [-2,2] to its walls.
double boxDistance(const Eigen::Vector3d& p) {
  const Eigen::Vector3d lo(-2.0, -1.5, -2.0), hi(2.0, 1.5, 2.0);
  return std::min((p - lo).minCoeff(), (hi - p).minCoeff());
}

double triangleArea(const ColoredTriangleMesh& mesh, const std::array<std::uint32_t, 3>& t) {
  return 0.5 * (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]).norm();
}

double meshArea(const ColoredTriangleMesh& mesh) {
  double area = 0;
  for (const auto& t : mesh.triangles) area += triangleArea(mesh, t);
  return area;
}

// Four views turning about the room's centre, and one close to the +z wall.
KeyframeGraph boxRoomGraph() {
  KeyframeGraph graph;
  for (int i = 0; i < 4; ++i) {
    const double a = i * M_PI / 2.5;
    const Transform T = test::lookAt({0.2 * i - 0.3, 0.1, 0.0}, {2.0 * std::sin(a), 0.3, 2.0 * std::cos(a)});
    test::addBoxRoomKeyframe(&graph, kCamera, T, T);
  }
  const Transform near = test::lookAt({0.1, 0.0, 1.2}, {0.2, 0.1, 2.0});
  test::addBoxRoomKeyframe(&graph, kCamera, near, near);
  return graph;
}

void expectSameMesh(const ColoredTriangleMesh& a, const ColoredTriangleMesh& b) {
  ASSERT_EQ(a.positions.size(), b.positions.size());
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  EXPECT_TRUE(a.positions == b.positions);
  EXPECT_TRUE(a.normals == b.normals);
  EXPECT_TRUE(a.colors == b.colors);
  EXPECT_TRUE(a.triangles == b.triangles);
}

// The 95th and 100th percentiles of the distances to the walls of the mesh's vertices and of its
// triangles' centroids.
struct WallDistances {
  double vertex_p95 = 0, vertex_max = 0, centroid_p95 = 0, centroid_max = 0;
};

WallDistances wallDistances(const ColoredTriangleMesh& mesh) {
  std::vector<double> v, c;
  for (const Eigen::Vector3f& p : mesh.positions) v.push_back(boxDistance(p.cast<double>()));
  for (const auto& t : mesh.triangles)
    c.push_back(
        boxDistance(((mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0f).cast<double>()));
  std::sort(v.begin(), v.end());
  std::sort(c.begin(), c.end());
  return {v[v.size() * 95 / 100], v.back(), c[c.size() * 95 / 100], c.back()};
}

TEST(SurfaceMesh, BoxRoomMeshLiesOnItsWallsWithUnitNormalsAndNothingNonFinite) {
  const KeyframeGraph graph = boxRoomGraph();
  MeshStats stats;
  const ColoredTriangleMesh mesh = buildSurfaceMesh(graph, keptOf(graph), MeshParams{}, &stats);
  ASSERT_GT(mesh.triangles.size(), 10000u);
  EXPECT_EQ(stats.keyframes, 5u);
  EXPECT_GT(stats.covered_triangles, 0u);
  EXPECT_EQ(stats.piece_triangles - stats.covered_triangles, mesh.triangles.size());
  ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
  ASSERT_EQ(mesh.colors.size(), mesh.positions.size());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    ASSERT_TRUE(mesh.positions[i].allFinite());
    ASSERT_TRUE(mesh.normals[i].allFinite());
    EXPECT_NEAR(mesh.normals[i].norm(), 1.0, 1e-5);
  }
  for (const auto& t : mesh.triangles)
    for (std::uint32_t v : t) ASSERT_LT(v, mesh.positions.size());
  // Cell means of a depth image quantised to 0.2 mm lie on the walls; a vertex averaging the cells of
  // 2 x 2 at a corner of the room, and a triangle across one, cut it by millimetres.
  const WallDistances d = wallDistances(mesh);
  EXPECT_LT(d.vertex_p95, 1e-3);
  EXPECT_LT(d.centroid_p95, 1e-3);
  EXPECT_LT(d.vertex_max, 0.02);
  EXPECT_LT(d.centroid_max, 0.03);
  // One vertex per cell: every vertex is a cell mean, on a wall but for the few cells the filter kept
  // in a corner of the room (their mean lies inside the corner).
  MeshParams cells;
  cells.stride = 1;
  const WallDistances e = wallDistances(buildSurfaceMesh(graph, keptOf(graph), cells));
  EXPECT_LT(e.vertex_p95, 1e-4);
  EXPECT_LT(e.vertex_max, 0.01);
  EXPECT_LT(e.centroid_p95, 1e-3);
}

TEST(SurfaceMesh, NormalsFaceTheCameraThatSawThem) {
  KeyframeGraph graph;
  const Transform T = test::lookAt({0, 0, 0}, {0, 0, 2});
  test::addBoxRoomKeyframe(&graph, kCamera, T, T);
  const ColoredTriangleMesh mesh = buildSurfaceMesh(graph, keptOf(graph), MeshParams{});
  ASSERT_FALSE(mesh.triangles.empty());
  for (std::size_t i = 0; i < mesh.positions.size(); ++i)
    EXPECT_LT(mesh.normals[i].dot(mesh.positions[i]), 0.0f) << i;  // the camera is at the origin
  for (const auto& t : mesh.triangles) {                           // front faces (counter-clockwise) face it too
    const Eigen::Vector3f n =
        (mesh.positions[t[1]] - mesh.positions[t[0]]).cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    EXPECT_LT(n.dot(mesh.positions[t[0]]), 0.0f);
  }
}

// The tests below look at the +z wall (2 m away) from 2 m and from 0.8 m: a triangle of the default
// mesh spans half a block of 5 px cells at the default stride, so one smaller than at 1.3 m is the near view's.
const double kFineArea = 0.5 * std::pow(1.3 * 5 * MeshParams{}.stride / kCamera.fx, 2);

TEST(SurfaceMesh, FusionKeepsTheFinerKeyframeWhereTwoSeeTheSameWall) {
  KeyframeGraph graph;
  const Transform far = test::lookAt({0, 0, 0}, {0, 0, 2}), near = test::lookAt({0, 0, 1.2}, {0, 0, 2});
  test::addBoxRoomKeyframe(&graph, kCamera, far, far);
  KeyframeGraph far_only = graph;
  test::addBoxRoomKeyframe(&graph, kCamera, near, near);
  MeshParams unfused;
  unfused.fuse = false;
  const double far_area = meshArea(buildSurfaceMesh(far_only, keptOf(far_only), MeshParams{}));
  const ColoredTriangleMesh fused = buildSurfaceMesh(graph, keptOf(graph), MeshParams{});
  const ColoredTriangleMesh both = buildSurfaceMesh(graph, keptOf(graph), unfused);
  // The near view sees a part of what the far one sees: fused, the area is the far view's alone
  // (less the seams), unfused the near piece comes twice.
  EXPECT_NEAR(meshArea(fused), far_area, 0.03 * far_area);
  EXPECT_GT(meshArea(both), 1.1 * far_area);
  // Where the near view sees the +z wall, the triangles are the near view's (finer ones).
  double fine = 0, coarse = 0;
  for (const auto& t : fused.triangles) {
    const Eigen::Vector3f c = (fused.positions[t[0]] + fused.positions[t[1]] + fused.positions[t[2]]) / 3.0f;
    if (std::abs(c.x()) < 0.2f && std::abs(c.y()) < 0.2f && c.z() > 1.9f)
      (triangleArea(fused, t) < kFineArea ? fine : coarse) += 1;
  }
  EXPECT_GT(fine, 100);
  EXPECT_EQ(coarse, 0);
}

// A keyframe whose local map holds `frames` ray-cast frames of the box room from T_W_K, of every
// `every`-th pixel each way, with Gaussian depth noise of sd `noise_m` (seeded).
int addBoxRoomViews(KeyframeGraph* graph, const Transform& T_W_K, int frames, int every, double noise_m) {
  Keyframe k{0, 0, 0.0, T_W_K, {}, {}, {}, KeyframeContainer(kCamera, 5), 0, {}};
  cv::RNG rng(11);
  for (int f = 0; f < frames; ++f) {
    RgbdFrame frame = test::renderBoxRoom(kCamera, T_W_K);
    for (int v = 0; v < frame.depth.rows; ++v)
      for (int u = 0; u < frame.depth.cols; ++u) {
        std::uint16_t& d = frame.depth.at<std::uint16_t>(v, u);
        d = (u % every || v % every)
                ? 0
                : static_cast<std::uint16_t>(std::lround(d + rng.gaussian(noise_m) * kCamera.depth_scale));
      }
    LocalMapIntegrator().integrateFrame(frame, kCamera, T_W_K, &k.container, nullptr);
  }
  return graph->add(std::move(k)).id;
}

TEST(SurfaceMesh, FusionKeepsTheBetterSupportedKeyframeWhereTheNearerHoldsFewNoisyPoints) {
  // A far keyframe holding 8 exact frames of the +z wall (2 m away) and a near one (0.8 m away) holding
  // one frame of every 3rd pixel with 3 mm of depth noise: the near one resolves the wall finer, the far
  // one measured it with more points per square metre (8 / 2^2 against 1 / 9 / 0.8^2), and its surface
  // is the exact one. Every cell is kept, so the near piece is not lost to the filter.
  KeyframeGraph graph;
  addBoxRoomViews(&graph, test::lookAt({0, 0, 0}, {0, 0, 2}), 8, 1, 0.0);
  addBoxRoomViews(&graph, test::lookAt({0, 0, 1.2}, {0, 0, 2}), 1, 3, 0.003);
  std::vector<std::vector<bool>> kept;
  for (const Keyframe& k : graph.keyframes()) kept.emplace_back(k.container.size(), true);
  const ColoredTriangleMesh fused = buildSurfaceMesh(graph, kept, MeshParams{});
  // Where both see the wall, the triangles are the far view's (coarser ones) and lie on the wall.
  std::size_t fine = 0, coarse = 0;
  for (const auto& t : fused.triangles) {
    const Eigen::Vector3f c = (fused.positions[t[0]] + fused.positions[t[1]] + fused.positions[t[2]]) / 3.0f;
    if (std::abs(c.x()) < 0.2f && std::abs(c.y()) < 0.2f && c.z() > 1.9f) {
      (triangleArea(fused, t) < kFineArea ? fine : coarse) += 1;
      EXPECT_LT(std::abs(c.z() - 2.0f), 1e-3f);  // the near piece's vertices stray by about a millimetre
    }
  }
  EXPECT_EQ(fine, 0u);
  EXPECT_GT(coarse, 50u);
}

TEST(SurfaceMesh, DepthStepIsLeftOpen) {
  // A board at 1 m in front of the left half of a wall at 2 m.
  KeyframeGraph graph;
  RgbdFrame frame;
  frame.T_W_C = Transform::Identity();
  frame.rgb = cv::Mat(kCamera.height, kCamera.width, CV_8UC3, cv::Scalar(90, 120, 150));
  frame.depth = cv::Mat(kCamera.height, kCamera.width, CV_16UC1);
  for (int v = 0; v < kCamera.height; ++v)
    for (int u = 0; u < kCamera.width; ++u)
      frame.depth.at<std::uint16_t>(v, u) =
          static_cast<std::uint16_t>((u < kCamera.width / 2 ? 1.0 : 2.0) * kCamera.depth_scale);
  Keyframe k{0, 0, 0.0, Transform::Identity(), {}, {}, {}, KeyframeContainer(kCamera, 5), 0, {}};
  LocalMapIntegrator().integrateFrame(frame, kCamera, Transform::Identity(), &k.container, nullptr);
  graph.add(std::move(k));
  const ColoredTriangleMesh mesh = buildSurfaceMesh(graph, keptOf(graph), MeshParams{});
  std::size_t near = 0, far = 0;
  for (const auto& t : mesh.triangles) {
    float lo = 9, hi = 0;
    for (std::uint32_t v : t) {
      lo = std::min(lo, mesh.positions[v].z());
      hi = std::max(hi, mesh.positions[v].z());
    }
    EXPECT_LT(hi - lo, 0.01f);  // no triangle bridges the step
    (hi < 1.5f ? near : far) += 1;
  }
  EXPECT_GT(near, 1000u);
  EXPECT_GT(far, 1000u);
}

TEST(SurfaceMesh, SameForAnyThreadCountAndAsTheReferenceWithoutPruning) {
  const KeyframeGraph graph = boxRoomGraph();
  const auto kept = keptOf(graph);
  MeshParams one, two;
  one.threads = 1;
  two.threads = 2;
  const ColoredTriangleMesh a = buildSurfaceMesh(graph, kept, one);
  expectSameMesh(a, buildSurfaceMesh(graph, kept, two));
  expectSameMesh(a, mesh_detail::buildMesh(graph, kept, two, nullptr, false));
}

TEST(SurfaceMesh, EmptyMapGivesAnEmptyMeshAndATooLargeOneIsRefusedWithTheEstimate) {
  const ColoredTriangleMesh empty = buildSurfaceMesh(KeyframeGraph{}, {}, MeshParams{});
  EXPECT_TRUE(empty.positions.empty());
  EXPECT_TRUE(empty.triangles.empty());
  const KeyframeGraph graph = boxRoomGraph();
  const auto kept = keptOf(graph);
  MeshParams small;
  small.max_triangles = 1000;
  try {
    buildSurfaceMesh(graph, kept, small);
    FAIL() << "no refusal";
  } catch (const std::length_error& e) {
    EXPECT_NE(std::string(e.what()).find(std::to_string(meshEstimate(graph, kept, small.stride))), std::string::npos)
        << e.what();
  }
  EXPECT_GE(meshEstimate(graph, kept, MeshParams{}.stride),
            buildSurfaceMesh(graph, kept, MeshParams{}).triangles.size());
  EXPECT_THROW(buildSurfaceMesh(graph, {}, MeshParams{}), std::invalid_argument);
}

TEST(SurfaceMesh, PlyAndObjKeepColoursAndNormals) {
  ColoredTriangleMesh mesh;
  mesh.positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  mesh.colors = {{{255, 0, 0}}, {{0, 255, 0}}, {{0, 0, 255}}};
  mesh.normals = {{0, 0, -1}, {0, 0, -1}, {0, 0, -1}};
  mesh.triangles = {{{0, 2, 1}}};
  test::TempDir dir;
  writeMeshPly(dir.path() / "m.ply", mesh);
  const ColoredTriangleMesh back = readPlyMesh(dir.path() / "m.ply");
  EXPECT_TRUE(back.positions == mesh.positions);
  EXPECT_TRUE(back.colors == mesh.colors);
  EXPECT_TRUE(back.triangles == mesh.triangles);
  const PlyVertexTable table = readPlyVertices(dir.path() / "m.ply");
  ASSERT_GE(table.column("nz"), 0);
  EXPECT_EQ(table.at(1, table.column("nz")), -1.0);
  writeMeshObj(dir.path() / "m.obj", mesh);
  EXPECT_EQ(test::readFile(dir.path() / "m.obj"),
            "# vdmap mesh\nv 0 0 1 1 0 0\nv 1 0 1 0 1 0\nv 0 1 1 0 0 1\nvn 0 0 -1\nvn 0 0 -1\nvn 0 0 -1\n"
            "f 1//1 3//3 2//2\n");
}

}  // namespace
}  // namespace vdmap
