#include "app/bench/bench_long.h"

#include <malloc.h>
#include <unistd.h>

#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "app/cli/release_memory.h"
#include "app/view/map_sequence.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/timing.h"
#include "mapping/io/json_text.h"

namespace vdmap::app {
namespace {

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

// Resident set size of this process, MB (0 where /proc is unavailable).
double residentMb() {
  std::ifstream statm("/proc/self/statm");
  std::size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// Bytes the allocator has handed out and not got back, MB: the live heap, which unlike the
// resident size does not count freed memory glibc keeps in its arenas for re-use.
double liveHeapMb() {
  const struct mallinfo2 m = mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd) / (1024.0 * 1024.0);
}

struct FrameRow {
  double cpu_ms = 0, wall_ms = 0, rss_mb = 0, heap_mb = 0;
  std::size_t keyframes = 0;
  long long global_ellipsoids = -1;  ///< -1: no global map built after this frame
  double t_g_s = 0;
};

double medianCpu(const std::vector<FrameRow>& rows, std::size_t begin, std::size_t end) {
  std::vector<double> v;
  for (std::size_t i = begin; i < end && i < rows.size(); ++i) v.push_back(rows[i].cpu_ms);
  return median(std::move(v));
}

// Maps every frame of `seq` with `mapper`, one row per frame; a global map every `global_every`
// frames and after the last frame.
std::vector<FrameRow> mapAndRecord(const Sequence& seq, Mapper& mapper, const GlobalMapParams& global, int global_every,
                                   const std::optional<MapRefinementParams>& refine) {
  std::vector<FrameRow> rows;
  rows.reserve(seq.size());
  auto buildGlobal = [&](FrameRow& row) {
    {
      const GlobalMap map = buildGlobalMap(mapper.graph(), global);
      row.global_ellipsoids = static_cast<long long>(map.sigma_e_prime);
      row.t_g_s = map.t_g_s;
    }
    releaseFreedMemory();  // as the workbench does after each build
  };
  double last = threadCpuMs();
  mapSequence(
      seq, mapper,
      [&](const FrameReport& report) {
        FrameRow row;
        row.cpu_ms = threadCpuMs() - last;  // the frame's mapping, and the progress bar's update
        row.wall_ms = report.ms.total_ms;
        row.rss_mb = residentMb();
        row.heap_mb = liveHeapMb();
        row.keyframes = mapper.graph().size();
        if (static_cast<int>(rows.size() + 1) % global_every == 0) buildGlobal(row);
        rows.push_back(row);
        last = threadCpuMs();  // a global-map build is not the next frame's cost
      },
      refine);
  if (!rows.empty() && rows.back().global_ellipsoids < 0) buildGlobal(rows.back());
  return rows;
}

std::string longCsv(const std::vector<FrameRow>& rows) {
  std::ostringstream csv;
  csv << "frame,cpu_ms,wall_ms,rss_mb,keyframes,global_ellipsoids,t_g_s,heap_mb\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const FrameRow& r = rows[i];
    csv << i << ',' << r.cpu_ms << ',' << r.wall_ms << ',' << r.rss_mb << ',' << r.keyframes << ',';
    if (r.global_ellipsoids >= 0) csv << r.global_ellipsoids << ',' << r.t_g_s;
    else csv << ',';
    csv << ',' << r.heap_mb << '\n';
  }
  return csv.str();
}

// The summary's figures: CPU medians early and late, memory half way and at the end.
struct LongFigures {
  std::size_t n = 0;
  double early = 0, late = 0, rss_half = 0, rss_end = 0, heap_half = 0, heap_end = 0;
};

LongFigures longFigures(const std::vector<FrameRow>& rows) {
  LongFigures f;
  const std::size_t n = f.n = rows.size();
  f.early = medianCpu(rows, n / 6, n / 3), f.late = medianCpu(rows, n - n / 6, n);
  f.rss_half = n > 0 ? rows[n / 2].rss_mb : 0.0, f.rss_end = n > 0 ? rows.back().rss_mb : 0.0;
  f.heap_half = n > 0 ? rows[n / 2].heap_mb : 0.0, f.heap_end = n > 0 ? rows.back().heap_mb : 0.0;
  return f;
}

nlohmann::json longSummary(const std::vector<FrameRow>& rows, const LongFigures& f, const Mapper& mapper,
                           const Sequence& seq) {
  const std::size_t n = f.n;
  const bool tracking = mapper.params().poses == PoseSource::kTrack;
  nlohmann::json summary = {
      {"frames", n},
      {"poses", tracking ? "track" : "gt"},
      {"keyframes", mapper.graph().size()},
      {"revisits", mapper.revisits()},
      {"cpu_ms_median_early", rounded(f.early)},
      {"early_frames", {n / 6, n / 3}},
      {"cpu_ms_median_late", rounded(f.late)},
      {"late_frames", {n - n / 6, n}},
      {"cpu_ratio_late_to_early", rounded(f.early > 0 ? f.late / f.early : 0.0)},
      {"cpu_ms_median_all", rounded(medianCpu(rows, 0, n))},
      {"rss_mb_half", rounded(f.rss_half)},
      {"rss_mb_end", rounded(f.rss_end)},
      {"rss_growth_last_half", rounded(f.rss_half > 0 ? f.rss_end / f.rss_half - 1.0 : 0.0)},
      {"heap_mb_half", rounded(f.heap_half)},
      {"heap_mb_end", rounded(f.heap_end)},
      {"heap_growth_last_half", rounded(f.heap_half > 0 ? f.heap_end / f.heap_half - 1.0 : 0.0)},
      {"global_ellipsoids_end", n > 0 ? rows.back().global_ellipsoids : 0},
      {"t_g_s_end", rounded(n > 0 ? rows.back().t_g_s : 0.0)},
  };
  if (tracking) addTrackingStats(mapper, mapper.trajectory(), seq, &summary);
  return summary;
}

void printLongSummary(const std::vector<FrameRow>& rows, const LongFigures& f, const Mapper& mapper,
                      const nlohmann::json& summary) {
  const std::size_t n = f.n;
  std::printf("long run: %zu frames, %zu keyframes, %d revisits\n", n, mapper.graph().size(), mapper.revisits());
  std::printf("CPU per frame, median: frames %zu-%zu %.2f ms, last %zu frames %.2f ms (x%.2f)\n", n / 6, n / 3, f.early,
              n / 6, f.late, f.early > 0 ? f.late / f.early : 0.0);
  std::printf("resident memory: %.0f MB half way, %.0f MB at the end (%+.1f%%)\n", f.rss_half, f.rss_end,
              f.rss_half > 0 ? 100.0 * (f.rss_end / f.rss_half - 1.0) : 0.0);
  std::printf("live heap: %.0f MB half way, %.0f MB at the end (%+.1f%%)\n", f.heap_half, f.heap_end,
              f.heap_half > 0 ? 100.0 * (f.heap_end / f.heap_half - 1.0) : 0.0);
  if (mapper.params().poses == PoseSource::kTrack) {
    std::printf("tracked poses: %d frames lost, %d placed on a weak estimate, %d relocalised, %zu loop closures",
                mapper.framesLost(), mapper.framesWeak(), mapper.framesRelocalised(),
                mapper.poseGraph().loops().size());
    if (summary.contains("ate_rmse_m")) std::printf(", ATE %.2f cm", 100 * summary["ate_rmse_m"].get<double>());
    std::printf("\n");
  }
  std::printf("global map at the end: %lld ellipsoids in %.2f s\n", n > 0 ? rows.back().global_ellipsoids : 0LL,
              n > 0 ? rows.back().t_g_s : 0.0);
}

}  // namespace

void runLongBench(const Sequence& seq, const MapperParams& mapper_params, const GlobalMapParams& global,
                  const std::filesystem::path& out_dir, const LongRunOptions& options,
                  const std::optional<MapRefinementParams>& refine) {
  if (options.global_every < 1) throw std::invalid_argument("--global-every must be at least 1");
  Mapper mapper(seq.camera(), mapper_params);
  const std::vector<FrameRow> rows = mapAndRecord(seq, mapper, global, options.global_every, refine);
  const LongFigures figures = longFigures(rows);
  const nlohmann::json summary = longSummary(rows, figures, mapper, seq);
  std::filesystem::create_directories(out_dir);  // checked before the run (checkExportFolder)
  writeFileAtomically(out_dir / "long.csv", longCsv(rows));
  writeFileAtomically(out_dir / "long.json", jsonText(summary) + "\n");
  if (options.json) {
    std::cout << jsonText(summary) << '\n';
    return;
  }
  printLongSummary(rows, figures, mapper, summary);
  std::printf("wrote %s and %s\n", (out_dir / "long.csv").c_str(), (out_dir / "long.json").c_str());
}

}  // namespace vdmap::app
