#include "tests/support/layouts.h"

#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "mapping/io/image_codec.h"

namespace fs = std::filesystem;

namespace vdmap::test {
namespace {

// A 4x4 matrix, row by row, every digit kept.
void writeMatrix(const fs::path& file, const Eigen::Matrix4d& M) {
  std::ofstream out(file);
  char text[64];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      std::snprintf(text, sizeof text, "%.17g%c", M(r, c), c == 3 ? '\n' : ' ');
      out << text;
    }
}

void copyFile(const fs::path& from, const fs::path& to) {
  fs::create_directories(to.parent_path());
  fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

std::string numbered(const char* format, int n) {
  char name[64];
  std::snprintf(name, sizeof name, format, n);
  return name;
}

Eigen::Matrix4d intrinsics(double fx, double fy, double cx, double cy) {
  Eigen::Matrix4d K = Eigen::Matrix4d::Identity();
  K(0, 0) = fx, K(1, 1) = fy, K(0, 2) = cx, K(1, 2) = cy;
  return K;
}

}  // namespace

void writeDataSetLayout(SequenceKind kind, const fs::path& tum_folder, const fs::path& out,
                        const LayoutOptions& options) {
  SequenceOptions open;
  open.frames = {0, options.frames};
  open.cut_range_at_end = true;
  const Sequence seq = Sequence::open(tum_folder, open);
  fs::create_directories(out);
  std::ofstream traj;
  if (kind == SequenceKind::kReplica) traj.open(out / "traj.txt");
  for (const FrameEntry& e : seq.entries()) {
    const int n = e.index;
    const Eigen::Matrix4d T = e.T_W_C.matrix();
    switch (kind) {
      case SequenceKind::kSevenScenes:
        copyFile(e.depth_path, out / numbered("frame-%06d.depth.png", n));
        if (options.colour_png)
          writeImageFile(out / numbered("frame-%06d.color.png", n),
                         readColorImage(e.rgb_path, {seq.camera().width, seq.camera().height}));
        else copyFile(e.rgb_path, out / numbered("frame-%06d.color.jpg", n));
        writeMatrix(out / numbered("frame-%06d.pose.txt", n), T);
        break;
      case SequenceKind::kReplica: {
        copyFile(e.depth_path, out / "results" / numbered("depth%06d.png", n));
        copyFile(e.rgb_path, out / "results" / numbered("frame%06d.jpg", n));
        char text[64];
        for (int k = 0; k < 16; ++k) {
          std::snprintf(text, sizeof text, "%.17g%c", T(k / 4, k % 4), k == 15 ? '\n' : ' ');
          traj << text;
        }
        break;
      }
      case SequenceKind::kScanNet:
        copyFile(e.depth_path, out / "depth" / numbered("%d.png", n));
        copyFile(e.rgb_path, out / "color" / numbered("%d.jpg", n));
        fs::create_directories(out / "pose");
        writeMatrix(out / "pose" / numbered("%d.txt", n), T);
        break;
      default: throw std::invalid_argument("writeDataSetLayout: not a data-set layout");
    }
  }
  if (fs::exists(tum_folder / "camera.yaml") && kind != SequenceKind::kScanNet)
    copyFile(tum_folder / "camera.yaml", out / "camera.yaml");
  if (kind == SequenceKind::kScanNet) {
    const PinholeCamera& c = seq.camera();
    fs::create_directories(out / "intrinsic");
    writeMatrix(out / "intrinsic" / "intrinsic_depth.txt", intrinsics(c.fx, c.fy, c.cx, c.cy));
    const ColourCamera colour = seq.colourCamera().value_or(ColourCamera{c.fx, c.fy, c.cx, c.cy});
    writeMatrix(out / "intrinsic" / "intrinsic_color.txt", intrinsics(colour.fx, colour.fy, colour.cx, colour.cy));
    writeMatrix(out / "intrinsic" / "extrinsic_color.txt", Eigen::Matrix4d::Identity());
    writeMatrix(out / "intrinsic" / "extrinsic_depth.txt", colour.T_colour_depth.matrix());
  }
}

void writeTumSubset(const fs::path& tum_folder, const fs::path& out, int first, int last, int step) {
  SequenceOptions open;
  open.frames = {first, last};
  const Sequence seq = Sequence::open(tum_folder, open);
  fs::create_directories(out);
  std::ofstream rgb(out / "rgb.txt"), depth(out / "depth.txt"), gt(out / "groundtruth.txt");
  char line[256];
  for (const FrameEntry& e : seq.entries()) {
    if ((e.index - first) % step != 0) continue;
    const std::string name = numbered("%06d", e.index);
    copyFile(e.depth_path, out / "depth" / (name + e.depth_path.extension().string()));
    copyFile(e.rgb_path, out / "rgb" / (name + e.rgb_path.extension().string()));
    std::snprintf(line, sizeof line, "%.6f depth/%s%s\n", e.t_depth, name.c_str(), e.depth_path.extension().c_str());
    depth << line;
    std::snprintf(line, sizeof line, "%.6f rgb/%s%s\n", e.t_rgb, name.c_str(), e.rgb_path.extension().c_str());
    rgb << line;
    const Eigen::Quaterniond q(e.T_W_C.linear());
    const Eigen::Vector3d t = e.T_W_C.translation();
    std::snprintf(line, sizeof line, "%.6f %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", e.t_depth, t.x(), t.y(), t.z(),
                  q.x(), q.y(), q.z(), q.w());
    gt << line;
  }
}

}  // namespace vdmap::test
