#pragma once
// `vdmap render --expect GOLDEN.png`: a rendered image checked against a reference ("golden")
// image with render::compareImages, the project's one image metric (docs/cli.md "Checking a
// render against a golden image").
#include <chrono>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "render/image_compare.h"

namespace vdmap::app {

/// The default tolerance of --expect and --suite: a pixel differs beyond 8 counts in a channel;
/// up to 2.5 % of the pixels may. llvmpipe builds (128/256-bit vectors, 1 or 2 threads) drew the
/// same pixels; softpipe, the nearest proxy for another driver, moved about half as many of a
/// global view's pixels (docs/dev/testing.md has the figures): twice that lets a golden made on
/// one driver pass on another, while a wrong camera, colour mode or map moves far more
/// (docs/cli.md says why).
inline constexpr render::ImageTolerance kGoldenTolerance{.channel_counts = 8, .pixel_share = 0.025};

/// The default of --suite and of --compare nearby: the nearby compare (render/image_compare.h),
/// 8 counts, 0.01 % of the pixels. softpipe renders at 640x480 of views whose goldens llvmpipe
/// drew kept under 0.004 % of their pixels there, while a merge distance of 0.1 instead of 0.25
/// seen from a keyframe and a global view turned by 0.2 degrees moved 0.015-0.056 % and 0.036 %
/// (docs/dev/testing.md has the figures).
inline constexpr render::ImageTolerance kSuiteTolerance{
    .channel_counts = 8, .pixel_share = 0.0001, .method = render::CompareMethod::kNearby};

/// The default tolerance of `method`: kSuiteTolerance for nearby, kGoldenTolerance for plain.
render::ImageTolerance defaultTolerance(render::CompareMethod method);

/// A share of the pixels as a fraction in 0..1 or a percentage ("0.025", "2.5%"). Throws
/// std::invalid_argument.
double parseShare(const std::string& text);

/// --tolerance COUNTS,SHARE: counts in 0..255 and a share of the pixels as a fraction in 0..1 or
/// a percentage ("8,0.005", "8,0.5%"). Throws std::invalid_argument naming what is wrong.
render::ImageTolerance parseTolerance(const std::string& text);

/// The options of the comparison.
struct RenderCheckArgs {
  std::string expect;                     ///< the golden PNG ("" : no comparison)
  std::string diff;                       ///< where the diff image goes when the render differs ("" : nowhere)
  std::string tolerance;                  ///< COUNTS,SHARE ("" : the compare's default)
  std::string compare;                    ///< --compare plain|nearby ("" : plain, with --suite nearby)
  bool update = false;                    ///< write the render as the golden instead of comparing
  std::vector<std::string> update_views;  ///< --update VIEW...: with --suite, only these views
  bool timings = false;                   ///< print the stage times on stderr
  std::string suite;                      ///< --suite views.yaml (app/view/render_suite.h)
};

/// Registers --expect, --tolerance, --compare, --diff, --update, --suite (and --timings) on `verb`.
void addRenderCheckArgs(CLI::App& verb, RenderCheckArgs& args);

/// The tolerance the arguments give (defaultTolerance of --compare without --tolerance).
render::ImageTolerance tolerance(const RenderCheckArgs& args);

/// Refuses --update, --tolerance or --diff without --expect (or, when `suite`, --suite) as a
/// command-line error (CLI::RequiredError, CLI11's code), and view names after --update
/// without --suite; checks that --diff and, with
/// --update, --expect can be written (std::invalid_argument).
void checkRenderCheckArgs(const RenderCheckArgs& args, bool suite = false);

/// A golden image as RGB (CV_8UC3), read and decoded through mapping/io/image_codec (libpng;
/// never prints). Throws InputError naming the file: missing ("no such golden image: render it
/// once with --update"), not a PNG, damaged. `size` given: also when the golden is of another
/// size ("the golden is 320x240, the view 160x120 (--size, or --update)").
cv::Mat readGolden(const std::string& file, std::optional<cv::Size> size = std::nullopt);

/// Throws InputError when a golden of size `golden` cannot be compared with a view of size `view`.
void checkGoldenSize(const std::string& file, cv::Size golden, cv::Size view);

/// What checking one render against its golden gave.
struct CheckResult {
  bool updated = false;  ///< --update wrote the golden
  render::ImageComparison comparison;
};

/// Compares `rgb` with `golden` (or, with `update`, writes `rgb` to `golden_file` atomically).
/// When it differs beyond the tolerance and `diff_file` is not empty, writes the diff image
/// there. Never throws ExitWith: the caller decides.
CheckResult checkRender(const cv::Mat& rgb, const cv::Mat& golden, const std::string& golden_file,
                        const render::ImageTolerance& tolerance, bool update, const std::string& diff_file);

/// The single-image form: reads the golden (checked early by the caller with readGolden), checks
/// `rgb`, prints one line on stdout when it matches or was written, and throws
/// ExitWith(2, "GOLDEN: SUMMARY[; diff: D.png]") when it differs.
/// Before that, marks the stage "check" in `times` and prints them. Does nothing but that
/// without --expect.
class StageTimes;
void finishRenderCheck(const RenderCheckArgs& args, const cv::Mat& golden, const cv::Mat& rgb, StageTimes* times);

/// Stage times for --timings: mark(stage) records the wall time since the previous mark (or the
/// start); print() writes one note line on stderr, "vdmap VERB: note: timings: load 0.412 s, ...,
/// total 1.203 s". Does nothing when off.
class StageTimes {
 public:
  explicit StageTimes(bool on) : on_(on) {}
  void mark(const std::string& stage);
  void print(const std::string& verb) const;
  const std::vector<std::pair<std::string, double>>& stages() const { return stages_; }

 private:
  bool on_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_ = start_;
  std::vector<std::pair<std::string, double>> stages_;
};

}  // namespace vdmap::app
