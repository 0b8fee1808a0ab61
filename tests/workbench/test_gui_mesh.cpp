// The workbench's mesh layer without a window (docs/workbench.md "Mesh"): the mapping worker builds
// the surface mesh with every global map while the layer is on, from the same local maps, poses
// and kept cells, so a threshold or pose edit re-meshes without re-integration.
#include <memory>

#include <gtest/gtest.h>

#include "app/workbench/workbench.h"
#include "mapping/files/ply_writer.h"
#include "render/map_scene.h"
#include "tests/support/render_scenes.h"
#include "tests/support/test_util.h"

namespace vdmap::app::gui {
namespace {

// The mesh buildSurfaceMesh makes of the worker's local maps with the map shown's kept cells.
render::ColoredMesh meshOfShownMap(MappingWorker& worker) {
  render::ColoredMesh mesh;
  worker.withMapper([&](const Mapper& mapper, const GlobalSnapshot& shown) {
    mesh = render::toColoredMesh(buildSurfaceMesh(mapper.graph(), shown.map, MeshParams{}, shown.params));
    return std::string();
  });
  worker.waitIdle();
  return mesh;
}

TEST(GuiMesh, TheLayerOnMeshesEveryMapAndAThresholdOrPoseEditRemeshes) {
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.files().open({.folder = test::builtinSequence(20).string()})) << bench.ui().status.text;
  bench.sync();
  bench.player().play();
  MappingWorker& worker = *bench.worker();
  worker.waitIdle();
  bench.sync();
  auto global = bench.global();
  ASSERT_TRUE(global);
  EXPECT_FALSE(global->mesh) << "off by default: no mesh is built";
  const int mapping_generation = bench.mapping()->generation;

  // On: the worker rebuilds the map shown with its mesh.
  bench.ui().settings.show_mesh = true;
  bench.sync();
  worker.waitIdle();
  global = bench.global();
  ASSERT_TRUE(global && global->mesh);
  const std::size_t triangles = global->mesh->triangles.size();
  EXPECT_GT(triangles, 1000u);
  EXPECT_EQ(global->mesh->positions, meshOfShownMap(worker).positions) << "the mesh of the map shown";

  // A threshold edit publishes a new map with a new mesh of the kept cells it filters.
  GlobalMapParams thresholds = global->params;
  thresholds.filter.min_points = 15;
  worker.setThresholds(thresholds);
  worker.waitIdle();
  const auto edited = bench.global();
  ASSERT_TRUE(edited && edited->mesh);
  EXPECT_GT(edited->generation, global->generation);
  EXPECT_LT(edited->mesh->triangles.size(), triangles) << "fewer cells kept, fewer triangles";
  EXPECT_EQ(edited->mesh->triangles, meshOfShownMap(worker).triangles);

  // A pose edit moves the keyframe's piece.
  Transform moved = bench.mapping()->keyframes[1].T_W_K;
  moved.translation() += Eigen::Vector3d(0.3, 0, 0);
  worker.setKeyframePose(1, moved);
  worker.waitIdle();
  const auto posed = bench.global();
  ASSERT_TRUE(posed && posed->mesh);
  EXPECT_NE(posed->mesh->positions, edited->mesh->positions);
  EXPECT_EQ(posed->mesh->positions, meshOfShownMap(worker).positions);
  EXPECT_EQ(bench.mapping()->frames_mapped, 20) << "nothing was mapped again";
  EXPECT_GT(bench.mapping()->generation, mapping_generation);  // the pose edit's snapshot, not a re-run

  // How the mesh is made (the Mesh section, settings' mesh keys): re-meshed, nothing mapped again.
  bench.ui().settings.mesh.stride = 4;
  bench.sync();
  worker.waitIdle();
  const auto coarse = bench.global();
  ASSERT_TRUE(coarse && coarse->mesh);
  EXPECT_LT(coarse->mesh->triangles.size(), posed->mesh->triangles.size() / 2) << "a vertex per 4x4 cells";
  EXPECT_EQ(bench.mapping()->frames_mapped, 20);
  bench.ui().settings.mesh = {};

  // Off: the next map comes without one.
  bench.ui().settings.show_mesh = false;
  bench.sync();
  worker.setThresholds(global->params);
  worker.waitIdle();
  EXPECT_FALSE(bench.global()->mesh);
}

// The ellipsoids lie on the mesh and cover it: the layer coming on hides the map, going off shows
// it again; a draw set meanwhile stands; a map file (no mesh) keeps its map.
TEST(GuiMesh, TurningTheLayerOnHidesTheMapThatCoversItAndOffBringsItBack) {
  test::TempDir dir;
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.files().open({.folder = test::builtinSequence(10).string()})) << bench.ui().status.text;
  bench.sync();
  bench.player().play();
  bench.worker()->waitIdle();
  bench.sync();
  Settings& s = bench.ui().settings;
  EXPECT_FALSE(s.hide_map);
  s.show_mesh = true;
  bench.sync();
  EXPECT_TRUE(s.hide_map) << "the mesh shown alone";
  bench.worker()->waitIdle();
  bench.sync();
  EXPECT_FALSE(bench.view().drawnMap().empty) << "the view frames the mesh shown instead of the hidden map";
  s.show_mesh = false;
  bench.sync();
  EXPECT_FALSE(s.hide_map) << "the map back";

  // Draw set while the mesh is on (both drawn, or centres) is what stays.
  s.show_mesh = true;
  bench.sync();
  s.hide_map = false;
  s.show_ellipsoids = false;
  bench.sync();
  EXPECT_FALSE(s.hide_map);
  s.show_mesh = false;
  bench.sync();
  EXPECT_FALSE(s.hide_map);
  EXPECT_FALSE(s.show_ellipsoids);
  s.show_ellipsoids = true;

  // A map hidden before the mesh came on stays hidden after.
  s.hide_map = true;
  s.show_mesh = true;
  bench.sync();
  s.show_mesh = false;
  bench.sync();
  EXPECT_TRUE(s.hide_map);
  s.hide_map = false;

  // A map file has no local maps to mesh: the layer on hides nothing; a session opened with the
  // layer on shows its mesh.
  GlobalMap map;
  map.ellipsoids.push_back({.mean = Eigen::Vector3d(0, 0, 1), .cov = 0.01 * Eigen::Matrix3d::Identity()});
  writePointPly(dir.path() / "points.ply", map.ellipsoids);
  s.show_mesh = true;
  ASSERT_TRUE(bench.files().openPath((dir.path() / "points.ply").string())) << bench.ui().status.text;
  bench.sync();
  EXPECT_FALSE(s.hide_map);
  ASSERT_TRUE(bench.files().open({.folder = test::builtinSequence(10).string()})) << bench.ui().status.text;
  bench.sync();
  EXPECT_TRUE(s.hide_map);
}

}  // namespace
}  // namespace vdmap::app::gui
