#include "app/bench/bench_method.h"

#include <cmath>
#include <cstdio>

namespace vdmap::app {

MethodResult peerRow(const std::string& name, const std::string& key, double res_m, const std::string& note) {
  char n[64], k[64];
  std::snprintf(n, sizeof n, "%s %.2f m", name.c_str(), res_m);
  std::snprintf(k, sizeof k, "%s_%03d", key.c_str(), static_cast<int>(std::lround(res_m * 100)));
  return MethodResult(n, k, 0.0, note);
}

void BenchInput::score(MethodResult* r, const std::vector<Eigen::Vector3f>& points) const {
  r->elements = points.size();
  if (!mesh) return;
  AccuracyParams p;
  p.completion_samples = args.completion_samples;
  r->accuracy = evaluateAccuracy(points, *mesh, p);
}

}  // namespace vdmap::app
