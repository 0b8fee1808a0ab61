// `vdmap render --expect`: reading goldens, comparing, --update and the diff image.
#include "app/view/render_check.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>

#include "app/cli/command_line.h"
#include "mapping/core/error.h"
#include "mapping/io/image_codec.h"
#include "render/framebuffer.h"

namespace vdmap::app {

render::ImageTolerance defaultTolerance(render::CompareMethod method) {
  return method == render::CompareMethod::kNearby ? kSuiteTolerance : kGoldenTolerance;
}

double parseShare(const std::string& text) {
  std::smatch m;
  static const std::regex pattern(R"(\s*([0-9]*\.?[0-9]+)\s*(%?)\s*)");
  if (!std::regex_match(text, m, pattern))
    throw std::invalid_argument("'" + text + "': expected a share, e.g. 0.025 or 2.5%");
  const double share = std::stod(m[1]) / (m[2].length() > 0 ? 100.0 : 1.0);
  if (!(share >= 0.0 && share <= 1.0))
    throw std::invalid_argument("'" + text + "': a share must be in 0..1 (or 0%..100%)");
  return share;
}

render::ImageTolerance parseTolerance(const std::string& text) {
  std::smatch m;
  static const std::regex pattern(R"((\d{1,3}),([0-9]*\.?[0-9]+%?))");
  if (!std::regex_match(text, m, pattern))
    throw std::invalid_argument("'" + text + "': expected COUNTS,SHARE, e.g. 8,0.025 or 8,2.5%");
  const int counts = std::stoi(m[1]);
  if (counts > 255) throw std::invalid_argument("'" + text + "': COUNTS must be in 0..255");
  try {
    return {.channel_counts = counts, .pixel_share = parseShare(m[2])};
  } catch (const std::invalid_argument&) {
    throw std::invalid_argument("'" + text + "': SHARE must be in 0..1 (or 0%..100%)");
  }
}

void addRenderCheckArgs(CLI::App& verb, RenderCheckArgs& args) {
  verb.add_option("--expect", args.expect,
                  "compare the render with this golden PNG: exit 0 within --tolerance, 2 beyond it (--out "
                  "becomes optional)");
  verb.add_option("--tolerance", args.tolerance,
                  "COUNTS,SHARE: a pixel differs when a channel is off by more than COUNTS; at most SHARE of "
                  "the pixels may (a fraction or a percentage; default 8,2.5%)")
      ->check(parsedBy(parseTolerance, "COUNTS,SHARE"));
  verb.add_option("--compare", args.compare,
                  "plain: every pixel against the same pixel (--expect's default); nearby: a pixel differs only when "
                  "nothing within 1 px matches it and its neighbours differ too, so another driver passes and a real "
                  "change fails (--suite's default, tolerance 8,0.01%)")
      ->check(parsedBy(render::parseCompareMethod, "plain|nearby"));
  verb.add_option("--diff", args.diff, "with --expect: where a differing render's diff image goes (a .png file)")
      ->check(CLI::Validator(
          [](std::string& file) {
            std::string ext = std::filesystem::path(file).extension().string();
            for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            return ext == ".png" ? std::string() : "'" + file + "': the diff image is a PNG: name it .png";
          },
          "FILE.png"));
  verb.add_option_function<std::vector<std::string>>(
          "--update",
          [&args](const std::vector<std::string>& views) {
            args.update = true;
            for (const std::string& view : views)
              if (!view.empty()) args.update_views.push_back(view);  // a bare --update gives one empty value
          },
          "with --expect: write the render as the golden (atomically) and exit 0; with --suite: write every "
          "view's golden, or only those of the views named (--update VIEW...)")
      ->expected(0, CLI::detail::expected_max_vector_size);
  verb.add_option("--suite", args.suite,
                  "render every view of this YAML file (maps loaded once), compare each with its golden; a table, "
                  "JUnit XML and the failing views' images in its out folder; exit 2 when any differs");
  verb.add_flag("--timings", args.timings, "print how long each stage took (load, build, render, check) on stderr");
}

render::ImageTolerance tolerance(const RenderCheckArgs& args) {
  const render::CompareMethod method =
      args.compare.empty() ? render::CompareMethod::kPlain : render::parseCompareMethod(args.compare);
  render::ImageTolerance t = args.tolerance.empty() ? defaultTolerance(method) : parseTolerance(args.tolerance);
  t.method = method;
  return t;
}

void checkRenderCheckArgs(const RenderCheckArgs& args, bool suite) {
  if (args.expect.empty() && !suite) {
    const char* alone = args.update               ? "--update"
                        : !args.tolerance.empty() ? "--tolerance"
                        : !args.compare.empty()   ? "--compare"
                        : !args.diff.empty()      ? "--diff"
                                                  : nullptr;
    if (alone)
      throw CLI::RequiredError(std::string(alone) + " needs --expect GOLDEN.png (or --suite)",
                               CLI::ExitCodes::RequiredError);
  }
  if (!suite && !args.update_views.empty())
    throw CLI::ValidationError(
        "--update", "view names ('" + args.update_views.front() + "') need --suite; give SEQ before --update");
  if (!args.diff.empty()) checkOutputFile(args.diff, "--diff");
  if (args.update && !args.expect.empty()) checkOutputFile(args.expect, "--expect");
}

namespace {

std::string sizeText(cv::Size s) { return std::to_string(s.width) + "x" + std::to_string(s.height); }

// The size a PNG's header (IHDR, the first chunk) gives, or nullopt when it is not a PNG.
std::optional<cv::Size> pngSize(const std::string& bytes) {
  static const char kMagic[] = "\x89PNG\r\n\x1a\nxxxxIHDR";
  if (bytes.size() < 24 || bytes.compare(0, 8, kMagic, 8) != 0 || bytes.compare(12, 4, "IHDR") != 0)
    return std::nullopt;
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    for (std::size_t i = 0; i < 4; ++i) v = v << 8 | static_cast<std::uint8_t>(bytes[at + i]);
    return v;
  };
  const std::uint32_t w = u32(16), h = u32(20);
  if (w == 0 || h == 0 || w > 1u << 20 || h > 1u << 20) return std::nullopt;
  return cv::Size(static_cast<int>(w), static_cast<int>(h));
}

}  // namespace

void checkGoldenSize(const std::string& file, cv::Size golden, cv::Size view) {
  if (golden != view)
    throw InputError(file,
                     "the golden is " + sizeText(golden) + ", the view " + sizeText(view) + " (--size, or --update)");
}

cv::Mat readGolden(const std::string& file, std::optional<cv::Size> size) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw InputError(file, "no such golden image (render it once with --update)");
  if (std::filesystem::is_directory(file, ec)) throw InputError(file, "is a folder, not a golden PNG");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "cannot open the golden image");
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::optional<cv::Size> found = pngSize(bytes);
  if (!found) throw InputError(file, "not a PNG image (a golden is a PNG; make one with --update)");
  if (size) checkGoldenSize(file, *found, *size);
  return decodeColorImage(bytes, *found, file);  // damaged or truncated: "FILE: cannot decode colour image: ..."
}

CheckResult checkRender(const cv::Mat& rgb, const cv::Mat& golden, const std::string& golden_file,
                        const render::ImageTolerance& tolerance, bool update, const std::string& diff_file) {
  CheckResult result;
  if (update) {
    render::writePng(golden_file, rgb);  // atomic: temporary file and rename
    result.updated = true;
    return result;
  }
  result.comparison = render::compareImages(golden, rgb, tolerance);
  if (!result.comparison.matches && !diff_file.empty())
    render::writePng(diff_file, render::diffImage(golden, rgb, tolerance));
  return result;
}

void finishRenderCheck(const RenderCheckArgs& args, const cv::Mat& golden, const cv::Mat& rgb, StageTimes* times) {
  if (args.expect.empty()) {
    times->print("render");
    return;
  }
  const CheckResult r = checkRender(rgb, golden, args.expect, tolerance(args), args.update, args.diff);
  times->mark("check");
  times->print("render");
  if (r.updated) {
    std::printf("golden       %s written (%dx%d)\n", args.expect.c_str(), rgb.cols, rgb.rows);
    return;
  }
  if (!r.comparison.matches)
    throw ExitWith(2, args.expect + ": " + r.comparison.summary() + (args.diff.empty() ? "" : "; diff: " + args.diff));
  std::printf("golden       %s matches: %s\n", args.expect.c_str(), r.comparison.summary().c_str());
}

void StageTimes::mark(const std::string& stage) {
  if (!on_) return;
  const auto now = std::chrono::steady_clock::now();
  stages_.emplace_back(stage, std::chrono::duration<double>(now - last_).count());
  last_ = now;
}

void StageTimes::print(const std::string& verb) const {
  if (!on_) return;
  std::string line;
  char buffer[64];
  for (const auto& [stage, seconds] : stages_) {
    std::snprintf(buffer, sizeof buffer, "%.3f s", seconds);
    line += stage + " " + buffer + ", ";
  }
  std::snprintf(buffer, sizeof buffer, "%.3f s", std::chrono::duration<double>(last_ - start_).count());
  std::fprintf(stderr, "vdmap %s: note: timings: %stotal %s\n", verb.c_str(), line.c_str(), buffer);
}

}  // namespace vdmap::app
