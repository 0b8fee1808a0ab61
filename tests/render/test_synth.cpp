// Synthetic sequences: the renderer's geometry against real renders of the Replica mesh, the
// sensor model, and the built-in scene.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <tbb/task_arena.h>

#include "mapping/files/ply_reader.h"
#include "mapping/io/camera_config.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/sequence/sequence.h"
#include "mapping/synth/builtin_scene.h"
#include "render/sequence_synth.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

// The replica reference frames are noise-free renders of the full-resolution Replica mesh; our
// mesh is its 50k-face decimation, whose surface lies a median 3.7 mm from those depths (the data
// set's README). So the synthetic depth should agree to within that: median |dz| under 6 mm.
constexpr double kReplicaMedianDzTolerance_m = 0.006;

// |dz| in metres where both depth images (16-bit at `depth_scale`) have a value, and the pixels
// only one of them has.
struct DepthComparison {
  std::vector<double> dz;
  int only_ref = 0, only_synth = 0;
};

DepthComparison compareDepth(const cv::Mat& ref, const cv::Mat& synth, double depth_scale) {
  DepthComparison c;
  for (int v = 0; v < synth.rows; ++v)
    for (int u = 0; u < synth.cols; ++u) {
      const int a = ref.at<std::uint16_t>(v, u), b = synth.at<std::uint16_t>(v, u);
      if (a && b) c.dz.push_back(std::abs(a - b) / depth_scale);
      c.only_ref += a && !b;
      c.only_synth += b && !a;
    }
  return c;
}

// The `q`-quantile (0..1) of `values` (reorders them).
double quantile(std::vector<double>& values, double q) {
  const auto nth =
      values.begin() + static_cast<long>(std::min(values.size() - 1, static_cast<std::size_t>(q * values.size())));
  std::nth_element(values.begin(), nth, values.end());
  return *nth;
}

TEST(Synth, ReplicaMeshReproducesReferenceDepth) {
  VDMAP_REQUIRE_SHARED_DATA(data, "replica-office0");
  const ColoredTriangleMesh mesh = readPlyMesh(data / "reference" / "office0_mesh.ply");
  const Sequence seq = Sequence::open(data);
  const PinholeCamera camera = cameraPreset("replica");
  std::unique_ptr<render::Context> context = render::createOffscreenContext();
  render::MeshViewRenderer renderer(*context, mesh, seq.camera());
  auto synthDepth = [&](const Transform& T_W_C) {
    return simulateDepth(renderer.render(T_W_C).z_cos, camera.depth_scale,
                         {.model = DepthNoiseModel::kNone, .max_range_m = 10.0}, 0);
  };
  for (std::size_t i = 0; i < seq.size(); ++i) {
    const RgbdFrame frame = seq.load(i);
    const cv::Mat synth = synthDepth(frame.T_W_C);
    DepthComparison c = compareDepth(frame.depth, synth, camera.depth_scale);
    ASSERT_GT(c.dz.size(), synth.total() / 2) << "frame " << i;
    const double median = quantile(c.dz, 0.5);
    std::printf("replica frame %zu: median |dz| %.2f mm, 90th pct %.2f mm, %zu px compared, %d only in the "
                "reference, %d only synthetic\n",
                i, 1000 * median, 1000 * quantile(c.dz, 0.9), c.dz.size(), c.only_ref, c.only_synth);
    EXPECT_LT(median, kReplicaMedianDzTolerance_m) << "frame " << i;
  }
  // Control: the same comparison from a pose 3 cm to the side must fail it clearly.
  const RgbdFrame frame = seq.load(0);
  Transform shifted = frame.T_W_C;
  shifted.translation() += frame.T_W_C.linear().col(0) * 0.03;
  DepthComparison control = compareDepth(frame.depth, synthDepth(shifted), camera.depth_scale);
  EXPECT_GT(quantile(control.dz, 0.5), 2 * kReplicaMedianDzTolerance_m);
}

TEST(Synth, NguyenNoiseHasTheModelsAxialSpreadAndCuts) {
  // A fronto-parallel plane at 2 m: the depth spread must match sd(2) = 6.06 mm (quantisation
  // at 5000/m adds 0.06 mm), grazing pixels and out-of-range depths return nothing.
  cv::Mat z_cos(200, 200, CV_32FC2, cv::Scalar(2.0f, 1.0f));
  for (int v = 0; v < 20; ++v)
    for (int u = 0; u < 200; ++u) z_cos.at<cv::Vec2f>(v, u) = {2.0f, 0.1f};  // 84 degrees
  for (int v = 180; v < 200; ++v)
    for (int u = 0; u < 200; ++u) z_cos.at<cv::Vec2f>(v, u) = {7.0f, 1.0f};  // beyond 5 m
  const DepthNoiseParams params;
  const cv::Mat depth = simulateDepth(z_cos, 5000.0, params, 3);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int v = 30; v < 170; ++v)
    for (int u = 10; u < 190; ++u) {
      const double d = depth.at<std::uint16_t>(v, u) / 5000.0;
      ASSERT_GT(d, 0);
      sum += d, sum2 += d * d, ++n;
    }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 2.0, 0.0005);
  EXPECT_NEAR(sd, nguyenAxialSd(2.0), 0.05 * nguyenAxialSd(2.0));
  EXPECT_EQ(cv::countNonZero(depth.rowRange(0, 18)), 0);
  EXPECT_EQ(cv::countNonZero(depth.rowRange(182, 200)), 0);
  // Deterministic per frame, different between frames.
  EXPECT_EQ(cv::norm(depth, simulateDepth(z_cos, 5000.0, params, 3), cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(depth, simulateDepth(z_cos, 5000.0, params, 4), cv::NORM_INF), 0);
}

TEST(Synth, BuiltinSceneIsAReadableSequenceThatRevisitsItsStart) {
  const BuiltinScene scene = makeBuiltinScene();
  ASSERT_GE(scene.trajectory.size(), 200u);
  const Transform& a = scene.trajectory.front().T_W_C;
  const Transform& b = scene.trajectory.back().T_W_C;
  EXPECT_LT((a.translation() - b.translation()).norm(), 0.05);
  EXPECT_GT(scene.mesh.triangles.size(), 10000u);
  test::TempDir tmp;
  render::writeBuiltinSequence(tmp / "builtin", {.frames = 12});
  const Sequence seq = Sequence::open(tmp / "builtin");
  ASSERT_EQ(seq.size(), 12u);
  EXPECT_EQ(seq.camera().width, 640);
  const RgbdFrame frame = seq.load(5);
  EXPECT_GT(cv::countNonZero(frame.depth), static_cast<int>(0.9 * frame.depth.total()));
  EXPECT_TRUE(frame.T_W_C.isApprox(makeBuiltinScene({.frames = 12}).trajectory[5].T_W_C, 1e-5));
  // Texture for ORB: strong local contrast everywhere.
  cv::Mat gray;
  cv::cvtColor(frame.rgb, gray, cv::COLOR_RGB2GRAY);
  cv::Scalar mean, stddev;
  cv::meanStdDev(gray, mean, stddev);
  EXPECT_GT(stddev[0], 20.0);
  // Its mesh.ply is the scene's mesh, so `vdmap eval --mesh` can score maps of it.
  const ColoredTriangleMesh mesh = readPlyMesh(tmp / "builtin" / "mesh.ply");
  ASSERT_EQ(mesh.positions.size(), scene.mesh.positions.size());
  EXPECT_TRUE(mesh.positions == scene.mesh.positions);
  EXPECT_TRUE(mesh.colors == scene.mesh.colors);
  EXPECT_TRUE(mesh.triangles == scene.mesh.triangles);
  // Only the sequence is left: its DIR.tmp-XXXXXX staging folder was renamed, not copied.
  for (const auto& entry : std::filesystem::directory_iterator(tmp.path()))
    EXPECT_EQ(entry.path().filename(), "builtin");
}

// Frames are written by several threads while the next ones render; each frame's noise has its
// own seed, so every file is the same on one thread as on all of them.
TEST(Synth, SequenceFilesDoNotDependOnTheThreadCount) {
  test::TempDir tmp;
  const BuiltinSceneParams walk{.frames = 20};  // more than one batch of frames
  tbb::task_arena(1).execute([&] { render::writeBuiltinSequence(tmp / "one", walk); });
  render::writeBuiltinSequence(tmp / "all", walk);
  int files = 0;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(tmp / "one")) {
    if (!entry.is_regular_file()) continue;
    const auto relative = std::filesystem::relative(entry.path(), tmp / "one");
    ASSERT_TRUE(test::readFile(entry.path()) == test::readFile(tmp / "all" / relative)) << relative;
    ++files;
  }
  EXPECT_EQ(files, 2 * 20 + 5);  // rgb and depth per frame, rgb.txt, depth.txt, groundtruth.txt, camera.yaml, mesh.ply
}

TEST(Synth, AFailureMidwayLeavesNothingBehind) {
  test::TempDir tmp;
  std::size_t calls = 0;
  auto failing = [&](std::size_t done, std::size_t) {
    ++calls;
    if (done > 8) throw std::runtime_error("stopped");
  };
  EXPECT_THROW(render::writeBuiltinSequence(tmp / "seq", {.frames = 30}, failing), std::runtime_error);
  EXPECT_EQ(calls, 2u);  // frames 1-8, then 9-16 throws
  EXPECT_TRUE(std::filesystem::is_empty(tmp.path()));
}

// Closing the workbench while it renders the built-in scene on first start: the render stops
// within a frame and leaves neither the folder nor its temporary sibling.
TEST(Synth, CancelledRenderLeavesNothing) {
  test::TempDir tmp;
  std::size_t asked = 0;
  auto cancelAfterOne = [&] { return ++asked > 1; };
  try {
    render::writeBuiltinSequence(tmp / "seq", {.frames = 30}, {}, cancelAfterOne);
    ADD_FAILURE() << "not cancelled";
  } catch (const render::SynthCancelled& e) {
    EXPECT_EQ(e.done, 1u);
    EXPECT_EQ(e.total, 30u);
  }
  EXPECT_EQ(asked, 2u);  // asked before each frame: rendered one, stopped before the second
  EXPECT_TRUE(std::filesystem::is_empty(tmp.path()));
}

}  // namespace
}  // namespace vdmap
