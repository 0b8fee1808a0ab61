#include "mapping/io/trajectory_io.h"

#include <cstdio>

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
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (q.norm() < 1e-6) throw InputError(file.string(), line.number, "quaternion (qx qy qz qw) has zero norm");
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
  for (const StampedPose& p : poses) {
    const Eigen::Quaterniond q(p.T_W_C.linear());
    const Eigen::Vector3d t = p.T_W_C.translation();
    std::snprintf(line, sizeof line, "%.6f %.9g %.9g %.9g %.9g %.9g %.9g %.9g\n", p.t, t.x(), t.y(), t.z(), q.x(),
                  q.y(), q.z(), q.w());
    text += line;
  }
  writeFileAtomically(file, text);
}

}  // namespace vdmap
