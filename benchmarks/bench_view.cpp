// bench_view MAP [--replicate N] [--size WxH] [--steps S] [--fast-budget K]: the 3-D view's frame
// times on a saved session or map (anything `vdmap render --map` opens), in the offscreen
// (OSMesa) context: S orbit steps (default 20, 0.03 rad apart as the window's --measure-orbit)
// drawn at full quality and with the fast pass (the LOD prefix of K ellipsoids; default a sweep),
// the settle frame (the full frame after the camera stops), and a frame the view image cache
// only copies. --replicate N places N copies of the map side by side (offset by its extent along
// x) to reach paper-scale maps. The default size is the 3-D viewport of a 1600x900 window.
// Prints medians (glFinish-timed) and instances per frame. Not a test: no figure is asserted
// (docs/performance.md "Workbench" quotes it).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "app/view/render_source.h"
#include "app/view/render_view.h"
#include "mapping/core/timing.h"
#include "render/framebuffer.h"
#include "render/legend.h"
#include "render/map_mirror.h"
#include "render/lod_order.h"
#include "render/map_scene.h"
#include "render/view_cache.h"
#include "render/view_draw.h"
#include "render/view_framing.h"

namespace {

using namespace vdmap;
using Clock = std::chrono::steady_clock;

// The process's CPU time (all of llvmpipe's threads), ms: less sensitive to other load than the wall clock.
double cpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  std::string map_path;
  int replicate = 1, steps = 20, width = 752, height = 870;
  std::vector<std::size_t> budgets;
  float points_below = -1.f;
  float zoom = 1.f;  // --zoom F: the orbit's distance is F times the framed one (F < 1: inside the map)
  std::string png;  // --png PREFIX: PREFIX_full.png and PREFIX_fast_K.png of the last step, to look at
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--replicate" && i + 1 < argc) replicate = std::max(1, std::atoi(argv[++i]));
    else if (a == "--steps" && i + 1 < argc) steps = std::max(2, std::atoi(argv[++i]));
    else if (a == "--fast-budget" && i + 1 < argc) budgets.push_back(std::strtoull(argv[++i], nullptr, 10));
    else if (a == "--zoom" && i + 1 < argc) zoom = std::atof(argv[++i]);
    else if (a == "--png" && i + 1 < argc) png = argv[++i];
    else if (a == "--points-below" && i + 1 < argc) points_below = std::atof(argv[++i]);
    else if (a == "--size" && i + 1 < argc) std::tie(width, height) = app::parseViewSize(argv[++i]);
    else if (map_path.empty() && a[0] != '-') map_path = a;
    else {
      std::fprintf(stderr, "usage: bench_view MAP [--replicate N] [--size WxH] [--steps S] [--zoom F] [--fast-budget K]... [--png PREFIX]\n");
      return 1;
    }
  }
  if (map_path.empty()) {
    std::fprintf(stderr, "usage: bench_view MAP [--replicate N] [--size WxH] [--steps S] [--zoom F] [--fast-budget K]... [--png PREFIX]\n");
    return 1;
  }
  app::RenderSource source({}, map_path, "");
  const app::ResolvedView resolved = app::resolveViewSpec({}, source.sessionThresholds());
  render::ViewSpec spec = resolved.spec;
  if (points_below >= 0.f) spec.points_below_px = points_below;
  const std::vector<Ellipsoid>& original = source.globalMap(resolved.thresholds);
  std::vector<Ellipsoid> map;
  {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e30), hi = -lo;
    for (const Ellipsoid& e : original) lo = lo.cwiseMin(e.mean), hi = hi.cwiseMax(e.mean);
    const double step_x = 1.05 * (hi.x() - lo.x());
    map.reserve(original.size() * replicate);
    for (int r = 0; r < replicate; ++r)
      for (Ellipsoid e : original) {
        e.mean.x() += r * step_x;
        map.push_back(e);
      }
  }
  const render::Gl& gl = app::sharedOffscreenGl();
  render::MapMirror mirror(gl);
  mirror.setStyle(render::mirrorStyle(spec));
  auto t0 = Clock::now();
  mirror.setMap(1, map);
  const double upload_ms = msSince(t0);
  render::GraphScene graph;
  if (source.graph()) graph = render::graphSceneOf(*source.graph(), MapperState{}, PinholeCamera{}, false);
  mirror.setGraph(1, -1, [&] { return graph; });
  mirror.setLegend(render::legendFor(spec.color, mirror.mapColorRange(), graph, true, true, true), spec.background, width);
  std::vector<glm::vec3> means;
  for (const Ellipsoid& e : map) means.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
  t0 = Clock::now();
  const std::size_t ordered = render::lodOrder(means).size();
  const double lod_ms = msSince(t0);
  render::ViewScene scene;
  scene.bounds = render::frameBounds(means, graph);
  scene.up = source.up(spec.up, resolved.thresholds);
  render::Framebuffer fb(gl, width, height);
  const render::PixelRect viewport{0, 0, width, height};
  spec.orbit = render::Orbit{};
  const float framed_m = render::orbitCamera(spec, scene, width, height).distance_m;
  auto cameraAt = [&](int s) {
    spec.orbit = render::Orbit{-60.f + glm::degrees(0.03f) * static_cast<float>(s), 35.f,
                               zoom == 1.f ? std::nullopt : std::optional<float>(zoom * framed_m)};
    return render::viewCamera(spec, scene, width, height);
  };
  // One frame of step s drawn into fb (through `cache` when given), glFinish-timed, ms.
  double last_cpu_ms = 0;  // timedFrame's CPU time
  auto timedFrame = [&](int s, render::ViewCache* cache) {
    const render::FramedView view = cameraAt(s);
    fb.bindAndClear(spec.background.r, spec.background.g, spec.background.b);
    gl.Finish();
    const auto start = Clock::now();
    const double cpu0 = cpuMs();
    if (cache) cache->draw(mirror, view, spec.background, viewport, true, true);
    else render::drawMapView(gl, mirror, view, spec.background, viewport, true, true);
    gl.Finish();
    last_cpu_ms = cpuMs() - cpu0;
    return msSince(start);
  };
  double load[3] = {0, 0, 0};
  getloadavg(load, 3);
  std::printf("bench_view %s x%d: %zu ellipsoids, %dx%d, %d orbit steps at %.2f x the framed distance, load average "
              "%.2f %.2f %.2f\n",
              map_path.c_str(), replicate, map.size(), width, height, steps, zoom, load[0], load[1], load[2]);
  std::printf("  map upload (geometry, colours, LOD order): %.0f ms, of which the LOD order of %zu: %.0f ms\n", upload_ms,
              ordered, lod_ms);
  // Full quality: every step re-selects the mesh instances (the view changed).
  {
    std::vector<double> ms, cpu, select_ms, mesh, points;
    for (int s = 0; s < steps; ++s) {
      const double frame_ms = timedFrame(s, nullptr);
      if (s == 0) continue;  // the first pays shader compilation and the first upload
      ms.push_back(frame_ms);
      cpu.push_back(last_cpu_ms);
      const auto& d = mirror.ellipsoidRenderer().lastDraw();
      select_ms.push_back(d.select_ms);
      mesh.push_back(static_cast<double>(d.mesh_instances));
      points.push_back(static_cast<double>(d.point_instances));
    }
    if (!png.empty()) render::writePng(png + "_full.png", fb.readRgb());
    std::printf("  full:  %.1f ms/frame (CPU %.1f ms; mesh selection %.1f ms), %.0f mesh + %.0f splat instances\n",
                median(ms), median(cpu), median(select_ms), median(mesh), median(points));
  }
  if (budgets.empty()) budgets = {50000, 100000, 200000, 400000};
  for (const std::size_t k : budgets) {
    mirror.setFastBudget(k);
    std::vector<double> ms, cpu;
    for (int s = 0; s < steps; ++s) {
      const double frame_ms = timedFrame(s, nullptr);
      if (s > 0) ms.push_back(frame_ms), cpu.push_back(last_cpu_ms);
    }
    if (!png.empty()) render::writePng(png + "_fast_" + std::to_string(k) + ".png", fb.readRgb());
    std::printf("  fast:  %.1f ms/frame (CPU %.1f ms), %zu point instances (budget %zu)\n", median(ms), median(cpu),
                mirror.ellipsoidRenderer().lastDraw().point_instances, k);
  }
  mirror.setFastBudget(0);
  // Settle: the camera stopped; the cache draws the full frame once, then only copies it.
  {
    render::ViewCache cache(gl);
    std::vector<double> settle, blit;
    for (int s = 0; s < std::min(steps, 6); ++s) {
      const double frame_ms = timedFrame(s, &cache);
      if (s > 0) settle.push_back(frame_ms);
      for (int b = 0; b < 3; ++b) blit.push_back(timedFrame(s, &cache));
    }
    std::printf("  settle (full frame into the cache): %.1f ms; cached frame (blit only): %.2f ms (%d redraws, %d blits)\n",
                median(settle), median(blit), cache.redraws(), cache.blits());
  }
  return 0;
}
