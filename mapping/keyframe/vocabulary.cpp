#include "mapping/keyframe/vocabulary.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>
#include <random>

#include "mapping/keyframe/projection_matcher.h"

namespace vdmap {
namespace {

using Centroid = std::array<std::uint8_t, 32>;

const std::uint8_t* row(const cv::Mat& m, int i) { return m.ptr<std::uint8_t>(i); }

// Nearest of `centroids` (lower index on ties) for every member; returns whether any changed.
__attribute__((target_clones("popcnt", "default"))) bool assign(const cv::Mat& d, const std::vector<int>& members,
                                                                const std::vector<Centroid>& centroids,
                                                                std::vector<int>* label) {
  bool changed = false;
  for (std::size_t m = 0; m < members.size(); ++m) {
    int best = 0, best_d = 257;
    for (std::size_t c = 0; c < centroids.size(); ++c) {
      const int dist = orbDistance(row(d, members[m]), centroids[c].data());
      if (dist < best_d) best_d = dist, best = static_cast<int>(c);
    }
    changed |= (*label)[m] != best;
    (*label)[m] = best;
  }
  return changed;
}

// k-means++ seeding: the first seed at random, then each next one with probability
// proportional to the squared distance to the nearest seed so far.
__attribute__((target_clones("popcnt", "default"))) std::vector<Centroid> seeds(const cv::Mat& d,
                                                                                const std::vector<int>& members, int k,
                                                                                std::mt19937* rng) {
  std::vector<Centroid> out;
  std::vector<double> nearest_sq(members.size(), 1e300);
  int next = static_cast<int>((*rng)() % members.size());
  while (static_cast<int>(out.size()) < k) {
    Centroid c;
    std::copy_n(row(d, members[next]), 32, c.begin());
    out.push_back(c);
    double total = 0;
    for (std::size_t m = 0; m < members.size(); ++m) {
      const double dist = orbDistance(row(d, members[m]), c.data());
      nearest_sq[m] = std::min(nearest_sq[m], dist * dist);
      total += nearest_sq[m];
    }
    if (total == 0) break;  // fewer distinct descriptors than k
    double pick = total * ((*rng)() / 4294967296.0);
    next = static_cast<int>(members.size()) - 1;
    for (std::size_t m = 0; m < members.size(); ++m) {
      pick -= nearest_sq[m];
      if (pick < 0) {
        next = static_cast<int>(m);
        break;
      }
    }
  }
  return out;
}

// Bitwise majority of the members labelled `cluster` (a bit is set when more than half have it).
Centroid majority(const cv::Mat& d, const std::vector<int>& members, const std::vector<int>& label, int cluster) {
  std::array<int, 256> ones{};
  int n = 0;
  for (std::size_t m = 0; m < members.size(); ++m) {
    if (label[m] != cluster) continue;
    ++n;
    const std::uint8_t* p = row(d, members[m]);
    for (int b = 0; b < 256; ++b) ones[b] += (p[b >> 3] >> (7 - (b & 7))) & 1;
  }
  Centroid c{};
  for (int b = 0; b < 256; ++b)
    if (2 * ones[b] > n) c[b >> 3] |= static_cast<std::uint8_t>(1 << (7 - (b & 7)));
  return c;
}

}  // namespace

Vocabulary Vocabulary::train(const cv::Mat& d, const std::vector<std::pair<int, int>>& documents,
                             const VocabularyParams& params) {
  assert(d.type() == CV_8UC1 && d.cols == 32 && d.rows > 0 && params.branching >= 2);
  Vocabulary v;
  std::mt19937 rng(16);
  std::vector<int> leaf_of_row(static_cast<std::size_t>(d.rows), -1);
  struct Pending {
    int node, depth;
    std::vector<int> members;
  };
  std::vector<Pending> stack;
  std::vector<int> all(static_cast<std::size_t>(d.rows));
  std::iota(all.begin(), all.end(), 0);
  v.nodes_.push_back({});
  stack.push_back({0, 0, std::move(all)});
  while (!stack.empty()) {
    Pending p = std::move(stack.back());
    stack.pop_back();
    const int k = params.branching;
    if (p.depth >= params.max_depth || static_cast<int>(p.members.size()) < k * params.min_per_word) {
      v.nodes_[p.node].word = static_cast<int>(v.idf_.size());
      v.idf_.push_back(0.0f);
      for (const int m : p.members) leaf_of_row[m] = v.nodes_[p.node].word;
      continue;
    }
    std::vector<Centroid> centroids = seeds(d, p.members, k, &rng);
    std::vector<int> label(p.members.size(), -1);
    for (int it = 0; it < params.max_iterations && assign(d, p.members, centroids, &label); ++it)
      for (std::size_t c = 0; c < centroids.size(); ++c)
        centroids[c] = majority(d, p.members, label, static_cast<int>(c));
    // Children: the non-empty clusters, in cluster order.
    std::vector<std::vector<int>> split(centroids.size());
    for (std::size_t m = 0; m < p.members.size(); ++m) split[label[m]].push_back(p.members[m]);
    const int first = static_cast<int>(v.nodes_.size());
    int children = 0;
    for (std::size_t c = 0; c < split.size(); ++c) {
      if (split[c].empty()) continue;
      Node child;
      child.centroid = centroids[c];
      v.nodes_.push_back(child);
      ++children;
    }
    v.nodes_[p.node].first_child = first;
    v.nodes_[p.node].children = children;
    // Deepest-first order does not matter for the result: every node's members are fixed here.
    for (std::size_t c = split.size(), slot = children; c-- > 0;) {
      if (split[c].empty()) continue;
      stack.push_back({first + static_cast<int>(--slot), p.depth + 1, std::move(split[c])});
    }
  }
  // idf = log(documents / documents holding the word).
  std::vector<int> holding(v.idf_.size(), 0), last_doc(v.idf_.size(), -1);
  for (std::size_t doc = 0; doc < documents.size(); ++doc)
    for (int r = documents[doc].first; r < documents[doc].second; ++r) {
      const int w = leaf_of_row[r];
      if (last_doc[w] != static_cast<int>(doc)) ++holding[w], last_doc[w] = static_cast<int>(doc);
    }
  for (std::size_t w = 0; w < v.idf_.size(); ++w)
    v.idf_[w] = holding[w] > 0 ? static_cast<float>(std::log(double(documents.size()) / holding[w])) : 0.0f;
  return v;
}

__attribute__((target_clones("popcnt", "default"))) int Vocabulary::wordOf(const std::uint8_t* descriptor) const {
  int node = 0;
  while (nodes_[node].children > 0) {
    const Node& n = nodes_[node];
    int best = n.first_child, best_d = 257;
    for (int c = n.first_child; c < n.first_child + n.children; ++c) {
      const int dist = orbDistance(descriptor, nodes_[c].centroid.data());
      if (dist < best_d) best_d = dist, best = c;
    }
    node = best;
  }
  return nodes_[node].word;
}

BowVector Vocabulary::transform(const cv::Mat& descriptors) const {
  BowVector bow;
  if (descriptors.empty()) return bow;
  std::vector<int> words(static_cast<std::size_t>(descriptors.rows));
  for (int r = 0; r < descriptors.rows; ++r) words[r] = wordOf(row(descriptors, r));
  std::sort(words.begin(), words.end());
  double total = 0;
  for (std::size_t i = 0; i < words.size();) {
    std::size_t j = i;
    while (j < words.size() && words[j] == words[i]) ++j;
    const float w = static_cast<float>(j - i) * idf_[words[i]];
    if (w > 0) bow.emplace_back(words[i], w), total += w;
    i = j;
  }
  for (auto& [word, weight] : bow) weight = static_cast<float>(weight / total);
  return bow;
}

}  // namespace vdmap
