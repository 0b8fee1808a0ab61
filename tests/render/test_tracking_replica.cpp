// Tracking on a render of the Replica office0 mesh along its recorded trajectory (exact poses
// known, Kinect-like depth noise): the drift per frame stays within a bound and the dense
// refinement against the local maps is what keeps it there.
#include <gtest/gtest.h>

#include "mapping/eval/trajectory_error.h"
#include "mapping/files/ply_reader.h"
#include "mapping/io/camera_config.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/pipeline/mapper.h"
#include "render/sequence_synth.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

// The Replica preset at half its resolution (600x340): pixel centres stay where they were.
PinholeCamera halfReplicaCamera() {
  PinholeCamera camera = cameraPreset("replica");
  camera.width /= 2, camera.height /= 2, camera.fx /= 2, camera.fy /= 2;
  camera.cx = (camera.cx + 0.5) / 2 - 0.5, camera.cy = (camera.cy + 0.5) / 2 - 0.5;
  return camera;
}

// The first 120 poses of the 2000-pose trajectory, rendered at half the Replica resolution
// (600x340) with the nguyen2012 sensor model.
std::vector<RgbdFrame> renderReplicaWalk(const std::filesystem::path& data) {
  const ColoredTriangleMesh mesh = readPlyMesh(data / "reference" / "office0_mesh.ply");
  const std::vector<StampedPose> trajectory = readTumTrajectory(data / "reference" / "groundtruth_full_2000.txt");
  const PinholeCamera camera = halfReplicaCamera();
  std::unique_ptr<render::Context> context = render::createOffscreenContext();
  render::MeshViewRenderer renderer(*context, mesh, camera);
  std::vector<RgbdFrame> frames;
  for (int i = 0; i < 120; ++i) {
    const render::SyntheticView view = renderer.render(trajectory[i].T_W_C);
    RgbdFrame f;
    f.index = i;
    f.timestamp = trajectory[i].t;
    f.T_W_C = trajectory[i].T_W_C;
    f.rgb = view.rgb;
    f.depth = simulateDepth(view.z_cos, camera.depth_scale, {}, i);
    frames.push_back(std::move(f));
  }
  return frames;
}

TrajectoryError track(const std::vector<RgbdFrame>& frames, const PinholeCamera& camera, bool dense) {
  MapperParams params;
  params.poses = PoseSource::kTrack;
  TrackingParams tracking;
  tracking.loops.enabled = false;
  tracking.tracker.relative.dense_refinement = dense;
  Mapper mapper(camera, params, tracking);
  std::vector<StampedPose> truth;
  for (const RgbdFrame& f : frames) {
    truth.push_back({f.timestamp, f.T_W_C});
    mapper.addFrame(f);
  }
  EXPECT_EQ(mapper.framesLost(), 0);
  return evaluateTrajectory(mapper.trajectory(), truth);
}

TEST(TrackingReplica, DriftsLittleAndTheDenseRefinementHelps) {
  VDMAP_REQUIRE_SHARED_DATA(data, "replica-office0");
  const std::vector<RgbdFrame> frames = renderReplicaWalk(data);
  const PinholeCamera camera = halfReplicaCamera();
  const TrajectoryError refined = track(frames, camera, true);
  const TrajectoryError pnp = track(frames, camera, false);
  std::printf("Replica office0 poses 0:120 at 600x340: RPE per frame %.2f mm / %.3f deg, ATE %.2f mm; "
              "PnP only %.2f mm / %.3f deg, %.2f mm\n",
              1000 * refined.rpe_per_frame.translation_m.rmse, refined.rpe_per_frame.rotation_deg.rmse,
              1000 * refined.ate_m.rmse, 1000 * pnp.rpe_per_frame.translation_m.rmse,
              pnp.rpe_per_frame.rotation_deg.rmse, 1000 * pnp.ate_m.rmse);
  EXPECT_LT(refined.rpe_per_frame.translation_m.rmse, 0.002);
  EXPECT_LT(refined.ate_m.rmse, 0.005);
  EXPECT_LT(refined.rpe_per_frame.translation_m.rmse, pnp.rpe_per_frame.translation_m.rmse);
  EXPECT_LT(refined.ate_m.rmse, pnp.ate_m.rmse);
}

}  // namespace
}  // namespace vdmap
