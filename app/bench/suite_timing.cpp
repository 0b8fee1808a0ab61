#include "app/bench/suite_timing.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>
#include <unistd.h>

#include "app/view/render_suite.h"
#include "mapping/core/timing.h"
#include "mapping/files/session_file.h"
#include "mapping/io/json_text.h"

namespace vdmap::app {
namespace {

namespace fs = std::filesystem;

// The medians of each stage over `runs`, as a line of text (after `what`) and as JSON.
nlohmann::json stages(const char* what, const std::vector<SuiteResult>& runs, std::ostringstream* text) {
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
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "%-8s validate %.3f s (of which load %.3f s)  context %.3f s  build %.3f s  per view: render %.3f s, "
                "check %.3f s  total %.3f s  (medians of %zu runs)\n",
                what, median(validate), median(load), median(context), median(build), median(render), median(check),
                median(total), runs.size());
  *text << buf;
  return {{"validate_s", rounded(median(validate))},
          {"load_s", rounded(median(load))},
          {"context_s", rounded(median(context))},
          {"build_s", rounded(median(build))},
          {"render_s_per_view", rounded(median(render))},
          {"check_s_per_view", rounded(median(check))},
          {"total_s", rounded(median(total))},
          {"runs", runs.size()}};
}

// The session's load, decoding every keyframe's images (the workbench) and not (render), medians
// of `runs`; returns the keyframes.
std::size_t timeSessionLoad(const fs::path& session, int runs, nlohmann::json* out, std::ostringstream* text) {
  std::vector<double> eager, lazy;
  std::size_t keyframes = 0;
  for (int i = 0; i < runs; ++i) {
    auto t0 = std::chrono::steady_clock::now();
    loadSession(session);
    eager.push_back(secondsSince(t0));
    t0 = std::chrono::steady_clock::now();
    keyframes = loadSession(session, {.decode_images = false}).graph.size();
    lazy.push_back(secondsSince(t0));
  }
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "load     %.3f s decoding every keyframe image (the workbench), %.3f s without (render; medians of "
                "%d)\n",
                median(eager), median(lazy), runs);
  *text << buf;
  (*out)["session_load"] = {{"decoded_s", rounded(median(eager))}, {"lazy_s", rounded(median(lazy))}};
  return keyframes;
}

// A suite of 20 views of `session` in `dir`/views.yaml: 8 global views orbiting the map, 6
// keyframe views and 6 containers, keyframes spread over the session.
fs::path writeSessionSuite(const fs::path& session, std::size_t keyframes, const fs::path& dir,
                           std::ostringstream* text) {
  constexpr int kGlobals = 8, kKeyframeViews = 6, kContainers = 6;
  std::ofstream yaml(dir / "views.yaml");
  yaml << "version: 1\ngoldens: goldens\nout: out\nmaps: {s: '" << session.string() << "'}\nviews:\n";
  for (int i = 0; i < kGlobals; ++i)
    yaml << "  - {name: orbit" << i << ", map: s, orbit: \"" << -60 + 360 * i / kGlobals << ",35\"}\n";
  for (int i = 0; i < kKeyframeViews; ++i)
    yaml << "  - {name: kf" << i << ", map: s, view: \"keyframe:" << i * keyframes / kKeyframeViews << "\"}\n";
  for (int i = 0; i < kContainers; ++i)
    yaml << "  - {name: c" << i << ", map: s, view: \"container:" << (2 * i + 1) * keyframes / (2 * kContainers)
         << "\"}\n";
  char buf[512];
  std::snprintf(buf, sizeof buf, "session  %s: %zu keyframes; %d views (%d global, %d keyframe, %d container)\n",
                session.c_str(), keyframes, kGlobals + kKeyframeViews + kContainers, kGlobals, kKeyframeViews,
                kContainers);
  *text << buf;
  return dir / "views.yaml";
}

// Removes the session suite's temporary folder however the run ends.
struct RemovedAtExit {
  fs::path dir;
  ~RemovedAtExit() {
    std::error_code ec;
    if (!dir.empty()) fs::remove_all(dir, ec);
  }
};

}  // namespace

void runSuiteBench(const std::string& file, int runs, bool json) {
  std::ostringstream text;  // printed unless --json
  nlohmann::json out = {{"file", file}};
  fs::path suite = file;
  RemovedAtExit temporary;
  if (isSessionPath(file)) {
    const std::size_t keyframes = timeSessionLoad(file, runs, &out, &text);
    temporary.dir = fs::temp_directory_path() / ("vdmap-bench-suite-" + std::to_string(::getpid()));
    fs::create_directories(temporary.dir);
    suite = writeSessionSuite(fs::absolute(file), keyframes, temporary.dir, &text);
    out["update"] = stages("update", {runSuite(suite, {.update = true, .tolerance = {}, .table = false})}, &text);
  }
  std::vector<SuiteResult> compares;
  for (int i = 0; i < runs; ++i)
    compares.push_back(runSuite(suite, {.tolerance = {}, .table = false, .require_goldens = true}));
  out["compare"] = stages("compare", compares, &text);
  const SuiteResult& last = compares.back();
  out["views"] = last.views.size();
  out["differ"] = last.failed();
  out["maps_loaded"] = last.maps_loaded;
  out["global_maps_built"] = last.global_maps_built;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "counts   %zu views, %d differ from their goldens; maps loaded %d, global maps built %d per run\n",
                last.views.size(), last.failed(), last.maps_loaded, last.global_maps_built);
  text << buf;
  if (json) std::cout << jsonText({{"suite", out}}) << "\n";
  else std::fputs(text.str().c_str(), stdout);
}

}  // namespace vdmap::app
