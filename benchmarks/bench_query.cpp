// Surface query speed on a saved session (docs/method.md 13.4-13.6; docs/performance.md "Queries").
// Not a test (ctest does not run it):
//   build/bin/bench_query SESSION.vdmap [--benchmark_repetitions=3 --benchmark_report_aggregates_only=true]
// Builds the session's global map and its QueryMap on one thread (params.threads = 1, so every
// figure is one core), then times:
// - SurfaceBuild: the gates, gate grid and box tree of the global map's ellipsoids;
// - Gate: SurfaceIndex::gate (the occupied test of classification) per point;
// - Distance: QueryMap::distance per point (batches of 10k; DistanceHalf/1 the near half, /0 the
//   uniform half);
// - CastRays: QueryMap::castRays per ray, 8 m (batches of 10k);
// - CastView: one 640x480 (the session camera's) QueryMap::castView from a keyframe's pose,
//   cycling through 8 keyframes spread over the session.
// Points: half uniform in the box of what the keyframes see, half within 10 cm of a random
// ellipsoid's mean (near surfaces, where planners ask); rays start at keyframe centres, uniform
// directions in the camera's half space.
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "mapping/global_map/global_map.h"
#include "mapping/files/session_file.h"
#include "mapping/query/ellipsoid_geometry.h"
#include "mapping/query/query_map.h"
#include "mapping/query/detail/surface_index.h"

namespace vdmap {
namespace {

struct Setup {
  Session session;
  GlobalMap global;
  QueryParams params;
  QueryMap map;
  std::vector<Eigen::Vector3d> points;
  std::vector<Ray> rays;
  std::vector<Transform> views;
};

Setup* setup = nullptr;

void makeSetup(const std::string& file) {
  setup = new Setup;
  SessionDecodeOptions options;
  options.decode_images = false;
  setup->session = loadSession(file, options);
  GlobalMapParams gp = setup->session.info.global;
  gp.threads = 0;
  setup->global = buildGlobalMap(setup->session.graph, gp);
  setup->params.threads = 1;
  setup->map = QueryMap::build(setup->session.graph, setup->global, setup->params);
  const KeyframeGraph& graph = setup->session.graph;
  std::printf("bench_query: %s: %zu keyframes, %zu global ellipsoids, query map %.1f MB\n", file.c_str(),
              graph.size(), setup->global.ellipsoids.size(), setup->map.memoryBytes() / 1e6);

  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n;
  Eigen::Vector3d lo, hi;
  setup->map.seenBounds(&lo, &hi);
  const auto& e = setup->global.ellipsoids;
  std::uniform_int_distribution<std::size_t> pick(0, e.empty() ? 0 : e.size() - 1);
  for (int i = 0; i < 10000; ++i) {
    if (i % 2 == 0 || e.empty())
      setup->points.push_back(lo + Eigen::Vector3d(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo));
    else
      setup->points.push_back(e[pick(rng)].mean + 0.1 * u(rng) * Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized());
  }
  std::uniform_int_distribution<int> kf(0, static_cast<int>(graph.size()) - 1);
  for (int i = 0; i < 10000; ++i) {
    const Transform& T = graph.keyframe(kf(rng)).T_W_K;
    Eigen::Vector3d d(n(rng), n(rng), n(rng));
    d.z() = std::abs(d.z());
    setup->rays.push_back({T.translation(), T.linear() * d, 8.0});
  }
  for (int i = 0; i < 8; ++i)
    setup->views.push_back(graph.keyframe(static_cast<int>((graph.size() * (2 * i + 1)) / 16)).T_W_K);

  // The first view raster against castRays on its pixel rays (bit for bit, as the tests check on
  // generated maps).
  const PinholeCamera& camera = setup->session.info.camera;
  const std::vector<RayHit> pixels = setup->map.castView(camera, setup->views[0], 8.0);
  std::vector<Ray> rays;
  for (int v = 0; v < camera.height; ++v)
    for (int x = 0; x < camera.width; ++x)
      rays.push_back({setup->views[0].translation(), pixelRay(camera, setup->views[0], x, v), 8.0});
  std::vector<RayHit> traced(rays.size());
  setup->map.castRays(rays, traced);
  std::size_t differ = 0;
  for (std::size_t p = 0; p < rays.size(); ++p)
    differ += pixels[p].hit != traced[p].hit || pixels[p].t_m != traced[p].t_m ||
              pixels[p].ellipsoid != traced[p].ellipsoid || pixels[p].normal_W != traced[p].normal_W;
  std::printf("bench_query: castView of keyframe %zu's view == castRays on its %zu pixels: %s (%zu differ)\n",
              graph.size() / 16, rays.size(), differ == 0 ? "yes" : "NO", differ);
}

void SurfaceBuild(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(SurfaceIndex::build(setup->global.ellipsoids, setup->params));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(setup->global.ellipsoids.size()));
}

void Gate(benchmark::State& state) {
  const SurfaceIndex index = SurfaceIndex::build(setup->global.ellipsoids, setup->params);
  std::size_t inside = 0;
  for (auto _ : state)
    for (const Eigen::Vector3d& q : setup->points) inside += index.gate(q).first >= 0;
  benchmark::DoNotOptimize(inside);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(setup->points.size()));
}

void Distance(benchmark::State& state) {
  std::vector<DistanceResult> out(setup->points.size());
  for (auto _ : state) setup->map.distance(setup->points, out);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(setup->points.size()));
}

// The two halves of the points apart: near surfaces (within 10 cm of a mean) and uniform in the
// seen box (mostly open space, where many surface patches are almost equally near).
void DistanceHalf(benchmark::State& state) {
  std::vector<Eigen::Vector3d> half;
  for (std::size_t i = static_cast<std::size_t>(state.range(0)); i < setup->points.size(); i += 2)
    half.push_back(setup->points[i]);
  std::vector<DistanceResult> out(half.size());
  for (auto _ : state) setup->map.distance(half, out);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(half.size()));
  state.SetLabel(state.range(0) == 1 ? "near surfaces" : "uniform in the seen box");
}

void CastRays(benchmark::State& state) {
  std::vector<RayHit> out(setup->rays.size());
  for (auto _ : state) setup->map.castRays(setup->rays, out);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(setup->rays.size()));
}

void CastView(benchmark::State& state) {
  std::size_t view = 0, hits = 0;
  for (auto _ : state) {
    const std::vector<RayHit> pixels =
        setup->map.castView(setup->session.info.camera, setup->views[view++ % setup->views.size()], 8.0);
    for (const RayHit& h : pixels) hits += h.hit;
  }
  state.counters["hit_fraction"] =
      static_cast<double>(hits) /
      (static_cast<double>(state.iterations()) * setup->session.info.camera.width * setup->session.info.camera.height);
}

BENCHMARK(SurfaceBuild)->Unit(benchmark::kMillisecond);
BENCHMARK(Gate)->Unit(benchmark::kMillisecond);
BENCHMARK(Distance)->Unit(benchmark::kMillisecond);
BENCHMARK(DistanceHalf)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);
BENCHMARK(CastRays)->Unit(benchmark::kMillisecond);
BENCHMARK(CastView)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vdmap

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (argc != 2 || std::strncmp(argv[1], "--", 2) == 0) {
    std::fprintf(stderr, "usage: bench_query SESSION.vdmap [--benchmark_...]\n");
    return 1;
  }
  vdmap::makeSetup(argv[1]);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  delete vdmap::setup;
  return 0;
}
