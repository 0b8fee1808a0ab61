// Map exports (SPEC section 7) through exportMap: every file written into one folder, each PLY
// reads back to the values written, and a folder that cannot be written fails cleanly.
#include <fstream>

#include <gtest/gtest.h>

#include "mapping/export/map_export.h"
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
  const nlohmann::json stats = exportMap(tmp / "out", scene.graph, scene.map, scene.params.filter, options);
  EXPECT_EQ(filesIn(tmp / "out"), (std::vector<std::string>{"global_ellipsoids.ply", "global_points.ply",
                                                             "graph.txt", "keyframes.txt", "local_maps.ply",
                                                             "stats.json"}));
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
}

TEST(Export, AFolderThatCannotBeWrittenFailsClearlyAndWritesNothing) {
  const TwoViews scene;
  test::TempDir tmp;
  test::writeText(tmp / "file", "not a folder\n");
  for (const fs::path& dir : {tmp / "file", tmp / "file" / "sub"}) {
    try {
      exportMap(dir, scene.graph, scene.map, scene.params.filter);
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
  EXPECT_THROW(exportMap(tmp / "out", scene.graph, scene.map, scene.params.filter), std::runtime_error);
  EXPECT_EQ(filesIn(tmp / "out"), (std::vector<std::string>{"graph.txt", "stats.json"}));
  std::ifstream old(tmp / "out" / "graph.txt");
  std::string line;
  std::getline(old, line);
  EXPECT_EQ(line, "old");
}

}  // namespace
}  // namespace vdmap
