// The built-in scene end to end (always runs: it is generated in code): its walk returns to the
// start, so the keyframe graph must close the loop by revisiting an early keyframe.
#include <gtest/gtest.h>

#include "mapping/global_map/global_map.h"
#include "mapping/io/frame_prefetcher.h"
#include "mapping/keyframe/mapper.h"
#include "render/sequence_synth.h"
#include "tests/test_util.h"

namespace vdmap {
namespace {

TEST(BuiltinScene, TheWalkBackToTheStartRevisitsTheFirstKeyframes) {
  test::TempDir dir;
  render::writeBuiltinSequence(dir / "builtin");
  const TumSequence seq = TumSequence::open(dir / "builtin");
  Mapper mapper(seq.camera());
  FramePrefetcher frames(seq);
  FrameReport last;
  while (auto f = frames.next()) last = mapper.addFrame(*f);
  const KeyframeGraph& graph = mapper.graph();
  EXPECT_GT(mapper.revisits(), 0);
  // The walk ends where it started: the last frame updates a keyframe made in the first tenth
  // of the walk instead of starting a new one.
  EXPECT_NE(last.decision.kind, FrameDecision::Kind::kNewKeyframe);
  EXPECT_LT(graph.keyframe(last.keyframe).frame_index, static_cast<int>(seq.size()) / 10);
  EXPECT_TRUE(graph.edges().hasEdge(last.keyframe, static_cast<int>(graph.size()) - 1))
      << "the loop closure links the last keyframe to the first";
  const GlobalMap global = buildGlobalMap(graph, {});
  EXPECT_GT(global.sigma_e_prime, 0u);
  EXPECT_LT(global.sigma_e_prime, global.sigma_e);
  std::printf("built-in scene: %zu frames, %zu keyframes, %d revisits, Sigma_e %zu -> %zu\n", seq.size(),
              graph.size(), mapper.revisits(), global.sigma_e, global.sigma_e_prime);
}

}  // namespace
}  // namespace vdmap
