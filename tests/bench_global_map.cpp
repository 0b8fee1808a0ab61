// bench_global_map SESSION.vdmap [RUNS]: builds the global map of a saved session RUNS times
// (default 5) with 1 and with 2 threads and prints the medians of t_g and of each stage, the
// time per input ellipsoid, the process CPU time (a loaded machine stretches wall time), and whether both thread counts gave the same map bit for bit.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "app/timing.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/session_file.h"

namespace {

using vdmap::app::median;

bool sameMap(const vdmap::GlobalMap& a, const vdmap::GlobalMap& b) {
  if (a.ellipsoids.size() != b.ellipsoids.size()) return false;
  for (std::size_t i = 0; i < a.ellipsoids.size(); ++i) {
    const vdmap::Ellipsoid &x = a.ellipsoids[i], &y = b.ellipsoids[i];
    if (std::memcmp(x.mean.data(), y.mean.data(), sizeof(double) * 3) != 0 ||
        std::memcmp(x.cov.data(), y.cov.data(), sizeof(double) * 9) != 0 || x.count != y.count ||
        x.keyframe != y.keyframe)
      return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_global_map SESSION.vdmap [RUNS]\n");
    return 2;
  }
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 5;
  const vdmap::Session session = vdmap::loadSession(argv[1]);
  vdmap::GlobalMapParams params = session.info.global;
  std::vector<vdmap::GlobalMap> first;
  for (int threads : {1, 2}) {
    params.threads = threads;
    std::vector<double> t_g, cpu, groups, merge, fusion, occlusion;
    vdmap::GlobalMap map;
    for (int r = 0; r < runs; ++r) {
      cpu.push_back(1e-3 * vdmap::app::cpuTimeMs([&] { map = vdmap::buildGlobalMap(session.graph, params); }));
      t_g.push_back(map.t_g_s);
      groups.push_back(map.groups_ms);
      merge.push_back(map.merge_ms);
      fusion.push_back(map.fusion_ms);
      occlusion.push_back(map.occlusion_ms);
    }
    std::printf("threads %d: %zu keyframes, sigma_e %zu -> merged %zu -> sigma_e' %zu; t_g median %.3f s "
                "(%.3f us/ellipsoid; CPU %.3f s; groups %.1f, merge %.1f, fusion %.1f, occlusion %.1f ms; %d runs)\n",
                threads, session.graph.size(), map.sigma_e, map.merged, map.sigma_e_prime, median(t_g),
                median(t_g) * 1e6 / static_cast<double>(std::max<std::size_t>(map.sigma_e, 1)), median(cpu), median(groups),
                median(merge), median(fusion), median(occlusion), runs);
    first.push_back(std::move(map));
  }
  // What fusion across groups (SPEC 6.5) costs and saves: the same build without it.
  params.threads = 1;
  params.fuse_across_groups = false;
  std::vector<double> cpu_apart;
  vdmap::GlobalMap apart;
  for (int r = 0; r < runs; ++r)
    cpu_apart.push_back(1e-3 * vdmap::app::cpuTimeMs([&] { apart = vdmap::buildGlobalMap(session.graph, params); }));
  std::printf("threads 1 without fusion: merged %zu -> sigma_e' %zu; CPU %.3f s (%d runs)\n", apart.merged,
              apart.sigma_e_prime, median(cpu_apart), runs);
  std::printf("1 and 2 threads give the same map: %s\n", sameMap(first[0], first[1]) ? "yes" : "NO");
  return sameMap(first[0], first[1]) ? 0 : 1;
}
