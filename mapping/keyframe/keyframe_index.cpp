#include "mapping/keyframe/keyframe_index.h"

#include <algorithm>
#include <cassert>

namespace vdmap {

void KeyframeIndex::train(std::span<const KeyframeView> keyframes, std::size_t count) {
  std::size_t total = 0;
  for (std::size_t i = 0; i < count; ++i) total += keyframes[i].features->size();
  const std::size_t stride = (total + params_.max_training_descriptors - 1) / params_.max_training_descriptors;
  cv::Mat rows(0, 32, CV_8UC1);
  std::vector<std::pair<int, int>> documents;
  std::size_t seen = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const int begin = rows.rows;
    const cv::Mat& d = keyframes[i].features->descriptors;
    for (int r = 0; r < d.rows; ++r, ++seen)
      if (seen % std::max<std::size_t>(stride, 1) == 0) rows.push_back(d.row(r));
    documents.emplace_back(begin, rows.rows);
  }
  bows_.clear();
  views_.clear();
  inverted_.clear();
  vocabulary_.reset();
  trained_on_ = count;
  if (rows.empty()) return;  // keyframes without features: nothing to index by
  vocabulary_ = Vocabulary::train(rows, documents, params_.vocabulary);
  inverted_.resize(vocabulary_->words());
}

namespace {

double medianKeypointDepth(const FrameFeatures& f) {
  std::vector<float> d;
  for (const float z : f.depth_m)
    if (z > 0) d.push_back(z);
  if (d.empty()) return 1.0;  // no depth: one metre ahead stands for the view
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

}  // namespace

void KeyframeIndex::index(const KeyframeView& keyframe) {
  const Transform& T = *keyframe.T_W_K;
  views_.push_back({T.translation(), T * Eigen::Vector3d(0, 0, medianKeypointDepth(*keyframe.features))});
  assert(keyframe.id == static_cast<int>(bows_.size()));
  bows_.push_back(vocabulary_ ? vocabulary_->transform(keyframe.features->descriptors) : BowVector{});
  for (const auto& [word, weight] : bows_.back()) inverted_[word].push_back({keyframe.id, weight});
}

void KeyframeIndex::sync(std::span<const KeyframeView> keyframes) {
  const std::size_t n = keyframes.size();
  std::size_t point = 0;  // the last training point reached
  for (std::size_t t = params_.first_training; t <= n; t *= params_.retrain_factor) point = t;
  if (point != 0 && point != trained_on_) train(keyframes, point);
  while (bows_.size() < n) index(keyframes[bows_.size()]);
}

std::vector<int> KeyframeIndex::ranked(const FrameFeatures& frame, const Transform& T_W_F,
                                       std::span<const KeyframeView> keyframes, const PosePrefilter& prefilter) const {
  assert(keyframes.size() == bows_.size());
  if (!vocabulary_) return {};
  // DBoW2's L1 score of two normalised vectors: the sum over shared words of the smaller weight.
  std::vector<float> score(keyframes.size(), 0.0f);
  std::vector<int> touched;
  for (const auto& [word, q] : vocabulary_->transform(frame.descriptors))
    for (const Posting& p : inverted_[word]) {
      if (score[p.keyframe] == 0.0f) touched.push_back(p.keyframe);
      score[p.keyframe] += std::min(q, p.weight);
    }
  std::vector<int> out;
  for (const int id : touched)
    if (prefilter.accepts(*keyframes[id].T_W_K, T_W_F)) out.push_back(id);
  std::sort(out.begin(), out.end(), [&](int a, int b) { return score[a] != score[b] ? score[a] > score[b] : a < b; });
  return out;
}

std::vector<int> KeyframeIndex::nearestViews(const FrameFeatures& frame, const Transform& T_W_F,
                                             std::span<const KeyframeView> keyframes,
                                             const PosePrefilter& prefilter) const {
  assert(keyframes.size() == views_.size());
  const Eigen::Vector3d centre = T_W_F.translation();
  const Eigen::Vector3d gaze = T_W_F * Eigen::Vector3d(0, 0, medianKeypointDepth(frame));
  std::vector<std::pair<double, int>> order;
  for (std::size_t i = 0; i < views_.size(); ++i)
    if (prefilter.accepts(*keyframes[i].T_W_K, T_W_F))
      order.emplace_back((views_[i].centre - centre).norm() + (views_[i].gaze - gaze).norm(), static_cast<int>(i));
  std::sort(order.begin(), order.end());
  std::vector<int> out;
  out.reserve(order.size());
  for (const auto& [d, id] : order) out.push_back(id);
  return out;
}

std::vector<KeyframeView> KeyframeIndex::candidates(const FrameFeatures& frame, const Transform& T_W_F,
                                                    std::span<const KeyframeView> keyframes,
                                                    const PosePrefilter& prefilter, std::initializer_list<int> always,
                                                    int max_count) const {
  std::vector<int> ids;
  if (!vocabulary_) {
    for (const KeyframeView& k : keyframes)
      if (prefilter.accepts(*k.T_W_K, T_W_F)) ids.push_back(k.id);
  } else {
    ids = ranked(frame, T_W_F, keyframes, prefilter);
    if (ids.size() > static_cast<std::size_t>(max_count)) ids.resize(static_cast<std::size_t>(max_count));
    std::vector<int> near = nearestViews(frame, T_W_F, keyframes, prefilter);
    if (near.size() > static_cast<std::size_t>(params_.nearest_views)) near.resize(params_.nearest_views);
    ids.insert(ids.end(), near.begin(), near.end());
  }
  for (const int id : always)
    if (id >= 0 && id < static_cast<int>(keyframes.size())) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  std::vector<KeyframeView> out;
  out.reserve(ids.size());
  for (const int id : ids) out.push_back(keyframes[id]);
  return out;
}

}  // namespace vdmap
