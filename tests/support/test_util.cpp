#include "tests/support/test_util.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "mapping/core/error.h"
#include "mapping/io/image_codec.h"

namespace vdmap::test {

TempDir::TempDir() {
  std::string pattern = (fs::temp_directory_path() / "vdmap-test-XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

void writeText(const fs::path& file, const std::string& text) {
  fs::create_directories(file.parent_path());
  std::ofstream(file, std::ios::binary) << text;
}

std::string readFile(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeTinySequence(const fs::path& dir, int frames, int width, int height) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::ostringstream rgb_list, depth_list, gt;
  rgb_list << "# timestamp filename\n";
  depth_list << "# timestamp filename\n";
  gt << "# timestamp tx ty tz qx qy qz qw\n";
  cv::RNG rng(7);
  for (int i = 0; i < frames; ++i) {
    const double t = i / 30.0;
    cv::Mat rgb(height, width, CV_8UC3);
    rng.fill(rgb, cv::RNG::UNIFORM, 0, 255);
    cv::Mat depth(height, width, CV_16UC1, cv::Scalar(7500));  // 1.5 m at scale 5000
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    writeImage(dir / "rgb" / name, rgb);
    writeImage(dir / "depth" / name, depth);
    rgb_list << std::fixed << t << " rgb/" << name << "\n";
    depth_list << std::fixed << t << " depth/" << name << "\n";
    gt << std::fixed << t << " " << 0.01 * i << " 0 0 0 0 0 1\n";
  }
  writeText(dir / "rgb.txt", rgb_list.str());
  writeText(dir / "depth.txt", depth_list.str());
  writeText(dir / "groundtruth.txt", gt.str());
  std::ostringstream cam;
  cam << "fx: 50\nfy: 50\ncx: " << (width - 1) / 2.0 << "\ncy: " << (height - 1) / 2.0
      << "\ndepth_scale: 5000\nwidth: " << width << "\nheight: " << height << "\n";
  writeText(dir / "camera.yaml", cam.str());
}

namespace {

const cv::Mat& faceTexture(int face) {
  static const std::vector<cv::Mat> textures = [] {
    std::vector<cv::Mat> t(6);
    for (int f = 0; f < 6; ++f) {
      cv::RNG rng(1000 + f);
      cv::Mat noise(512, 512, CV_8UC3);
      rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
      cv::GaussianBlur(noise, t[f], cv::Size(0, 0), 1.5);
      cv::normalize(t[f], t[f], 0, 255, cv::NORM_MINMAX);
    }
    return t;
  }();
  return textures[face];
}

}  // namespace

RgbdFrame renderBoxRoom(const PinholeCamera& camera, const Transform& T_W_C) {
  const Eigen::Vector3d lo(-2.0, -1.5, -2.0), hi(2.0, 1.5, 2.0);
  RgbdFrame frame;
  frame.T_W_C = T_W_C;
  frame.rgb = cv::Mat(camera.height, camera.width, CV_8UC3);
  frame.depth = cv::Mat(camera.height, camera.width, CV_16UC1);
  const Eigen::Vector3d o = T_W_C.translation();
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d ray_C = camera.backProject(u, v, 1.0);
      const Eigen::Vector3d d = T_W_C.linear() * ray_C;
      double t_hit = INFINITY;
      int face = 0;
      for (int axis = 0; axis < 3; ++axis) {
        if (d[axis] == 0.0) continue;
        const double bound = d[axis] > 0 ? hi[axis] : lo[axis];
        const double t = (bound - o[axis]) / d[axis];
        if (t > 0 && t < t_hit) {
          t_hit = t;
          face = 2 * axis + (d[axis] > 0);
        }
      }
      const Eigen::Vector3d p = o + t_hit * d;
      const int a = face / 2 == 0 ? 1 : 0, b = face / 2 == 2 ? 1 : 2;  // the face's in-plane axes
      const double s = (p[a] - lo[a]) / (hi[a] - lo[a]), r = (p[b] - lo[b]) / (hi[b] - lo[b]);
      const cv::Mat& tex = faceTexture(face);
      const int tx = std::clamp(static_cast<int>(s * tex.cols), 0, tex.cols - 1);
      const int ty = std::clamp(static_cast<int>(r * tex.rows), 0, tex.rows - 1);
      frame.rgb.at<cv::Vec3b>(v, u) = tex.at<cv::Vec3b>(ty, tx);
      const double z = t_hit * ray_C.z();  // ray_C has z = 1, so z = t
      frame.depth.at<std::uint16_t>(v, u) =
          static_cast<std::uint16_t>(std::min(65535.0, std::round(z * camera.depth_scale)));
    }
  return frame;
}

Transform lookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - position).normalized();
  Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z);  // image x right when world -y is up
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Transform T = Transform::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = y;
  T.linear().col(2) = z;
  T.translation() = position;
  return T;
}

RgbdFrame turningBoxRoomFrame(const PinholeCamera& camera, int i, double degrees_per_frame) {
  const double a = i * degrees_per_frame * M_PI / 180.0;
  RgbdFrame f = renderBoxRoom(camera, lookAt({0, 0.2, 0}, {std::sin(a), 0.3, std::cos(a)}));
  f.index = i;
  f.timestamp = i / 30.0;
  return f;
}

namespace {
const PinholeCamera kTurningCamera{160, 120, 131.25, 131.25, 79.5, 59.5, 5000.0};
}  // namespace

void writeBoxRoomSequence(const fs::path& dir, int frames) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::ostringstream rgb_list, depth_list, gt;
  for (int i = 0; i < frames; ++i) {
    const RgbdFrame f = turningBoxRoomFrame(kTurningCamera, i, 6.0);
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    cv::Mat bgr;
    cv::cvtColor(f.rgb, bgr, cv::COLOR_RGB2BGR);
    writeImage(dir / "rgb" / name, bgr);
    writeImage(dir / "depth" / name, f.depth);
    rgb_list << std::fixed << std::setprecision(6) << f.timestamp << " rgb/" << name << "\n";
    depth_list << std::fixed << std::setprecision(6) << f.timestamp << " depth/" << name << "\n";
    const Eigen::Quaterniond q(f.T_W_C.linear());
    const Eigen::Vector3d t = f.T_W_C.translation();
    gt << std::setprecision(17) << f.timestamp << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x() << " "
       << q.y() << " " << q.z() << " " << q.w() << "\n";
  }
  writeText(dir / "rgb.txt", rgb_list.str());
  writeText(dir / "depth.txt", depth_list.str());
  writeText(dir / "groundtruth.txt", gt.str());
  const PinholeCamera& c = kTurningCamera;
  std::ostringstream cam;
  cam << std::setprecision(17) << "fx: " << c.fx << "\nfy: " << c.fy << "\ncx: " << c.cx << "\ncy: " << c.cy
      << "\ndepth_scale: " << c.depth_scale << "\nwidth: " << c.width << "\nheight: " << c.height << "\n";
  writeText(dir / "camera.yaml", cam.str());
}

Mapper mapTurningBoxRoom(int frames) {
  const PinholeCamera& camera = kTurningCamera;
  Mapper mapper(camera);
  for (int i = 0; i < frames; ++i) mapper.addFrame(turningBoxRoomFrame(camera, i, 6.0));
  return mapper;
}

cv::Mat readImage(const fs::path& file) {
  try {
    cv::Mat bgr;
    cv::cvtColor(decodeColorImage(readFile(file), file.string()), bgr, cv::COLOR_RGB2BGR);
    return bgr;
  } catch (const InputError&) {
    return cv::Mat();
  }
}

cv::Mat readDepthImage(const fs::path& file) {
  try {
    return decodeDepthImage(readFile(file), file.string());
  } catch (const InputError&) {
    return cv::Mat();
  }
}

void writeImage(const fs::path& file, const cv::Mat& image) { writeImageFile(file, image, ChannelOrder::kBgr); }

fs::path sharedCache() {
  const fs::path root(VDMAP_TEST_CACHE);
  const std::string built = std::to_string(fs::last_write_time(VDMAP_BINARY).time_since_epoch().count());
  if (!fs::exists(root / built)) {
    std::error_code ec;  // another process may be removing the same folders
    if (fs::is_directory(root))
      for (const auto& entry : fs::directory_iterator(root, ec))
        if (entry.path().filename() != built) fs::remove_all(entry.path(), ec);
    fs::create_directories(root / built);
  }
  return root / built;
}

bool haveXvfb() { return std::system("command -v xvfb-run >/dev/null 2>&1") == 0; }

RunResult runVdmapInXvfb(const fs::path& home, const std::string& args, const std::string& screen, BuiltinCache cache) {
  if (cache == BuiltinCache::kShared && !fs::exists(home / "cache" / "vdmap")) {
    fs::create_directories(home / "cache");
    fs::create_directory_symlink(sharedCache(), home / "cache" / "vdmap");
  }
  const int first_display = 100 + static_cast<int>(getpid() % 5000) * 8;
  // One llvmpipe raster thread: the window draws the same pixels with any number (see
  // docs/dev/testing.md, "How far drivers spread"), and test processes running side by side
  // each spinning up a thread per core spend more CPU on the same frames.
  const std::string prefix = "LP_NUM_THREADS=1 XDG_CONFIG_HOME='" + (home / "config").string() + "' XDG_CACHE_HOME='" +
                             (home / "cache").string() + "' xvfb-run -a -n " + std::to_string(first_display) + " -f '" +
                             (home / "Xauthority").string() + "' -s '-screen 0 " + screen + "x24 -noreset'";
  return runVdmap(args, prefix);
}

fs::path sharedData(const std::string& name) {
  const fs::path path = fs::path(VDMAP_SHARED_DATA) / name;
  return fs::is_directory(path) ? path : fs::path();
}

RunResult runVdmap(const std::string& args, const std::string& prefix) {
  TempDir tmp;
  const std::string cmd = prefix + " '" + VDMAP_BINARY + "' " + args + " >'" + (tmp / "out").string() + "' 2>'" +
                          (tmp / "err").string() + "'";
  const int status = std::system(cmd.c_str());
  RunResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = readFile(tmp / "out");
  result.err = readFile(tmp / "err");
  return result;
}

}  // namespace vdmap::test
