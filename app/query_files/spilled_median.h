#pragma once
// The median of more values than should be held in memory: the summary of `vdmap query` over a
// points file of any size.
#include <cstddef>
#include <cstdio>
#include <memory>
#include <vector>

namespace vdmap::app {

/// Collects values (no NaN) and gives their median exactly as median() of a vector of them
/// would, holding at most `memory_values` of them in memory: the rest go to a temporary file
/// (removed when this is destroyed), from which the median is selected by radix in a few passes.
class SpilledMedian {
 public:
  explicit SpilledMedian(std::size_t memory_values = std::size_t{1} << 18);
  void add(double v);
  std::size_t size() const { return spilled_ + values_.size(); }
  /// 0 for no values, as median(). Throws std::runtime_error when the temporary file fails.
  double median() const;

 private:
  double kth(std::size_t k) const;  // the k-th smallest value, from 0
  template <typename F>
  void forEach(const F& f) const;

  std::size_t memory_values_;
  std::vector<double> values_;
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> spill_{nullptr, &std::fclose};
  std::size_t spilled_ = 0;
};

}  // namespace vdmap::app
