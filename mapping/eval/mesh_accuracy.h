#pragma once
// Reconstruction accuracy against a reference mesh (docs/method.md 12, paper Table III): exact
// point-to-triangle distances of the map's element centres, and completion of the mesh surface.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mapping/files/ply_reader.h"

namespace vdmap {

/// The point of triangle (a, b, c) closest to p (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c);

/// Exact distance (m) from each point to the nearest triangle of the mesh, through a bounding-
/// volume hierarchy. Same frame and unit as the mesh. Runs on all cores; results do not depend on that.
std::vector<double> distancesToMesh(const std::vector<Eigen::Vector3f>& points, const ColoredTriangleMesh& mesh);

/// The obviously-correct reference for distancesToMesh: every point against every triangle.
std::vector<double> distancesToMeshBruteForce(const std::vector<Eigen::Vector3f>& points,
                                              const ColoredTriangleMesh& mesh);

/// Exact distance (m) from each query to the nearest of `points` (empty `points`: infinity).
std::vector<double> distancesToPoints(const std::vector<Eigen::Vector3f>& queries,
                                      const std::vector<Eigen::Vector3f>& points);

/// `count` points uniformly distributed over the mesh surface by area (deterministic per seed);
/// with `triangles`, each point's triangle index there (the points do not depend on it).
std::vector<Eigen::Vector3f> sampleMeshSurface(const ColoredTriangleMesh& mesh, std::size_t count, std::uint32_t seed,
                                               std::vector<std::uint32_t>* triangles = nullptr);

struct AccuracyParams {
  std::size_t completion_samples = 200000;  ///< mesh samples for completion (docs/method.md 12)
  static constexpr std::size_t kMaxCompletionSamples = 100'000'000;  ///< what --samples accepts
  std::uint32_t seed = 8;                                            ///< fixed, so the same map always scores the same
  double completion_within_m = 0.05;                                 ///< "complete" when a map element is this close
};

/// docs/method.md 12 figures. Distances in millimetres.
struct AccuracyReport {
  std::size_t elements = 0;  ///< map elements evaluated
  double rmse_mm = 0.0;      ///< of element-centre to mesh distances
  double mean_mm = 0.0;
  double median_mm = 0.0;
  double completion_mean_mm = 0.0;  ///< mean distance from mesh samples to the nearest element
  double completion_ratio = 0.0;    ///< fraction of mesh samples within completion_within_m
};

/// Scores map element centres `points` against `mesh` (same world frame, metres).
AccuracyReport evaluateAccuracy(const std::vector<Eigen::Vector3f>& points, const ColoredTriangleMesh& mesh,
                                const AccuracyParams& params = {});

/// docs/method.md 12, a surface against a reference mesh. Distances in millimetres.
struct SurfaceAccuracyReport {
  std::size_t triangles = 0;  ///< of the surface scored
  double median_mm = 0.0;     ///< of the surface samples' distances to the reference
  double p95_mm = 0.0;
  double mean_mm = 0.0;
  double rmse_mm = 0.0;
  double completion_ratio = 0.0;       ///< reference samples within completion_within_m of the surface
  double seen_completion_ratio = 0.0;  ///< the same among the samples `seen` marks (all when it is empty)
};

/// Scores a triangle mesh `surface` against `reference`: params.completion_samples points uniformly
/// over each by area (sampleMeshSurface, the seed for both), the surface's samples' exact distances to
/// the reference (accuracy) and the reference's samples' exact distances to the surface (completion).
/// `seen` (empty, or one flag per sample of sampleMeshSurface(reference, completion_samples, seed)) marks
/// the reference samples the frames saw, for seen_completion_ratio. An empty surface has no accuracy
/// figures and completion 0.
SurfaceAccuracyReport evaluateSurfaceAccuracy(const ColoredTriangleMesh& surface, const ColoredTriangleMesh& reference,
                                              const AccuracyParams& params = {}, const std::vector<bool>& seen = {});

}  // namespace vdmap
