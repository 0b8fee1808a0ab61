#include "mapping/eval/occupancy_truth.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include <Eigen/Geometry>

#include "mapping/core/parallel.h"
#include "mapping/eval/mesh_accuracy.h"

namespace vdmap {
namespace {

std::vector<Eigen::Vector3f> asFloat(const std::vector<Eigen::Vector3d>& points) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(points.size());
  for (const Eigen::Vector3d& p : points) out.push_back(p.cast<float>());
  return out;
}

// A candidate drawn on a frame's pixel ray: the frame, the pixel and its exact depth.
struct RayDraw {
  std::size_t frame = 0;
  int u = 0, v = 0;
  double depth_m = 0;
};

}  // namespace

OccupancyTruth::OccupancyTruth(const PinholeCamera& camera, const OccupancyTruthParams& params)
    : camera_(camera), params_(params) {
  camera_.validate();
  if (!(params_.free_margin_m >= 0 && params_.surface_tolerance_m >= 0 && params_.min_range_m >= 0 &&
        params_.clearance_m >= 0 && params_.near_min_m >= 0 && params_.near_max_m > params_.near_min_m &&
        params_.occupied_offset_m >= 0))
    throw std::invalid_argument("OccupancyTruthParams: distances must be >= 0 and near_max_m > near_min_m");
}

void OccupancyTruth::addFrame(const cv::Mat& depth, const Transform& T_W_C) {
  if (depth.type() != CV_16UC1 || depth.cols != camera_.width || depth.rows != camera_.height)
    throw std::invalid_argument("OccupancyTruth::addFrame: expected a CV_16UC1 depth image of the camera's size");
  frames_.push_back({depth, T_W_C, T_W_C.inverse()});
}

double OccupancyTruth::depthAt(const Frame& frame, int u, int v) const {
  return frame.depth.at<std::uint16_t>(v, u) / camera_.depth_scale;
}

FrameSight OccupancyTruth::sight(std::size_t f, const Eigen::Vector3d& p_W) const {
  const Frame& frame = frames_[f];
  const Eigen::Vector3d p_C = frame.T_C_W * p_W;
  const double z = p_C.z();
  if (!(z > 0)) return FrameSight::kNone;
  const Eigen::Vector2d uv = camera_.project(p_C);
  if (!camera_.inImage(uv.x(), uv.y())) return FrameSight::kNone;
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  const double d = depthAt(frame, u, v);
  if (d <= 0) return FrameSight::kNone;  // no surface measured: nothing known along the ray
  if (std::abs(z - d) <= params_.surface_tolerance_m) return FrameSight::kSurface;
  if (!(z < d - params_.free_margin_m)) return FrameSight::kNone;
  // No depth edge around: every neighbour's surface (a missing depth counts as an edge) lies
  // beyond the point by the margin.
  for (int dv = -1; dv <= 1; ++dv)
    for (int du = -1; du <= 1; ++du) {
      const int nu = std::clamp(u + du, 0, camera_.width - 1), nv = std::clamp(v + dv, 0, camera_.height - 1);
      if (!(depthAt(frame, nu, nv) > z + params_.free_margin_m)) return FrameSight::kNone;
    }
  return FrameSight::kFree;
}

OccupancyTruth::Seen OccupancyTruth::seen(const Eigen::Vector3d& p_W) const {
  Seen s;
  for (std::size_t f = 0; f < frames_.size() && !(s.free && s.surface); ++f) {
    const FrameSight k = sight(f, p_W);
    s.free |= k == FrameSight::kFree;
    s.surface |= k == FrameSight::kSurface;
  }
  return s;
}

OccupancyTruthSets OccupancyTruth::sample(const ColoredTriangleMesh& mesh) const {
  OccupancyTruthSets sets;
  if (frames_.empty() || mesh.triangles.empty()) return sets;
  const OccupancyTruthParams& P = params_;
  // Candidates come in rounds of a few times the points wanted, until a set is full (a frame
  // sees little of a large mesh) or kRounds ran out.
  constexpr int kRounds = 32;
  std::mt19937_64 rng(P.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);

  // O: surface samples some frame sees on the surface, moved along their triangle's normal
  // (turned towards the first such frame's camera); dropped (and counted) when some frame then
  // sees the moved point free (a grazing view: neither answer is sure there).
  for (int round = 0; round < kRounds && sets.occupied.size() < P.occupied; ++round) {
    std::vector<std::uint32_t> tri;
    const std::vector<Eigen::Vector3f> samples = sampleMeshSurface(mesh, 4 * P.occupied, P.seed + round, &tri);
    std::vector<double> offset(samples.size());
    for (double& s : offset) s = P.occupied_offset_m * (2 * unit(rng) - 1);
    std::vector<Eigen::Vector3d> moved(samples.size());
    std::vector<std::uint8_t> state(samples.size(), 0);  // 0 unseen, 1 kept, 2 ambiguous
    parallelFor(P.threads, samples.size(), [&](std::size_t i) {
      const Eigen::Vector3d p = samples[i].cast<double>();
      for (std::size_t f = 0; f < frames_.size(); ++f) {
        if (sight(f, p) != FrameSight::kSurface) continue;
        const auto& t = mesh.triangles[tri[i]];
        const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
        Eigen::Vector3d normal =
            (mesh.positions[t[1]].cast<double>() - a).cross(mesh.positions[t[2]].cast<double>() - a);
        if (!(normal.norm() > 0)) return;  // a degenerate triangle has no normal
        normal.normalize();
        if (normal.dot(frames_[f].T_W_C.translation() - p) < 0) normal = -normal;
        moved[i] = p + offset[i] * normal;
        state[i] = seen(moved[i]).free ? 2 : 1;
        return;
      }
    });
    for (std::size_t i = 0; i < samples.size() && sets.occupied.size() < P.occupied; ++i) {
      if (state[i] == 2) ++sets.ambiguous_occupied;
      if (state[i] != 1) continue;
      sets.occupied.push_back(moved[i]);
      sets.occupied_offset_m.push_back(offset[i]);
    }
  }

  // Draws of a random frame's random pixel with a depth; `count` draws (pixels without depth are
  // drawn again, up to 100 times each).
  auto drawRays = [&](std::size_t count) {
    std::uniform_int_distribution<std::size_t> pick_frame(0, frames_.size() - 1);
    std::uniform_int_distribution<int> pick_u(0, camera_.width - 1), pick_v(0, camera_.height - 1);
    std::vector<RayDraw> draws;
    for (std::size_t i = 0; i < count; ++i)
      for (int attempt = 0; attempt < 100; ++attempt) {
        RayDraw d{pick_frame(rng), pick_u(rng), pick_v(rng), 0.0};
        d.depth_m = depthAt(frames_[d.frame], d.u, d.v);
        if (d.depth_m > 0) {
          draws.push_back(d);
          break;
        }
      }
    return draws;
  };

  // F: on a mapped frame's pixel ray, depth uniform in [min_range, D - clearance], seen free by
  // that frame, more than `clearance` from the mesh.
  for (int round = 0; round < kRounds && sets.free.size() < P.free; ++round) {
    const std::vector<RayDraw> draws = drawRays(3 * P.free);
    std::vector<Eigen::Vector3d> candidates;
    std::vector<std::size_t> frame_of;
    for (const RayDraw& d : draws) {
      const double far = d.depth_m - P.clearance_m;
      const double z = P.min_range_m + unit(rng) * (far - P.min_range_m);
      if (far <= P.min_range_m) continue;
      candidates.push_back(frames_[d.frame].T_W_C * camera_.backProject(d.u, d.v, z));
      frame_of.push_back(d.frame);
    }
    const std::vector<double> dist = distancesToMesh(asFloat(candidates), mesh);
    std::vector<std::uint8_t> free_in_frame(candidates.size());
    parallelFor(P.threads, candidates.size(),
                [&](std::size_t i) { free_in_frame[i] = sight(frame_of[i], candidates[i]) == FrameSight::kFree; });
    for (std::size_t i = 0; i < candidates.size() && sets.free.size() < P.free; ++i) {
      if (!(dist[i] > P.clearance_m) || !free_in_frame[i]) continue;
      sets.free.push_back(candidates[i]);
      sets.free_distance_m.push_back(dist[i]);
    }
  }

  // F_near: on a mapped frame's pixel ray, near_min..near_max before the surface it hits, and
  // that far from the mesh.
  for (int round = 0; round < kRounds && sets.free_near.size() < P.free_near; ++round) {
    const std::vector<RayDraw> draws = drawRays(4 * P.free_near);
    std::vector<Eigen::Vector3d> candidates;
    for (const RayDraw& d : draws) {
      const double back = P.near_min_m + unit(rng) * (P.near_max_m - P.near_min_m);
      const Eigen::Vector3d hit_C = camera_.backProject(d.u, d.v, d.depth_m);
      const double range = hit_C.norm();
      if (range - back <= P.min_range_m) continue;
      candidates.push_back(frames_[d.frame].T_W_C * (hit_C * ((range - back) / range)));
    }
    const std::vector<double> dist = distancesToMesh(asFloat(candidates), mesh);
    for (std::size_t i = 0; i < candidates.size() && sets.free_near.size() < P.free_near; ++i) {
      if (!(dist[i] >= P.near_min_m && dist[i] <= P.near_max_m)) continue;
      sets.free_near.push_back(candidates[i]);
      sets.free_near_distance_m.push_back(dist[i]);
    }
  }

  // U: uniform in the mesh's box, never seen (free or surface) by any frame, more than
  // `clearance` from the mesh.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Eigen::Vector3f& p : mesh.positions)
    lo = lo.cwiseMin(p.cast<double>()), hi = hi.cwiseMax(p.cast<double>());
  for (int round = 0; round < kRounds && sets.unknown.size() < P.unknown; ++round) {
    std::vector<Eigen::Vector3d> candidates(4 * P.unknown);
    for (Eigen::Vector3d& c : candidates)
      for (int k = 0; k < 3; ++k) c[k] = lo[k] + unit(rng) * (hi[k] - lo[k]);
    const std::vector<double> dist = distancesToMesh(asFloat(candidates), mesh);
    std::vector<std::uint8_t> never(candidates.size(), 0);
    parallelFor(P.threads, candidates.size(), [&](std::size_t i) {
      if (!(dist[i] > P.clearance_m)) return;
      const Seen s = seen(candidates[i]);
      never[i] = !s.free && !s.surface;
    });
    for (std::size_t i = 0; i < candidates.size() && sets.unknown.size() < P.unknown; ++i)
      if (never[i]) sets.unknown.push_back(candidates[i]);
  }

  // The seen part of the mesh and the free points' distances to it.
  {
    std::vector<std::uint32_t> tri;
    const std::vector<Eigen::Vector3f> samples = sampleMeshSurface(mesh, P.seen_mesh_samples, P.seed + 1000, &tri);
    std::vector<std::uint8_t> seen_sample(samples.size());
    parallelFor(P.threads, samples.size(), [&](std::size_t i) {
      for (std::size_t f = 0; f < frames_.size() && !seen_sample[i]; ++f)
        seen_sample[i] = sight(f, samples[i].cast<double>()) == FrameSight::kSurface;
    });
    std::vector<std::uint8_t> seen_triangle(mesh.triangles.size(), 0);
    for (std::size_t i = 0; i < samples.size(); ++i) seen_triangle[tri[i]] |= seen_sample[i];
    ColoredTriangleMesh seen_mesh;
    seen_mesh.positions = mesh.positions;
    seen_mesh.colors = mesh.colors;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      if (seen_triangle[t]) seen_mesh.triangles.push_back(mesh.triangles[t]);
    sets.seen_triangles = seen_mesh.triangles.size();
    const auto toSeen = [&](const std::vector<Eigen::Vector3d>& points) {
      if (seen_mesh.triangles.empty())
        return std::vector<double>(points.size(), std::numeric_limits<double>::infinity());
      return distancesToMesh(asFloat(points), seen_mesh);
    };
    sets.free_seen_distance_m = toSeen(sets.free);
    sets.free_near_seen_distance_m = toSeen(sets.free_near);
  }
  return sets;
}

}  // namespace vdmap
