#pragma once
// The odometry peers of `vdmap bench --poses track`: OpenCV's cv::rgbd::RgbdOdometry
// (photometric + depth) and cv::rgbd::ICPOdometry (point-to-plane ICP) from opencv_contrib, each
// frame to frame and against the last keyframe, and Open3D's hybrid RGB-D odometry frame to frame
// through the optional plugin (app/bench/open3d/odometry_peer_abi.h). They run on the bench's decoded frames,
// one thread, and only estimate poses; the bench scores them against the ground truth.
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "mapping/core/camera.h"
#include "mapping/core/rgbd_frame.h"
#include "mapping/io/trajectory_io.h"

namespace vdmap::app {

enum class OdometryMethod { kOpenCvRgbd, kOpenCvIcp, kOpen3dHybrid };

/// What each frame is registered against.
enum class OdometryReference {
  kPreviousFrame,
  /// The last keyframe; the frame becomes the new keyframe when it lies more than
  /// keyframe_translation_m or keyframe_rotation_deg from it, or when registration fails.
  kKeyframe,
};

struct OdometryPeerParams {
  OdometryMethod method = OdometryMethod::kOpenCvRgbd;
  OdometryReference reference = OdometryReference::kPreviousFrame;
  double keyframe_translation_m = 0.05;
  double keyframe_rotation_deg = 5.0;
};

struct OdometryRun {
  std::string name;  ///< e.g. "OpenCV RgbdOdometry, last keyframe"
  std::string key;   ///< JSON key, e.g. "opencv_rgbd_keyframe"
  /// T_W_C of every frame at its timestamp; the first frame at its own (ground-truth) pose.
  std::vector<StampedPose> trajectory;
  /// Process CPU time per registered frame (all but the first), ms: the method's input
  /// conversion (grey image, depth in metres) and registration.
  std::vector<double> ms;
  int failures = 0;   ///< frames the method did not register (placed at the prediction)
  int keyframes = 0;  ///< keyframes used, the first frame included (kKeyframe; 0 frame to frame)
  std::string note;   ///< why the peer did not run (the Open3D plugin is not built); else empty
};

/// The peer's name and key, without running it.
OdometryRun describeOdometryPeer(const OdometryPeerParams& params);

/// Runs the peer over the frames in order. OpenCV's methods run with their default parameters
/// (depth 0-4 m, correspondences within 0.07 m of depth), cv::setNumThreads(1) for the run; the
/// prediction is the identity frame to frame and the previous frame's pose against a keyframe.
/// A frame the method fails on (including OpenCV's own check: more than 0.15 m or 15 degrees
/// from the reference) is placed at the prediction and counted.
/// `on_frame(n)` is called after each of the n frames (for a progress bar).
OdometryRun runOdometryPeer(const OdometryPeerParams& params, std::span<const RgbdFrame> frames,
                            const PinholeCamera& camera, const std::function<void(std::size_t)>& on_frame = {});

}  // namespace vdmap::app
