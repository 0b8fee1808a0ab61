#pragma once
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace vdmap {

/// Shape of a vocabulary tree.
struct VocabularyParams {
  int branching = 10;       ///< children per node (k)
  int max_depth = 4;        ///< levels below the root (L); at most k^L words
  int min_per_word = 16;    ///< a node with fewer training descriptors than k * this is a leaf
  int max_iterations = 10;  ///< k-majority rounds per node
};

/// A bag-of-words vector: (word, weight) sorted by word, weights summing to 1 (tf-idf, L1).
using BowVector = std::vector<std::pair<int, float>>;

/// A vocabulary tree over 32-byte binary ORB descriptors (Nister & Stewenius 2006; the binary
/// variant of Galvez-Lopez & Tardos 2012, DBoW2): hierarchical k-majority clustering, a word
/// per leaf, idf weights from the training documents. Built by the project from the sequence's
/// own keyframes; nothing is downloaded. Immutable after train(); safe to read from any thread.
class Vocabulary {
 public:
  /// Clusters the rows of `descriptors` (CV_8UC1, 32 columns; at least one). `documents` holds
  /// the row ranges [begin, end) of the images they came from (for idf). Deterministic: k-means++
  /// seeding from a fixed-seed generator, lower index on ties.
  static Vocabulary train(const cv::Mat& descriptors, const std::vector<std::pair<int, int>>& documents,
                          const VocabularyParams& params = {});

  std::size_t words() const { return idf_.size(); }
  /// The leaf a descriptor falls into (greedy descent, nearest child at each level).
  int wordOf(const std::uint8_t* descriptor) const;
  /// The tf-idf vector of one image's descriptors (empty for none).
  BowVector transform(const cv::Mat& descriptors) const;

 private:
  struct Node {
    std::array<std::uint8_t, 32> centroid{};
    int first_child = -1;  ///< children are nodes [first_child, first_child + children)
    int children = 0;
    int word = -1;  ///< leaves only
  };
  std::vector<Node> nodes_;  ///< nodes_[0] is the root
  std::vector<float> idf_;   ///< per word
};

}  // namespace vdmap
