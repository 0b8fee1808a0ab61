// vdmap info SEQ: what a sequence holds, what was dropped and why.
#include <algorithm>
#include <iostream>

#include <nlohmann/json.hpp>

#include "app/cli/sequence_args.h"
#include "app/verbs.h"
#include "app/view/progress.h"
#include "mapping/core/message_text.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"

namespace vdmap::app {
namespace {

// Raw depth codes that are not measurements: 0 (no return, docs/method.md 1) and 65535, the largest
// 16-bit value, which 7-Scenes writes for invalid pixels (65.535 m at its scale of 1000) and
// other sensors for saturation; no real reading lands exactly on it.
constexpr std::uint16_t kNoDepth = 0, kInvalidDepthCode = 65535;

struct DepthStats {
  int frames_sampled = 0;
  double min_m = 0, median_m = 0, max_m = 0;  ///< over valid pixels
  double valid_fraction = 0;
  double no_depth_fraction = 0;      ///< raw 0
  double invalid_code_fraction = 0;  ///< raw 65535
};

// The colour camera of an unregistered sequence (null when the colour is registered already).
nlohmann::json colourJson(const std::optional<ColourCamera>& c) {
  if (!c) return nullptr;
  const Eigen::Matrix<double, 3, 4> T = c->T_colour_depth.matrix().topRows<3>();
  std::vector<double> rows;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k) rows.push_back(T(r, k));
  return {{"fx", c->fx}, {"fy", c->fy}, {"cx", c->cx}, {"cy", c->cy}, {"T_colour_depth", rows}};
}

// Reads up to `samples` evenly spaced depth images: enough for the range, cheap on long runs.
DepthStats sampleDepth(const Sequence& seq, int samples) {
  DepthStats stats;
  std::vector<std::uint16_t> valid;
  std::size_t pixels = 0, zero = 0, code = 0;
  const std::size_t n = std::min<std::size_t>(samples, seq.size());
  ProgressBar progress("reading depth", n);
  for (std::size_t k = 0; k < n; ++k) {
    const RgbdFrame frame = seq.load(n == 1 ? 0 : k * (seq.size() - 1) / (n - 1));
    pixels += frame.depth.total();
    for (auto it = frame.depth.begin<std::uint16_t>(); it != frame.depth.end<std::uint16_t>(); ++it) {
      if (*it == kNoDepth) ++zero;
      else if (*it == kInvalidDepthCode) ++code;
      else valid.push_back(*it);
    }
    progress.update(k + 1);
  }
  stats.frames_sampled = static_cast<int>(n);
  const double scale = seq.camera().depth_scale, total = static_cast<double>(std::max<std::size_t>(pixels, 1));
  if (!valid.empty()) {
    std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
    stats.median_m = valid[valid.size() / 2] / scale;
    const auto [lo, hi] = std::minmax_element(valid.begin(), valid.end());
    stats.min_m = *lo / scale;
    stats.max_m = *hi / scale;
  }
  stats.valid_fraction = static_cast<double>(valid.size()) / total;
  stats.no_depth_fraction = static_cast<double>(zero) / total;
  stats.invalid_code_fraction = static_cast<double>(code) / total;
  return stats;
}

void runInfo(const SequenceArgs& args, bool json) {
  const Sequence seq = openSequence(args);
  const PinholeCamera& cam = seq.camera();
  const DepthStats depth = sampleDepth(seq, 10);
  const double t0 = seq.entries().front().t_depth, t1 = seq.entries().back().t_depth;
  const DropCounts& d = seq.dropped();
  const auto with_pose =
      std::count_if(seq.entries().begin(), seq.entries().end(), [](const FrameEntry& e) { return e.has_pose; });
  if (json) {
    nlohmann::json out = {
        {"folder", seq.folder().string()},
        {"kind", sequenceKindName(seq.kind())},
        {"kind_reason", seq.kindReason()},
        {"poses_source", seq.posesSource()},
        {"notes", seq.notes()},
        {"listed_depth_frames", seq.listedDepthFrames()},
        {"frames", seq.size()},
        {"frame_range", frameRangeText(seq.frameRange())},
        {"frames_with_pose", with_pose},
        {"groundtruth", seq.hasGroundTruth()},
        {"time_span_s", {t0, t1}},
        {"camera",
         {{"source", seq.cameraSource()},
          {"width", cam.width},
          {"height", cam.height},
          {"fx", cam.fx},
          {"fy", cam.fy},
          {"cx", cam.cx},
          {"cy", cam.cy},
          {"depth_scale", cam.depth_scale}}},
        {"colour_camera", colourJson(seq.colourCamera())},
        {"depth_m",
         {{"frames_sampled", depth.frames_sampled},
          {"min", depth.min_m},
          {"median", depth.median_m},
          {"max", depth.max_m},
          {"valid_fraction", rounded(depth.valid_fraction)},
          {"invalid_fraction", rounded(1.0 - depth.valid_fraction)},
          {"no_depth_fraction", rounded(depth.no_depth_fraction)},
          {"invalid_code_fraction", rounded(depth.invalid_code_fraction)}}},
        {"dropped",
         {{"no_rgb", d.no_rgb},
          {"no_pose", d.no_pose},
          {"outside_frames", d.outside_range},
          {"rgb_window_s", d.max_rgb_dt_s}}},
    };
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::printf("sequence   %s\n", seq.folder().c_str());
  std::printf("kind       %s (it %s)\n", sequenceKindName(seq.kind()).c_str(), seq.kindReason().c_str());
  for (const std::string& note : seq.notes()) std::printf("           %s\n", note.c_str());
  if (seq.hasGroundTruth())
    std::printf("frames     %zu usable (all with poses, from %s) of %s; frames %s\n", seq.size(),
                seq.posesSource().c_str(), counted(seq.listedDepthFrames(), "listed depth frame").c_str(),
                frameRangeText(seq.frameRange()).c_str());
  else
    std::printf("frames     %zu usable of %s; frames %s; no recorded poses (vdmap tracks the poses)\n", seq.size(),
                counted(seq.listedDepthFrames(), "listed depth frame").c_str(),
                frameRangeText(seq.frameRange()).c_str());
  std::printf("time span  %.3f .. %.3f s (%.1f s)\n", t0, t1, t1 - t0);
  std::printf("camera     %dx%d fx %.3f fy %.3f cx %.3f cy %.3f depth scale %g  [%s]\n", cam.width, cam.height, cam.fx,
              cam.fy, cam.cx, cam.cy, cam.depth_scale, seq.cameraSource().c_str());
  if (const auto& c = seq.colourCamera())
    std::printf("colour     fx %.3f fy %.3f cx %.3f cy %.3f, %.1f mm and %.2f deg from the depth camera: registered "
                "to the depth when loaded\n",
                c->fx, c->fy, c->cx, c->cy, 1000.0 * c->T_colour_depth.translation().norm(),
                Eigen::AngleAxisd(c->T_colour_depth.linear()).angle() * 180.0 / M_PI);
  std::printf("depth      %.3f .. %.3f m, median %.3f m over valid pixels; %.3g%% invalid (%.3g%% 0 = no "
              "measurement, %.3g%% 65535 = invalid code) (%s sampled)\n",
              depth.min_m, depth.max_m, depth.median_m, 100.0 * (1.0 - depth.valid_fraction),
              100.0 * depth.no_depth_fraction, 100.0 * depth.invalid_code_fraction,
              counted(depth.frames_sampled, "frame").c_str());
  std::printf("dropped    %d without an rgb frame within %g s, %d without a pose within %g s, %d outside --frames\n",
              d.no_rgb, d.max_rgb_dt_s, d.no_pose, d.max_pose_dt_s, d.outside_range);
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("info", "Describe a sequence: frames, time span, camera, depth, drops");
  auto args = std::make_shared<SequenceArgs>();
  auto json = std::make_shared<bool>(false);
  addSequenceArgs(*verb, *args);
  verb->add_flag("--json", *json, "print JSON instead of text");
  verb->callback([args, json] { runInfo(*args, *json); });
}

}  // namespace vdmap::app
