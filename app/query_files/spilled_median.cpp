#include "app/query_files/spilled_median.h"

#include <array>
#include <bit>
#include <cstdint>
#include <stdexcept>

#include "mapping/core/timing.h"

namespace vdmap::app {
namespace {

// Doubles as unsigned keys in the same order (negatives flipped whole, positives above them).
std::uint64_t key(double v) {
  const auto bits = std::bit_cast<std::uint64_t>(v);
  return bits >> 63 ? ~bits : bits | (std::uint64_t{1} << 63);
}
double value(std::uint64_t key) { return std::bit_cast<double>(key >> 63 ? key & ~(std::uint64_t{1} << 63) : ~key); }

}  // namespace

SpilledMedian::SpilledMedian(std::size_t memory_values) : memory_values_(std::max<std::size_t>(1, memory_values)) {}

void SpilledMedian::add(double v) {
  values_.push_back(v);
  if (values_.size() < memory_values_) return;
  if (!spill_) spill_.reset(std::tmpfile());
  if (!spill_ || std::fwrite(values_.data(), sizeof(double), values_.size(), spill_.get()) != values_.size())
    throw std::runtime_error("cannot write a temporary file for the median");
  spilled_ += values_.size();
  values_.clear();
}

template <typename F>
void SpilledMedian::forEach(const F& f) const {
  if (spill_) {
    std::rewind(spill_.get());
    std::vector<double> chunk(std::min<std::size_t>(spilled_, 65536));
    for (std::size_t left = spilled_; left > 0;) {
      const std::size_t n = std::min(left, chunk.size());
      if (std::fread(chunk.data(), sizeof(double), n, spill_.get()) != n)
        throw std::runtime_error("cannot read back the temporary file for the median");
      for (std::size_t i = 0; i < n; ++i) f(chunk[i]);
      left -= n;
    }
    std::fseek(spill_.get(), 0, SEEK_END);
  }
  for (const double v : values_) f(v);
}

double SpilledMedian::kth(std::size_t k) const {
  // Four passes of 16 bits: each counts the values under the prefix found so far by their next
  // 16 bits and keeps the bucket holding the k-th.
  std::uint64_t prefix = 0;
  std::vector<std::size_t> counts(std::size_t{1} << 16);
  for (int pass = 0; pass < 4; ++pass) {
    const int shift = 48 - 16 * pass;
    std::fill(counts.begin(), counts.end(), 0);
    forEach([&](double v) {
      const std::uint64_t kv = key(v);
      if (pass == 0 || kv >> (shift + 16) == prefix) ++counts[(kv >> shift) & 0xffff];
    });
    std::size_t bucket = 0;
    while (k >= counts[bucket]) k -= counts[bucket++];
    prefix = prefix << 16 | bucket;
  }
  return value(prefix);
}

double SpilledMedian::median() const {
  if (!spill_) return vdmap::median(values_);
  const std::size_t n = size();
  return n % 2 ? kth(n / 2) : 0.5 * (kth(n / 2 - 1) + kth(n / 2));
}

}  // namespace vdmap::app
