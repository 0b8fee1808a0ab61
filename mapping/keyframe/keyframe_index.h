#pragma once
#include <optional>
#include <span>
#include <vector>

#include "mapping/keyframe/keyframe_selector.h"
#include "mapping/keyframe/vocabulary.h"

namespace vdmap {

/// How the place-recognition index is built and how many candidates it proposes.
struct KeyframeIndexParams {
  /// Keyframes proposed at most besides the `always` ones (the current keyframe), for the
  /// loop-closure search and for a new keyframe's edges (tau_edge is lower than tau, so more
  /// keyframes qualify; the edges are computed only when a keyframe is made).
  int max_candidates = 32;
  int max_edge_candidates = 64;
  /// Proposed besides, by pose: the keyframes whose view is nearest the frame's (camera centres
  /// plus the points their optical axes reach at the median keypoint depth). Poses are known, and
  /// a keyframe that shares a quarter of its features with the frame nearly always views the
  /// same spot from nearby, while repetitive texture can push it down the word ranking.
  int nearest_views = 32;
  /// The vocabulary is trained from the first N keyframes' descriptors when the graph reaches N
  /// = first_training, and again at every `retrain_factor` times that (32, 128, 512, ...), so
  /// the words follow the places seen; each (re)training re-indexes every keyframe.
  int first_training = 32;
  int retrain_factor = 4;
  int max_training_descriptors = 200000;  ///< evenly strided subset beyond this
  VocabularyParams vocabulary;
};

/// The keyframes a frame is compared with: an inverted index of visual words (vocabulary tree
/// over the keyframes' ORB descriptors, tf-idf, DBoW2's L1 score) proposing the best-scoring
/// keyframes that pass the pose pre-filter; the covisibility delta then decides among them
/// (decideKeyframe(), edgesOfNewKeyframe()). Query cost: one vocabulary descent per frame
/// descriptor plus the posting lists of the frame's words, not a match per keyframe.
///
/// Its state is a function of the keyframes' features alone (the training points depend only
/// on the keyframe count), so a graph restored from a session rebuilds it exactly: sync() it
/// with the keyframes. Not thread-safe for writes.
class KeyframeIndex {
 public:
  explicit KeyframeIndex(const KeyframeIndexParams& params = {}) : params_(params) {}

  /// Indexes `keyframes` (ids 0..n-1 in order) not yet indexed; trains or retrains the
  /// vocabulary when the count crosses a training point. Keyframe features must not change.
  void sync(std::span<const KeyframeView> keyframes);
  std::size_t indexed() const { return bows_.size(); }
  const Vocabulary* vocabulary() const { return vocabulary_ ? &*vocabulary_ : nullptr; }

  /// The keyframes to compare frame F with: `always` (the current keyframe; -1 for none), the
  /// nearest_views keyframes nearest by pose, and up to max_candidates others of the highest
  /// word score (ties to the lower id), all passing the pose pre-filter; every keyframe the
  /// pre-filter accepts until the vocabulary is trained (first_training keyframes). Sorted by
  /// id. Call sync() first.
  std::vector<KeyframeView> candidates(const FrameFeatures& frame, const Transform& T_W_F,
                                       std::span<const KeyframeView> keyframes, const PosePrefilter& prefilter,
                                       std::initializer_list<int> always) const {
    return candidates(frame, T_W_F, keyframes, prefilter, always, params_.max_candidates);
  }
  /// The same with at most `max_count` proposed.
  std::vector<KeyframeView> candidates(const FrameFeatures& frame, const Transform& T_W_F,
                                       std::span<const KeyframeView> keyframes, const PosePrefilter& prefilter,
                                       std::initializer_list<int> always, int max_count) const;
  /// Every keyframe the pre-filter accepts that shares a word with the frame, best score first
  /// (ties to the lower id); empty before the vocabulary is trained. For tests and diagnostics.
  std::vector<int> ranked(const FrameFeatures& frame, const Transform& T_W_F, std::span<const KeyframeView> keyframes,
                          const PosePrefilter& prefilter) const;
  /// Every keyframe the pre-filter accepts, nearest view first (ties to the lower id).
  std::vector<int> nearestViews(const FrameFeatures& frame, const Transform& T_W_F,
                                std::span<const KeyframeView> keyframes, const PosePrefilter& prefilter) const;
  const KeyframeIndexParams& params() const { return params_; }

 private:
  void train(std::span<const KeyframeView> keyframes, std::size_t count);
  void index(const KeyframeView& keyframe);

  KeyframeIndexParams params_;
  std::optional<Vocabulary> vocabulary_;
  std::size_t trained_on_ = 0;
  std::vector<BowVector> bows_;  ///< per indexed keyframe
  struct ViewPoints {
    Eigen::Vector3d centre, gaze;  ///< camera centre, optical axis at the median keypoint depth (world)
  };
  std::vector<ViewPoints> views_;  ///< per indexed keyframe
  struct Posting {
    int keyframe;
    float weight;
  };
  std::vector<std::vector<Posting>> inverted_;  ///< per word, ascending keyframe id
};

}  // namespace vdmap
