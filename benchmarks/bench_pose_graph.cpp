// Pose-graph optimisation speed (the target: ~100 ms for 1000 nodes / 3000 edges). Not a
// test (ctest does not run it): build/bin/bench_pose_graph [--benchmark_repetitions=N ...].
//
// Two graphs of N nodes and 3N edges; odometry edges are biased (0.1 degrees of yaw per step) and
// noisy, so the chained odometry, where every iteration starts again, has drifted:
// - Loop/N: one loop of N keyframes 10 cm apart, edges i -> i+1, i+2, i+3 around the loop; the 6
//   that close it are loop edges (robust). The shape of vdmap's graph: revisits reuse keyframes,
//   so edges are mostly local.
// - Laps/1000: 10 laps of a 2 m circle (100 keyframes a lap) with edges i -> i+1, i+2 and 1003
//   loop edges between the same place on different laps (i -> i+100, and i -> i+200 for the
//   first 103): a much denser Cholesky factor (a new keyframe on every lap).
#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "mapping/posegraph/pose_graph.h"

namespace vdmap {
namespace {

constexpr double kDeg = M_PI / 180.0;

Matrix6d information(double sigma_m, double sigma_rad) {
  Matrix6d info = Matrix6d::Zero();
  info.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma_m * sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  return info;
}

struct Graph {
  std::vector<Transform> initial;
  std::vector<PoseGraphEdge> edges;
};

/// Measures truth[i]^-1 * truth[j] with noise, and a yaw bias on odometry edges.
class Measure {
 public:
  explicit Measure(const std::vector<Transform>& truth) : truth_(truth), rng_(1000) {}
  Transform operator()(int i, int j, double bias_rad) {
    Transform T = truth_[i].inverse() * truth_[j];
    const Eigen::Vector3d dt(noise_(rng_), noise_(rng_), noise_(rng_)), dr(noise_(rng_), noise_(rng_), noise_(rng_));
    T.translation() += 0.002 * dt;
    T.linear() = T.linear() * Eigen::AngleAxisd(bias_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                 Eigen::AngleAxisd(kDeg * 0.05 * dr.norm(), dr.normalized()).toRotationMatrix();
    return T;
  }

 private:
  const std::vector<Transform>& truth_;
  std::mt19937 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
};

std::vector<Transform> circle(int nodes, int per_lap, double radius_m) {
  std::vector<Transform> truth(nodes);
  for (int i = 0; i < nodes; ++i) {
    const double a = 2.0 * M_PI * i / per_lap;
    truth[i].setIdentity();
    truth[i].linear() = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()).toRotationMatrix();
    truth[i].translation() = Eigen::Vector3d(radius_m * std::cos(a), 0.1 * std::sin(3 * a), radius_m * std::sin(a));
  }
  return truth;
}

/// Initial guess: node 0 at the truth, the others chained from the edges i -> i+1 (the first N-1).
std::vector<Transform> chain(const Transform& start, const std::vector<PoseGraphEdge>& edges, int nodes) {
  std::vector<Transform> poses = {start};
  for (int i = 0; i + 1 < nodes; ++i) poses.push_back(poses.back() * edges[i].T_from_to);
  return poses;
}

Graph loop(int nodes) {
  const std::vector<Transform> truth = circle(nodes, nodes, 0.1 * nodes / (2.0 * M_PI));
  Measure measure(truth);
  Graph g;
  for (int step : {1, 2, 3})
    for (int i = 0; i < nodes; ++i) {
      const int j = (i + step) % nodes;
      const bool closes = j < i;
      g.edges.push_back({i, j, measure(i, j, closes ? 0.0 : step * 0.1 * kDeg),
                         closes ? information(0.002, 0.05 * kDeg) : information(0.005, 0.15 * kDeg), closes});
    }
  g.initial = chain(truth[0], g.edges, nodes);
  return g;
}

Graph laps(int nodes) {
  const int per_lap = 100;
  const std::vector<Transform> truth = circle(nodes, per_lap, 2.0);
  Measure measure(truth);
  Graph g;
  for (int step : {1, 2})
    for (int i = 0; i + step < nodes; ++i)
      g.edges.push_back({i, i + step, measure(i, i + step, step * 0.1 * kDeg), information(0.005, 0.15 * kDeg), false});
  for (int gap = per_lap; static_cast<int>(g.edges.size()) < 3 * nodes && gap < nodes; gap += per_lap)
    for (int i = 0; i + gap < nodes && static_cast<int>(g.edges.size()) < 3 * nodes; ++i)
      g.edges.push_back({i, i + gap, measure(i, i + gap, 0.0), information(0.002, 0.05 * kDeg), true});
  g.initial = chain(truth[0], g.edges, nodes);
  return g;
}

void run(benchmark::State& state, const Graph& graph) {
  PoseGraphResult result;
  for (auto _ : state) {
    std::vector<Transform> nodes = graph.initial;
    result = optimizePoseGraph(&nodes, graph.edges);
    benchmark::DoNotOptimize(nodes.data());
  }
  state.counters["edges"] = static_cast<double>(graph.edges.size());
  state.counters["iterations"] = result.iterations;
  state.counters["converged"] = result.converged;
}

void BM_Loop(benchmark::State& state) { run(state, loop(static_cast<int>(state.range(0)))); }
void BM_Laps(benchmark::State& state) { run(state, laps(static_cast<int>(state.range(0)))); }
BENCHMARK(BM_Loop)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Laps)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vdmap

BENCHMARK_MAIN();
