#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "mapping/core/types.h"

namespace vdmap {

/// How far from the world origin a pose may lie, m. The exports store coordinates as float32,
/// whose spacing is 0.98 mm up to 16 km: within 10 km every exported point keeps a millimetre, as
/// fine as the depth sensors measure; farther out the maps lose resolution silently, and far
/// enough (1e39 m) they turn into inf. RGB-D recordings span rooms to buildings; a trajectory in
/// geographic coordinates (UTM: 1e5 to 1e7 m) is to be moved near the origin first.
inline constexpr double kMaxPoseDistanceM = 1e4;

/// A pose with its timestamp (T_W_C, camera-to-world).
struct StampedPose {
  double t = 0.0;
  Transform T_W_C = Transform::Identity();
};

/// Reads a TUM trajectory (`timestamp tx ty tz qx qy qz qw` per line, '#' comments), timestamps
/// strictly increasing. Quaternions are normalised. Throws InputError naming the file and line for
/// a malformed line, a non-finite value, a translation component beyond kMaxPoseDistanceM, a
/// quaternion whose norm is zero or overflows, or a timestamp out of order.
std::vector<StampedPose> readTumTrajectory(const std::filesystem::path& file);

/// The pose at time t of a trajectory sorted by time: interpolated between the poses around t
/// (linear translation, slerp rotation), or nothing when either is more than max_dt away. A pose
/// within 1 us of t is taken as it is.
std::optional<Transform> interpolatePose(const std::vector<StampedPose>& poses, double t, double max_dt);

/// Writes a TUM trajectory with `header` as a comment line (atomically: temp file + rename).
/// Throws std::runtime_error naming the file, and writes nothing, when a pose is not finite.
void writeTumTrajectory(const std::filesystem::path& file, const std::vector<StampedPose>& poses,
                        const std::string& header);

}  // namespace vdmap
