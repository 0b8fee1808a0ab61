// QueryMap: building, parameters and classification (docs/method.md 13.1-13.3). Distance,
// collision and rays are in query_map_surface.cpp.
#include "mapping/query/query_map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "mapping/core/message_text.h"
#include "mapping/core/parallel.h"
#include "mapping/query/detail/query_map_data.h"

namespace vdmap {
namespace {

/// Chi-square CDF with 3 degrees of freedom: erf(sqrt(x/2)) - sqrt(2x/pi) e^(-x/2).
double chi2Cdf3(double x) {
  if (!(x > 0.0)) return 0.0;
  return std::erf(std::sqrt(0.5 * x)) - std::sqrt(2.0 * x / M_PI) * std::exp(-0.5 * x);
}

/// docs/method.md 13.3: occupied at squared gate distance m2 -> 0.5 + 0.5 (1 - F_chi2_3(m2)).
float pOccupied(double m2) { return static_cast<float>(0.5 + 0.5 * (1.0 - chi2Cdf3(m2))); }
/// Free at depth z (< -k) in front of the surface -> Phi(z).
float pFree(double z) { return static_cast<float>(0.5 * std::erfc(-z / std::sqrt(2.0))); }

Classification fromVerdict(const ViewVerdict& v, int keyframe) {
  Classification c;
  c.state = v.state;
  if (v.state == Occupancy::kFree) c.p_occupied = pFree(v.z);
  if (v.state == Occupancy::kOccupied) c.p_occupied = pOccupied(v.m2);
  if (v.state != Occupancy::kUnknown) c.keyframe = keyframe;
  return c;
}

void checkPoints(std::span<const Eigen::Vector3d> q_W, std::size_t out_size) {
  if (out_size != q_W.size())
    throw std::invalid_argument("classify: " + std::to_string(q_W.size()) + " points but " + std::to_string(out_size) +
                                " outputs");
  for (std::size_t i = 0; i < q_W.size(); ++i)
    if (!q_W[i].allFinite()) throw std::invalid_argument("point " + std::to_string(i) + " is not finite");
}

void checkKeyframe(int keyframe, std::size_t keyframes) {
  if (keyframe < 0 || static_cast<std::size_t>(keyframe) >= keyframes)
    throw std::invalid_argument("keyframe " + std::to_string(keyframe) + " is not in the map (" +
                                counted(static_cast<long long>(keyframes), "keyframe") + ")");
}

/// body(i) for i in [0, n) through parallelFor in chunks of 1024 points (a point is cheap: a
/// task per point would cost as much as the point).
template <typename Body>
void forEachPoint(int threads, std::size_t n, const Body& body) {
  constexpr std::size_t kChunk = 1024;
  parallelFor(threads, (n + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    for (std::size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i) body(i);
  });
}

}  // namespace

const char* occupancyName(Occupancy state) {
  switch (state) {
    case Occupancy::kFree: return "free";
    case Occupancy::kOccupied: return "occupied";
    case Occupancy::kUnknown: break;
  }
  return "unknown";
}

void QueryParams::validate() const {
  if (!(std::isfinite(gate_sigma) && gate_sigma > 0.0 && gate_sigma <= kMaxGateSigma))
    throw std::invalid_argument("gate_sigma must be > 0 and at most " + shortNumber(kMaxGateSigma) + ", got " +
                                shortNumber(gate_sigma));
  if (!(std::isfinite(min_sigma_m) && min_sigma_m > 0.0 && min_sigma_m <= kMaxMinSigmaM))
    throw std::invalid_argument("min_sigma_m must be > 0 and at most " + shortNumber(kMaxMinSigmaM) + " m, got " +
                                shortNumber(min_sigma_m));
  if (conflict != ConflictRule::kOccupied && conflict != ConflictRule::kRecent && conflict != ConflictRule::kPrecise)
    throw std::invalid_argument("conflict must be occupied, recent or precise");
  if (threads < 0 || threads > kMaxThreads)
    throw std::invalid_argument("threads must be within 0.." + std::to_string(kMaxThreads));
}

QueryMap::QueryMap() : data_(std::make_shared<const Data>()) {}

QueryMap QueryMap::build(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& params,
                         std::span<const int> keyframe_rank) {
  params.validate();
  if (global.kept.size() != graph.size())
    throw std::invalid_argument("the global map was built from " + std::to_string(global.kept.size()) +
                                " keyframes, the graph has " + std::to_string(graph.size()));
  auto data = std::make_shared<Data>();
  data->params = params;
  data->views = KeyframeViews::build(graph, global, params, keyframe_rank);
  data->surface = SurfaceIndex::build(global.ellipsoids, params);
  QueryMap out;
  out.data_ = std::move(data);
  return out;
}

const QueryParams& QueryMap::params() const { return data_->params; }
bool QueryMap::empty() const { return keyframes() == 0 && ellipsoids() == 0; }
std::size_t QueryMap::keyframes() const { return data_->views.size(); }
std::size_t QueryMap::ellipsoids() const { return data_->surface.size(); }
std::size_t QueryMap::memoryBytes() const {
  const MemoryParts parts = memoryParts();
  return sizeof(Data) + parts.keyframe_views + parts.frames + parts.surface;
}
QueryMap::MemoryParts QueryMap::memoryParts() const {
  return {data_->views.memoryBytes(), data_->views.frameMemoryBytes(), data_->surface.memoryBytes()};
}
void QueryMap::seenBounds(Eigen::Vector3d* lo, Eigen::Vector3d* hi) const { data_->views.seenBounds(lo, hi); }

void QueryMap::classify(std::span<const Eigen::Vector3d> q_W, std::span<Classification> out) const {
  checkPoints(q_W, out.size());
  const Data& d = *data_;
  forEachPoint(d.params.threads, q_W.size(), [&](std::size_t i) {
    const Eigen::Vector3d& q = q_W[i];
    if (d.params.conflict == ConflictRule::kOccupied) {
      // docs/method.md 13.2: the global map's gates decide occupied, the keyframes' views free.
      const auto [ellipsoid, m2] = d.surface.gate(q);
      if (ellipsoid >= 0) {
        Classification c;
        c.state = Occupancy::kOccupied;
        c.p_occupied = pOccupied(m2);
        c.ellipsoid = ellipsoid;
        out[i] = c;
        return;
      }
    }
    int keyframe = -1;
    const ViewVerdict v = d.views.combined(q, &keyframe);
    out[i] = fromVerdict(v, keyframe);
  });
}

void QueryMap::classifyInKeyframe(int keyframe, std::span<const Eigen::Vector3d> q_W,
                                  std::span<Classification> out) const {
  const Data& d = *data_;
  checkKeyframe(keyframe, d.views.size());
  checkPoints(q_W, out.size());
  forEachPoint(d.params.threads, q_W.size(),
               [&](std::size_t i) { out[i] = fromVerdict(d.views.localMapVerdict(keyframe, q_W[i]), keyframe); });
}

ViewVerdict QueryMap::keyframeVerdict(int keyframe, const Eigen::Vector3d& q_W) const {
  checkKeyframe(keyframe, data_->views.size());
  if (!q_W.allFinite()) throw std::invalid_argument("the point is not finite");
  return data_->views.verdict(keyframe, q_W);
}

}  // namespace vdmap
