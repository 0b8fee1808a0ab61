// The workbench's point queries without a window (docs/workbench.md "Queries"): the queries the
// worker publishes with each global map, the probe through the Workbench, the query slice's
// pixels, and `vdmap render --query-slice`.
#include <cmath>
#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "app/workbench/workbench.h"
#include "mapping/eval/mesh_accuracy.h"
#include "mapping/files/map_export.h"
#include "mapping/io/camera_config.h"
#include "mapping/synth/builtin_scene.h"
#include "render/legend.h"
#include "render/query_slice.h"
#include "render/sequence_synth.h"
#include "tests/support/box_room_keyframes.h"
#include "tests/support/render_scenes.h"
#include "tests/support/test_util.h"

namespace vdmap::app::gui {
namespace {
namespace fs = std::filesystem;

// One lap of the built-in walk in 40 frames (ground-truth poses), mapped to the end in the
// workbench with the probe on, so the worker builds the queries with every global map.
struct BuiltinBench {
  Workbench bench{Settings{}};
  BuiltinBench() {
    EXPECT_TRUE(bench.files().open({.folder = test::builtinSequence(40).string()})) << bench.ui().status.text;
    bench.ui().settings.probe = true;
    bench.sync();  // asks the worker for the queries
    bench.player().play();
    bench.worker()->waitIdle();
    bench.sync();
  }
};

// The workbench's map, built once for the tests that ask for it (mapping 40 frames takes seconds)
// and destroyed after the suite, with its worker (the sanitizers' leak check sees the worker's
// per-thread buffers as leaked when it outlives the run).
class GuiQueries : public ::testing::Test {
 protected:
  static BuiltinBench& builtin() {
    if (!bench_) bench_ = std::make_unique<BuiltinBench>();
    return *bench_;
  }
  static void TearDownTestSuite() { bench_.reset(); }

 private:
  static inline std::unique_ptr<BuiltinBench> bench_;
};

TEST_F(GuiQueries, TheQueriesFollowEveryGlobalMapAndAnswerAtTheCorrectedPoses) {
  Workbench& bench = builtin().bench;
  auto global = bench.global();
  auto query = bench.queries().snapshot();
  ASSERT_TRUE(global && query);
  EXPECT_EQ(query->generation, global->generation) << "the queries of the map shown";
  EXPECT_GE(query->map->keyframes(), 3u);
  EXPECT_EQ(query->map->ellipsoids(), global->map.ellipsoids.size());
  EXPECT_TRUE(query->note.empty()) << query->note;

  // Random points in the room, classified by the snapshot's queries before and after keyframe 1
  // moves 30 cm: afterwards they agree with queries built from the graph at the new poses, and
  // some answers changed.
  std::mt19937 rng(36);
  std::uniform_real_distribution<double> x(-2.4, 2.4), y(-1.9, 1.9), z(0.05, 2.5);
  std::vector<Eigen::Vector3d> points(4000);
  for (auto& p : points) p = {x(rng), y(rng), z(rng)};
  const auto classify = [&](const QueryMap& map) {
    std::vector<Classification> out(points.size());
    map.classify(points, out);
    return out;
  };
  const std::vector<Classification> before = classify(*query->map);
  Transform moved = bench.mapping()->keyframes[1].T_W_K;
  moved.translation() += Eigen::Vector3d(0.3, 0, 0);
  MappingWorker& worker = *bench.worker();
  worker.setKeyframePose(1, moved);
  worker.waitIdle();
  global = bench.global();
  query = bench.queries().snapshot();
  ASSERT_EQ(query->generation, global->generation);
  std::vector<Classification> reference;
  worker.withMapper([&](const Mapper& mapper, const GlobalSnapshot& shown) {
    EXPECT_TRUE(mapper.graph().keyframe(1).T_W_K.isApprox(moved));
    reference = classify(QueryMap::build(mapper.graph(), shown.map, QueryParams{}));
    return std::string();
  });
  worker.waitIdle();
  const std::vector<Classification> after = classify(*query->map);
  int changed = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(after[i].state, reference[i].state) << i;
    EXPECT_EQ(after[i].p_occupied, reference[i].p_occupied) << i;
    changed += after[i].state != before[i].state;
  }
  EXPECT_GT(changed, 0) << "moving a keyframe moves its free space";
  moved.translation() -= Eigen::Vector3d(0.3, 0, 0);
  worker.setKeyframePose(1, moved);  // back, for the tests after this one
  worker.waitIdle();
  bench.sync();
}

// The probe through the Workbench: points on the scene's surface (the built-in mesh, where the
// map has an ellipsoid within 1 cm) are occupied, every keyframe's camera centre is not.
TEST_F(GuiQueries, ProbeOnTheSceneSurfaceIsOccupiedAndAtTheCamerasNot) {
  Workbench& bench = builtin().bench;
  const auto global = bench.global();
  ASSERT_TRUE(global && bench.queries().snapshot());
  const ColoredTriangleMesh mesh = makeBuiltinScene().mesh;
  std::vector<Eigen::Vector3f> samples = sampleMeshSurface(mesh, 3000, 36);
  std::vector<Eigen::Vector3f> seen;
  for (const Eigen::Vector3f& s : samples) {
    for (const Ellipsoid& e : global->map.ellipsoids)
      if ((e.mean.cast<float>() - s).squaredNorm() < 1e-4f) {
        seen.push_back(s);
        break;
      }
    if (seen.size() == 200) break;
  }
  ASSERT_GE(seen.size(), 100u);
  int occupied = 0;
  for (const Eigen::Vector3f& s : seen) {
    const ProbeResult r = bench.queries().probe({s.x(), s.y(), s.z()});
    EXPECT_TRUE(r.note.empty()) << r.note;
    EXPECT_EQ(r.generation, global->generation);
    if (r.state.state == Occupancy::kOccupied) {
      ++occupied;
      EXPECT_GT(r.state.p_occupied, 0.5f);
      EXPECT_EQ(r.distance.distance_m, 0.0) << "occupied is inside a gate";
    }
  }
  EXPECT_GE(occupied, static_cast<int>(0.9 * static_cast<double>(seen.size())))
      << occupied << " of " << seen.size() << " surface points occupied";
  for (const KeyframeInfo& k : bench.mapping()->keyframes) {
    const Eigen::Vector3d c = k.T_W_K.translation();
    const ProbeResult r = bench.queries().probe(glm::vec3(c.x(), c.y(), c.z()));
    EXPECT_NE(r.state.state, Occupancy::kOccupied) << "K" << k.id;
    EXPECT_GT(r.distance.distance_m, 0.1) << "K" << k.id << ": a camera is in free space";
    EXPECT_NE(r.text().find(r.state.state == Occupancy::kFree ? "free p" : "unknown p=0.500"), std::string::npos)
        << r.text();
  }
}

// The probe's point: the surface under the cursor moved toward the eye by the offset; on the
// query slice's plane while the slice is shown.
TEST_F(GuiQueries, ProbePointStandsTheOffsetInFrontOfTheSurfaceOrOnTheSlice) {
  Workbench& bench = builtin().bench;
  UiState& ui = bench.ui();
  const int w = 640, h = 480;
  const glm::vec3 eye = bench.view().viewport(w, h).camera.eye();
  const glm::vec3 surface = eye + 2.f * glm::normalize(glm::vec3(0.1f, 0.2f, 0.3f) - eye);
  ui.settings.probe_offset_m = 0.05f;
  const auto p = bench.queries().probePoint(320, 240, w, h, surface);
  ASSERT_TRUE(p);
  EXPECT_NEAR(glm::length(*p - surface), 0.05f, 1e-5f);
  EXPECT_NEAR(glm::length(eye - *p) + 0.05f, glm::length(eye - surface), 1e-4f) << "toward the eye";
  EXPECT_FALSE(bench.queries().probePoint(320, 240, w, h, std::nullopt)) << "no surface, no slice: no probe";
  EXPECT_TRUE(bench.queries().probeAt(320, 240, w, h, surface));
  ASSERT_TRUE(ui.probe_result);
  EXPECT_FALSE(ui.probe_result->on_slice);

  ui.settings.query_slice = true;
  ui.settings.query_slice_spec = {.axis = render::QuerySliceAxis::kZ, .offset_m = 1.2};
  bench.queries().waitSlice();
  ASSERT_TRUE(bench.queries().slice());
  const auto q = bench.queries().probePoint(320, 240, w, h, std::nullopt);
  ASSERT_TRUE(q) << "the cursor's ray meets the slice's plane";
  EXPECT_NEAR(q->z, 1.2f, 1e-4f);
  bench.queries().probeAt(320, 240, w, h, surface);
  ASSERT_TRUE(ui.probe_result);
  EXPECT_TRUE(ui.probe_result->on_slice);
  EXPECT_NE(ui.probe_result->text().find("(slice)"), std::string::npos);
  ui.settings.query_slice = false;
  bench.sync();
  EXPECT_FALSE(bench.queries().slice());
}

// The slice plane across z = 1.2 m (above the table, below the ceiling): red where it cuts the
// wall x = -2.5 m, green in the open room in front of it; the same pixels for 1 and 2 threads.
TEST_F(GuiQueries, SlicePixelsAreOccupiedAtTheWallAndFreeInFrontOfIt) {
  Workbench& bench = builtin().bench;
  const auto query = bench.queries().snapshot();
  ASSERT_TRUE(query);
  const render::QuerySliceSpec spec{.axis = render::QuerySliceAxis::kZ, .offset_m = 1.2};
  const render::QuerySliceImage slice = render::computeQuerySlice(*query->map, spec, {});
  ASSERT_FALSE(slice.plane.empty());
  EXPECT_EQ(std::max(slice.plane.width, slice.plane.height), 256);
  ASSERT_EQ(slice.rgba.rows, slice.plane.height);
  ASSERT_EQ(slice.rgba.cols, slice.plane.width);
  EXPECT_EQ(slice.occupied + slice.free + slice.unknown, static_cast<std::size_t>(slice.rgba.total()));
  EXPECT_GT(slice.free, slice.occupied);
  const auto colour = [&](int i, int j) {
    const cv::Vec4b c = slice.rgba.at<cv::Vec4b>(j, i);
    return std::array<std::uint8_t, 4>{c[0], c[1], c[2], c[3]};
  };
  // Along y in [-1.2, -0.6] (nothing stands at that wall there): per row, the samples within
  // 3 cm of the wall include an occupied one, and those 0.2-0.6 m in front are free.
  int rows = 0, wall_rows = 0, free_samples = 0, samples = 0;
  for (int j = 0; j < slice.plane.height; ++j) {
    const Eigen::Vector3d row = slice.plane.sample(0, j);
    if (row.y() < -1.2 || row.y() > -0.6) continue;
    ++rows;
    bool wall = false;
    for (int i = 0; i < slice.plane.width; ++i) {
      const Eigen::Vector3d p = slice.plane.sample(i, j);
      EXPECT_NEAR(p.z(), 1.2, 1e-12);
      if (std::abs(p.x() + 2.5) < 0.03) wall = wall || colour(i, j) == render::kSliceOccupied;
      if (p.x() > -2.3 && p.x() < -1.9) {
        ++samples;
        free_samples += colour(i, j) == render::kSliceFree;
      }
    }
    wall_rows += wall;
  }
  ASSERT_GT(rows, 10);
  EXPECT_GE(wall_rows, rows * 9 / 10) << "the slice cuts the wall";
  EXPECT_GE(free_samples, samples * 9 / 10) << "the room in front of the wall is free";

  // Deterministic: the queries on 1 and 2 threads give the same image, bit for bit.
  std::vector<cv::Mat> images;
  bench.worker()->withMapper([&](const Mapper& mapper, const GlobalSnapshot& shown) {
    for (const int threads : {1, 2})
      images.push_back(
          render::computeQuerySlice(
              QueryMap::build(mapper.graph(), shown.map, {.threads = threads}),
              {.axis = render::QuerySliceAxis::kZ, .offset_m = 1.2, .color = render::QuerySliceColor::kDistance}, {})
              .rgba);
    return std::string();
  });
  bench.worker()->waitIdle();
  ASSERT_EQ(images.size(), 2u);
  EXPECT_EQ(cv::norm(images[0], images[1], cv::NORM_INF), 0.0);
}

// A map file (a `vdmap map` folder) has no local maps: its queries hold the ellipsoids alone, so
// the probe finds its surfaces occupied with their distances and nothing free, and says why.
TEST_F(GuiQueries, AMapFileAnswersFromItsEllipsoidsAlone) {
  test::TempDir dir;
  KeyframeGraph graph;
  test::addTwoBoxRoomViews(&graph, cameraPreset("tum-default"));
  const GlobalMap map = buildGlobalMap(graph, GlobalMapParams{});
  exportMap(dir / "map", graph, map, MapExportOptions{});
  Workbench bench{Settings{}};
  ASSERT_TRUE(bench.files().openPath((dir / "map").string())) << bench.ui().status.text;
  bench.ui().settings.probe = true;
  bench.ui().settings.query_slice = true;
  bench.sync();
  bench.worker()->waitIdle();
  const auto query = bench.queries().snapshot();
  ASSERT_TRUE(query);
  EXPECT_EQ(bench.player().status().error, "");
  EXPECT_EQ(query->map->keyframes(), 0u);
  EXPECT_EQ(query->map->ellipsoids(), map.ellipsoids.size());
  EXPECT_EQ(query->note, "no keyframes: free space unknown");
  const Eigen::Vector3d mean = map.ellipsoids[map.ellipsoids.size() / 2].mean;
  const ProbeResult on = bench.queries().probe(glm::vec3(mean.x(), mean.y(), mean.z()));
  EXPECT_EQ(on.state.state, Occupancy::kOccupied);
  EXPECT_EQ(on.distance.distance_m, 0.0);
  const Eigen::Vector3d c = graph.keyframe(0).T_W_K.translation();
  const ProbeResult camera = bench.queries().probe(glm::vec3(c.x(), c.y(), c.z()));
  EXPECT_EQ(camera.state.state, Occupancy::kUnknown) << "nothing is seen free without keyframes";
  EXPECT_GT(camera.distance.distance_m, 0.5);
  EXPECT_NE(camera.text().find("no keyframes: free space unknown"), std::string::npos) << camera.text();
  // The slice spans the map's box instead of what keyframes see.
  bench.queries().waitSlice();
  ASSERT_TRUE(bench.queries().slice());
  EXPECT_FALSE(bench.queries().slice()->plane.empty());
  EXPECT_EQ(bench.queries().slice()->free, 0u);
  EXPECT_GT(bench.queries().slice()->occupied, 0u);
}

TEST_F(GuiQueries, SlicePlaneAxesAndParsing) {
  const Eigen::Vector3d lo(-1, -2, 0), hi(3, 2, 1);
  render::HeightFrame tilted{glm::normalize(glm::vec3(0.f, 0.3f, 1.f)), 0.4f};
  const render::QuerySliceSpec up{.axis = render::QuerySliceAxis::kUp, .offset_m = 0.5, .samples = 100};
  const render::QuerySlicePlane plane = render::querySlicePlane(up, lo, hi, tilted);
  ASSERT_FALSE(plane.empty());
  EXPECT_EQ(std::max(plane.width, plane.height), 100);
  const Eigen::Vector3d n(tilted.up.x, tilted.up.y, tilted.up.z);
  for (const auto& [i, j] : {std::pair{0, 0}, {plane.width - 1, 0}, {7, plane.height - 1}})
    EXPECT_NEAR(tilted.height(glm::vec3(plane.sample(i, j).cast<float>().x(), plane.sample(i, j).cast<float>().y(),
                                        plane.sample(i, j).cast<float>().z())),
                0.5f, 1e-4f)
        << "0.5 m above the floor along the up axis";
  EXPECT_NEAR(plane.du.dot(n), 0, 1e-12);
  EXPECT_NEAR(plane.dv.dot(n), 0, 1e-12);
  const auto hit = render::intersectPlane(plane, n * 3.0, -n);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->dot(n), 0.9, 1e-6);  // the floor is a float
  EXPECT_FALSE(render::intersectPlane(plane, n * 3.0, n)) << "the plane is behind the ray";
  EXPECT_TRUE(render::querySlicePlane(up, hi, lo, tilted).empty()) << "nothing seen";

  const render::QuerySliceSpec x = render::parseQuerySlice("x=-1.5");
  EXPECT_EQ(x.axis, render::QuerySliceAxis::kX);
  EXPECT_EQ(x.offset_m, -1.5);
  EXPECT_EQ(render::parseQuerySlice("up=1").axis, render::QuerySliceAxis::kUp);
  for (const char* bad : {"", "z", "w=1", "z=", "z=1m", "z=nan", "=1"})
    EXPECT_THROW(render::parseQuerySlice(bad), std::invalid_argument) << bad;
  EXPECT_EQ(render::parseQuerySliceColor("distance"), render::QuerySliceColor::kDistance);
  EXPECT_THROW(render::parseQuerySliceColor("height"), std::invalid_argument);
}

// `vdmap render S.vdmap --query-slice z=1.2` draws the slice headless: the image differs from
// the same view without it, and the summary names the slice's samples.
TEST_F(GuiQueries, RenderDrawsTheQuerySlice) {
  test::TempDir dir;
  const fs::path session = dir / "b.vdmap";
  ASSERT_EQ(test::runVdmap("map '" + test::builtinSequence(30).string() + "' --out '" + (dir / "m").string() +
                           "' --save '" + session.string() + "'")
                .exit_code,
            0);
  const std::string common = "render '" + session.string() + "' --size 320x240 --orbit 30,60";
  const test::RunResult plain = test::runVdmap(common + " --out '" + (dir / "plain.png").string() + "'");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  const test::RunResult sliced =
      test::runVdmap(common + " --query-slice z=1.2 --out '" + (dir / "slice.png").string() + "'");
  ASSERT_EQ(sliced.exit_code, 0) << sliced.err;
  EXPECT_NE(sliced.out.find("query slice z=1.200 (occupancy): "), std::string::npos) << sliced.out;
  const cv::Mat a = test::readImage((dir / "plain.png")), b = test::readImage((dir / "slice.png"));
  ASSERT_FALSE(a.empty() || b.empty());
  cv::Mat diff;
  cv::absdiff(a, b, diff);
  EXPECT_GT(cv::countNonZero(diff.reshape(1) > 30), 1000) << "the slice shows";
  const test::RunResult bad = test::runVdmap(common + " --query-slice w=1 --out '" + (dir / "bad.png").string() + "'");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_FALSE(fs::exists(dir / "bad.png"));
}

// The query slice's colours have a key in the view's legend.
TEST(GuiQueryKey, TheQuerySliceHasAColourKey) {
  render::QuerySliceSpec spec;
  render::Legend occupancy;
  render::addQuerySliceKey(occupancy, spec);
  ASSERT_EQ(occupancy.lines.size(), 3u);
  EXPECT_EQ(occupancy.lines[0].text, "slice: free");
  EXPECT_EQ(occupancy.lines[0].color, glm::u8vec3(render::kSliceFree[0], render::kSliceFree[1], render::kSliceFree[2]));
  EXPECT_EQ(occupancy.lines[1].text, "occupied");
  EXPECT_EQ(occupancy.lines[2].text, "unknown");
  spec.color = render::QuerySliceColor::kDistance;
  spec.max_distance_m = 0.25;
  render::Legend distance;
  render::addQuerySliceKey(distance, spec);
  EXPECT_EQ(distance.ramp_title, "slice: distance to the surface (m)");
  EXPECT_EQ(distance.ramp_lo, "0");
  EXPECT_EQ(distance.ramp_hi, "0.25");
  // The map's own ramp (height colours) stays; the slice's ends come as lines.
  render::Legend height = render::legendFor(render::ColorMode::kHeight, render::ColorRange{0.f, 2.f}, {});
  render::addQuerySliceKey(height, spec);
  EXPECT_EQ(height.ramp_title, "height above floor (m)");
  ASSERT_EQ(height.lines.size(), 2u);
  EXPECT_EQ(height.lines[1].text, "0.25 m or more");
}

}  // namespace
}  // namespace vdmap::app::gui
