#pragma once
// Shared helpers for vdmap's tests: temporary folders, tiny generated sequences, running the
// vdmap binary, and access to ../shared/data (tests skip when it is absent).
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "mapping/core/rgbd_frame.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap::test {

namespace fs = std::filesystem;

/// A fresh, empty folder under the system temp dir, removed on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const fs::path& path() const { return path_; }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

/// Writes `text` (any bytes) to `file` (creating parent folders).
void writeText(const fs::path& file, const std::string& text);

/// The bytes of `file` ("" when it cannot be read).
std::string readFile(const fs::path& file);

/// Writes a small valid TUM sequence: `frames` frames of `width`x`height` at 30 fps, a fronto-
/// parallel plane at 1.5 m (depth scale 5000), textured colour, identity-ish poses moving along x,
/// and a camera.yaml. Returns nothing; the folder is `dir`.
void writeTinySequence(const fs::path& dir, int frames = 3, int width = 64, int height = 48);

/// An RGB-D frame of the inside of a textured box room [-2,2] x [-1.5,1.5] x [-2,2] m seen from
/// T_W_C, ray-cast analytically (no GL). Each of the six faces has its own blurred-noise texture
/// (deterministic), rich enough for ORB. Depth at camera.depth_scale, exact up to quantisation.
RgbdFrame renderBoxRoom(const PinholeCamera& camera, const Transform& T_W_C);

/// A camera pose at `position` looking at `target` (y of the image pointing down, world -y up).
Transform lookAt(const Eigen::Vector3d& position, const Eigen::Vector3d& target);

/// Frame `i` of a camera at the centre of the box room turning on the spot by
/// `degrees_per_frame` (index i, 30 fps timestamp).
RgbdFrame turningBoxRoomFrame(const PinholeCamera& camera, int i, double degrees_per_frame);

/// Writes frames 0..frames-1 of the turning box room (mapTurningBoxRoom's camera and walk) as a
/// TUM sequence with a camera.yaml, for command-line tests that need real keyframe decisions.
void writeBoxRoomSequence(const fs::path& dir, int frames);

/// A small whole session: a 160x120 camera at the centre of the box room turning 6 degrees a
/// frame through `frames` frames (several keyframes, covisibility edges, a revisit past 60).
Mapper mapTurningBoxRoom(int frames);

/// The image file as OpenCV's imread gives it, decoded by vdmap's own codec (tests load no
/// OpenCV codecs: they cost each process 0.1 s at start): a colour or grey PNG or JPEG as 8-bit
/// BGR (IMREAD_COLOR), or empty when it cannot be decoded.
cv::Mat readImage(const fs::path& file);
/// A 16-bit grey PNG (a depth image) as stored, or empty when it cannot be decoded.
cv::Mat readDepthImage(const fs::path& file);
/// Writes `image` as imwrite does (colour taken as BGR; PNG or JPEG by the extension).
void writeImage(const fs::path& file, const cv::Mat& image);

/// Folder of a shared data set (../shared/data/NAME), or empty when absent.
fs::path sharedData(const std::string& name);

/// Result of running the vdmap binary.
struct RunResult {
  int exit_code = -1;
  std::string out;  ///< stdout
  std::string err;  ///< stderr
};
/// Runs `PREFIX vdmap ARGS` (both passed through the shell: quote paths); PREFIX may set
/// variables or name a wrapper such as xvfb-run.
RunResult runVdmap(const std::string& args, const std::string& prefix = "");

/// A folder the test processes of this build of vdmap share for what is costly to make and
/// never changes (build/tests/builtin-cache/<build time of vdmap>): folders of earlier builds
/// are removed when it is first made.
fs::path sharedCache();

/// True when xvfb-run is installed: the workbench's end-to-end tests need it and skip without.
bool haveXvfb();

/// Runs `vdmap ARGS` in a virtual X server of its own (a `screen` of "WxH" pixels) with config
/// and cache folders and the X authority file under `home`. Safe to run several at once: each
/// starts looking for a free display at its own number and xvfb-run takes the next one when
/// another server has it. -noreset: vdmap checks for a display (connect, disconnect) before
/// opening its window, and Xvfb resets when its last client leaves, refusing connections
/// meanwhile. The authority file in `home`: without -f, xvfb-run makes a temporary folder for it
/// and exits 5 instead of vdmap's code when removing that folder fails.
/// BuiltinCache::kShared: the built-in scene's frames are cached where every test run of this
/// build of vdmap finds them (vdmap renders them once, atomically), so each run does not render
/// them again; kOwn: `home` holds the run's own cache (first-start tests).
enum class BuiltinCache { kShared, kOwn };
RunResult runVdmapInXvfb(const fs::path& home, const std::string& args, const std::string& screen = "3840x2160",
                         BuiltinCache cache = BuiltinCache::kShared);

}  // namespace vdmap::test

/// Skips the current test with a clear message when xvfb-run is missing (a window test).
#define VDMAP_REQUIRE_XVFB() \
  if (!::vdmap::test::haveXvfb()) GTEST_SKIP() << "xvfb-run not installed (window test skipped)"

/// Skips the current test with a clear message when ../shared/data/NAME is absent.
#define VDMAP_REQUIRE_SHARED_DATA(var, name)                                               \
  const std::filesystem::path var = ::vdmap::test::sharedData(name);                       \
  if (var.empty())                                                                         \
  GTEST_SKIP() << "shared data set '" << name << "' not found under " << VDMAP_SHARED_DATA \
               << " (real-data test skipped)"
