#pragma once
// Dense refinement of a frame's pose against one keyframe's local map (docs/method.md 8): frame
// points are projected into the keyframe's container, associated with the ellipsoid of the cell
// they land in (the container's projective association, no search), and the point-to-distribution
// (NDT) distances are minimised by Gauss-Newton.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "mapping/core/rgbd_frame.h"
#include "mapping/local_map/keyframe_container.h"

namespace vdmap {

/// The pose change of a Gauss-Newton step xi = (translation, rotation vector) as the refinements
/// apply it (exp(xi) to first order: the rotation, then the translation).
Transform stepTransform(const Eigen::Matrix<double, 6, 1>& xi);

/// A frame's points on a regular pixel grid (camera frame C, metres): what the dense refinement
/// aligns. Computed once per frame and shared by every keyframe the frame is compared with.
struct DensePoints {
  std::vector<Eigen::Vector3f> points_C;
  std::size_t size() const { return points_C.size(); }
};

/// Every `stride_px`-th pixel of every `stride_px`-th row whose depth lies in `range`.
DensePoints sampleDensePoints(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range,
                              int stride_px);

/// A colour image as the photometric term reads it: grey (0-255), at half the camera's
/// resolution (INTER_AREA: half-resolution pixel i covers full-resolution pixels 2i and 2i + 1),
/// smoothed by a Gaussian of sigma 1, and its central-difference gradients; CV_32F each. At half
/// resolution and smoothed, a pose a few pixels off still sees the slope towards the right one.
struct PhotometricImage {
  cv::Mat grey, gx, gy;
  bool empty() const { return grey.empty(); }
};
/// Of a CV_8UC3 RGB image (empty in, empty out).
PhotometricImage photometricImage(const cv::Mat& rgb);

/// The photometric term's points of a frame (camera frame C) and their grey levels in the
/// frame's PhotometricImage.
struct PhotometricPoints {
  std::vector<Eigen::Vector3f> points_C;
  std::vector<float> intensity;
  bool empty() const { return points_C.empty(); }
};

/// Grey levels per half-resolution pixel: weaker gradients give the photometric term no point.
constexpr float kMinPhotometricGradient = 4.0f;

/// In each block of stride_px x stride_px pixels, the half-resolution pixel of the largest
/// intensity gradient (at least kMinPhotometricGradient) whose four full-resolution depths lie in
/// `range` within 2 % of each other (not on a depth edge, where the keyframe may see the
/// background). Empty when the frame has no colour.
PhotometricPoints samplePhotometricPoints(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range,
                                          int stride_px);

/// The photometric term's two sides: the frame's points and the keyframe's image.
struct PhotometricTerm {
  const PhotometricPoints& frame;
  const PhotometricImage& keyframe;
};

/// A feature correspondence the refinement also honours: keyframe point X_K (the keyframe's
/// keypoint with its depth) observed at frame pixel `pixel` (PnP's inliers).
struct FeatureObservation {
  Eigen::Vector3d X_K;
  Eigen::Vector2d pixel;
};

struct NdtRefinementParams {
  /// About this many frame points whatever the resolution: sampleDensePoints' pixel grid has
  /// the stride strideFor() (8 px at 640x480). A fixed stride left a 160x120 recording 300 points,
  /// too few for the refinement to be trusted (min_dense_inliers), and it tracked far off.
  int points = 4800;
  int strideFor(const PinholeCamera& camera) const {
    return std::max(
        1, static_cast<int>(std::lround(std::sqrt(double(camera.width) * camera.height / std::max(points, 1)))));
  }
  int iterations = 6;           ///< Gauss-Newton steps at most
  int min_cell_points = 6;      ///< cells with fewer points give no distribution (min_points, docs/method.md 4)
  double max_distance_m = 0.1;  ///< a point farther than this from its cell's mean is not associated
  /// Tukey biweight threshold on the Mahalanobis distance: a point beyond it has no weight, so
  /// the far side of an occluding edge cannot pull the pose (a Huber tail, whose pull never
  /// vanishes, biased 7-Scenes estimates by centimetres).
  double robust_k = 3.0;
  /// The first step's threshold is this times robust_k (and the features' likewise); each step
  /// halves it down to robust_k. 1: no annealing.
  double annealing_factor = 8.0;
  /// Isotropic variance added to every cell covariance besides the sensor's axial noise at the
  /// cell's depth: keeps a cell of perfectly planar (noise-free, synthetic) points invertible.
  double min_variance_m2 = 1e-6;
  /// false: the sensor model's axial variance at the cell's depth is taken out of the cell's
  /// covariance along the keyframe's ray instead of added to it, so the cell has the surface's
  /// own shape (the noise tilts a cell's thinnest axis towards its keyframe's ray, and the
  /// projective association's in-cell offsets then pull along it). Right for points that are
  /// themselves averages (another map's cell means: the joint map refinement); a single frame's
  /// points carry that noise, so tracking keeps it.
  bool axial_noise = true;
  /// Weight of the in-plane axes of a cell: its two larger eigenvalues are multiplied by this.
  /// The projective association puts a point in whichever cell it lands in, so its offset
  /// along the surface says little about the pose; at full weight it pulls points towards cell
  /// centres and slows convergence along the surface (feature terms constrain that instead).
  /// 10, not 3: with 3, the 4800 points of a 320x240 box-room frame still slid along the walls
  /// after 6 steps (docs/notes/tracking.md), and more steps cost time.
  double in_plane_inflation = 10.0;
  /// Reprojection noise of a feature observation, px (one sigma), and its Tukey threshold in
  /// sigmas. 2 px, not 1: JPEG colour that is not registered to the depth (7-Scenes) biases
  /// keypoint depths, and the dense terms should decide along the surface normals.
  double feature_sigma_px = 2.0;
  double feature_robust_k = 4.0;
  /// Photometric term (refineAgainstLocalMap's PhotometricTerm): each photometric point's grey
  /// level against the keyframe's where the pose projects it, less the median difference over
  /// the points (an exposure change), Tukey-weighted at photometric_robust_k sigmas (annealed as
  /// the dense points'), sigma being the differences' own spread (1.4826 times their median
  /// absolute deviation, at least photometric_min_sigma grey levels), so the term weighs as much
  /// as the images agree.
  double photometric_min_sigma = 2.0;
  double photometric_robust_k = 4.0;
  double converged_m = 1e-5;    ///< stop when a step moves less than this ...
  double converged_rad = 1e-5;  ///< ... and turns less than this
};

struct NdtRefinementResult {
  int points = 0;                ///< points of the frame
  int associated = 0;            ///< of those, landing on a cell with an ellipsoid within max_distance_m (last step)
  int inliers = 0;               ///< of those, within robust_k (Mahalanobis)
  double rms_mahalanobis = 0.0;  ///< over the inliers
  /// Sum over the points and the features of 1 - rho(d) / rho_max (Tukey's loss of the
  /// Mahalanobis distance d, or of the reprojection error): a soft inlier count, higher where the
  /// frame fits the local map and the matched keypoints better. The features count: the dense
  /// points alone favour a pose slid along a wall that puts more of them inside the map.
  double support = 0.0;
  int iterations = 0;  ///< Gauss-Newton steps taken
  /// The photometric term at the solution (0 without it): its points that project into the
  /// keyframe's image and the spread of their grey-level differences (sigma, grey levels).
  int photometric_points = 0;
  double photometric_sigma = 0.0;
  /// Gauss-Newton normal matrix at the solution for a perturbation T_K_C <- exp(xi) T_K_C,
  /// xi = (translation, rotation) in the keyframe frame: the estimate's information matrix.
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> gradient =
      Eigen::Matrix<double, 6, 1>::Zero();  ///< of the cost at the solution, same perturbation
  double inlierRatio() const { return associated > 0 ? static_cast<double>(inliers) / associated : 0.0; }
  /// The translation block of `information` without the photometric term: the surfaces' and
  /// the features' hold on the position.
  Eigen::Matrix3d translation_information = Eigen::Matrix3d::Zero();
  /// Smallest over largest eigenvalue of translation_information: near 0 where the surfaces
  /// leave a direction free (two walls: the pose can slide along their line). The photometric
  /// term is left out: from a prediction 0.3 m off, it settles wherever the image is locally
  /// similar (the box room's textured walls, tests/mapping/test_tracking.cpp), so the frame's pixels
  /// can tell how well a pose is placed only where the surfaces could.
  double translationConditioning() const;
};

/// One cell's distribution as the refinement uses it: the mean and the information matrix (upper
/// triangle xx xy xz yy yz zz) of the cell's covariance with the sensor noise, floor and in-plane
/// inflation of NdtRefinementParams; not usable when the cell has too few points.
struct CellDistribution {
  bool usable = false;
  Eigen::Vector3f mean = Eigen::Vector3f::Zero();
  float omega[6] = {};
};

/// Every cell's distribution of a local map, computed once for a map that does not change while
/// it is linearised many times (the joint map refinement evaluates each pair at every step).
/// Index i is the distribution of map.cells()[i].
std::vector<CellDistribution> cellDistributions(const KeyframeContainer& local_map, const NdtRefinementParams& params);

/// The refinement's objective at T_K_C, without moving it (Tukey threshold robust_k, no
/// annealing, no features), the map's cells taken from `cells` (cellDistributions of local_map
/// with the same params): `information` and `gradient` of the Gauss-Newton step for the
/// perturbation exp(xi) T_K_C, `support` the soft inlier count the step should raise; what
/// refineAgainstLocalMap measures with 0 iterations, bit for bit. `inliers`, when given, gets a
/// flag per point of `frame`: set for the points within robust_k (NdtRefinementResult::inliers).
NdtRefinementResult lineariseAgainstLocalMap(const KeyframeContainer& local_map,
                                             std::span<const CellDistribution> cells, const DensePoints& frame,
                                             const Transform& T_K_C, const NdtRefinementParams& params = {},
                                             std::vector<std::uint8_t>* inliers = nullptr);

/// Refines T_K_C (the frame's pose in the keyframe frame) in place: NDT distances of the frame's
/// points to the local map plus the reprojection errors of `features` (may be empty).
/// Deterministic. A step whose normal matrix is singular (too few associations) ends the
/// refinement with T_K_C unchanged by it.
/// `photometric`, when not null, adds the photometric term.
NdtRefinementResult refineAgainstLocalMap(const KeyframeContainer& local_map, const DensePoints& frame,
                                          std::span<const FeatureObservation> features, Transform* T_K_C,
                                          const NdtRefinementParams& params = {},
                                          const PhotometricTerm* photometric = nullptr);

}  // namespace vdmap
