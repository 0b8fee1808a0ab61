// Accuracy against a reference mesh (docs/method.md 12): the tree-accelerated distances equal the
// brute-force ones, and known offsets give known errors.
#include <fstream>
#include <random>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "mapping/eval/mesh_accuracy.h"
#include "mapping/synth/builtin_scene.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

// The surface of the unit cube [0,1]^3, each face split into n x n squares of two triangles,
// wound so that (b - a) x (c - a) points outwards.
ColoredTriangleMesh unitCube(int n = 4) {
  ColoredTriangleMesh mesh;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const auto at = [&](int i, int j) {
        Eigen::Vector3f p;
        p(axis) = static_cast<float>(side);
        p(u) = static_cast<float>(i) / n;
        p(v) = static_cast<float>(j) / n;
        mesh.positions.push_back(p);
        mesh.colors.push_back({128, 128, 128});
        return static_cast<std::uint32_t>(mesh.positions.size() - 1);
      };
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          std::uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
          if (side == 0) std::swap(b, d);  // u x v is +axis; the side-0 face looks down -axis
          mesh.triangles.push_back({a, b, c});
          mesh.triangles.push_back({a, c, d});
        }
    }
  return mesh;
}

Eigen::Vector3f outwardNormal(const ColoredTriangleMesh& mesh, std::size_t t) {
  const auto& tri = mesh.triangles[t];
  const Eigen::Vector3f a = mesh.positions[tri[0]];
  return (mesh.positions[tri[1]] - a).cross(mesh.positions[tri[2]] - a).normalized();
}

AccuracyParams withSamples(std::size_t n) {
  AccuracyParams p;
  p.completion_samples = n;
  return p;
}

// Points on each triangle (interior barycentric grid), moved `offset_m` along its outer normal.
std::vector<Eigen::Vector3f> pointsOnCube(const ColoredTriangleMesh& mesh, float offset_m) {
  std::vector<Eigen::Vector3f> out;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    for (const auto& [r, s] : {std::pair{0.2f, 0.2f}, {0.6f, 0.2f}, {0.2f, 0.6f}, {0.3f, 0.3f}}) {
      const Eigen::Vector3f a = mesh.positions[tri[0]];
      const Eigen::Vector3f p = a + r * (mesh.positions[tri[1]] - a) + s * (mesh.positions[tri[2]] - a);
      out.push_back(p + offset_m * outwardNormal(mesh, t));
    }
  }
  return out;
}

TEST(Eval, ClosestPointOnTriangleRegions) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_TRUE(closestPointOnTriangle({0.2, 0.2, 3}, a, b, c).isApprox(Eigen::Vector3d(0.2, 0.2, 0)));
  EXPECT_TRUE(closestPointOnTriangle({-1, -1, 0}, a, b, c).isApprox(a));
  EXPECT_TRUE(closestPointOnTriangle({2, -0.5, 1}, a, b, c).isApprox(b));
  EXPECT_TRUE(closestPointOnTriangle({0.5, -2, 0}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0, 0)));
  EXPECT_TRUE(closestPointOnTriangle({1, 1, 0}, a, b, c).isApprox(Eigen::Vector3d(0.5, 0.5, 0)));
}

TEST(Eval, TreeDistancesEqualBruteForce) {
  // A bumpy height field plus the cube: triangles of many sizes; queries near, inside and far.
  ColoredTriangleMesh mesh = unitCube(5);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> h(-0.05f, 0.05f), q(-1.5f, 2.5f);
  const int n = 20, base = static_cast<int>(mesh.positions.size());
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      mesh.positions.emplace_back(-1.0f + 3.0f * i / n, -0.5f + h(rng), -1.0f + 3.0f * j / n);
      mesh.colors.push_back({0, 0, 0});
    }
  const auto id = [&](int i, int j) { return static_cast<std::uint32_t>(base + i * (n + 1) + j); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      mesh.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      mesh.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  std::vector<Eigen::Vector3f> points;
  for (int i = 0; i < 3000; ++i) points.emplace_back(q(rng), q(rng), q(rng));
  for (int i = 0; i < 20; ++i) points.emplace_back(40.0f * q(rng), -30.0f, 25.0f * q(rng));  // far outside
  const std::vector<double> fast = distancesToMesh(points, mesh), slow = distancesToMeshBruteForce(points, mesh);
  ASSERT_EQ(fast.size(), slow.size());
  for (std::size_t i = 0; i < fast.size(); ++i) ASSERT_EQ(fast[i], slow[i]) << "point " << i;

  // The point index against brute force the same way.
  std::vector<Eigen::Vector3f> cloud(points.begin(), points.begin() + 500);
  const std::vector<double> near = distancesToPoints(points, cloud);
  for (std::size_t i = 0; i < points.size(); i += 7) {
    double best = 1e30;
    for (const auto& c : cloud) best = std::min(best, (c.cast<double>() - points[i].cast<double>()).norm());
    ASSERT_EQ(near[i], best) << "point " << i;
  }
}

TEST(Eval, ExactSamplesScoreZero) {
  const ColoredTriangleMesh mesh = unitCube();
  const AccuracyReport r = evaluateAccuracy(sampleMeshSurface(mesh, 20000, 1), mesh, withSamples(20000));
  EXPECT_EQ(r.elements, 20000u);
  // Samples are stored as float: their distance to the surface is float rounding, < 1e-4 mm.
  EXPECT_LT(r.rmse_mm, 1e-3);
  EXPECT_GT(r.completion_ratio, 0.999);
}

TEST(Eval, OneCentimetreAlongTheNormalsScoresTenMillimetres) {
  const ColoredTriangleMesh mesh = unitCube();
  const AccuracyReport r = evaluateAccuracy(pointsOnCube(mesh, 0.01f), mesh, withSamples(5000));
  // Outside a convex solid, a point moved d along the normal of a face is exactly d from it;
  // the tolerance is float rounding of 1 m coordinates.
  EXPECT_NEAR(r.rmse_mm, 10.0, 1e-3);
  EXPECT_NEAR(r.mean_mm, 10.0, 1e-3);
  EXPECT_NEAR(r.median_mm, 10.0, 1e-3);
}

TEST(Eval, CompletionDropsWhenHalfTheMeshIsUncovered) {
  const ColoredTriangleMesh mesh = unitCube();
  const std::vector<Eigen::Vector3f> all = sampleMeshSurface(mesh, 20000, 2);
  std::vector<Eigen::Vector3f> half;
  for (const auto& p : all)
    if (p.x() < 0.5f) half.push_back(p);
  const AccuracyParams params = withSamples(20000);
  const AccuracyReport full = evaluateAccuracy(all, mesh, params), part = evaluateAccuracy(half, mesh, params);
  EXPECT_GT(full.completion_ratio, 0.99);
  // x >= 0.5 holds half of the area; only a 5 cm band beyond x = 0.5 is still within reach.
  EXPECT_NEAR(part.completion_ratio, 0.5 + 0.05 * 4 / 6, 0.02);
  EXPECT_GT(part.completion_mean_mm, 10 * full.completion_mean_mm);
  EXPECT_LT(part.rmse_mm, 1e-3);  // what is there is still exact
}

void writeAsciiPly(const std::filesystem::path& file, const ColoredTriangleMesh& mesh, bool faces) {
  std::ofstream out(file);
  out << "ply\nformat ascii 1.0\nelement vertex " << mesh.positions.size()
      << "\nproperty float x\nproperty float y\nproperty float z\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\n";
  if (faces) out << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\n";
  out << "end_header\n";
  for (const auto& p : mesh.positions) out << p.x() << " " << p.y() << " " << p.z() << " 0 0 0\n";
  if (faces)
    for (const auto& t : mesh.triangles) out << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
}

TEST(Eval, CommandLine) {
  test::TempDir dir;
  const ColoredTriangleMesh mesh = unitCube();
  writeAsciiPly(dir / "mesh.ply", mesh, true);
  ColoredTriangleMesh cloud;
  cloud.positions = pointsOnCube(mesh, 0.01f);
  writeAsciiPly(dir / "points.ply", cloud, false);
  const auto r = test::runVdmap("eval --map '" + (dir / "points.ply").string() + "' --mesh '" +
                                (dir / "mesh.ply").string() + "' --samples 2000 --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["rmse_mm"].get<double>(), 10.0, 1e-2);  // ascii text keeps ~6 digits
  EXPECT_EQ(j["elements"].get<std::size_t>(), cloud.positions.size());

  const auto bad =
      test::runVdmap("eval --map '" + (dir / "nope.ply").string() + "' --mesh '" + (dir / "mesh.ply").string() + "'");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("nope.ply: no such file"), std::string::npos) << bad.err;
  const auto not_mesh = test::runVdmap("eval --map '" + (dir / "points.ply").string() + "' --mesh '" +
                                       (dir / "points.ply").string() + "'");
  EXPECT_EQ(not_mesh.exit_code, 1);
  EXPECT_NE(not_mesh.err.find("no faces"), std::string::npos) << not_mesh.err;
}

// The whole comparison on two frames of the built-in scene: every contract key in bench.json,
// and every method's map lands on the reference mesh (so frames, poses and units agree).
TEST(Bench, BuiltinSceneWritesEveryKey) {
  test::TempDir dir;
  const auto synth = test::runVdmap("synth --builtin --builtin-frames 3 --out '" + (dir / "seq").string() + "'");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  writeAsciiPly(dir / "mesh.ply", makeBuiltinScene().mesh, true);
  const auto r = test::runVdmap("bench '" + (dir / "seq").string() + "' --frames 2 --mesh '" +
                                (dir / "mesh.ply").string() + "' --samples 5000 --out '" + dir.path().string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream in(dir / "bench.json");
  const auto j = nlohmann::json::parse(in);
  for (const char* key : {"frames", "vd_update_ms", "octomap_010_ms", "octomap_005_ms", "octomap_002_ms",
                          "ratio_octomap_010", "vd_pipeline_ms", "t_g_s", "sigma_e", "sigma_e_prime",
                          "t_g_us_per_ellipsoid", "ndt_om_010_ms", "open3d_tsdf_002_ms", "open3d_tsdf_001_ms"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["method_order"].size(), j["methods"].size());
  for (const auto& key : j["method_order"]) EXPECT_TRUE(j["methods"].contains(key)) << key;
  EXPECT_EQ(j["frames"], 2);
  EXPECT_TRUE(std::filesystem::exists(dir / "bench.md"));
  for (const auto& [key, m] : j["methods"].items()) {
    if (m.contains("note")) continue;  // a peer that is not built (Open3D is optional)
    ASSERT_TRUE(m.contains("accuracy")) << key;
    // The coarsest map (OctoMap 0.10 m voxel centres) is within half a voxel diagonal, 87 mm.
    EXPECT_LT(m["accuracy"]["median_mm"].get<double>(), 87.0) << key;
    EXPECT_GT(m["accuracy"]["completion_ratio_5cm"].get<double>(), 0.0) << key;
  }
}

}  // namespace
}  // namespace vdmap
