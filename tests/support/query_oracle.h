#pragma once
// The plainest reference for QueryMap::classify and classifyInKeyframe (docs/method.md 13.1-13.3):
// every keyframe, every kept cell of the 3x3 around the point's cell, every global ellipsoid, the
// formulas written as the definitions read. Slow on purpose; the fast path must agree with it.
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <span>
#include <vector>

#include <Eigen/Dense>

#include "mapping/global_map/global_map.h"
#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/query/detail/keyframe_views.h"
#include "mapping/query/query_map.h"

namespace vdmap::test {

struct OracleVerdict {
  Occupancy state = Occupancy::kUnknown;
  double z = 0, sigma_t = 0, m2 = 0;
};

class QueryOracle {
 public:
  QueryOracle(const KeyframeGraph& graph, const GlobalMap& global, const QueryParams& params,
              std::vector<int> rank = {})
      : graph_(graph), global_(global), params_(params), rank_(std::move(rank)) {
    // d'A d >= |d|^2 / lambda_max(cov) >= |d|^2 / trace(cov), so no point farther than
    // gate_sigma * sqrt(trace) from an ellipsoid's mean lies in its gate: each ellipsoid is listed
    // in every 10 cm bucket that box overlaps, and gate() scans the point's bucket alone (which
    // only saves time: the answer is the scan's over every ellipsoid).
    for (std::size_t i = 0; i < global.ellipsoids.size(); ++i) {
      const Ellipsoid& e = global.ellipsoids[i];
      gate_A_.push_back(floored(e.cov).inverse());
      const double reach = params.gate_sigma * std::sqrt(floored(e.cov).trace());
      const auto lo = bucketOf((e.mean.array() - reach).matrix()), hi = bucketOf((e.mean.array() + reach).matrix());
      for (int x = lo[0]; x <= hi[0]; ++x)
        for (int y = lo[1]; y <= hi[1]; ++y)
          for (int z = lo[2]; z <= hi[2]; ++z) buckets_[{x, y, z}].push_back(static_cast<int>(i));
    }
  }

  /// docs/method.md 13.1, keyframe `id` about world point q_W.
  OracleVerdict verdict(int id, const Eigen::Vector3d& q_W) const {
    OracleVerdict out;
    const Keyframe& kf = graph_.keyframe(id);
    const KeyframeContainer& container = kf.container;
    const Eigen::Vector3d q = kf.T_W_K.inverse() * q_W;
    if (q.z() <= 0) return out;
    const Eigen::Vector2d uv = container.camera().project(q);
    const int g = container.gridIndexOfPixel(uv.x(), uv.y());
    if (g < 0) return out;
    const int col = g % container.cols(), row = g / container.cols();
    const double k = params_.gate_sigma;
    double best_m2 = std::numeric_limits<double>::infinity(), best_sigma_t = 0, best_z = 0;
    bool own = false;
    double own_z = 0, own_sigma_t = 0, own_mlat2 = 0, own_m2 = 0;
    for (int dr = -1; dr <= 1; ++dr)
      for (int dc = -1; dc <= 1; ++dc) {
        const int r = row + dr, c = col + dc;
        if (r < 0 || c < 0 || r >= container.rows() || c >= container.cols()) continue;
        const StoredCell* cell = container.find(r * container.cols() + c);
        if (cell == nullptr || !global_.kept[id][static_cast<std::size_t>(cell - container.cells().data())]) continue;
        const Ellipsoid e = cellEllipsoid(*cell, Transform::Identity(), id);
        const Eigen::Matrix3d A = floored(e.cov).inverse();
        const Eigen::Vector3d mu = storedViewMean(container, *cell);  // the float mean, its ray rounded
        const double m2 = (q - mu).dot(A * (q - mu));
        const double a = q.dot(A * q), b = q.dot(A * mu), cc = mu.dot(A * mu);
        const double z = (a - b) / std::sqrt(a), sigma_t = q.norm() / std::sqrt(a);
        if (m2 < best_m2) best_m2 = m2, best_sigma_t = sigma_t, best_z = z;
        if (dr == 0 && dc == 0) own = true, own_z = z, own_sigma_t = sigma_t, own_mlat2 = cc - b * b / a, own_m2 = m2;
      }
    if (best_m2 <= k * k) return {Occupancy::kOccupied, best_z, best_sigma_t, best_m2};
    if (own && own_z < -k && own_mlat2 <= k * k) return {Occupancy::kFree, own_z, own_sigma_t, own_m2};
    return out;
  }

  /// docs/method.md 13.2: free when some frame integrated into keyframe `id` saw q_W nearer than
  /// its block's nearest depth d by more than k sigma, sigma^2 = sd_axial(d)^2 + s0^2.
  OracleVerdict frameVerdict(int id, const Eigen::Vector3d& q_W) const {
    const Keyframe& kf = graph_.keyframe(id);
    const PinholeCamera& camera = kf.container.camera();
    for (const FrameFreeSpace& f : kf.frames_free) {
      const Eigen::Vector3d q = (kf.T_W_K * f.T_K_C).inverse() * q_W;
      if (q.z() <= 0) continue;
      const Eigen::Vector2d uv = camera.project(q);
      if (uv.x() < 0 || uv.y() < 0 || uv.x() >= camera.width || uv.y() >= camera.height) continue;
      const int block = static_cast<int>(std::floor(uv.y() / kFreeBlockPx)) * f.cols +
                        static_cast<int>(std::floor(uv.x() / kFreeBlockPx));
      const int mm = f.near_mm[static_cast<std::size_t>(block)];
      if (mm == 0) continue;
      const double d = mm / 1000.0, sd = 0.0012 + 0.0019 * (d - 0.4) * (d - 0.4);
      const double sigma = std::sqrt(sd * sd + params_.min_sigma_m * params_.min_sigma_m);
      const double z = (q.z() - d) / sigma;
      if (z < -params_.gate_sigma) return {Occupancy::kFree, z, sigma, 0};
    }
    return {};
  }

  /// What keyframe `id`'s local map says: its own verdict, else its frames'.
  OracleVerdict localMapVerdict(int id, const Eigen::Vector3d& q_W) const {
    const OracleVerdict v = verdict(id, q_W);
    return v.state != Occupancy::kUnknown ? v : frameVerdict(id, q_W);
  }

  /// No keyframe has a verdict: the first keyframe (by id) one of whose frames sees q_W free.
  Classification framesFree(const Eigen::Vector3d& q_W) const {
    for (int id = 0; id < static_cast<int>(graph_.size()); ++id) {
      const OracleVerdict v = frameVerdict(id, q_W);
      if (v.state == Occupancy::kFree) return fromVerdict(v, id);
    }
    return {};
  }

  /// The global ellipsoid whose gate holds q_W with the smallest m^2 (ties: lower index), or -1.
  int gate(const Eigen::Vector3d& q_W, double* m2_out) const {
    int best = -1;
    double best_m2 = std::numeric_limits<double>::infinity();
    const auto bucket = buckets_.find(bucketOf(q_W));
    if (bucket != buckets_.end())
      for (const int i : bucket->second) {  // in index order
        const Eigen::Vector3d d = q_W - global_.ellipsoids[static_cast<std::size_t>(i)].mean;
        const double m2 = d.dot(gate_A_[static_cast<std::size_t>(i)] * d);
        if (m2 <= params_.gate_sigma * params_.gate_sigma && m2 < best_m2) best = i, best_m2 = m2;
      }
    *m2_out = best_m2;
    return best;
  }

  /// gate() by a scan over every ellipsoid: what the buckets must give (checked in the tests).
  int gateByScan(const Eigen::Vector3d& q_W, double* m2_out) const {
    int best = -1;
    double best_m2 = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < gate_A_.size(); ++i) {
      const Eigen::Vector3d d = q_W - global_.ellipsoids[i].mean;
      const double m2 = d.dot(gate_A_[i] * d);
      if (m2 <= params_.gate_sigma * params_.gate_sigma && m2 < best_m2) best = static_cast<int>(i), best_m2 = m2;
    }
    *m2_out = best_m2;
    return best;
  }

  static double pOccupied(double m2) {
    const double chi2_3 = std::erf(std::sqrt(m2 / 2)) - std::sqrt(2 * m2 / M_PI) * std::exp(-m2 / 2);
    return 0.5 + 0.5 * (1 - chi2_3);
  }
  static double pFree(double z) { return 0.5 * (1 + std::erf(z / std::sqrt(2.0))); }

  static Classification fromVerdict(const OracleVerdict& v, int id) {
    Classification c;
    c.state = v.state;
    if (v.state == Occupancy::kFree) c.p_occupied = static_cast<float>(pFree(v.z));
    if (v.state == Occupancy::kOccupied) c.p_occupied = static_cast<float>(pOccupied(v.m2));
    if (v.state != Occupancy::kUnknown) c.keyframe = id;
    return c;
  }

  /// docs/method.md 13.2 under params.conflict.
  Classification classify(const Eigen::Vector3d& q_W) const {
    const int n = static_cast<int>(graph_.size());
    if (params_.conflict == ConflictRule::kOccupied) {
      double m2 = 0;
      const int e = gate(q_W, &m2);
      if (e >= 0) {
        Classification c;
        c.state = Occupancy::kOccupied;
        c.p_occupied = static_cast<float>(pOccupied(m2));
        c.ellipsoid = e;
        return c;
      }
      for (int id = 0; id < n; ++id) {
        const OracleVerdict v = verdict(id, q_W);
        if (v.state == Occupancy::kFree) return fromVerdict(v, id);
      }
      return framesFree(q_W);
    }
    int best = -1;
    OracleVerdict best_v;
    for (int id = 0; id < n; ++id) {
      const OracleVerdict v = verdict(id, q_W);
      if (v.state == Occupancy::kUnknown) continue;
      const bool wins = best < 0 || (params_.conflict == ConflictRule::kRecent ? rankOf(id) > rankOf(best)
                                                                               : v.sigma_t < best_v.sigma_t);
      if (wins) best = id, best_v = v;
    }
    return best < 0 ? framesFree(q_W) : fromVerdict(best_v, best);
  }

 private:
  Eigen::Matrix3d floored(const Eigen::Matrix3d& cov) const {
    return cov + params_.min_sigma_m * params_.min_sigma_m * Eigen::Matrix3d::Identity();
  }
  int rankOf(int id) const { return rank_.empty() ? id : rank_[static_cast<std::size_t>(id)]; }

  const KeyframeGraph& graph_;
  const GlobalMap& global_;
  QueryParams params_;
  std::vector<int> rank_;
  std::vector<Eigen::Matrix3d> gate_A_;
  static std::array<int, 3> bucketOf(const Eigen::Vector3d& p) {
    const Eigen::Vector3d b = (p / 0.1).array().floor();
    return {static_cast<int>(b.x()), static_cast<int>(b.y()), static_cast<int>(b.z())};
  }
  std::map<std::array<int, 3>, std::vector<int>> buckets_;  ///< ellipsoids whose gate may reach in
};

}  // namespace vdmap::test
