// The workbench's mesh layer without a window (docs/workbench.md "Mesh"): the mapping worker builds
// the surface mesh with every global map while the layer is on, from the same local maps, poses
// and kept cells, so a threshold or pose edit re-meshes without re-integration.
#include <memory>

#include <gtest/gtest.h>

#include "app/workbench/workbench.h"
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

  // Off: the next map comes without one.
  bench.ui().settings.show_mesh = false;
  bench.sync();
  worker.setThresholds(global->params);
  worker.waitIdle();
  EXPECT_FALSE(bench.global()->mesh);
}

}  // namespace
}  // namespace vdmap::app::gui
