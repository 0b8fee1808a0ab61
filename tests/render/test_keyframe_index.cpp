// The place-recognition index (vocabulary tree + inverted file) against the exhaustive search
// it replaces: the keyframe decision and a new keyframe's edges with the index's candidates
// must be those of trying every keyframe, on the built-in scene's 8-lap walk.
#include <algorithm>
#include <deque>
#include <random>

#include <gtest/gtest.h>

#include "mapping/keyframe/keyframe_index.h"
#include "mapping/synth/depth_noise.h"
#include "render/context.h"
#include "render/sequence_synth.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

cv::Mat randomDescriptors(int rows, std::mt19937* rng) {
  cv::Mat d(rows, 32, CV_8UC1);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < 32; ++c) d.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>((*rng)() & 0xff);
  return d;
}

TEST(Vocabulary, TrainingIsDeterministicAndNearDescriptorsShareAWord) {
  // 20 clusters of descriptors a few bits from their centre.
  std::mt19937 rng(1);
  const cv::Mat centres = randomDescriptors(20, &rng);
  cv::Mat d(0, 32, CV_8UC1);
  for (int i = 0; i < 4000; ++i) {
    cv::Mat row = centres.row(i % 20).clone();
    for (int flip = 0; flip < 6; ++flip)
      row.at<std::uint8_t>(0, rng() % 32) ^= static_cast<std::uint8_t>(1 << (rng() % 8));
    d.push_back(row);
  }
  std::vector<std::pair<int, int>> documents;
  for (int i = 0; i < 40; ++i) documents.emplace_back(i * 100, (i + 1) * 100);
  const VocabularyParams params{.branching = 4, .max_depth = 3, .min_per_word = 8};
  const Vocabulary a = Vocabulary::train(d, documents, params);
  const Vocabulary b = Vocabulary::train(d, documents, params);
  ASSERT_GT(a.words(), 10u);
  EXPECT_LE(a.words(), 64u);
  int same_as_centre = 0;
  for (int r = 0; r < d.rows; ++r) {
    EXPECT_EQ(a.wordOf(d.ptr<std::uint8_t>(r)), b.wordOf(d.ptr<std::uint8_t>(r)));
    same_as_centre += a.wordOf(d.ptr<std::uint8_t>(r)) == a.wordOf(centres.ptr<std::uint8_t>(r % 20));
  }
  EXPECT_GT(same_as_centre, d.rows * 9 / 10) << "descriptors 6 bits from a centre fall into its word";
  const BowVector bow = a.transform(d.rowRange(0, 100));
  float sum = 0;
  for (std::size_t i = 0; i < bow.size(); ++i) {
    sum += bow[i].second;
    if (i > 0) {
      EXPECT_LT(bow[i - 1].first, bow[i].first);
    }
  }
  EXPECT_NEAR(sum, 1.0f, 1e-5f);
}

struct Walk {
  PinholeCamera camera;
  std::vector<FrameFeatures> features;
  std::vector<Transform> poses;
};

// Every `stride`-th frame of the built-in scene's walk, rendered in memory with exact depth, reduced
// to its ORB features. (The sensor model's noise was half of this test's time and changed none of
// the walk's keyframes, searches or ranks.)
Walk renderWalk(int laps, int stride) {
  const BuiltinScene scene = makeBuiltinScene({.laps = laps});
  std::unique_ptr<render::Context> context = render::createOffscreenContext();
  render::MeshViewRenderer renderer(*context, scene.mesh, scene.camera);
  const FeatureExtractor extractor;
  Walk walk{scene.camera, {}, {}};
  for (std::size_t i = 0; i < scene.trajectory.size(); i += static_cast<std::size_t>(stride)) {
    const render::SyntheticView view = renderer.render(scene.trajectory[i].T_W_C);
    RgbdFrame frame;
    frame.rgb = view.rgb;
    frame.depth =
        simulateDepth(view.z_cos, scene.camera.depth_scale, {.model = DepthNoiseModel::kNone}, static_cast<int>(i));
    walk.features.push_back(extractor.extract(frame, scene.camera));
    walk.poses.push_back(scene.trajectory[i].T_W_C);
  }
  return walk;
}

// The walk's keyframe decisions as the exhaustive search makes them; at every frame that
// searches, the same search over the index's candidates must decide alike, and every new
// keyframe's edges must be the same: the goal is no difference at all.
TEST(KeyframeIndex, CandidatesDecideAsTheExhaustiveSearchOnTheEightLapWalk) {
  // Every 6th frame of the 2400 keeps the test short; bench_keyframe checks all frames.
  constexpr int kStride = 6;
  const Walk walk = renderWalk(8, kStride);
  const KeyframeParams params;
  KeyframeIndex index;
  std::vector<KeyframeView> views;
  int current = -1, searches = 0, differ = 0, edge_sets = 0, edges_differ = 0, worst_rank = 0, worst_edge_rank = 0;
  std::size_t max_candidates = 0;
  for (std::size_t i = 0; i < walk.features.size(); ++i) {
    const FrameFeatures& f = walk.features[i];
    const Transform& T = walk.poses[i];
    const FrameDecision all = decideKeyframe(f, T, current, views, walk.camera, params);
    if (all.kind == FrameDecision::Kind::kUpdate) {
      current = all.keyframe;
      continue;
    }
    index.sync(views);
    const std::vector<KeyframeView> candidates = index.candidates(f, T, views, params.prefilter, {current});
    max_candidates = std::max(max_candidates, candidates.size());
    const FrameDecision some = decideKeyframe(f, T, current, candidates, walk.camera, params);
    ++searches;
    if (some.kind != all.kind || some.keyframe != all.keyframe) ++differ;
    // How deep in the index's ranking the exhaustive answers lie (what max_*candidates must cover).
    const std::vector<int> by_words = index.ranked(f, T, views, params.prefilter);
    const std::vector<int> by_pose = index.nearestViews(f, T, views, params.prefilter);
    auto rank = [&](int id) {  // best of the two rankings
      if (id == current || by_words.empty()) return 0;
      auto rank_in = [&](const std::vector<int>& r) {
        const auto it = std::find(r.begin(), r.end(), id);
        return it == r.end() ? 1 << 20 : static_cast<int>(it - r.begin()) + 1;
      };
      return std::min(rank_in(by_words), rank_in(by_pose));
    };
    if (all.kind == FrameDecision::Kind::kRevisit) worst_rank = std::max(worst_rank, rank(all.keyframe));
    if (all.kind == FrameDecision::Kind::kNewKeyframe) {
      ++edge_sets;
      const auto edges = edgesOfNewKeyframe(f, T, current, views, walk.camera, params);
      for (const auto& [id, w] : edges) worst_edge_rank = std::max(worst_edge_rank, rank(id));
      edges_differ += edges != edgesOfNewKeyframe(f, T, current,
                                                  index.candidates(f, T, views, params.prefilter, {current},
                                                                   index.params().max_edge_candidates),
                                                  walk.camera, params);
      views.push_back({static_cast<int>(views.size()), &walk.poses[i], &walk.features[i]});
      current = views.back().id;
    } else {
      current = all.keyframe;
    }
  }
  std::printf("8-lap walk, every %dth frame: %zu frames, %zu keyframes, %d searches; the index's candidates "
              "(at most %zu) decide otherwise in %d, give other edges in %d of %d new keyframes; lowest rank "
              "(by words or by pose) of a revisited keyframe %d, of an edge %d\n",
              kStride, walk.features.size(), views.size(), searches, max_candidates, differ, edges_differ, edge_sets,
              worst_rank, worst_edge_rank);
  ASSERT_GT(views.size(), 64u) << "the walk must outgrow the first vocabulary";
  EXPECT_NE(index.vocabulary(), nullptr);
  EXPECT_EQ(differ, 0);
  EXPECT_EQ(edges_differ, 0);

  // A graph restored from a session rebuilds the same index from its keyframes alone.
  index.sync(views);
  KeyframeIndex rebuilt;
  rebuilt.sync(views);
  for (std::size_t i = 0; i < walk.features.size(); i += 40) {
    const auto a = index.candidates(walk.features[i], walk.poses[i], views, params.prefilter, {0});
    const auto b = rebuilt.candidates(walk.features[i], walk.poses[i], views, params.prefilter, {0});
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t j = 0; j < a.size(); ++j) EXPECT_EQ(a[j].id, b[j].id);
  }
}

}  // namespace
}  // namespace vdmap
