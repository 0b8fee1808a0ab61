// The built-in scene end to end (always runs: it is generated in code): its walk returns to the
// start, so the keyframe graph must close the loop by revisiting an early keyframe. Both tests map
// the same 150-frame lap, rendered once per build into the tests' shared cache.
#include <gtest/gtest.h>

#include <optional>

#include "mapping/eval/mesh_accuracy.h"
#include "mapping/eval/trajectory_error.h"
#include "mapping/files/ply_reader.h"
#include "mapping/global_map/global_map.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/sequence/frame_prefetcher.h"
#include "tests/support/render_scenes.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

TEST(BuiltinScene, TheWalkBackToTheStartRevisitsTheFirstKeyframes) {
  const Sequence seq = Sequence::open(test::builtinSequence(150));
  Mapper mapper(seq.camera());
  FramePrefetcher frames(seq);
  FrameReport last;
  while (auto f = frames.next()) last = mapper.addFrame(*f);
  const KeyframeGraph& graph = mapper.graph();
  EXPECT_GT(mapper.revisits(), 0);
  // The walk ends where it started: the last frame updates a keyframe made in the first tenth
  // of the walk instead of starting a new one.
  EXPECT_NE(last.decision.kind, FrameDecision::Kind::kNewKeyframe);
  EXPECT_LT(graph.keyframe(last.keyframe).frame_index, static_cast<int>(seq.size()) / 10);
  EXPECT_TRUE(graph.edges().hasEdge(last.keyframe, static_cast<int>(graph.size()) - 1))
      << "the loop closure links the last keyframe to the first";
  const GlobalMap global = buildGlobalMap(graph, {});
  EXPECT_GT(global.sigma_e_prime, 0u);
  EXPECT_LT(global.sigma_e_prime, global.sigma_e);
  std::printf("built-in scene: %zu frames, %zu keyframes, %d revisits, Sigma_e %zu -> %zu\n", seq.size(), graph.size(),
              mapper.revisits(), global.sigma_e, global.sigma_e_prime);
}

// Tracked poses on one lap of the built-in walk (150 frames, the sensor model's noise): refining
// the keyframe poses jointly brings the global map closer to the scene's mesh, and the trajectory
// closer to the truth, than refining them pair by pair.
TEST(BuiltinScene, JointRefinementOfTrackedPosesBringsTheMapCloserToTheMesh) {
  const std::filesystem::path folder = test::builtinSequence(150);
  const Sequence seq = Sequence::open(folder);
  const ColoredTriangleMesh mesh = readPlyMesh(folder / "mesh.ply");
  std::vector<StampedPose> truth;
  for (const FrameEntry& e : seq.entries()) truth.push_back({e.t_depth, e.T_W_C});
  struct Outcome {
    double map_rmse_mm = 0, ate_mm = 0;
  };
  // One tracked run; each refinement starts from a copy of its state.
  MapperParams params;
  params.poses = PoseSource::kTrack;
  Mapper tracked_run(seq.camera(), params);
  FramePrefetcher frames(seq, 4, tracked_run.featuresAhead());
  while (auto f = frames.next()) tracked_run.addFrame(*f);
  const auto run = [&](std::optional<MapRefinementMethod> method) {
    Mapper mapper = tracked_run;
    if (method) {
      MapRefinementParams refine;
      refine.method = *method;
      mapper.refineKeyframePoses(refine);
    }
    std::vector<Eigen::Vector3f> points;
    for (const Ellipsoid& e : buildGlobalMap(mapper.graph(), {}).ellipsoids) points.push_back(e.mean.cast<float>());
    return Outcome{evaluateAccuracy(points, mesh).rmse_mm,
                   1000 * evaluateTrajectory(mapper.trajectory(), truth).ate_m.rmse};
  };
  const Outcome tracked = run(std::nullopt), pairwise = run(MapRefinementMethod::kPairwise),
                joint = run(MapRefinementMethod::kJoint);
  std::printf("built-in lap, tracked poses: map RMSE %.2f mm as tracked, %.2f pairwise, %.2f joint; ATE %.2f / %.2f / "
              "%.2f mm\n",
              tracked.map_rmse_mm, pairwise.map_rmse_mm, joint.map_rmse_mm, tracked.ate_mm, pairwise.ate_mm,
              joint.ate_mm);
  EXPECT_LT(joint.map_rmse_mm, 0.6 * pairwise.map_rmse_mm);
  EXPECT_LT(joint.map_rmse_mm, 0.6 * tracked.map_rmse_mm);
  EXPECT_LT(joint.ate_mm, pairwise.ate_mm);
  EXPECT_LT(joint.ate_mm, tracked.ate_mm);
}

}  // namespace
}  // namespace vdmap
