// Loop-closure search cost against the size of the map (issue #5): maps a long sequence once,
// then times the per-frame keyframe decision against the first 10 and the first 100 keyframes,
// with the pose pre-filter on and off, on the same query frames. Not a test (ctest does not
// run it); figures are medians of 3 repetitions.
//
//   bench_keyframe [SEQ] [--benchmark_...]
// Without SEQ it renders the built-in scene's 8-lap walk (2400 frames, 133 keyframes) into a
// temporary folder first, which takes minutes; `vdmap synth --builtin --builtin-laps 8 --out
// DIR` makes the same folder once for repeated runs.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <span>
#include <string>

#include <benchmark/benchmark.h>

#include "app/timing.h"
#include "mapping/io/frame_prefetcher.h"
#include "mapping/keyframe/mapper.h"
#include "render/sequence_synth.h"
#include "tests/test_util.h"

namespace vdmap {
namespace {

struct Query {
  FrameFeatures features;
  Transform T_W_C;
};

// The map of the whole sequence and every 100th frame as a query (spread over all laps).
struct Recording {
  std::unique_ptr<Mapper> mapper;
  std::vector<KeyframeView> views;
  std::vector<Query> queries;
};
Recording* g_recording = nullptr;

using app::median;

// Decision cost of the frames mapped while the graph held [lo, hi] keyframes.
void printRunCost(const std::vector<FrameReport>& reports, std::size_t lo, std::size_t hi,
                  const std::vector<std::size_t>& sizes) {
  std::vector<double> ms, searched_ms;
  for (std::size_t i = 0; i < reports.size(); ++i) {
    if (sizes[i] < lo || sizes[i] > hi) continue;
    ms.push_back(reports[i].ms.decision_ms);
    if (reports[i].decision.kind != FrameDecision::Kind::kUpdate) searched_ms.push_back(reports[i].ms.decision_ms);
  }
  double mean = 0;
  for (const double m : ms) mean += m;
  std::printf("run, %3zu..%3zu keyframes: %4zu frames, decision median %.2f ms, mean %.2f ms; "
              "%zu frames searched for a loop (median %.2f ms)\n",
              lo, hi, ms.size(), median(ms), ms.empty() ? 0.0 : mean / ms.size(), searched_ms.size(),
              median(searched_ms));
}

Recording record(const std::filesystem::path& folder) {
  Recording rec;
  const TumSequence seq = TumSequence::open(folder);
  rec.mapper = std::make_unique<Mapper>(seq.camera());
  const FeatureExtractor extractor(rec.mapper->params().features);
  std::vector<FrameReport> reports;
  std::vector<std::size_t> sizes;
  FramePrefetcher frames(seq);
  while (std::optional<RgbdFrame> f = frames.next()) {
    sizes.push_back(rec.mapper->graph().size());
    reports.push_back(rec.mapper->addFrame(*f));
    reports.back().touched_cells.clear();
    if (reports.size() % 100 == 0)
      rec.queries.push_back({extractor.extract(*f, seq.camera(), rec.mapper->params().local_map.depth_range), f->T_W_C});
  }
  rec.views = rec.mapper->graph().views();
  std::printf("%s: %zu frames, %zu keyframes, %d revisits, %zu query frames\n", folder.c_str(), reports.size(),
              rec.views.size(), rec.mapper->revisits(), rec.queries.size());
  printRunCost(reports, 8, 12, sizes);
  printRunCost(reports, 90, 110, sizes);
  return rec;
}

// The first state.range(0) keyframes, and the decision parameters with the pose pre-filter on
// when state.range(1) != 0.
struct SearchSetup {
  std::span<const KeyframeView> keyframes;
  KeyframeParams params;
};
SearchSetup searchSetup(const benchmark::State& state, const Recording& rec) {
  SearchSetup s{{rec.views.data(), std::min<std::size_t>(state.range(0), rec.views.size())},
                rec.mapper->params().keyframes};
  s.params.prefilter.enabled = state.range(1) != 0;
  return s;
}

// CPU time per query in seconds (the iteration's time divided by the number of queries); Google
// Benchmark prints it with an SI prefix and an "s", e.g. 13.4ms.
benchmark::Counter perSearch(const Recording& rec) {
  return benchmark::Counter(static_cast<double>(rec.queries.size()),
                            benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// One iteration = the loop-closure search of every query frame (current keyframe -1: nothing
// is updated first, every keyframe is a candidate) against the first range(0) keyframes;
// time_per_search is the CPU time of one.
void BM_LoopClosureSearch(benchmark::State& state) {
  const Recording& rec = *g_recording;
  const auto [keyframes, params] = searchSetup(state, rec);
  double matched = 0, searches = 0;
  for (auto _ : state)
    for (const Query& query : rec.queries) {
      const FrameDecision d = decideKeyframe(query.features, query.T_W_C, -1, keyframes, rec.mapper->camera(), params);
      benchmark::DoNotOptimize(d);
      matched += d.matched;
      searches += 1;
    }
  state.counters["keyframes"] = static_cast<double>(keyframes.size());
  state.counters["matched_per_search"] = matched / searches;
  state.counters["time_per_search"] = perSearch(rec);
}
BENCHMARK(BM_LoopClosureSearch)
    ->ArgNames({"keyframes", "prefilter"})
    ->Args({10, 1})->Args({100, 1})->Args({10, 0})->Args({100, 0})
    ->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3)->ReportAggregatesOnly(true);

// The edges of a new keyframe (SPEC section 5): the other search that visits every keyframe.
void BM_NewKeyframeEdges(benchmark::State& state) {
  const Recording& rec = *g_recording;
  const auto [keyframes, params] = searchSetup(state, rec);
  for (auto _ : state)
    for (const Query& query : rec.queries)
      benchmark::DoNotOptimize(
          edgesOfNewKeyframe(query.features, query.T_W_C, -1, keyframes, rec.mapper->camera(), params));
  state.counters["keyframes"] = static_cast<double>(keyframes.size());
  state.counters["time_per_search"] = perSearch(rec);
}
BENCHMARK(BM_NewKeyframeEdges)
    ->ArgNames({"keyframes", "prefilter"})
    ->Args({10, 1})->Args({100, 1})
    ->Unit(benchmark::kMillisecond)->Iterations(1)->Repetitions(3)->ReportAggregatesOnly(true);

}  // namespace
}  // namespace vdmap

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::unique_ptr<vdmap::test::TempDir> tmp;
  std::filesystem::path folder;
  if (argc > 1) {
    folder = argv[1];
  } else {
    tmp = std::make_unique<vdmap::test::TempDir>();
    folder = *tmp / "builtin-8-laps";
    std::printf("rendering the built-in 8-lap walk into %s ...\n", folder.c_str());
    vdmap::render::writeBuiltinSequence(folder, vdmap::BuiltinSceneParams{.laps = 8});
  }
  vdmap::Recording rec = vdmap::record(folder);
  vdmap::g_recording = &rec;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
