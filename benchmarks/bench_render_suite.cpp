// bench_render_suite SESSION.vdmap [VIEWS [RUNS]]: the speed of `vdmap render --suite` on one
// session. Writes a suite of VIEWS views (default 20: 8 global views orbiting the map, 6 keyframe
// views and 6 containers, keyframes spread over the session, default sizes) into a temporary
// folder, runs it once with --update (writing the goldens), then RUNS times (default 3) comparing,
// in this process, and prints the medians of each stage and of the total. The first run pays the
// offscreen context (printed on its own); a `vdmap render --suite` process pays it once too.
// Not a test: no figure is asserted (docs/performance.md "Rendering" quotes it).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "app/view/render_suite.h"
#include "mapping/core/timing.h"
#include "mapping/files/session_file.h"

namespace {

namespace fs = std::filesystem;
using vdmap::median;

void printStages(const char* what, const std::vector<vdmap::app::SuiteResult>& runs) {
  std::vector<double> validate, load, context, build, render, check, total;
  for (const auto& r : runs) {
    validate.push_back(r.validate_s);
    load.push_back(r.load_s);
    context.push_back(r.context_s);
    double b = 0;
    std::vector<double> rs, cs;
    for (const auto& v : r.views) {
      b += v.build_s;
      rs.push_back(v.render_s);
      cs.push_back(v.check_s);
    }
    build.push_back(b);
    render.push_back(median(rs));
    check.push_back(median(cs));
    total.push_back(r.total_s);
  }
  std::printf("%-8s validate %.3f s (of which load %.3f s)  context %.3f s  build %.3f s  per view: render %.3f s, "
              "check %.3f s  total %.3f s  (medians of %zu runs)\n",
              what, median(validate), median(load), median(context), median(build), median(render), median(check),
              median(total), runs.size());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_render_suite SESSION.vdmap [VIEWS=20 [RUNS=3]]\n");
    return 1;
  }
  const fs::path session = fs::absolute(argv[1]);
  const int views = argc > 2 ? std::max(3, std::atoi(argv[2])) : 20;
  const int runs = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
  try {
    // What the lazy images save: loading with and without decoding every keyframe's images.
    std::vector<double> eager, lazy;
    std::size_t keyframes = 0;
    for (int i = 0; i < runs; ++i) {
      auto t0 = std::chrono::steady_clock::now();
      vdmap::loadSession(session);
      eager.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      t0 = std::chrono::steady_clock::now();
      keyframes = vdmap::loadSession(session, {.decode_images = false}).graph.size();
      lazy.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::printf("load     %.3f s decoding every keyframe image (the workbench), %.3f s without (render; medians of %d)\n",
                median(eager), median(lazy), runs);
    const fs::path dir = fs::temp_directory_path() / ("bench_render_suite-" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const int globals = views * 8 / 20, keyframe_views = (views - globals) / 2, containers = views - globals - keyframe_views;
    std::ofstream yaml(dir / "views.yaml");
    yaml << "version: 1\ngoldens: goldens\nout: out\nmaps: {s: '" << session.string() << "'}\nviews:\n";
    for (int i = 0; i < globals; ++i)
      yaml << "  - {name: orbit" << i << ", map: s, orbit: \"" << -60 + 360 * i / globals << ",35\"}\n";
    for (int i = 0; i < keyframe_views; ++i)
      yaml << "  - {name: kf" << i << ", map: s, view: \"keyframe:" << i * keyframes / keyframe_views << "\"}\n";
    for (int i = 0; i < containers; ++i)
      yaml << "  - {name: c" << i << ", map: s, view: \"container:" << (2 * i + 1) * keyframes / (2 * containers) << "\"}\n";
    yaml.close();
    std::printf("session  %s: %zu keyframes; %d views (%d global, %d keyframe, %d container)\n", session.c_str(), keyframes,
                views, globals, keyframe_views, containers);
    const auto update = vdmap::app::runSuite(dir / "views.yaml", {.update = true, .tolerance = {}, .table = false});
    printStages("update", {update});
    std::vector<vdmap::app::SuiteResult> compares;
    for (int i = 0; i < runs; ++i) {
      compares.push_back(vdmap::app::runSuite(dir / "views.yaml", {.tolerance = {}, .table = false}));
      if (compares.back().failed() > 0) std::printf("warning: %d views differ from the goldens just written\n", compares.back().failed());
    }
    printStages("compare", compares);
    std::printf("counts   maps loaded %d, global maps built %d per run\n", compares.back().maps_loaded,
                compares.back().global_maps_built);
    fs::remove_all(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_render_suite: %s\n", e.what());
    return 1;
  }
  return 0;
}
