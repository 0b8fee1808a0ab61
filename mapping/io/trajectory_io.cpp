#include "mapping/io/trajectory_io.h"

#include <algorithm>

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "mapping/core/atomic_file.h"
#include "mapping/core/error.h"
#include "mapping/io/text_list.h"

namespace vdmap {

std::vector<StampedPose> readTumTrajectory(const std::filesystem::path& file) {
  std::vector<StampedPose> poses;
  double previous = -INFINITY;
  for (const ListLine& line : readListFile(file, 8, "timestamp tx ty tz qx qy qz qw")) {
    static const char* kNames[8] = {"the timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
    double v[8];
    for (int i = 0; i < 8; ++i) v[i] = parseListNumber(line.tokens[i], file, line.number, kNames[i]);
    checkIncreasing(v[0], &previous, file, line.number);
    for (int i = 1; i <= 3; ++i)
      if (std::abs(v[i]) > kMaxPoseDistanceM)
        throw InputError(file.string(), line.number,
                         std::string(kNames[i]) + " is " + printable(line.tokens[i]) + " m: a pose must lie within " +
                             std::to_string(static_cast<long>(kMaxPoseDistanceM)) + " m of the origin");
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (q.norm() < 1e-6) throw InputError(file.string(), line.number, "quaternion (qx qy qz qw) has zero norm");
    // Its squared norm overflows (components beyond ~1e154): normalising would give zeros.
    if (!std::isfinite(q.norm()))
      throw InputError(file.string(), line.number, "quaternion (qx qy qz qw) is too large to normalise");
    StampedPose pose{v[0], Transform::Identity()};
    pose.T_W_C.linear() = q.normalized().toRotationMatrix();
    pose.T_W_C.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back(pose);
  }
  return poses;
}

void writeTumTrajectory(const std::filesystem::path& file, const std::vector<StampedPose>& poses,
                        const std::string& header) {
  std::string text = "# " + header + "\n# timestamp tx ty tz qx qy qz qw\n";
  char line[256];
  for (std::size_t i = 0; i < poses.size(); ++i)
    if (!std::isfinite(poses[i].t) || !poses[i].T_W_C.matrix().allFinite())
      throw std::runtime_error(file.string() + ": pose " + std::to_string(i) +
                               " is not finite; not written (vdmap reads no such file back)");
  for (const StampedPose& p : poses) {
    const Eigen::Quaterniond q(p.T_W_C.linear());
    const Eigen::Vector3d t = p.T_W_C.translation();
    std::snprintf(line, sizeof line, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", p.t, t.x(), t.y(), t.z(), q.x(),
                  q.y(), q.z(), q.w());
    text += line;
  }
  writeFileAtomically(file, text);
}

std::optional<Transform> interpolatePose(const std::vector<StampedPose>& poses, double t, double max_dt) {
  auto next =
      std::lower_bound(poses.begin(), poses.end(), t, [](const StampedPose& p, double time) { return p.t < time; });
  constexpr double kSameTime = 1e-6;
  if (next != poses.end() && next->t - t < kSameTime) return next->T_W_C;
  if (next != poses.begin() && t - std::prev(next)->t < kSameTime) return std::prev(next)->T_W_C;
  if (next == poses.end() || next == poses.begin()) return std::nullopt;
  const StampedPose& a = *std::prev(next);
  const StampedPose& b = *next;
  if (t - a.t > max_dt || b.t - t > max_dt) return std::nullopt;
  const double s = (t - a.t) / (b.t - a.t);
  Transform T = Transform::Identity();
  T.translation() = (1.0 - s) * a.T_W_C.translation() + s * b.T_W_C.translation();
  T.linear() = Eigen::Quaterniond(a.T_W_C.linear()).slerp(s, Eigen::Quaterniond(b.T_W_C.linear())).toRotationMatrix();
  return T;
}

}  // namespace vdmap
