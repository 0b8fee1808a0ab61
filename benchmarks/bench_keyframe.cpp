// Loop-closure search cost against the size of the map (issues #5, #16): maps a long sequence
// once, then times the keyframe decision of the same query frames against 10, 100 and 1000
// keyframes, exhaustively (every keyframe the pose pre-filter accepts gets a covisibility
// bound) and with the place-recognition index proposing the candidates. Not a test (ctest does
// not run it); figures are medians of 3 repetitions of CPU time.
//
//   bench_keyframe [SEQ] [--benchmark_...]
// Without SEQ it renders the built-in scene's 8-lap walk (2400 frames, over 100 keyframes) into a
// temporary folder first, which takes minutes; `vdmap synth --builtin --builtin-laps 8 --out
// DIR` makes the same folder once for repeated runs.
//
// Two graphs: the mapper's own keyframes (10, 100: the first ones it made), and a dense graph
// whose keyframes are every 2nd frame of the sequence (10, 100, 1000: a long-run graph where
// many keyframes see the same place, the index's hard case). While recording, every frame
// that searched is also decided exhaustively and the two are compared (the oracle).
#include <algorithm>
#include <cstdio>
#include <deque>
#include <memory>
#include <span>
#include <string>

#include <benchmark/benchmark.h>

#include "mapping/core/timing.h"
#include "mapping/keyframe/keyframe_index.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/sequence/frame_prefetcher.h"
#include "render/sequence_synth.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

struct Posed {
  FrameFeatures features;
  Transform T_W_C;
};

struct Recording {
  std::unique_ptr<Mapper> mapper;
  std::vector<KeyframeView> views;  ///< the mapper's keyframes
  std::deque<Posed> dense;          ///< every 2nd frame
  std::vector<KeyframeView> dense_views;
  std::vector<Posed> queries;  ///< every 100th frame (spread over all laps)
};
Recording* g_recording = nullptr;

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
  const Sequence seq = Sequence::open(folder);
  rec.mapper = std::make_unique<Mapper>(seq.camera());
  const Mapper& m = *rec.mapper;
  const FeatureExtractor extractor(m.params().features);
  const KeyframeParams& params = m.params().keyframes;
  std::vector<FrameReport> reports;
  std::vector<std::size_t> sizes;
  int searches = 0, differ = 0, new_keyframes = 0, edges_differ = 0;
  FramePrefetcher frames(seq);
  while (std::optional<RgbdFrame> f = frames.next()) {
    const FrameFeatures features = extractor.extract(*f, seq.camera(), m.params().local_map.depth_range);
    const std::vector<KeyframeView> all = m.graph().views();
    const int current = m.currentKeyframe();
    const FrameDecision oracle = decideKeyframe(features, f->T_W_C, current, all, seq.camera(), params);
    sizes.push_back(m.graph().size());
    reports.push_back(rec.mapper->addFrame(*f));
    reports.back().touched_cells.clear();
    const FrameDecision& got = reports.back().decision;
    if (oracle.kind != FrameDecision::Kind::kUpdate) {
      ++searches;
      differ += got.kind != oracle.kind || got.keyframe != oracle.keyframe;
    }
    if (got.kind == FrameDecision::Kind::kNewKeyframe && oracle.kind == got.kind) {
      ++new_keyframes;
      auto want = edgesOfNewKeyframe(features, f->T_W_C, current, all, seq.camera(), params);
      const int id = reports.back().keyframe;
      auto have = m.graph().edges().neighbours(id);
      edges_differ += want != have;
    }
    if (reports.size() % 2 == 1) {
      rec.dense.push_back({features, f->T_W_C});
      rec.dense_views.push_back(
          {static_cast<int>(rec.dense_views.size()), &rec.dense.back().T_W_C, &rec.dense.back().features});
    }
    if (reports.size() % 100 == 0) rec.queries.push_back({features, f->T_W_C});
  }
  rec.views = m.graph().views();
  std::printf("%s: %zu frames, %zu keyframes, %d revisits, %zu query frames, dense graph of %zu\n", folder.c_str(),
              reports.size(), rec.views.size(), m.revisits(), rec.queries.size(), rec.dense.size());
  std::printf("index vs exhaustive search: %d of %d searching frames decided otherwise; %d of %d new keyframes "
              "got other edges\n",
              differ, searches, edges_differ, new_keyframes);
  printRunCost(reports, 8, 12, sizes);
  printRunCost(reports, 90, 110, sizes);
  return rec;
}

// The first state.range(0) keyframes of the chosen graph, their index, and the parameters.
struct SearchSetup {
  std::span<const KeyframeView> keyframes;
  KeyframeParams params;
  std::unique_ptr<KeyframeIndex> index;
};
SearchSetup searchSetup(const benchmark::State& state, const Recording& rec, bool dense) {
  const std::vector<KeyframeView>& views = dense ? rec.dense_views : rec.views;
  SearchSetup s{{views.data(), std::min<std::size_t>(state.range(0), views.size())},
                rec.mapper->params().keyframes,
                std::make_unique<KeyframeIndex>()};
  s.index->sync(s.keyframes);
  return s;
}

// CPU time per query in seconds (the iteration's time divided by the number of queries); Google
// Benchmark prints it with an SI prefix and an "s", e.g. 13.4ms.
benchmark::Counter perSearch(const Recording& rec) {
  return benchmark::Counter(static_cast<double>(rec.queries.size()),
                            benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// The keyframes one query considers: all (range(1) == 0) or the index's candidates.
std::vector<KeyframeView> considered(const SearchSetup& s, const Posed& q, bool use_index) {
  if (!use_index) return {s.keyframes.begin(), s.keyframes.end()};
  return s.index->candidates(q.features, q.T_W_C, s.keyframes, s.params.prefilter, {-1});
}

// One iteration = the loop-closure search of every query frame (current keyframe -1: nothing
// is updated first, every keyframe is a candidate) against the first range(0) keyframes;
// time_per_search is the CPU time of one, the index's query included.
void loopClosureSearch(benchmark::State& state, bool dense) {
  const Recording& rec = *g_recording;
  const SearchSetup s = searchSetup(state, rec, dense);
  const bool use_index = state.range(1) != 0;
  double matched = 0, searches = 0, candidates = 0;
  for (auto _ : state)
    for (const Posed& q : rec.queries) {
      const std::vector<KeyframeView> keyframes = considered(s, q, use_index);
      const FrameDecision d = decideKeyframe(q.features, q.T_W_C, -1, keyframes, rec.mapper->camera(), s.params);
      benchmark::DoNotOptimize(d);
      matched += d.matched;
      candidates += static_cast<double>(keyframes.size());
      searches += 1;
    }
  state.counters["keyframes"] = static_cast<double>(s.keyframes.size());
  state.counters["candidates"] = candidates / searches;
  state.counters["matched_per_search"] = matched / searches;
  state.counters["time_per_search"] = perSearch(rec);
}
void BM_LoopClosureSearch(benchmark::State& state) { loopClosureSearch(state, false); }
void BM_LoopClosureSearchDense(benchmark::State& state) { loopClosureSearch(state, true); }
BENCHMARK(BM_LoopClosureSearch)
    ->ArgNames({"keyframes", "index"})
    ->Args({10, 0})
    ->Args({10, 1})
    ->Args({100, 0})
    ->Args({100, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_LoopClosureSearchDense)
    ->ArgNames({"keyframes", "index"})
    ->Args({10, 0})
    ->Args({10, 1})
    ->Args({100, 0})
    ->Args({100, 1})
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

// The index's query alone (vocabulary descent and inverted file), on the dense graph.
void BM_IndexQueryDense(benchmark::State& state) {
  const Recording& rec = *g_recording;
  const SearchSetup s = searchSetup(state, rec, true);
  for (auto _ : state)
    for (const Posed& q : rec.queries) benchmark::DoNotOptimize(considered(s, q, true));
  state.counters["keyframes"] = static_cast<double>(s.keyframes.size());
  state.counters["time_per_search"] = perSearch(rec);
}
BENCHMARK(BM_IndexQueryDense)
    ->ArgNames({"keyframes"})
    ->Arg(10)
    ->Arg(100)
    ->Arg(1000)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

// The edges of a new keyframe (docs/method.md 5): the other search that visits every keyframe.
void BM_NewKeyframeEdgesDense(benchmark::State& state) {
  const Recording& rec = *g_recording;
  const SearchSetup s = searchSetup(state, rec, true);
  const bool use_index = state.range(1) != 0;
  for (auto _ : state)
    for (const Posed& q : rec.queries)
      benchmark::DoNotOptimize(
          edgesOfNewKeyframe(q.features, q.T_W_C, -1, considered(s, q, use_index), rec.mapper->camera(), s.params));
  state.counters["keyframes"] = static_cast<double>(s.keyframes.size());
  state.counters["time_per_search"] = perSearch(rec);
}
BENCHMARK(BM_NewKeyframeEdgesDense)
    ->ArgNames({"keyframes", "index"})
    ->Args({100, 0})
    ->Args({100, 1})
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

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
