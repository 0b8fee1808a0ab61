// The level-of-detail order of the 3-D view's fast pass (render/lod_order.h): a deterministic
// permutation whose prefix is a spatially even sample of the map.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

#include "render/lod_order.h"

namespace vdmap::render {
namespace {

// A dense floor (2 x 2 m, 1 cm apart: 40k centres) and a sparse column of 20 centres far above it.
std::vector<glm::vec3> floorAndColumn() {
  std::vector<glm::vec3> out;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.004f, 0.004f);
  for (int j = 0; j < 200; ++j)
    for (int i = 0; i < 200; ++i) out.push_back({0.01f * i + jitter(rng), 0.01f * j + jitter(rng), jitter(rng)});
  for (int k = 0; k < 20; ++k) out.push_back({5.f, 5.f, 0.5f * k});
  std::shuffle(out.begin(), out.end(), rng);
  return out;
}

std::tuple<long, long, long> cell(const glm::vec3& p, float size) {
  return {std::lround(std::floor(p.x / size)), std::lround(std::floor(p.y / size)),
          std::lround(std::floor(p.z / size))};
}

TEST(LodOrder, IsAPermutationAndDeterministic) {
  std::vector<glm::vec3> centres = floorAndColumn();
  centres.push_back({NAN, 0.f, 0.f});  // a broken centre comes last
  const std::vector<std::uint32_t> order = lodOrder(centres);
  ASSERT_EQ(order.size(), centres.size());
  std::vector<std::uint32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  EXPECT_EQ(order.back(), centres.size() - 1);
  EXPECT_EQ(lodOrder(centres), order);
  EXPECT_TRUE(lodOrder(std::span<const glm::vec3>{}).empty());
}

TEST(LodOrder, APrefixCoversEveryOccupied32cmCell) {
  const std::vector<glm::vec3> centres = floorAndColumn();
  const std::vector<std::uint32_t> order = lodOrder(centres);
  for (const float size : kLodCellSizesM) {
    std::set<std::tuple<long, long, long>> occupied;
    for (const glm::vec3& p : centres) occupied.insert(cell(p, size));
    // The order's first |occupied cells of this level| entries cover them all (coarser levels'
    // picks are one per coarser cell, so at most that many come first).
    std::set<std::tuple<long, long, long>> covered;
    for (std::size_t i = 0; i < occupied.size(); ++i) covered.insert(cell(centres[order[i]], size));
    EXPECT_EQ(covered.size(), occupied.size()) << "cells of " << size << " m";
  }
  // The 20 column centres, one per 50 cm, are all within the first 32 cm level: the sparse part
  // of the map is never thinned away.
  std::size_t column_first = 0;
  std::set<std::tuple<long, long, long>> coarse;
  for (const glm::vec3& p : centres) coarse.insert(cell(p, 0.32f));
  for (std::size_t i = 0; i < coarse.size(); ++i) column_first += centres[order[i]].x == 5.f;
  EXPECT_EQ(column_first, 20u);
}

}  // namespace
}  // namespace vdmap::render
