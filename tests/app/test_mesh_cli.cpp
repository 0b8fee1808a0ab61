// vdmap mesh and vdmap map --mesh (docs/cli.md "mesh", docs/method.md 14) on a tiny session of the
// built-in scene.
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <gtest/gtest.h>

#include "mapping/files/ply_reader.h"
#include "mapping/io/trajectory_io.h"
#include "tests/support/test_util.h"

namespace vdmap::test {
namespace mesh_cli {  // a unity build joins this file with others that have their own q and Fixture
namespace {

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// 3 frames of the built-in walk, 16 px cells, mapped with --mesh and saved; made once.
struct Fixture {
  TempDir dir;
  fs::path session, map;
  Fixture() {
    const RunResult s = runVdmap("synth --builtin --builtin-frames 8 --out " + q(dir / "bi"));
    if (s.exit_code != 0) throw std::runtime_error("synth: " + s.err);
    session = dir / "s.vdmap";
    map = dir / "m";
    const RunResult m = runVdmap("map " + q(dir / "bi") + " --frames 0:3 --cell-size 16 --mesh --out " + q(map) +
                                 " --save " + q(session));
    if (m.exit_code != 0) throw std::runtime_error("map: " + m.err);
  }
};
const Fixture& fixture() {
  static const Fixture f;
  return f;
}

TEST(MeshCli, SessionMeshIsMapMeshAndTheSameForAnyThreadCount) {
  const Fixture& f = fixture();
  TempDir out;
  const RunResult one = runVdmap("mesh " + q(f.session) + " --out " + q(out / "one.ply") + " --threads 1");
  ASSERT_EQ(one.exit_code, 0) << one.err;
  EXPECT_NE(one.out.find("triangles from"), std::string::npos) << one.out;
  const RunResult two = runVdmap("mesh " + q(f.session) + " --out " + q(out / "two.ply") + " --threads 2");
  ASSERT_EQ(two.exit_code, 0) << two.err;
  const std::string bytes = readFile(out / "one.ply");
  EXPECT_EQ(bytes, readFile(out / "two.ply"));
  EXPECT_EQ(bytes, readFile(f.map / "global_mesh.ply"));
  const ColoredTriangleMesh mesh = readPlyMesh(out / "one.ply");
  EXPECT_GT(mesh.triangles.size(), 100u);
  EXPECT_NE(bytes.find("property float nx"), std::string::npos);
}

TEST(MeshCli, MapFolderGivesTheSessionsMeshAsObj) {
  const Fixture& f = fixture();
  TempDir out;
  const RunResult r = runVdmap("mesh " + q(f.map) + " --out " + q(out / "m.obj"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ColoredTriangleMesh session_mesh = readPlyMesh(f.map / "global_mesh.ply");
  std::ifstream in(out / "m.obj");
  std::size_t v = 0, vn = 0, faces = 0;
  for (std::string line; std::getline(in, line);) {
    v += line.rfind("v ", 0) == 0;
    vn += line.rfind("vn ", 0) == 0;
    faces += line.rfind("f ", 0) == 0;
  }
  EXPECT_EQ(v, vn);
  // local_maps.ply holds the same kept cells, its means rounded to float in the world frame.
  EXPECT_NEAR(static_cast<double>(faces), static_cast<double>(session_mesh.triangles.size()),
              0.01 * session_mesh.triangles.size());
}

TEST(MeshCli, CorrectedKeyframePosesMoveTheMeshWithoutReintegration) {
  const Fixture& f = fixture();
  TempDir out;
  std::vector<StampedPose> poses = readTumTrajectory(f.map / "keyframes.txt");
  for (StampedPose& p : poses) p.T_W_C.pretranslate(Eigen::Vector3d(1.0, 0.0, 0.0));
  std::ofstream file(out / "moved.txt");
  for (const StampedPose& p : poses) {
    const Eigen::Quaterniond r(p.T_W_C.linear());
    const Eigen::Vector3d t = p.T_W_C.translation();
    char line[256];
    std::snprintf(line, sizeof line, "%.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", p.t, t.x(), t.y(), t.z(), r.x(),
                  r.y(), r.z(), r.w());
    file << line;
  }
  file.close();
  const RunResult r =
      runVdmap("mesh " + q(f.session) + " --out " + q(out / "moved.ply") + " --keyframe-poses " + q(out / "moved.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const ColoredTriangleMesh before = readPlyMesh(f.map / "global_mesh.ply"), after = readPlyMesh(out / "moved.ply");
  ASSERT_EQ(before.positions.size(), after.positions.size());
  EXPECT_TRUE(before.triangles == after.triangles);
  for (std::size_t i = 0; i < before.positions.size(); ++i)
    ASSERT_LT((after.positions[i] - before.positions[i] - Eigen::Vector3f(1, 0, 0)).norm(), 1e-4) << i;
}

TEST(MeshCli, EmptyMapGivesAnEmptyMeshWithANote) {
  const Fixture& f = fixture();
  TempDir out;
  const RunResult m =
      runVdmap("map " + q(f.dir.path() / "bi") + " --frames 0:2 --min-depth 0.1 --max-depth 0.11 --out " +
               q(out / "m") + " --save " + q(out / "e.vdmap"));
  ASSERT_EQ(m.exit_code, 0) << m.err;
  const RunResult r = runVdmap("mesh " + q(out / "e.vdmap") + " --out " + q(out / "e.ply"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("vdmap mesh: note:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("the mesh is empty"), std::string::npos) << r.err;
  const std::string bytes = readFile(out / "e.ply");
  EXPECT_NE(bytes.find("element vertex 0\n"), std::string::npos);
  EXPECT_NE(bytes.find("element face 0\n"), std::string::npos);
}

TEST(MeshCli, TooLargeAMeshIsRefusedBeforeAnyWorkWithTheEstimate) {
  const Fixture& f = fixture();
  TempDir out;
  const RunResult r = runVdmap("mesh " + q(f.session) + " --out " + q(out / "big.ply") + " --max-triangles 10");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("the mesh would have up to "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("above the limit of 10"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(out / "big.ply"));
  const RunResult stl = runVdmap("mesh " + q(f.session) + " --out " + q(out / "m.stl"));
  EXPECT_EQ(stl.exit_code, 1);
  EXPECT_NE(stl.err.find(".ply or .obj"), std::string::npos) << stl.err;
}

}  // namespace
}  // namespace mesh_cli
}  // namespace vdmap::test
