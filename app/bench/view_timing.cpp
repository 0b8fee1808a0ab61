#include "app/bench/view_timing.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "app/view/render_source.h"
#include "app/view/render_view.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"
#include "render/framebuffer.h"
#include "render/legend.h"
#include "render/lod_order.h"
#include "render/map_mirror.h"
#include "render/map_scene.h"
#include "render/view_cache.h"
#include "render/view_draw.h"
#include "render/view_framing.h"

namespace vdmap::app {
namespace {

using Clock = std::chrono::steady_clock;

// `replicate` copies of `original` side by side along x, each offset by 1.05 x its extent.
std::vector<Ellipsoid> replicated(const std::vector<Ellipsoid>& original, int replicate) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e30), hi = -lo;
  for (const Ellipsoid& e : original) lo = lo.cwiseMin(e.mean), hi = hi.cwiseMax(e.mean);
  const double step_x = 1.05 * (hi.x() - lo.x());
  std::vector<Ellipsoid> map;
  map.reserve(original.size() * static_cast<std::size_t>(replicate));
  for (int r = 0; r < replicate; ++r)
    for (Ellipsoid e : original) {
      e.mean.x() += r * step_x;
      map.push_back(e);
    }
  return map;
}

// The map drawn offscreen along an orbit around it, 0.03 rad per step, and one timed frame.
struct OrbitFrames {
  const render::Gl& gl;
  render::MapMirror& mirror;
  render::ViewSpec& spec;
  const render::ViewScene& scene;
  render::Framebuffer& fb;
  int width, height;
  float zoom, framed_m;
  double last_cpu_ms = 0;  ///< the last frame's process CPU time (all of llvmpipe's threads)

  render::FramedView cameraAt(int s) {
    spec.orbit = render::Orbit{-60.f + glm::degrees(0.03f) * static_cast<float>(s), 35.f,
                               zoom == 1.f ? std::nullopt : std::optional<float>(zoom * framed_m)};
    return render::viewCamera(spec, scene, width, height);
  }

  // Step s drawn into fb (through `cache` when given): wall ms; its CPU time, less sensitive to
  // other load, into last_cpu_ms.
  double timed(int s, render::ViewCache* cache) {
    const render::FramedView view = cameraAt(s);
    const render::PixelRect viewport{0, 0, width, height};
    fb.bindAndClear(spec.background.r, spec.background.g, spec.background.b);
    gl.Finish();
    const auto start = Clock::now();
    last_cpu_ms = cpuTimeMs([&] {
      if (cache) cache->draw(mirror, view, spec.background, viewport, true, true);
      else render::drawMapView(gl, mirror, view, spec.background, viewport, true, true);
      gl.Finish();
    });
    return msSince(start);
  }
};

// Full quality: every step re-selects the mesh instances (the view changed).
void timeFullFrames(OrbitFrames& frames, const ViewTimingOptions& options, const DrawTimingOptions& draw,
                    std::ostringstream& text, nlohmann::json& out) {
  char buf[512];
  std::vector<double> ms, cpu, select_ms, mesh, points;
  for (int s = 0; s < options.steps; ++s) {
    const double frame_ms = frames.timed(s, nullptr);
    if (s == 0) continue;  // the first pays shader compilation and the first upload
    ms.push_back(frame_ms);
    cpu.push_back(frames.last_cpu_ms);
    const auto& d = frames.mirror.ellipsoidRenderer().lastDraw();
    select_ms.push_back(d.select_ms);
    mesh.push_back(static_cast<double>(d.mesh_instances));
    points.push_back(static_cast<double>(d.point_instances));
  }
  if (!draw.png.empty()) render::writePng(draw.png + "_full.png", frames.fb.readRgb());
  std::snprintf(buf, sizeof buf,
                "  full:  %.1f ms/frame (CPU %.1f ms; mesh selection %.1f ms), %.0f mesh + %.0f splat instances\n",
                median(ms), median(cpu), median(select_ms), median(mesh), median(points));
  text << buf;
  out["full"] = {{"ms", rounded(median(ms))},
                 {"cpu_ms", rounded(median(cpu))},
                 {"select_ms", rounded(median(select_ms))},
                 {"mesh_instances", median(mesh)},
                 {"splat_instances", median(points)}};
}

// The fast pass at each budget.
void timeFastFrames(OrbitFrames& frames, const ViewTimingOptions& options, const DrawTimingOptions& draw,
                    std::ostringstream& text, nlohmann::json& out) {
  char buf[512];
  out["fast"] = nlohmann::json::array();
  const std::vector<std::size_t> budgets =
      options.fast_budgets.empty() ? std::vector<std::size_t>{50000, 100000, 200000, 400000} : options.fast_budgets;
  for (const std::size_t k : budgets) {
    frames.mirror.setFastBudget(k);
    std::vector<double> ms, cpu;
    for (int s = 0; s < options.steps; ++s) {
      const double frame_ms = frames.timed(s, nullptr);
      if (s > 0) ms.push_back(frame_ms), cpu.push_back(frames.last_cpu_ms);
    }
    if (!draw.png.empty()) render::writePng(draw.png + "_fast_" + std::to_string(k) + ".png", frames.fb.readRgb());
    const std::size_t drawn = frames.mirror.ellipsoidRenderer().lastDraw().point_instances;
    std::snprintf(buf, sizeof buf, "  fast:  %.1f ms/frame (CPU %.1f ms), %zu point instances (budget %zu)\n",
                  median(ms), median(cpu), drawn, k);
    text << buf;
    out["fast"].push_back(
        {{"budget", k}, {"ms", rounded(median(ms))}, {"cpu_ms", rounded(median(cpu))}, {"point_instances", drawn}});
  }
  frames.mirror.setFastBudget(0);
}

// Settled: the camera stopped; the cache draws the full frame once, then only copies it.
void timeSettledFrames(OrbitFrames& frames, const ViewTimingOptions& options, std::ostringstream& text,
                       nlohmann::json& out) {
  char buf[512];
  render::ViewCache cache(frames.gl);
  std::vector<double> settle, blit;
  for (int s = 0; s < std::min(options.steps, 6); ++s) {
    const double frame_ms = frames.timed(s, &cache);
    if (s > 0) settle.push_back(frame_ms);
    for (int b = 0; b < 3; ++b) blit.push_back(frames.timed(s, &cache));
  }
  std::snprintf(buf, sizeof buf,
                "  settle (full frame into the cache): %.1f ms; cached frame (blit only): %.2f ms (%d redraws, %d "
                "blits)\n",
                median(settle), median(blit), cache.redraws(), cache.blits());
  text << buf;
  out["settle_ms"] = rounded(median(settle));
  out["cached_ms"] = rounded(median(blit));
  out["redraws"] = cache.redraws();
  out["blits"] = cache.blits();
}

}  // namespace

void runViewBench(const std::string& map_path, const ViewTimingOptions& options, const DrawTimingOptions& draw,
                  bool json) {
  const auto [width, height] = parseViewSize(draw.size.empty() ? "752x870" : draw.size);
  RenderSource source({}, map_path, "");
  const ResolvedView resolved = resolveViewSpec({}, source.sessionThresholds());
  render::ViewSpec spec = resolved.spec;
  if (draw.points_below) spec.points_below_px = *draw.points_below;
  const std::vector<Ellipsoid> map = replicated(source.globalMap(resolved.thresholds), options.replicate);
  const render::Gl& gl = sharedOffscreenGl();
  render::MapMirror mirror(gl);
  mirror.setStyle(render::mirrorStyle(spec));
  // The level-of-detail order is the mapping worker's (computed with the map); the rest of the
  // upload is on the UI thread.
  auto t0 = Clock::now();
  const std::vector<std::uint32_t> order = render::lodOrder(map);
  const double lod_ms = msSince(t0);
  t0 = Clock::now();
  mirror.setMap(1, map, order);
  const double upload_ms = msSince(t0);
  render::GraphScene graph;
  if (source.graph()) graph = render::graphSceneOf(*source.graph(), MapperState{}, PinholeCamera{}, false);
  mirror.setGraph(1, -1, [&] { return graph; });
  mirror.setLegend(render::legendFor(spec.color, mirror.mapColorRange(), graph, true, true, true), spec.background,
                   width);
  std::vector<glm::vec3> means;
  for (const Ellipsoid& e : map) means.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
  render::ViewScene scene;
  scene.bounds = render::frameBounds(means, graph);
  scene.up = source.up(spec.up, resolved.thresholds);
  render::Framebuffer fb(gl, width, height);
  spec.orbit = render::Orbit{};
  const float framed_m = render::orbitCamera(spec, scene, width, height).distance_m;
  OrbitFrames frames{gl, mirror, spec, scene, fb, width, height, options.zoom, framed_m};
  double load[3] = {0, 0, 0};
  getloadavg(load, 3);
  std::ostringstream text;  // printed unless --json
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "view bench %s x%d: %zu ellipsoids, %dx%d, %d orbit steps at %.2f x the framed distance, load "
                "average %.2f %.2f %.2f\n",
                map_path.c_str(), options.replicate, map.size(), width, height, options.steps, options.zoom, load[0],
                load[1], load[2]);
  text << buf;
  std::snprintf(buf, sizeof buf,
                "  map upload on the UI thread (geometry, colours): %.0f ms; the LOD order of %zu (worker): %.0f ms\n",
                upload_ms, order.size(), lod_ms);
  text << buf;
  nlohmann::json out = {{"map", map_path},
                        {"replicate", options.replicate},
                        {"ellipsoids", map.size()},
                        {"width", width},
                        {"height", height},
                        {"steps", options.steps},
                        {"zoom", options.zoom},
                        {"load_average", {rounded(load[0], 3), rounded(load[1], 3), rounded(load[2], 3)}},
                        {"upload_ms", rounded(upload_ms)},
                        {"lod_order_ms", rounded(lod_ms)}};
  timeFullFrames(frames, options, draw, text, out);
  timeFastFrames(frames, options, draw, text, out);
  timeSettledFrames(frames, options, text, out);
  if (json) std::cout << jsonText({{"view", out}}) << "\n";
  else std::fputs(text.str().c_str(), stdout);
}

}  // namespace vdmap::app
