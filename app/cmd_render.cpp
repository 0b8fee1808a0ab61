// vdmap render: draws a map (and/or a mesh) headless with OSMesa into a PNG, or times the
// ellipsoid renderer (--bench-ellipsoids).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <random>
#include <regex>

#include <glm/gtc/matrix_transform.hpp>

#include "app/commands.h"
#include "mapping/io/ply_reader.h"
#include "render/colormap.h"
#include "render/container_renderer.h"
#include "render/context.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "render/mesh_renderer.h"

namespace vdmap::app {
namespace {

struct RenderArgs {
  std::string sequence, map, mesh, view = "global", out, size = "1280x720", color = "rgb";
  float sigma = 2.f;
  int bench_ellipsoids = 0;
  int sphere_subdivisions = 1;
};

std::pair<int, int> parseSize(const std::string& text) {
  std::smatch m;
  static const std::regex pattern(R"((\d{1,9})x(\d{1,9}))");
  if (!std::regex_match(text, m, pattern))
    throw std::invalid_argument("--size '" + text + "': expected WIDTHxHEIGHT, e.g. 1280x720");
  const int w = std::stoi(m[1]), h = std::stoi(m[2]);
  if (w < 1 || h < 1 || w > render::kMaxImageSide || h > render::kMaxImageSide)
    throw std::invalid_argument("--size '" + text + "': each side must be in 1.." + std::to_string(render::kMaxImageSide));
  return {w, h};
}

std::vector<render::EllipsoidInstance> toInstances(const std::vector<EllipsoidRecord>& records) {
  std::vector<render::EllipsoidInstance> out(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    const EllipsoidRecord& r = records[i];
    out[i].mean = {r.mean.x(), r.mean.y(), r.mean.z()};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) out[i].cov[c][k] = r.cov(k, c);
    out[i].rgb = {r.rgb[0], r.rgb[1], r.rgb[2]};
    out[i].keyframe = r.keyframe;
    out[i].count = r.count;
  }
  return out;
}

render::ColoredMesh toMesh(const ColoredTriangleMesh& m) {
  render::ColoredMesh out;
  for (const auto& p : m.positions) out.positions.emplace_back(p.x(), p.y(), p.z());
  for (const auto& c : m.colors) out.colors.emplace_back(c[0], c[1], c[2]);
  for (const auto& t : m.triangles) out.triangles.emplace_back(t[0], t[1], t[2]);
  return out;
}

// Bounds of the central 96% of the points, so a few stray ellipsoids do not shrink the view.
std::pair<glm::vec3, glm::vec3> robustBounds(const std::vector<glm::vec3>& points) {
  if (points.empty()) return {glm::vec3(-1.f), glm::vec3(1.f)};
  glm::vec3 lo, hi;
  for (int k = 0; k < 3; ++k) {
    std::vector<float> v;
    v.reserve(points.size());
    for (const auto& p : points) v.push_back(p[k]);
    std::sort(v.begin(), v.end());
    lo[k] = v[v.size() * 2 / 100];
    hi[k] = v[std::min(v.size() - 1, v.size() * 98 / 100)];
  }
  return {lo, hi};
}

void runBench(const RenderArgs& args) {
  const auto [w, h] = parseSize(args.size);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-5.f, 5.f), size(0.005f, 0.04f), angle(0.f, 6.2832f);
  std::vector<render::EllipsoidInstance> set(static_cast<std::size_t>(args.bench_ellipsoids));
  for (auto& e : set) {
    e.mean = {pos(rng), pos(rng), pos(rng)};
    const glm::mat3 R = glm::mat3(glm::rotate(glm::mat4(1.f), angle(rng), glm::normalize(glm::vec3(pos(rng), pos(rng), pos(rng)) + 1e-3f)));
    const glm::vec3 s(size(rng), size(rng), size(rng) * 0.3f);
    e.cov = R * glm::mat3(s.x * s.x, 0, 0, 0, s.y * s.y, 0, 0, 0, s.z * s.z) * glm::transpose(R);
    e.rgb = {static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng())};
  }
  auto context = render::createOffscreenContext();
  const render::Gl& gl = context->gl();
  render::Framebuffer fb(gl, w, h);
  render::EllipsoidRenderer renderer(gl, {.sigma = args.sigma, .sphere_subdivisions = args.sphere_subdivisions});
  auto t0 = std::chrono::steady_clock::now();
  renderer.set(set);
  gl.Finish();
  const double upload_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const render::ViewCamera view = render::ViewCamera::lookAt({12.f, -9.f, 7.f}, {0.f, 0.f, 0.f}, {0, 0, 1}, 60.f, w, h);
  std::vector<double> times;
  for (int i = 0; i < 4; ++i) {
    t0 = std::chrono::steady_clock::now();
    fb.bindAndClear(1.f, 1.f, 1.f);
    renderer.draw(view);
    gl.Finish();
    times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::sort(times.begin(), times.end());
  std::printf("renderer     %s\n", context->description().c_str());
  std::printf("ellipsoids   %d instanced, icosphere level %d, %dx%d\n", args.bench_ellipsoids, args.sphere_subdivisions, w, h);
  std::printf("upload       %.1f ms (eigen-decomposition + buffer upload)\n", upload_ms);
  std::printf("frame time   %.1f ms median of %zu frames (min %.1f ms)\n", times[times.size() / 2], times.size(), times[0]);
  if (!args.out.empty()) render::writePng(args.out, fb.readRgb());
}

void runRender(const RenderArgs& args) {
  if (args.bench_ellipsoids > 0) return runBench(args);
  if (args.out.empty()) throw std::invalid_argument("--out PNG is required");
  if (!args.sequence.empty() && args.map.empty())
    throw NotBuiltYet("'vdmap render SEQ' maps the sequence first and needs the mapper (issue #3); "
                      "render an exported map with --map FILE");
  if (args.map.empty() && args.mesh.empty()) throw std::invalid_argument("give --map FILE (ellipsoid PLY), --mesh PLY, or both");
  const auto [w, h] = parseSize(args.size);
  const render::ColorMode color = render::parseColorMode(args.color);
  std::vector<render::EllipsoidInstance> ellipsoids;
  if (!args.map.empty()) ellipsoids = toInstances(readPlyEllipsoids(args.map));
  ColoredTriangleMesh mesh;
  if (!args.mesh.empty()) mesh = readPlyMesh(args.mesh);

  std::smatch m;
  static const std::regex view_pattern(R"((global)|(keyframe|container):(\d+))");
  if (!std::regex_match(args.view, m, view_pattern))
    throw std::invalid_argument("--view '" + args.view + "': expected global, keyframe:K or container:K");
  if (m[2].matched) {
    // Keyframe poses and images come from a mapped sequence; until the mapper lands there is
    // no keyframe list to name K in.
    throw NotBuiltYet("--view " + args.view + " needs keyframes from the mapper (issue #3); use --view global");
  }
  auto context = render::createOffscreenContext();
  const render::Gl& gl = context->gl();
  render::Framebuffer fb(gl, w, h);
  std::vector<glm::vec3> points;
  for (const auto& e : ellipsoids) points.push_back(e.mean);
  for (const auto& p : mesh.positions) points.emplace_back(p.x(), p.y(), p.z());
  const auto [lo, hi] = robustBounds(points);
  const render::ViewCamera view = render::OrbitCamera::framing(lo, hi).view(w, h);
  fb.bindAndClear(1.f, 1.f, 1.f);
  if (!mesh.triangles.empty()) {
    render::MeshRenderer mesh_renderer(gl);
    mesh_renderer.set(toMesh(mesh));
    mesh_renderer.draw(view);
  }
  if (!ellipsoids.empty()) {
    render::EllipsoidRenderer renderer(gl, {.sigma = args.sigma, .color = color});
    renderer.set(ellipsoids);
    renderer.draw(view);
  }
  render::writePng(args.out, fb.readRgb());
  std::printf("wrote %s (%dx%d, %zu ellipsoids, %zu triangles)\n", args.out.c_str(), w, h, ellipsoids.size(),
              mesh.triangles.size());
}

}  // namespace

void addRenderCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("render", "Render a map (ellipsoid PLY) and/or a mesh headless to PNG with OSMesa");
  auto args = std::make_shared<RenderArgs>();
  verb->add_option("SEQ", args->sequence, "sequence to map and render (needs the mapper, not built yet)");
  verb->add_option("--map", args->map, "ellipsoid PLY (SPEC section 7 layout)");
  verb->add_option("--mesh", args->mesh, "triangle mesh PLY with vertex colours, drawn shaded");
  verb->add_option("--view", args->view, "global | keyframe:K | container:K")->capture_default_str();
  verb->add_option("--out", args->out, "PNG to write");
  verb->add_option("--size", args->size, "image size WIDTHxHEIGHT")->capture_default_str();
  verb->add_option("--color", args->color, "rgb | keyframe | uncertainty | count")->capture_default_str();
  verb->add_option("--sigma", args->sigma, "ellipsoid surface at this many standard deviations")->capture_default_str();
  verb->add_option("--bench-ellipsoids", args->bench_ellipsoids,
                   "time N random instanced ellipsoids at --size instead of rendering a map");
  verb->add_option("--sphere-level", args->sphere_subdivisions, "icosphere subdivisions of one ellipsoid (0..3)")
      ->check(CLI::Range(0, 3))->capture_default_str();
  verb->callback([args] { runRender(*args); });
}

}  // namespace vdmap::app
