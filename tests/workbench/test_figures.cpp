// Figures the workbench shows about its snapshots (app/workbench/figures.h): the tracking error against
// ground truth, and which optimisation "before" (B) undoes.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "app/workbench/figures.h"
#include "mapping/eval/trajectory_error.h"
#include "mapping/io/trajectory_io.h"
#include "tests/support/test_util.h"

namespace vdmap::app::gui {
namespace {

namespace fs = std::filesystem;

// The box room turning on the spot (tests/support/test_util.h), whose ground-truth timestamps are written
// as its depth list's (%.6f): each frame's ground truth is then a sample of the file, not an
// interpolation between two, as `vdmap eval` matches it.
fs::path boxRoomWithFrameStampedTruth(const test::TempDir& dir, int frames) {
  const fs::path seq = dir / "seq";
  test::writeBoxRoomSequence(seq, frames);
  std::vector<StampedPose> truth = readTumTrajectory(seq / "groundtruth.txt");
  for (StampedPose& p : truth) {
    char t[32];
    std::snprintf(t, sizeof t, "%.6f", p.t);
    p.t = std::strtod(t, nullptr);
  }
  // Written with all digits (the file's own precision), only the timestamps rounded.
  std::string text;
  for (const StampedPose& p : truth) {
    const Eigen::Quaterniond q(p.T_W_C.linear());
    const Eigen::Vector3d x = p.T_W_C.translation();
    char line[320];
    std::snprintf(line, sizeof line, "%.6f %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", p.t, x.x(), x.y(), x.z(),
                  q.x(), q.y(), q.z(), q.w());
    text += line;
  }
  test::writeText(seq / "groundtruth.txt", text);
  return seq;
}

MapperParams tracked() {
  MapperParams params;
  params.poses = PoseSource::kTrack;
  return params;
}

// The figures of the workbench's snapshot are `vdmap eval`'s (evaluateTrajectoryFiles) on the
// trajectory a map export writes (Mapper::trajectory(), trajectory.txt). That file holds 9
// significant digits (%.9g): metres agree to 1e-9, degrees (a rounded quaternion) to 1e-6.
TEST(Figures, TrackingErrorEqualsVdmapEvalOnTheExportedTrajectory) {
  test::TempDir dir;
  const fs::path seq = boxRoomWithFrameStampedTruth(dir, 70);
  MappingWorker worker(Sequence::open(seq), tracked(), GlobalMapParams{});
  worker.play();
  worker.waitIdle();
  const auto mapping = worker.mapping();
  ASSERT_EQ(mapping->frames_mapped, 70);
  const TrackingError figures = trackingError(*mapping);
  ASSERT_TRUE(figures.valid);
  const fs::path exported = dir / "trajectory.txt";
  worker.withMapper([&](const Mapper& mapper, const GlobalSnapshot&) {
    writeTumTrajectory(exported, mapper.trajectory(), "tracked T_W_C");
    return std::string();
  });
  worker.waitIdle();
  const TrajectoryError eval = evaluateTrajectoryFiles(exported, seq / "groundtruth.txt");
  EXPECT_EQ(figures.matched, eval.matched);
  EXPECT_EQ(figures.matched, 70u - static_cast<std::size_t>(mapping->frames_lost));
  EXPECT_NEAR(figures.ate_rmse_m, eval.ate_m.rmse, 1e-9);
  EXPECT_NEAR(figures.ate_median_m, eval.ate_m.median, 1e-9);
  EXPECT_NEAR(figures.ate_max_m, eval.ate_m.max, 1e-9);
  EXPECT_NEAR(figures.rpe_frame_m, eval.rpe_per_frame.translation_m.rmse, 1e-9);
  EXPECT_NEAR(figures.rpe_second_m, eval.rpe_per_second.translation_m.rmse, 1e-9);
  EXPECT_NEAR(figures.rpe_frame_deg, eval.rpe_per_frame.rotation_deg.rmse, 1e-6);
  EXPECT_NEAR(figures.rpe_second_deg, eval.rpe_per_second.rotation_deg.rmse, 1e-6);
  EXPECT_GT(figures.rpe_second_pairs, 0u);
  EXPECT_GT(figures.ate_rmse_m, 0.0);
  EXPECT_LT(figures.ate_rmse_m, 0.05);
  // The command itself, at the 5 digits its JSON gives.
  const test::RunResult r = test::runVdmap("eval --trajectory '" + exported.string() + "' --groundtruth '" +
                                           (seq / "groundtruth.txt").string() + "' --json");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json json = nlohmann::json::parse(r.out);
  EXPECT_NEAR(json["ate_rmse_m"].get<double>(), figures.ate_rmse_m, 1e-4 * figures.ate_rmse_m);
  // Asked again (the UI asks every frame), the same figures.
  const TrackingError again = trackingError(*mapping);
  EXPECT_EQ(again.ate_rmse_m, figures.ate_rmse_m);
  EXPECT_EQ(again.rpe_frame_deg, figures.rpe_frame_deg);
}

TEST(Figures, GroundTruthPosesHaveNoTrackingError) {
  test::TempDir dir;
  test::writeBoxRoomSequence(dir / "seq", 8);
  MappingWorker worker(Sequence::open(dir / "seq"), MapperParams{}, GlobalMapParams{});
  worker.play();
  worker.waitIdle();
  EXPECT_FALSE(trackingError(*worker.mapping()).valid);
}

// The banner names the last optimisation: the final refinement once it has moved the keyframes,
// else the newest loop closure.
TEST(Figures, LastOptimisationIsTheRefinementOrTheNewestLoop) {
  test::TempDir dir;
  test::writeBoxRoomSequence(dir / "seq", 70);
  {
    MappingWorker worker(Sequence::open(dir / "seq"), tracked(), GlobalMapParams{}, std::nullopt);
    worker.play();
    worker.waitIdle();
    const auto mapping = worker.mapping();
    ASSERT_GE(mapping->loops.size(), 1u);
    EXPECT_EQ(mapping->last_optimisation.kind, LastOptimisation::Kind::kLoop);
    EXPECT_EQ(mapping->last_optimisation.loop, static_cast<int>(mapping->loops.size()) - 1);
  }
  MapRefinementParams joint;
  joint.method = MapRefinementMethod::kJoint;
  MappingWorker worker(Sequence::open(dir / "seq"), tracked(), GlobalMapParams{}, joint);
  worker.play();
  worker.waitIdle();
  const LastOptimisation& last = worker.mapping()->last_optimisation;
  ASSERT_EQ(last.kind, LastOptimisation::Kind::kRefinement) << worker.status().message;
  EXPECT_EQ(last.method, "joint");
  EXPECT_GT(last.pairs, 0);
  EXPECT_GT(last.correction_m, 0.0);
  EXPECT_FALSE(worker.mapping()->keyframes_before.empty());
  // Seeking back re-maps from the start: the refinement is forgotten.
  worker.seek(10);
  worker.waitIdle();
  EXPECT_NE(worker.mapping()->last_optimisation.kind, LastOptimisation::Kind::kRefinement);
}

}  // namespace
}  // namespace vdmap::app::gui
