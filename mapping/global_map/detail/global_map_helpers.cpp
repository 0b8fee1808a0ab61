#include "mapping/global_map/detail/global_map_helpers.h"

#include <numeric>

#include "mapping/core/parallel.h"

namespace vdmap::global_map_detail {

std::vector<double> largestEigenvalues(const std::vector<Ellipsoid>& ellipsoids, int threads) {
  std::vector<double> lambda_max(ellipsoids.size());
  parallelFor(threads, ellipsoids.size(),
              [&](std::size_t i) { lambda_max[i] = largestEigenvalue(floored(ellipsoids[i].cov)); });
  return lambda_max;
}

std::vector<const Ellipsoid*> addressesOf(const std::vector<Ellipsoid>& ellipsoids) {
  std::vector<const Ellipsoid*> out(ellipsoids.size());
  for (std::size_t i = 0; i < ellipsoids.size(); ++i) out[i] = &ellipsoids[i];
  return out;
}

void bucketByKey(const std::vector<int>& keys, std::size_t buckets, Buckets* b, std::vector<int>* fill) {
  b->start.assign(buckets + 1, 0);
  for (int k : keys)
    if (k >= 0) ++b->start[static_cast<std::size_t>(k) + 1];
  std::partial_sum(b->start.begin(), b->start.end(), b->start.begin());
  b->order.resize(static_cast<std::size_t>(b->start.back()));
  fill->assign(b->start.begin(), b->start.end() - 1);
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (keys[i] >= 0)
      b->order[static_cast<std::size_t>((*fill)[static_cast<std::size_t>(keys[i])]++)] = static_cast<int>(i);
}

}  // namespace vdmap::global_map_detail
