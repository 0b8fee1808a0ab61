#pragma once
// Ground truth for the point queries (docs/method.md 13; docs/results.md "Queries"): what exact
// (noise-free) depth renders of a mesh saw, and seeded point sets with known answers: occupied
// near the surface, free on the mapped frames' rays, free just in front of the surface, and
// never seen. A method's classification and distance are scored against these sets.
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"
#include "mapping/files/ply_reader.h"

namespace vdmap {

/// What one exact depth frame says about a point.
enum class FrameSight : std::uint8_t {
  kNone = 0,     ///< outside the image, behind the surface, at a depth edge or between free and surface
  kFree = 1,     ///< z < D - free_margin with every depth of the 3x3 pixels around > z + free_margin
  kSurface = 2,  ///< |z - D| <= surface_tolerance
};

struct OccupancyTruthParams {
  double free_margin_m = 0.02;         ///< seen free: this far in front of the pixel's and its neighbours' depths
  double surface_tolerance_m = 0.005;  ///< seen on the surface: within this of the pixel's depth
  double min_range_m = 0.1;            ///< F: nearest depth sampled on a ray
  double clearance_m = 0.05;           ///< F and U: mesh distance above this; F: at most D - this
  double near_min_m = 0.005, near_max_m = 0.05;  ///< F_near: mesh distance (and range before the surface)
  double occupied_offset_m = 0.005;              ///< O: moved along the normal by U[-this, this]
  std::size_t occupied = 100000, free = 100000, free_near = 50000, unknown = 100000;
  /// Mesh samples that decide which triangles were seen (one of its samples seen on the surface).
  std::size_t seen_mesh_samples = 1000000;
  std::uint32_t seed = 36;
  int threads = 0;  ///< 0: all cores; the sets do not depend on it
};

/// The point sets with their truth (world frame, metres). Distances are exact: to the whole mesh,
/// and to its seen part (the triangles with a sample some frame sees on the surface), which is all
/// a map of these frames can know.
struct OccupancyTruthSets {
  std::vector<Eigen::Vector3d> occupied;  ///< O: truth occupied
  std::vector<double> occupied_offset_m;  ///< O: signed offset along the normal, + towards the camera that saw it
  std::vector<Eigen::Vector3d> free;      ///< F: truth free
  std::vector<double> free_distance_m;
  std::vector<double> free_seen_distance_m;
  std::vector<Eigen::Vector3d> free_near;  ///< F_near: truth free, near_min..near_max from the mesh
  std::vector<double> free_near_distance_m;
  std::vector<double> free_near_seen_distance_m;
  std::size_t seen_triangles = 0;        ///< of the mesh's
  std::vector<Eigen::Vector3d> unknown;  ///< U: truth unknown (never seen, away from the mesh)
  /// O candidates dropped because some frame sees them free (grazing views): neither class is sure.
  std::size_t ambiguous_occupied = 0;
};

/// The exact depth frames of the mapped poses and the labels they give.
class OccupancyTruth {
 public:
  /// `camera.depth_scale` converts the frames' raw CV_16UC1 depth (0: no depth) to metres.
  explicit OccupancyTruth(const PinholeCamera& camera, const OccupancyTruthParams& params = {});

  /// Adds one exact depth frame (CV_16UC1, camera size; kept by reference-counted cv::Mat) at pose
  /// T_W_C. Throws std::invalid_argument for a wrong type or size.
  void addFrame(const cv::Mat& depth, const Transform& T_W_C);
  std::size_t frames() const { return frames_.size(); }
  const PinholeCamera& camera() const { return camera_; }
  const OccupancyTruthParams& params() const { return params_; }

  /// What frame `f` says about p_W.
  FrameSight sight(std::size_t f, const Eigen::Vector3d& p_W) const;
  /// Whether any frame sees p_W free / on the surface.
  struct Seen {
    bool free = false, surface = false;
  };
  Seen seen(const Eigen::Vector3d& p_W) const;

  /// The point sets over `mesh` (the mesh the frames were rendered from), seeded by params.seed:
  /// the same frames, mesh and params give the same sets for any thread count. A set may hold
  /// fewer points than asked when candidates run out (a mostly unseen mesh).
  OccupancyTruthSets sample(const ColoredTriangleMesh& mesh) const;

 private:
  struct Frame {
    cv::Mat depth;
    Transform T_W_C, T_C_W;
  };
  double depthAt(const Frame& frame, int u, int v) const;  // metres, 0 for none

  PinholeCamera camera_;
  OccupancyTruthParams params_;
  std::vector<Frame> frames_;
};

}  // namespace vdmap
