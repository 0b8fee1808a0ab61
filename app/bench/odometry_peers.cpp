#include "app/bench/odometry_peers.h"

#include <cstring>
#include <memory>
#include <stdexcept>

#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/rgbd.hpp>

#include "app/bench/open3d/odometry_peer_abi.h"
#include "app/bench/peer_plugin.h"
#include "mapping/core/timing.h"

namespace vdmap::app {
namespace {

/// Registers frames one after another: returns T_ref_cur for the frame against the reference
/// (given the prediction), and whether it succeeded. `make_reference` keeps the frame as the next
/// reference.
class Registration {
 public:
  virtual ~Registration() = default;
  /// Prepares the frame (timed by the caller with register_).
  virtual void setFrame(const RgbdFrame& frame) = 0;
  virtual bool registerToReference(const Transform& prediction, Transform* T_ref_cur) = 0;
  virtual void makeReference() = 0;
};

class OpenCvRegistration : public Registration {
 public:
  OpenCvRegistration(OdometryMethod method, const PinholeCamera& cam)
      : photometric_(method == OdometryMethod::kOpenCvRgbd) {
    const cv::Mat K = (cv::Mat_<double>(3, 3) << cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
    if (photometric_) odometry_ = cv::rgbd::RgbdOdometry::create(K);
    else odometry_ = cv::rgbd::ICPOdometry::create(K);
    depth_scale_ = cam.depth_scale;
  }
  void setFrame(const RgbdFrame& frame) override {
    cv::Mat grey, depth_m;
    if (photometric_) cv::cvtColor(frame.rgb, grey, cv::COLOR_RGB2GRAY);
    frame.depth.convertTo(depth_m, CV_32F, 1.0 / depth_scale_);  // CV_32F metres, as the rgbd module needs
    current_ = cv::rgbd::OdometryFrame::create(grey, depth_m);
  }
  bool registerToReference(const Transform& prediction, Transform* T_ref_cur) override {
    cv::Mat init, Rt;
    cv::eigen2cv(Eigen::Matrix4d(prediction.matrix()), init);
    // dst_p = Rt * src_p with src the current frame and dst the reference: Rt = T_ref_cur.
    if (!odometry_->compute(current_, reference_, Rt, init)) return false;
    Eigen::Matrix4d T;
    cv::cv2eigen(Rt, T);
    T_ref_cur->matrix() = T;
    return true;
  }
  void makeReference() override { reference_ = current_; }  // its pyramids are kept and reused

 private:
  bool photometric_;
  double depth_scale_;
  cv::Ptr<cv::rgbd::Odometry> odometry_;
  cv::Ptr<cv::rgbd::OdometryFrame> current_, reference_;
};

/// Open3D's odometry is frame to frame inside the plugin: setFrame does the work.
class Open3dRegistration : public Registration {
 public:
  static std::unique_ptr<Open3dRegistration> open(const PinholeCamera& cam, std::string* why) {
    const auto create = reinterpret_cast<VdmapOdometryCreateFn>(open3dPeerSymbol("vdmap_odometry_create", why));
    const auto track = reinterpret_cast<VdmapOdometryTrackFn>(open3dPeerSymbol("vdmap_odometry_track", why));
    const auto destroy = reinterpret_cast<VdmapOdometryDestroyFn>(open3dPeerSymbol("vdmap_odometry_destroy", why));
    if (!create || !track || !destroy) return nullptr;
    void* state = create(cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy, cam.depth_scale);
    if (!state) {
      *why = "Open3D could not create the odometry";
      return nullptr;
    }
    return std::unique_ptr<Open3dRegistration>(new Open3dRegistration(track, destroy, state));
  }
  ~Open3dRegistration() override { destroy_(state_); }
  void setFrame(const RgbdFrame& frame) override {
    const cv::Mat rgb = frame.rgb.isContinuous() ? frame.rgb : frame.rgb.clone();
    const cv::Mat depth = frame.depth.isContinuous() ? frame.depth : frame.depth.clone();
    Eigen::Matrix4d T;
    ok_ = track_(state_, rgb.ptr<std::uint8_t>(), depth.ptr<std::uint16_t>(), T.data()) != 0;
    T_prev_cur_.matrix() = T;
  }
  bool registerToReference(const Transform&, Transform* T_ref_cur) override {
    *T_ref_cur = T_prev_cur_;
    return ok_;
  }
  void makeReference() override {}

 private:
  Open3dRegistration(VdmapOdometryTrackFn track, VdmapOdometryDestroyFn destroy, void* state)
      : track_(track), destroy_(destroy), state_(state) {}
  VdmapOdometryTrackFn track_;
  VdmapOdometryDestroyFn destroy_;
  void* state_;
  Transform T_prev_cur_ = Transform::Identity();
  bool ok_ = true;
};

/// Restores OpenCV's thread count when the run ends.
class OpenCvThreads {
 public:
  explicit OpenCvThreads(int n) : saved_(cv::getNumThreads()) { cv::setNumThreads(n); }
  ~OpenCvThreads() { cv::setNumThreads(saved_); }

 private:
  int saved_;
};

}  // namespace

OdometryRun describeOdometryPeer(const OdometryPeerParams& p) {
  OdometryRun run;
  const bool keyframe = p.reference == OdometryReference::kKeyframe;
  switch (p.method) {
    case OdometryMethod::kOpenCvRgbd: run.name = "OpenCV RgbdOdometry", run.key = "opencv_rgbd"; break;
    case OdometryMethod::kOpenCvIcp: run.name = "OpenCV ICPOdometry", run.key = "opencv_icp"; break;
    case OdometryMethod::kOpen3dHybrid: run.name = "Open3D hybrid odometry", run.key = "open3d_hybrid"; break;
  }
  run.name += keyframe ? ", last keyframe" : ", frame to frame";
  run.key += keyframe ? "_keyframe" : "_frame";
  return run;
}

OdometryRun runOdometryPeer(const OdometryPeerParams& p, std::span<const RgbdFrame> frames, const PinholeCamera& cam,
                            const std::function<void(std::size_t)>& on_frame) {
  OdometryRun run = describeOdometryPeer(p);
  const bool keyframe = p.reference == OdometryReference::kKeyframe;
  std::unique_ptr<Registration> registration;
  if (p.method == OdometryMethod::kOpen3dHybrid) {
    if (keyframe) throw std::invalid_argument("the Open3D odometry peer runs frame to frame only");
    registration = Open3dRegistration::open(cam, &run.note);
    if (!registration) return run;
  } else {
    registration = std::make_unique<OpenCvRegistration>(p.method, cam);
  }
  if (frames.empty()) return run;
  const OpenCvThreads one_thread(1);
  registration->setFrame(frames[0]);
  registration->makeReference();
  Transform T_W_ref = frames[0].T_W_C, T_ref_previous = Transform::Identity();
  run.trajectory.push_back({frames[0].timestamp, T_W_ref});
  run.keyframes = keyframe ? 1 : 0;
  if (on_frame) on_frame(1);
  for (std::size_t i = 1; i < frames.size(); ++i) {
    const Transform prediction = keyframe ? T_ref_previous : Transform::Identity();
    Transform T_ref_cur = prediction;
    bool ok = false;
    run.ms.push_back(cpuTimeMs([&] {
      registration->setFrame(frames[i]);
      ok = registration->registerToReference(prediction, &T_ref_cur);
    }));
    if (!ok) {
      T_ref_cur = prediction;
      ++run.failures;
    }
    const Transform T_W_cur = T_W_ref * T_ref_cur;
    run.trajectory.push_back({frames[i].timestamp, T_W_cur});
    const bool far = T_ref_cur.translation().norm() > p.keyframe_translation_m ||
                     Eigen::AngleAxisd(T_ref_cur.linear()).angle() > p.keyframe_rotation_deg * M_PI / 180.0;
    if (!keyframe || !ok || far) {
      registration->makeReference();
      T_W_ref = T_W_cur;
      T_ref_previous = Transform::Identity();
      run.keyframes += keyframe;
    } else {
      T_ref_previous = T_ref_cur;
    }
    if (on_frame) on_frame(i + 1);
  }
  return run;
}

}  // namespace vdmap::app
