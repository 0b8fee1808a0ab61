// Covisibility (docs/method.md 5) and the per-frame keyframe decision, on an analytic textured
// room whose frames are ray-cast exactly, so poses and depths are known.
#include <random>

#include <gtest/gtest.h>

#include "mapping/io/camera_config.h"
#include "mapping/keyframe/covisibility_graph.h"
#include "mapping/keyframe/keyframe_selector.h"
#include "tests/support/test_util.h"

namespace vdmap {
namespace {

struct View {
  Transform T_W_C;
  FrameFeatures features;
};

class Covisibility : public ::testing::Test {
 protected:
  View view(const Transform& T_W_C) {
    return {T_W_C, extractor_.extract(test::renderBoxRoom(camera_, T_W_C), camera_)};
  }
  double delta(const View& K, const View& F, const CovisibilityParams& p = {}) {
    return covisibility(K.features, K.T_W_C, F.features, F.T_W_C, camera_, p);
  }
  PinholeCamera camera_ = cameraPreset("tum-default");
  FeatureExtractor extractor_;
};

TEST_F(Covisibility, SameViewIsAlmostFullyReobserved) {
  const View a = view(test::lookAt({0, 0, 0}, {0, 0, 2}));
  ASSERT_GT(a.features.size(), 500u);
  EXPECT_GT(delta(a, a), 0.9);
}

TEST_F(Covisibility, NearbyViewsOfOneWallShareFeaturesOppositeViewsDoNot) {
  const View a = view(test::lookAt({0, 0, 0}, {0, 0, 2}));
  const View b = view(test::lookAt({0.1, 0.05, 0.1}, {0.3, 0, 2}));
  const View back = view(test::lookAt({0, 0, 0}, {0, 0, -2}));
  EXPECT_GE(delta(a, b), 0.25);
  EXPECT_LT(delta(a, back), 0.02);  // a different wall: chance descriptor matches only
  KeyframeParams params;
  const std::vector<KeyframeView> keyframes = {{0, &a.T_W_C, &a.features}};
  EXPECT_EQ(edgesOfNewKeyframe(b.features, b.T_W_C, -1, keyframes, camera_, params).size(), 1u);
  EXPECT_TRUE(edgesOfNewKeyframe(back.features, back.T_W_C, -1, keyframes, camera_, params).empty());
  EXPECT_FALSE(params.prefilter.accepts(a.T_W_C, back.T_W_C));
}

TEST_F(Covisibility, PoseCheckRejectsMatchesThatDisagreeWithThePoses) {
  const View a = view(test::lookAt({0, 0, 0}, {0, 0, 2}));
  View wrong = a;
  wrong.T_W_C.translation() += Eigen::Vector3d(0.3, 0, 0);  // same image, pose off by 30 cm
  EXPECT_LT(delta(a, wrong), 0.05);
  CovisibilityParams loose;
  loose.max_reprojection_px = 1e9;  // descriptor test only
  EXPECT_GT(delta(a, wrong, loose), 0.9);
}

TEST_F(Covisibility, BoundIsNeverBelowTheMeasure) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> pos(-0.8, 0.8), dir(-2, 2);
  const View k = view(test::lookAt({0, 0, 0}, {0.2, 0.1, 2}));
  for (int i = 0; i < 8; ++i) {
    const View f = view(test::lookAt({pos(rng), pos(rng), pos(rng)}, {dir(rng), dir(rng), 2}));
    EXPECT_GE(covisibilityBound(k.features, k.T_W_C, f.T_W_C, camera_) + 1e-12, delta(k, f));
  }
}

TEST_F(Covisibility, DecisionEqualsExhaustiveSearch) {
  // Keyframes around the room; frames anywhere. The pruned search must pick what trying every
  // keyframe picks.
  std::vector<View> keys;
  for (int i = 0; i < 6; ++i) {
    const double a = i * M_PI / 3;
    keys.push_back(
        view(test::lookAt({0.3 * std::cos(a), 0, 0.3 * std::sin(a)}, {2 * std::cos(a), 0.2, 2 * std::sin(a)})));
  }
  std::vector<KeyframeView> views;
  for (int i = 0; i < 6; ++i) views.push_back({i, &keys[i].T_W_C, &keys[i].features});
  KeyframeParams params;
  params.prefilter.enabled = false;
  for (int j = 0; j < 6; ++j) {
    const double a = j * M_PI / 3 + 0.15;
    const View f =
        view(test::lookAt({0.25 * std::cos(a), 0.05, 0.25 * std::sin(a)}, {2 * std::cos(a), 0, 2 * std::sin(a)}));
    const int current = (j + 3) % 6;  // the opposite keyframe: forces the loop-closure search
    int best = -1;
    double best_delta = 0;
    for (int i = 0; i < 6; ++i) {
      if (i == current) continue;
      const double d = delta(keys[i], f);
      if (d >= params.tau && d > best_delta) best = i, best_delta = d;
    }
    const FrameDecision decision = decideKeyframe(f.features, f.T_W_C, current, views, camera_, params);
    EXPECT_EQ(decision.keyframe, best) << "frame " << j;
    EXPECT_EQ(decision.kind, best >= 0 ? FrameDecision::Kind::kRevisit : FrameDecision::Kind::kNewKeyframe);
    EXPECT_GT(decision.pruned, 0) << "the bound should spare some matching";
  }
}

TEST_F(Covisibility, TexturelessFrameUpdatesCurrentKeyframeWhenPosesAgree) {
  const View k = view(test::lookAt({0, 0, 0}, {0, 0, 2}));
  const std::vector<KeyframeView> keyframes = {{4, &k.T_W_C, &k.features}};
  FrameFeatures blank;  // what ORB finds on a uniform wall: nothing
  const KeyframeParams params;
  Transform near = k.T_W_C;
  near.translation().x() += 0.2;
  EXPECT_EQ(decideKeyframe(blank, near, 4, keyframes, camera_, params).kind, FrameDecision::Kind::kUpdate);
  Transform far = k.T_W_C;
  far.translation().x() += 5.0;
  EXPECT_EQ(decideKeyframe(blank, far, 4, keyframes, camera_, params).kind, FrameDecision::Kind::kNewKeyframe);
  FeatureExtractor extractor;
  RgbdFrame uniform = test::renderBoxRoom(camera_, k.T_W_C);
  uniform.rgb.setTo(cv::Scalar(128, 128, 128));
  EXPECT_EQ(extractor.extract(uniform, camera_).size(), 0u);
}

TEST(CovisibilityGraph, StrengthenKeepsTheLargerWeightAndNeighboursAreSorted) {
  CovisibilityGraph g;
  g.strengthen(3, 1, 0.2);
  g.strengthen(1, 3, 0.1);
  g.strengthen(1, 2, 0.5);
  EXPECT_DOUBLE_EQ(g.weight(3, 1), 0.2);
  EXPECT_EQ(g.size(), 2u);
  const auto n = g.neighbours(1);
  ASSERT_EQ(n.size(), 2u);
  EXPECT_EQ(n[0].first, 2);
  EXPECT_EQ(n[1].first, 3);
  EXPECT_EQ(g.edges()[0].a, 1);
  EXPECT_FALSE(g.hasEdge(2, 3));
}

}  // namespace
}  // namespace vdmap
