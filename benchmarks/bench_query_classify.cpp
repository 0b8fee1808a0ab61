// bench_query_classify SESSION.vdmap [POINTS [RUNS]]: classification speed (docs/method.md 13.1-13.3)
// on a saved session, one thread. Builds the global map (the session's settings) and the QueryMap
// (RUNS times: median build time, memoryBytes), then classifies POINTS points (default 1 M: half
// uniform in seenBounds, half global means + N(0, 2 cm), seed 36) RUNS times under each conflict
// rule and prints the median process CPU time, points/s and the classes. The two parts alone are
// timed too: the global gates (SurfaceIndex::gate) and the keyframes' free test (KeyframeViews::combined).
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "mapping/core/timing.h"
#include "mapping/global_map/global_map.h"
#include "mapping/files/session_file.h"
#include "mapping/query/detail/keyframe_views.h"
#include "mapping/query/query_map.h"
#include "mapping/query/detail/surface_index.h"

namespace {

using vdmap::cpuTimeMs;
using vdmap::median;

const char* ruleName(vdmap::ConflictRule r) {
  return r == vdmap::ConflictRule::kOccupied ? "occupied" : r == vdmap::ConflictRule::kRecent ? "recent" : "precise";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_query_classify SESSION.vdmap [POINTS [RUNS]]\n");
    return 2;
  }
  const std::size_t n = argc > 2 ? static_cast<std::size_t>(std::atof(argv[2])) : 1000000;
  const int runs = argc > 3 ? std::max(1, std::atoi(argv[3])) : 3;
  vdmap::SessionDecodeOptions decode;
  decode.decode_images = false;
  const vdmap::Session session = vdmap::loadSession(argv[1], decode);
  const vdmap::GlobalMap global = vdmap::buildGlobalMap(session.graph, session.info.global);
  std::printf("%s: %zu keyframes, %zu kept local ellipsoids, %zu global ellipsoids\n", argv[1], session.graph.size(),
              global.sigma_e, global.ellipsoids.size());

  vdmap::QueryParams params;
  params.threads = 1;
  std::vector<double> build_ms;
  vdmap::QueryMap map;
  for (int r = 0; r < runs; ++r)
    build_ms.push_back(cpuTimeMs([&] { map = vdmap::QueryMap::build(session.graph, global, params); }));
  std::printf("QueryMap::build, 1 thread: median %.1f ms CPU; memoryBytes %.1f MB\n", median(build_ms),
              static_cast<double>(map.memoryBytes()) / 1e6);

  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  std::mt19937_64 rng(36);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_int_distribution<std::size_t> pick(0, global.ellipsoids.size() - 1);
  std::vector<Eigen::Vector3d> points(n);
  for (std::size_t i = 0; i < n; ++i)
    points[i] = i % 2 == 0 ? Eigen::Vector3d(lo + (hi - lo).cwiseProduct(Eigen::Vector3d(unit(rng), unit(rng), unit(rng))))
                           : Eigen::Vector3d(global.ellipsoids[pick(rng)].mean + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  std::printf("%zu points: half uniform in seenBounds [%.2f %.2f %.2f]..[%.2f %.2f %.2f], half global means + N(0, 2 cm)\n",
              n, lo.x(), lo.y(), lo.z(), hi.x(), hi.y(), hi.z());

  // The keyframes' part alone (free space under kOccupied), on every point.
  {
    const vdmap::KeyframeViews views = vdmap::KeyframeViews::build(session.graph, global, params, {});
    std::vector<double> ms;
    std::size_t free = 0, candidates = 0;
    for (std::size_t i = 0; i < n; ++i) candidates += views.candidates(points[i]).size();
    for (int r = 0; r < runs; ++r)
      ms.push_back(cpuTimeMs([&] {
        free = 0;
        for (std::size_t i = 0; i < n; ++i) {
          int kf = -1;
          free += views.combined(points[i], &kf).state == vdmap::Occupancy::kFree;
        }
      }));
    std::printf("keyframe views alone (kOccupied's free test): median %.1f ms CPU, %.2f M points/s; %.1f %% free; "
                "%.1f candidate keyframes per point; %.1f MB\n",
                median(ms), 1e-3 * static_cast<double>(n) / median(ms), 100.0 * static_cast<double>(free) / n,
                static_cast<double>(candidates) / n, static_cast<double>(views.memoryBytes()) / 1e6);
  }

  // The global gates alone (SurfaceIndex::gate, what kOccupied asks first), on every point.
  {
    const vdmap::SurfaceIndex surface = vdmap::SurfaceIndex::build(global.ellipsoids, params);
    std::vector<double> ms;
    std::size_t inside = 0;
    for (int r = 0; r < runs; ++r)
      ms.push_back(cpuTimeMs([&] {
        inside = 0;
        for (std::size_t i = 0; i < n; ++i) inside += surface.gate(points[i]).first >= 0;
      }));
    std::printf("global gates alone: median %.1f ms CPU, %.2f M points/s; %.1f %% inside a gate; %.1f MB\n", median(ms),
                1e-3 * static_cast<double>(n) / median(ms), 100.0 * static_cast<double>(inside) / n,
                static_cast<double>(surface.memoryBytes()) / 1e6);
  }

  for (const vdmap::ConflictRule rule : {vdmap::ConflictRule::kOccupied, vdmap::ConflictRule::kRecent, vdmap::ConflictRule::kPrecise}) {
    params.conflict = rule;
    const vdmap::QueryMap m = vdmap::QueryMap::build(session.graph, global, params);
    std::vector<vdmap::Classification> out(n);
    std::vector<double> ms;
    for (int r = 0; r < runs; ++r) ms.push_back(cpuTimeMs([&] { m.classify(points, out); }));
    std::size_t count[3] = {0, 0, 0};
    for (const auto& c : out) ++count[static_cast<int>(c.state)];
    std::printf("classify, conflict %-8s 1 thread: median %.1f ms CPU, %.2f M points/s (%.3f us/point); "
                "%.1f %% occupied, %.1f %% free, %.1f %% unknown\n",
                ruleName(rule), median(ms), 1e-3 * static_cast<double>(n) / median(ms), 1e3 * median(ms) / n,
                100.0 * count[2] / n, 100.0 * count[1] / n, 100.0 * count[0] / n);
  }
  return 0;
}
