#include "tests/test_util.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

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
  std::ofstream(file) << text;
}

void writeTinySequence(const fs::path& dir, int frames, int width, int height) {
  fs::create_directories(dir / "rgb");
  fs::create_directories(dir / "depth");
  std::ostringstream rgb_list, depth_list, gt;
  rgb_list << "# timestamp filename\n";
  depth_list << "# timestamp filename\n";
  gt << "# timestamp tx ty tz qx qy qz qw\n";
  std::mt19937 rng(7);
  for (int i = 0; i < frames; ++i) {
    const double t = i / 30.0;
    cv::Mat rgb(height, width, CV_8UC3);
    cv::randu(rgb, 0, 255);
    cv::Mat depth(height, width, CV_16UC1, cv::Scalar(7500));  // 1.5 m at scale 5000
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", i);
    cv::imwrite((dir / "rgb" / name).string(), rgb);
    cv::imwrite((dir / "depth" / name).string(), depth);
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

fs::path sharedData(const std::string& name) {
  const fs::path path = fs::path(VDMAP_SHARED_DATA) / name;
  return fs::is_directory(path) ? path : fs::path();
}

RunResult runVdmap(const std::string& args) {
  TempDir tmp;
  const std::string cmd = std::string("'") + VDMAP_BINARY + "' " + args + " >'" +
                          (tmp / "out").string() + "' 2>'" + (tmp / "err").string() + "'";
  const int status = std::system(cmd.c_str());
  RunResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  auto slurp = [](const fs::path& p) {
    std::ifstream in(p);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  result.out = slurp(tmp / "out");
  result.err = slurp(tmp / "err");
  return result;
}

}  // namespace vdmap::test
