// compare_images EXPECTED.png ACTUAL.png [--counts C] [--share S] [--compare plain|nearby] [--diff DIFF.png]: the
// comparison of render/image_compare.h from the shell, for scripts/render-driver-spread (the
// same metric as the golden tests). Prints ImageComparison::summary(); exits 0 when the images
// match, 2 when they differ, 1 on bad input.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>

#include <fstream>
#include <iterator>

#include "mapping/io/image_codec.h"
#include "render/framebuffer.h"
#include "render/image_compare.h"

namespace {

cv::Mat readRgb(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error(file + ": cannot read the image");
  return vdmap::decodeColorImage(std::string{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()},
                                 file);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string files[2], diff;
    int nfiles = 0;
    vdmap::render::ImageTolerance tolerance;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (i + 1 < argc && arg == "--counts") tolerance.channel_counts = std::stoi(argv[++i]);
      else if (i + 1 < argc && arg == "--share") tolerance.pixel_share = std::stod(argv[++i]);
      else if (i + 1 < argc && arg == "--diff") diff = argv[++i];
      else if (i + 1 < argc && arg == "--compare") tolerance.method = vdmap::render::parseCompareMethod(argv[++i]);
      else if (nfiles < 2 && arg.rfind("--", 0) != 0) files[nfiles++] = arg;
      else throw std::runtime_error("unexpected argument '" + arg + "'");
    }
    if (nfiles != 2)
      throw std::runtime_error(
          "usage: compare_images EXPECTED ACTUAL [--counts C] [--share S] [--compare M] [--diff D]");
    const cv::Mat expected = readRgb(files[0]), actual = readRgb(files[1]);
    const vdmap::render::ImageComparison c = vdmap::render::compareImages(expected, actual, tolerance);
    std::printf("%s\n", c.summary().c_str());
    if (!diff.empty()) vdmap::render::writePng(diff, vdmap::render::diffImage(expected, actual, tolerance));
    return c.matches ? 0 : 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "compare_images: %s\n", e.what());
    return 1;
  }
}
