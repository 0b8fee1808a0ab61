#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "mapping/core/types.h"

namespace vdmap {

/// A pose with its timestamp (T_W_C, camera-to-world).
struct StampedPose {
  double t = 0.0;
  Transform T_W_C = Transform::Identity();
};

/// Reads a TUM trajectory (`timestamp tx ty tz qx qy qz qw` per line, '#' comments), timestamps
/// strictly increasing. Quaternions are normalised. Throws InputError naming the file and line for
/// a malformed line, a non-finite value, a zero-norm quaternion or a timestamp out of order.
std::vector<StampedPose> readTumTrajectory(const std::filesystem::path& file);

/// Writes a TUM trajectory with `header` as a comment line (atomically: temp file + rename).
void writeTumTrajectory(const std::filesystem::path& file, const std::vector<StampedPose>& poses,
                        const std::string& header);

}  // namespace vdmap
