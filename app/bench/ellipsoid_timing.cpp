#include "app/bench/ellipsoid_timing.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <random>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "app/view/render_view.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"
#include "render/context.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"

namespace vdmap::app {

void runEllipsoidBench(int count, std::optional<int> sphere_level, const DrawTimingOptions& draw, bool json) {
  const auto [w, h] = parseViewSize(draw.size.empty() ? "1280x720" : draw.size);
  render::EllipsoidStyle style;
  if (sphere_level) style.sphere_subdivisions = *sphere_level;
  if (draw.points_below) style.point_below_px = *draw.points_below;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-5.f, 5.f), size(0.005f, 0.04f), angle(0.f, 6.2832f);
  std::vector<render::EllipsoidInstance> set(static_cast<std::size_t>(count));
  for (auto& e : set) {
    e.mean = {pos(rng), pos(rng), pos(rng)};
    const glm::mat3 R = glm::mat3(
        glm::rotate(glm::mat4(1.f), angle(rng), glm::normalize(glm::vec3(pos(rng), pos(rng), pos(rng)) + 1e-3f)));
    const glm::vec3 s(size(rng), size(rng), size(rng) * 0.3f);
    e.cov = R * glm::mat3(s.x * s.x, 0, 0, 0, s.y * s.y, 0, 0, 0, s.z * s.z) * glm::transpose(R);
    e.rgb = {static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng())};
  }
  auto context = render::createOffscreenContext();
  const render::Gl& gl = context->gl();
  render::Framebuffer fb(gl, w, h);
  render::EllipsoidRenderer renderer(gl, style);
  auto t0 = std::chrono::steady_clock::now();
  renderer.set(set);
  gl.Finish();
  const double upload_ms = msSince(t0);
  std::vector<double> times;
  for (int i = 0; i < 5; ++i) {
    // The eye moves 1 mm per frame, as in an interactive view: an unchanged view would let the
    // renderer reuse its mesh-pass selection and time less than a real frame.
    const render::ViewCamera view =
        render::ViewCamera::lookAt({12.f + 0.001f * i, -9.f, 7.f}, {0.f, 0.f, 0.f}, {0, 0, 1}, 60.f, w, h);
    t0 = std::chrono::steady_clock::now();
    fb.bindAndClear(1.f, 1.f, 1.f);
    renderer.draw(view);
    gl.Finish();
    times.push_back(msSince(t0));
  }
  if (!draw.png.empty()) render::writePng(draw.png + ".png", fb.readRgb());
  const double min_ms = *std::min_element(times.begin(), times.end());
  if (json) {
    const nlohmann::json out = {{"ellipsoids",
                                 {{"renderer", context->description()},
                                  {"count", count},
                                  {"sphere_level", style.sphere_subdivisions},
                                  {"points_below_px", style.point_below_px},
                                  {"width", w},
                                  {"height", h},
                                  {"upload_ms", rounded(upload_ms)},
                                  {"frames", times.size()},
                                  {"frame_ms_median", rounded(median(times))},
                                  {"frame_ms_min", rounded(min_ms)}}}};
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::printf("renderer     %s\n", context->description().c_str());
  std::printf("ellipsoids   %d instanced, icosphere level %d, points below %.1f px, %dx%d\n", count,
              style.sphere_subdivisions, style.point_below_px, w, h);
  std::printf("upload       %.1f ms (eigen-decomposition + buffer upload)\n", upload_ms);
  std::printf("frame time   %.1f ms median of %zu frames (min %.1f ms)\n", median(times), times.size(), min_ms);
}

}  // namespace vdmap::app
