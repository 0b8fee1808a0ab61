// bench_global_map SESSION.vdmap [RUNS [THREADS]]: builds the global map of a saved session RUNS times
// (default 5) with 1 and with 2 threads (only THREADS when given), each without a workspace (cold) and
// with one reused (warm), and prints the medians of t_g and of each stage, the
// time per input ellipsoid, the process CPU time (a loaded machine stretches wall time), and whether both thread counts gave the same map bit for bit.
// Then each live parameter edited to another value and back RUNS times with one workspace (the
// workbench's slider edits): the median rebuild and what the stage cache kept.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <sys/resource.h>

#include "mapping/core/timing.h"
#include "mapping/files/session_file.h"
#include "mapping/global_map/global_map.h"
#include "mapping/pipeline/parameters.h"

namespace {

using vdmap::median;

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

// FNV-1a over every field of the map's ellipsoids, its groups and kept cells: equal hashes of
// two builds (or two binaries) mean the same map bit for bit.
std::uint64_t mapHash(const vdmap::GlobalMap& map) {
  std::uint64_t h = 1469598103934665603ull;
  auto add = [&h](const void* data, std::size_t bytes) {
    for (std::size_t i = 0; i < bytes; ++i) h = (h ^ static_cast<const unsigned char*>(data)[i]) * 1099511628211ull;
  };
  for (const vdmap::Ellipsoid& e : map.ellipsoids) {
    add(e.mean.data(), sizeof(double) * 3);
    add(e.cov.data(), sizeof(double) * 9);
    add(e.color.data(), sizeof(float) * 3);
    add(&e.count, sizeof e.count);
    add(&e.keyframe, sizeof e.keyframe);
    add(&e.grid_index, sizeof e.grid_index);
  }
  for (const vdmap::MergeGroup& g : map.groups) {
    add(&g.centre, sizeof g.centre);
    add(g.members.data(), sizeof(int) * g.members.size());
  }
  for (const std::vector<bool>& kept : map.kept)
    for (bool k : kept) add(&k, 1);
  const std::size_t counts[] = {map.sigma_e, map.merged, map.merged_across_groups, map.sigma_e_prime};
  add(counts, sizeof counts);
  return h;
}

// One live parameter edited at a time, as on the workbench's sliders: with one workspace, the
// parameter goes to another value and back RUNS times, each build timed (the stage cache re-runs
// only the stages after it, GlobalMap::reuse). Each value's map is checked against a fresh build.
bool editSeries(const vdmap::Session& session, int runs, int threads = 2) {
  vdmap::ParameterValues values;
  values.global = session.info.global;
  values.global.threads = threads;
  vdmap::GlobalMapWorkspace workspace;
  vdmap::buildGlobalMap(session.graph, values.global, &workspace);
  bool all_same = true;
  for (const vdmap::Parameter& p : vdmap::parameters()) {
    if (!p.live) continue;
    const double was = p.get(values);
    double other = was * 0.8;
    if (p.kind == vdmap::ParameterSpec::Kind::kBool || p.kind == vdmap::ParameterSpec::Kind::kChoice)
      other = was == 0 ? 1 : 0;
    else if (p.kind == vdmap::ParameterSpec::Kind::kInt) other = was + 2;
    else if (std::string(p.key) == "tau_group") other = was + 0.05;
    std::vector<double> t_g, groups, merge, occlusion, fusion, t_g_before, cpu, cpu_before;
    std::vector<double> merged_groups;
    int occlusion_reused = 0, fusion_reused = 0;
    std::uint64_t hash[2] = {0, 0};
    for (int r = 0; r < 2 * runs; ++r) {
      // Before the stage cache: the same edit with every stage re-run (in turns, under the same load).
      p.set(values, r % 2 == 0 ? other : was);
      workspace.forgetStages();
      cpu_before.push_back(vdmap::cpuTimeMs(
          [&] { t_g_before.push_back(1e3 * vdmap::buildGlobalMap(session.graph, values.global, &workspace).t_g_s); }));
      p.set(values, r % 2 == 0 ? was : other);
      vdmap::buildGlobalMap(session.graph, values.global, &workspace);
      p.set(values, r % 2 == 0 ? other : was);
      vdmap::GlobalMap map;
      cpu.push_back(vdmap::cpuTimeMs([&] { map = vdmap::buildGlobalMap(session.graph, values.global, &workspace); }));
      t_g.push_back(1e3 * map.t_g_s);
      groups.push_back(map.groups_ms);
      merge.push_back(map.merge_ms);
      occlusion.push_back(map.occlusion_ms);
      fusion.push_back(map.fusion_ms);
      merged_groups.push_back(static_cast<double>(map.reuse.merged_groups) /
                              std::max<std::size_t>(map.groups.size(), 1));
      occlusion_reused += map.reuse.occlusion;
      fusion_reused += map.reuse.fusion;
      if (r < 2) hash[r] = mapHash(map);
    }
    bool same = true;
    for (int v = 0; v < 2; ++v) {
      p.set(values, v == 0 ? other : was);
      same = same && mapHash(vdmap::buildGlobalMap(session.graph, values.global)) == hash[v];
    }
    p.set(values, was);
    all_same = all_same && same;
    std::printf(
        "edit %-20s threads %d: t_g median %7.1f ms (CPU %7.1f), all stages %7.1f ms (CPU %7.1f) (groups %.1f, merge %.1f, occlusion %.1f, fusion %.1f ms); "
        "merge groups kept %3.0f %%, occlusion kept %d/%d, fusion kept %d/%d; fresh build's map: %s\n",
        std::string(p.key).c_str(), threads, median(t_g), median(cpu), median(t_g_before), median(cpu_before),
        median(groups), median(merge), median(occlusion), median(fusion), 100 * median(merged_groups), occlusion_reused,
        2 * runs, fusion_reused, 2 * runs, same ? "yes" : "NO");
  }
  return all_same;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_global_map SESSION.vdmap [RUNS [THREADS]]\n");
    return 2;
  }
  const int runs = argc > 2 ? std::max(1, std::atoi(argv[2])) : 5;
  const int only_threads = argc > 3 ? std::atoi(argv[3]) : 0;  // > 0: just this thread count
  const vdmap::Session session = vdmap::loadSession(argv[1]);
  vdmap::GlobalMapParams params = session.info.global;
  std::vector<vdmap::GlobalMap> first;  // per thread count: a cold and a warm build
  for (int threads : {1, 2}) {
    if (only_threads > 0 && threads != only_threads) continue;
    params.threads = threads;
    // Cold: every build allocates afresh (vdmap map's one build at the end). Warm: one workspace
    // reused across builds (the workbench's rebuilds after loop closures and edits), warmed by a
    // first build that is not timed. Taken in turns, so both see the same load.
    struct Series {
      std::vector<double> t_g, cpu, sys, faults, groups, merge, fusion, occlusion;
      vdmap::GlobalMap map;
    } cold, warm;
    vdmap::GlobalMapWorkspace workspace;
    warm.map = vdmap::buildGlobalMap(session.graph, params, &workspace);
    for (int r = 0; r < 2 * runs; ++r) {
      Series& s = r % 2 == 0 ? cold : warm;
      vdmap::GlobalMapWorkspace* w = r % 2 == 0 ? nullptr : &workspace;
      rusage before{}, after{};
      getrusage(RUSAGE_SELF, &before);
      s.cpu.push_back(1e-3 * vdmap::cpuTimeMs([&] { s.map = vdmap::buildGlobalMap(session.graph, params, w); }));
      getrusage(RUSAGE_SELF, &after);
      // Page faults and system time of the build (the map of the previous run is freed outside).
      s.faults.push_back(static_cast<double>(after.ru_minflt - before.ru_minflt));
      s.sys.push_back(static_cast<double>(after.ru_stime.tv_sec - before.ru_stime.tv_sec) +
                      1e-6 * static_cast<double>(after.ru_stime.tv_usec - before.ru_stime.tv_usec));
      s.t_g.push_back(s.map.t_g_s);
      s.groups.push_back(s.map.groups_ms);
      s.merge.push_back(s.map.merge_ms);
      s.fusion.push_back(s.map.fusion_ms);
      s.occlusion.push_back(s.map.occlusion_ms);
    }
    for (Series* s : {&cold, &warm}) {
      const vdmap::GlobalMap& map = s->map;
      std::printf(
          "threads %d %s: %zu keyframes, sigma_e %zu -> merged %zu -> sigma_e' %zu; t_g median %.3f s "
          "(%.3f us/ellipsoid; CPU %.3f s, of it system %.3f s, %.0fk page faults; groups %.1f, merge %.1f, fusion %.1f, "
          "occlusion %.1f ms; %d runs)\n",
          threads, s == &cold ? "cold" : "warm", session.graph.size(), map.sigma_e, map.merged, map.sigma_e_prime,
          median(s->t_g), median(s->t_g) * 1e6 / static_cast<double>(std::max<std::size_t>(map.sigma_e, 1)),
          median(s->cpu), median(s->sys), 1e-3 * median(s->faults), median(s->groups), median(s->merge),
          median(s->fusion), median(s->occlusion), runs);
      first.push_back(std::move(s->map));
    }
  }
  bool same = true;
  std::printf("map hash:");
  for (const vdmap::GlobalMap& map : first) {
    std::printf(" %016llx", static_cast<unsigned long long>(mapHash(map)));
    same = same && sameMap(map, first.front());
  }
  std::printf(" (cold, warm per thread count)\n");
  if (only_threads > 0) return (editSeries(session, runs, only_threads) && same) ? 0 : 1;
  // What fusion across groups (docs/method.md 7) costs and saves: the same build without it.
  params.threads = 1;
  params.fuse_across_groups = false;
  std::vector<double> cpu_apart;
  vdmap::GlobalMap apart;
  for (int r = 0; r < runs; ++r)
    cpu_apart.push_back(1e-3 * vdmap::cpuTimeMs([&] { apart = vdmap::buildGlobalMap(session.graph, params); }));
  std::printf("threads 1 without fusion: merged %zu -> sigma_e' %zu; CPU %.3f s (%d runs)\n", apart.merged,
              apart.sigma_e_prime, median(cpu_apart), runs);
  std::printf("1 and 2 threads, cold and warm, give the same map: %s\n", same ? "yes" : "NO");
  return (editSeries(session, runs) && same) ? 0 : 1;
}
