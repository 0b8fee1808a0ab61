#include "mapping/query/surface_index.h"

#include "mapping/core/parallel.h"

namespace vdmap {

struct SurfaceIndex::Impl {
  std::vector<EllipsoidGate> gates;
};

SurfaceIndex SurfaceIndex::build(const std::vector<Ellipsoid>& ellipsoids_W, const QueryParams& params) {
  auto impl = std::make_shared<Impl>();
  impl->gates.resize(ellipsoids_W.size());
  parallelFor(params.threads, ellipsoids_W.size(), [&](std::size_t i) {
    impl->gates[i] = makeGate(ellipsoids_W[i], params.gate_sigma, params.min_sigma_m);
  });
  SurfaceIndex index;
  index.impl_ = std::move(impl);
  return index;
}

std::size_t SurfaceIndex::size() const { return impl_ ? impl_->gates.size() : 0; }

std::size_t SurfaceIndex::memoryBytes() const {
  return impl_ ? impl_->gates.capacity() * sizeof(EllipsoidGate) : 0;
}

const EllipsoidGate& SurfaceIndex::gateOf(std::size_t i) const { return impl_->gates[i]; }

std::pair<std::int32_t, double> SurfaceIndex::gate(const Eigen::Vector3d& q_W) const {
  std::pair<std::int32_t, double> best{-1, std::numeric_limits<double>::infinity()};
  for (std::size_t i = 0; i < size(); ++i) {
    const EllipsoidGate& g = impl_->gates[i];
    const double m2 = gateDistance2(g, q_W);
    if (m2 <= g.k2 && m2 < best.second) best = {static_cast<std::int32_t>(i), m2};
  }
  return best;
}

SurfaceIndex::Nearest SurfaceIndex::nearest(const Eigen::Vector3d& q_W, double max_distance) const {
  Nearest best;
  const auto inside = gate(q_W);
  if (inside.first >= 0) {
    best.ellipsoid = inside.first, best.distance = 0, best.closest = q_W;
    return best;
  }
  for (std::size_t i = 0; i < size(); ++i) {
    Eigen::Vector3d x;
    const double d = distanceToGate(impl_->gates[i], q_W, &x);
    if (d < best.distance && d < max_distance) best = {static_cast<std::int32_t>(i), d, x};
  }
  return best;
}

SurfaceIndex::Hit SurfaceIndex::firstHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double max_t) const {
  Hit best;
  for (std::size_t i = 0; i < size(); ++i) {
    const EllipsoidGate& g = impl_->gates[i];
    const double t = gateRayEntry(g, gateRayOrigin(g, o), d, max_t);
    if (t < best.t) best = {static_cast<std::int32_t>(i), t};
  }
  return best;
}

}  // namespace vdmap
