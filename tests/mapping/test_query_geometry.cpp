// The surface half of the point queries (docs/method.md 13.4-13.6): the gate kernels against
// dense sampling and bisection, the box tree's first hit and SurfaceIndex against plain loops over
// every ellipsoid, and QueryMap's distance, collision and ray casts against the same loops (bit for
// bit), on random ellipsoids and on the analytic box room.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "mapping/core/box_tree.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/camera_config.h"
#include "mapping/local_map/sensor_model.h"
#include "mapping/query/detail/surface_index.h"
#include "mapping/query/ellipsoid_geometry.h"
#include "mapping/query/query_map.h"
#include "tests/support/box_room_keyframes.h"

namespace vdmap {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- plain references: every ellipsoid, in index order -------------------------------------

std::vector<EllipsoidGate> allGates(const std::vector<Ellipsoid>& e, const QueryParams& p) {
  std::vector<EllipsoidGate> g;
  for (const Ellipsoid& x : e) g.push_back(makeGate(x, p.gate_sigma, p.min_sigma_m));
  return g;
}

std::pair<std::int32_t, double> gateByLoop(const std::vector<EllipsoidGate>& gates, const Eigen::Vector3d& q) {
  std::pair<std::int32_t, double> best{-1, kInf};
  for (std::size_t i = 0; i < gates.size(); ++i) {
    const double m2 = gateDistance2(gates[i], q);
    if (m2 <= gates[i].k2 && m2 < best.second) best = {static_cast<std::int32_t>(i), m2};
  }
  return best;
}

SurfaceIndex::Nearest nearestByLoop(const std::vector<EllipsoidGate>& gates, const Eigen::Vector3d& q,
                                    double max_distance = kInf) {
  SurfaceIndex::Nearest best;
  const auto inside = gateByLoop(gates, q);
  if (inside.first >= 0) return {inside.first, 0.0, q};
  double best_d2 = max_distance * max_distance;
  for (std::size_t i = 0; i < gates.size(); ++i) {
    Eigen::Vector3d x;
    const double d = distanceToGate(gates[i], q, &x);
    if (d * d < best_d2) best_d2 = d * d, best = {static_cast<std::int32_t>(i), d, x};
  }
  return best;
}

SurfaceIndex::Hit firstHitByLoop(const std::vector<EllipsoidGate>& gates, const Eigen::Vector3d& o,
                                 const Eigen::Vector3d& d, double max_t) {
  SurfaceIndex::Hit best;
  for (std::size_t i = 0; i < gates.size(); ++i) {
    const double t = gateRayEntry(gates[i], gateRayOrigin(gates[i], o), d, max_t);
    if (t < best.t) best = {static_cast<std::int32_t>(i), t};
  }
  return best;
}

// ---- generated ellipsoids --------------------------------------------------------------------

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n;
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

Ellipsoid ellipsoidWithSigmas(const Eigen::Vector3d& mean, const Eigen::Vector3d& sigmas, const Eigen::Matrix3d& R) {
  Ellipsoid e;
  e.mean = mean;
  e.cov = R * sigmas.cwiseAbs2().asDiagonal() * R.transpose();
  e.count = 10;
  return e;
}

// Random ellipsoids in a 4 m cube: mostly surface patches (sigmas 0.5 mm .. 5 cm, some flat, some
// needles), and a few large ones for the coarse grid levels and the oversize list.
std::vector<Ellipsoid> randomEllipsoids(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-2, 2), logs(std::log(5e-4), std::log(5e-2)), u(0, 1);
  std::vector<Ellipsoid> out;
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Vector3d s(std::exp(logs(rng)), std::exp(logs(rng)), std::exp(logs(rng)));
    const double kind = u(rng);
    if (kind < 0.2) s.z() = 1e-5;                               // disc (below the floor)
    else if (kind < 0.3) s.y() = s.z() = 1e-4, s.x() = 0.2;     // needle
    else if (kind < 0.32) s = Eigen::Vector3d(0.5, 0.4, 0.3);   // large
    else if (kind < 0.325) s = Eigen::Vector3d(3.0, 2.0, 1.0);  // larger than every grid level
    out.push_back(ellipsoidWithSigmas({pos(rng), pos(rng), pos(rng)}, s, randomRotation(rng)));
  }
  return out;
}

// Query points: uniform in the cube grown by 0.5 m, and as many near the ellipsoids (within 4
// sigma of a random one) so that gates hold many of them.
std::vector<Eigen::Vector3d> randomPoints(const std::vector<Ellipsoid>& e, std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> pos(-2.5, 2.5);
  std::normal_distribution<double> g;
  std::uniform_int_distribution<std::size_t> pick(0, e.size() - 1);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 2 == 0 || e.empty()) {
      out.push_back({pos(rng), pos(rng), pos(rng)});
    } else {
      const Ellipsoid& x = e[pick(rng)];
      const Eigen::Matrix3d L = (x.cov + 1e-6 * Eigen::Matrix3d::Identity()).llt().matrixL();
      out.push_back(x.mean + 3.0 * L * Eigen::Vector3d(g(rng), g(rng), g(rng)));
    }
  }
  return out;
}

// ---- kernels ---------------------------------------------------------------------------------

// Distance to the ellipsoid surface by sampling: a coarse (theta, phi) grid, then shrinking grids
// around the best sample.
double distanceBySampling(const Eigen::Vector3d& e, const Eigen::Vector3d& y) {
  const auto at = [&](double th, double ph) {
    return Eigen::Vector3d(e[0] * std::sin(th) * std::cos(ph), e[1] * std::sin(th) * std::sin(ph), e[2] * std::cos(th));
  };
  double best = kInf, bt = 0, bp = 0;
  constexpr int kTheta = 200, kPhi = 400;
  for (int i = 0; i <= kTheta; ++i)
    for (int j = 0; j < kPhi; ++j) {
      const double th = M_PI * i / kTheta, ph = 2 * M_PI * j / kPhi;
      const double d = (at(th, ph) - y).norm();
      if (d < best) best = d, bt = th, bp = ph;
    }
  // Pattern search: move to a better neighbour at this step, else halve the step.
  double step_t = M_PI / kTheta, step_p = 2 * M_PI / kPhi;
  while (step_t > 1e-13) {
    bool moved = false;
    for (int i = -1; i <= 1; ++i)
      for (int j = -1; j <= 1; ++j) {
        const double th = bt + i * step_t, ph = bp + j * step_p;
        const double d = (at(th, ph) - y).norm();
        if (d < best) best = d, bt = th, bp = ph, moved = true;
      }
    if (!moved) step_t *= 0.5, step_p *= 0.5;
  }
  return best;
}

TEST(QueryGeometry, DistanceToEllipsoidMatchesDenseSampling) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n;
  const std::vector<Eigen::Vector3d> shapes = {{1.0, 0.003, 0.003},  // needle
                                               {0.5, 0.5, 0.002},    // disc
                                               {0.3, 0.1, 0.05},     // generic
                                               {0.2, 0.2, 0.2}};     // sphere
  for (const Eigen::Vector3d& e : shapes) {
    for (int k = 0; k < 12; ++k) {
      // Points outside at distances from 1 mm to 1 m, in every octant and on the axes' planes.
      Eigen::Vector3d dir(n(rng), n(rng), n(rng));
      if (k == 0) dir.z() = 0;
      if (k == 1) dir.y() = dir.z() = 0;
      // From the surface point along dir (radially outward: the ellipsoid is star-shaped).
      const Eigen::Vector3d p = dir.normalized();
      const Eigen::Vector3d y = p / p.cwiseQuotient(e).norm() + std::pow(10.0, -3 + k % 4) * p;
      if (y.cwiseQuotient(e).squaredNorm() <= 1) continue;
      Eigen::Vector3d x;
      const double d = distanceToEllipsoidSurface(e, y, &x);
      const double sampled = distanceBySampling(e, y);
      EXPECT_NEAR(d, sampled, 1e-6) << "semi-axes " << e.transpose() << " point " << y.transpose();
      EXPECT_LE(d, sampled + 1e-12);
      EXPECT_NEAR(x.cwiseQuotient(e).squaredNorm(), 1.0, 1e-9);  // on the surface
      EXPECT_NEAR((x - y).norm(), d, 1e-12);
    }
  }
}

TEST(QueryGeometry, DistanceToGateIsZeroInsideAndMatchesThePrincipalFrame) {
  std::mt19937 rng(3);
  const Ellipsoid e = ellipsoidWithSigmas({0.3, -0.2, 1.5}, {0.05, 0.02, 0.004}, randomRotation(rng));
  const EllipsoidGate g = makeGate(e, 3.0, 0.001);
  Eigen::Vector3d closest;
  EXPECT_EQ(distanceToGate(g, e.mean, &closest), 0.0);
  EXPECT_EQ(closest, e.mean);
  // Semi-axes k sqrt(sigma^2 + s0^2), longest first; A (Sigma + s0^2 I) = I; all in float
  // (6e-8 relative).
  EXPECT_NEAR(g.semi_axes[0], 3 * std::sqrt(0.05 * 0.05 + 1e-6), 1.2e-7 * g.semi_axes[0]);
  EXPECT_NEAR(g.semi_axes[2], 3 * std::sqrt(0.004 * 0.004 + 1e-6), 1.2e-7 * g.semi_axes[2]);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(g.semi_axes[i], static_cast<float>(g.semi_axes[i])) << i;
  for (int i = 0; i < 9; ++i) EXPECT_EQ(g.A.data()[i], static_cast<float>(g.A.data()[i])) << i;
  // The frame: the rotation of a float quaternion, whose columns diagonalise the covariance.
  for (int i = 0; i < 4; ++i) EXPECT_EQ(g.rotation[i], static_cast<float>(g.rotation[i])) << i;
  EXPECT_EQ(g.axes, axesFromQuaternion(g.rotation.data()));
  const Eigen::Matrix3d S = 9 * g.axes.transpose() * (e.cov + 1e-6 * Eigen::Matrix3d::Identity()) * g.axes;
  EXPECT_TRUE(S.isApprox(Eigen::Matrix3d(g.semi_axes.cwiseAbs2().asDiagonal()), 1e-6)) << S;
  EXPECT_TRUE((g.A * (e.cov + 1e-6 * Eigen::Matrix3d::Identity())).isApprox(Eigen::Matrix3d::Identity(), 1e-6));
  // A point 10 cm out along the shortest axis: the distance is 10 cm and the closest point is on
  // the gate's surface (m^2 = k^2, to float rounding of the shape).
  const Eigen::Vector3d q = g.mean + (g.semi_axes[2] + 0.1) * g.axes.col(2);
  EXPECT_NEAR(distanceToGate(g, q, &closest), 0.1, 1e-7);
  EXPECT_NEAR(gateDistance2(g, closest), 9.0, 1e-5);
  // Half-extent of the box: k sqrt(Sigma_ii + s0^2), and the gate inside it.
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(g.half_extent[a], 3 * std::sqrt(e.cov(a, a) + 1e-6), 1e-12);
}

TEST(QueryGeometry, RayEntryMatchesBisection) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  const std::vector<Ellipsoid> ells = randomEllipsoids(200, 5);
  int hits = 0, inside = 0;
  for (const Ellipsoid& e : ells) {
    const EllipsoidGate g = makeGate(e, 3.0, 0.001);
    for (int k = 0; k < 10; ++k) {
      const Eigen::Vector3d o = e.mean + Eigen::Vector3d(u(rng), u(rng), u(rng)) * (k < 2 ? 0.01 : 1.0);
      // Aim near the mean (most rays hit) or anywhere.
      const Eigen::Vector3d target = e.mean + Eigen::Vector3d(u(rng), u(rng), u(rng)) * (k % 2 ? 0.02 : 0.5);
      const Eigen::Vector3d d = unitDirection(target - o);
      const double t = gateRayEntry(g, gateRayOrigin(g, o), d, kInf);
      const auto f = [&](double s) { return gateDistance2(g, o + s * d) - g.k2; };
      if (f(0) <= 0) {
        EXPECT_EQ(t, 0.0);
        ++inside;
        continue;
      }
      // The ray's closest approach in the gate's metric: f is a parabola in s.
      const Eigen::Vector3d Ad = g.A * d;
      const double s_min = std::max(0.0, -d.dot(g.A * (o - g.mean)) / d.dot(Ad));
      if (f(s_min) > 1e-9) {
        EXPECT_EQ(t, kInf);
        continue;
      }
      if (f(s_min) > -1e-6) continue;  // grazing: either answer is right
      ASSERT_LT(t, kInf);
      double lo = 0, hi = s_min;  // f(lo) > 0 >= f(hi)
      for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (f(mid) > 0 ? lo : hi) = mid;
      }
      EXPECT_NEAR(t, hi, 1e-9 * std::max(1.0, hi));
      // And beyond a smaller maximum range it is a miss.
      EXPECT_EQ(gateRayEntry(g, gateRayOrigin(g, o), d, 0.5 * t), kInf);
      ++hits;
    }
  }
  EXPECT_GT(hits, 300);
  EXPECT_GT(inside, 50);
}

TEST(QueryGeometry, PixelRayProjectsBackToItsPixel) {
  const PinholeCamera camera = cameraPreset("tum-default");
  const Transform T = test::lookAt({0.3, -0.2, 0.1}, {1, 0.5, 2});
  for (const auto& [u, v] : std::vector<std::pair<int, int>>{{0, 0}, {639, 479}, {320, 17}, {5, 400}}) {
    const Eigen::Vector3d d = pixelRay(camera, T, u, v);
    EXPECT_NEAR(d.norm(), 1.0, 1e-15);
    const Eigen::Vector2d px = camera.project(T.inverse() * (T.translation() + 2.0 * d));
    EXPECT_NEAR(px.x(), u, 1e-9);
    EXPECT_NEAR(px.y(), v, 1e-9);
  }
}

TEST(QueryGeometry, ImageBoundsHoldEveryPixelWhoseRayMeetsTheGate) {
  PinholeCamera camera;
  camera.width = 80, camera.height = 60, camera.fx = camera.fy = 70, camera.cx = 39.5, camera.cy = 29.5;
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0, whole = 0, tight = 0, slack = 0;
  for (int k = 0; k < 300; ++k) {
    const Transform T = test::lookAt({0, 0, 0}, {u(rng) * 0.2, u(rng) * 0.2, 1});
    Eigen::Vector3d s(0.01 + 0.1 * std::abs(u(rng)), 0.01 + 0.1 * std::abs(u(rng)), 0.002);
    if (k % 10 == 0) s *= 10;  // some reach behind the camera
    const Ellipsoid e = ellipsoidWithSigmas({u(rng), u(rng), 0.2 + 2 * std::abs(u(rng))}, s, randomRotation(rng));
    const EllipsoidGate g = makeGate(e, 3.0, 0.001);
    int u0 = 0, u1 = -1, v0 = 0, v1 = -1;
    const bool seen = gateImageBounds(g, camera, T.inverse(), 1.0, &u0, &u1, &v0, &v1);
    int hu0 = camera.width, hu1 = -1, hv0 = camera.height, hv1 = -1;
    const GateRayOrigin o = gateRayOrigin(g, T.translation());
    for (int v = 0; v < camera.height; ++v)
      for (int uu = 0; uu < camera.width; ++uu)
        if (gateRayEntry(g, o, pixelRay(camera, T, uu, v), kInf) < kInf) {
          ASSERT_TRUE(seen) << k;
          ASSERT_TRUE(uu >= u0 && uu <= u1 && v >= v0 && v <= v1) << k << ": pixel " << uu << "," << v;
          hu0 = std::min(hu0, uu), hu1 = std::max(hu1, uu), hv0 = std::min(hv0, v), hv1 = std::max(hv1, v);
        }
    if (hu1 < 0) continue;
    ++checked;
    if (u0 == 0 && u1 == camera.width - 1 && v0 == 0 && v1 == camera.height - 1) ++whole;
    // Tight: the box is the silhouette's plus the 1 px margin; pixel centres sample the silhouette,
    // so its thin tips may reach a few pixels past the last centre hit.
    if (hu0 > 2 && hu1 < camera.width - 3 && hv0 > 2 && hv1 < camera.height - 3) {
      slack += (hu0 - u0) + (u1 - hu1) + (hv0 - v0) + (v1 - hv1);
      tight += 4;
    }
  }
  EXPECT_GT(checked, 100);
  EXPECT_GT(tight, 200);
  EXPECT_LT(static_cast<double>(slack) / tight, 2.5);  // 1 px margin + rounding + tips
  EXPECT_LT(whole, checked);
}

// ---- box tree --------------------------------------------------------------------------------

TEST(BoxTree, FirstHitIsTheSmallestHitOverAllItems) {
  // Items: spheres; hit = the ray's entry into the sphere (0 inside), in its bounding box.
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> c;
  std::vector<double> r;
  std::vector<Eigen::Vector3f> lo, hi;
  for (int i = 0; i < 2000; ++i) {
    c.push_back({u(rng), u(rng), u(rng)});
    r.push_back(0.01 + 0.05 * std::abs(u(rng)));
    lo.push_back((c.back().array() - r.back()).cast<float>() - 1e-6f);
    hi.push_back((c.back().array() + r.back()).cast<float>() + 1e-6f);
  }
  // Some items share a centre: equal hits, the lower index wins.
  for (int i = 0; i < 20; ++i) c[1000 + i] = c[i], r[1000 + i] = r[i], lo[1000 + i] = lo[i], hi[1000 + i] = hi[i];
  const BoxTree tree(lo, hi);
  const auto entry = [&](std::size_t i, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
    const Eigen::Vector3d oc = o - c[i];
    const double b = oc.dot(d), cc = oc.squaredNorm() - r[i] * r[i];
    if (cc <= 0) return 0.0;
    const double disc = b * b - cc;
    if (disc < 0 || b >= 0) return kInf;
    return cc / (std::sqrt(disc) - b);
  };
  int hits = 0;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector3d o(1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng));
    Eigen::Vector3d d(u(rng), u(rng), u(rng));
    if (k % 7 == 0) d.x() = 0;  // axis-parallel rays
    if (k % 11 == 0) d.y() = d.z() = 0;
    if (d.norm() == 0) continue;
    d.normalize();
    const double max_t = k % 3 == 0 ? 0.5 : kInf;
    std::int64_t best = -1;
    double best_t = kInf;
    for (std::size_t i = 0; i < c.size(); ++i) {
      const double t = entry(i, o, d);
      if (t <= max_t && t < best_t) best_t = t, best = static_cast<std::int64_t>(i);
    }
    const auto [i, t] = tree.firstHit(o, d, max_t, [&](std::uint32_t j, double bound) {
      const double t = entry(j, o, d);
      return t <= bound ? t : kInf;
    });
    ASSERT_EQ(i, best) << k;
    ASSERT_EQ(t, best_t) << k;
    hits += best >= 0;
  }
  EXPECT_GT(hits, 300);
  // No items: no hit.
  const BoxTree empty({}, {});
  EXPECT_EQ(empty.firstHit({0, 0, 0}, {0, 0, 1}, kInf, [](std::uint32_t, double) { return 0.0; }).first, -1);
}

// ---- SurfaceIndex against the loops ------------------------------------------------------------

void expectIndexMatchesLoops(const std::vector<Ellipsoid>& ells, const QueryParams& params, std::size_t gate_points,
                             std::size_t nearest_points, std::size_t rays) {
  const SurfaceIndex index = SurfaceIndex::build(ells, params);
  const std::vector<EllipsoidGate> gates = allGates(ells, params);
  ASSERT_EQ(index.size(), ells.size());
  const std::vector<Eigen::Vector3d> pts = randomPoints(ells, gate_points, 17);
  std::size_t inside = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto a = index.gate(pts[i]), b = gateByLoop(gates, pts[i]);
    ASSERT_EQ(a.first, b.first) << i;
    ASSERT_EQ(a.second, b.second) << i;
    inside += b.first >= 0;
  }
  EXPECT_GT(inside, pts.size() / 100);
  for (std::size_t i = 0; i < nearest_points; ++i) {
    const double max_d = i % 4 == 3 ? 0.05 : kInf;
    const auto a = index.nearest(pts[i], max_d), b = nearestByLoop(gates, pts[i], max_d);
    ASSERT_EQ(a.ellipsoid, b.ellipsoid) << i;
    ASSERT_EQ(a.distance, b.distance) << i;
    ASSERT_EQ(a.closest, b.closest) << i;
  }
  std::mt19937 rng(19);
  std::uniform_real_distribution<double> u(-1, 1);
  std::size_t hit = 0;
  for (std::size_t i = 0; i < rays; ++i) {
    const Eigen::Vector3d o = pts[(i * 7) % pts.size()];
    const Eigen::Vector3d d = unitDirection({u(rng), u(rng), u(rng)});
    const double max_t = i % 5 == 4 ? 0.3 : 8.0;
    const auto a = index.firstHit(o, d, max_t), b = firstHitByLoop(gates, o, d, max_t);
    ASSERT_EQ(a.ellipsoid, b.ellipsoid) << i;
    ASSERT_EQ(a.t, b.t) << i;
    hit += b.ellipsoid >= 0;
  }
  EXPECT_GT(hit, rays / 10);
}

TEST(SurfaceIndex, MatchesLoopsOverEveryEllipsoidOnRandomEllipsoids) {
  const QueryParams params;
  expectIndexMatchesLoops(randomEllipsoids(3000, 1), params, 20000, 2000, 5000);
}

TEST(SurfaceIndex, MatchesLoopsOverEveryEllipsoidOnTheBoxRoom) {
  KeyframeGraph graph;
  test::addTwoBoxRoomViews(&graph, cameraPreset("tum-default"));
  const GlobalMap map = buildGlobalMap(graph, GlobalMapParams{});
  ASSERT_GT(map.ellipsoids.size(), 1000u) << map.ellipsoids.size();
  std::printf("box room: %zu ellipsoids\n", map.ellipsoids.size());
  QueryParams params;
  expectIndexMatchesLoops(map.ellipsoids, params, 20000, 200, 1000);
  params.gate_sigma = 2.0, params.min_sigma_m = 0.0001;
  expectIndexMatchesLoops(map.ellipsoids, params, 2000, 50, 200);
}

TEST(SurfaceIndex, TiesGoToTheLowerIndexWhateverTheStorageOrder) {
  // Two equal spheres (gate radius 0.3 m) mirrored about x = 0, the one at +x first: the gates
  // are stored in Morton order (the -x one first), yet a point or a ray equally near both
  // answers ellipsoid 0.
  const auto mirrored = [](double x) {
    std::vector<Ellipsoid> ells(2);
    ells[0].mean = {x, 0.25, 0.25}, ells[1].mean = {-x, 0.25, 0.25};
    for (Ellipsoid& e : ells) e.cov = 0.01 * Eigen::Matrix3d::Identity();
    return SurfaceIndex::build(ells, QueryParams{});
  };
  const SurfaceIndex apart = mirrored(0.5), overlapping = mirrored(0.2);
  ASSERT_EQ(apart.ellipsoidAtRank(0), 1);
  ASSERT_EQ(overlapping.ellipsoidAtRank(0), 1);
  const SurfaceIndex::Nearest n = apart.nearest({0, 0.25, 0.25});
  EXPECT_EQ(n.ellipsoid, 0);
  EXPECT_GT(n.distance, 0);
  const SurfaceIndex::Hit h = overlapping.firstHit({0, -2, 0.25}, {0, 1, 0}, 8.0);
  EXPECT_EQ(h.ellipsoid, 0);
  EXPECT_LT(h.t, 8.0);
}

TEST(SurfaceIndex, SameAnswersForAnyThreadCountAndEmpty) {
  const std::vector<Ellipsoid> ells = randomEllipsoids(2000, 2);
  QueryParams one, two;
  one.threads = 1, two.threads = 2;
  const SurfaceIndex a = SurfaceIndex::build(ells, one), b = SurfaceIndex::build(ells, two);
  for (const Eigen::Vector3d& q : randomPoints(ells, 3000, 4)) {
    ASSERT_EQ(a.gate(q), b.gate(q));
    ASSERT_EQ(a.nearest(q).distance, b.nearest(q).distance);
  }
  const SurfaceIndex empty = SurfaceIndex::build({}, one);
  EXPECT_EQ(empty.size(), 0u);
  EXPECT_EQ(empty.gate({0, 0, 0}).first, -1);
  EXPECT_EQ(empty.nearest({0, 0, 0}).distance, kInf);
  EXPECT_EQ(empty.firstHit({0, 0, 0}, {0, 0, 1}, 8.0).ellipsoid, -1);
  EXPECT_EQ(SurfaceIndex().gate({0, 0, 0}).first, -1);
}

// ---- QueryMap: distance, collision, rays -------------------------------------------------------

// The two box-room keyframes looking at the wall z = 2 (keyframe 0 from the origin, 2 m away) and
// their query map.
struct BoxRoomMap {
  KeyframeGraph graph;
  GlobalMap global;
  QueryMap map;
  std::vector<EllipsoidGate> gates;
  explicit BoxRoomMap(int threads = 0) {
    test::addTwoBoxRoomViews(&graph, cameraPreset("tum-default"));
    global = buildGlobalMap(graph, GlobalMapParams{});
    QueryParams params;
    params.threads = threads;
    map = QueryMap::build(graph, global, params);
    gates = allGates(global.ellipsoids, params);
  }
};

const BoxRoomMap& boxRoom() {
  static const BoxRoomMap scene;
  return scene;
}

std::vector<Eigen::Vector3d> roomPoints(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-2.2, 2.2), y(-1.7, 1.7), z(-0.5, 2.2);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back({x(rng), y(rng), z(rng)});
  return out;
}

bool sameHit(const RayHit& a, const RayHit& b) {
  return a.hit == b.hit && a.t_m == b.t_m && a.ellipsoid == b.ellipsoid && a.point_W == b.point_W &&
         a.normal_W == b.normal_W;
}

TEST(QueryMapSurface, DistanceIsTheMinimumOverEveryEllipsoid) {
  const BoxRoomMap& s = boxRoom();
  // Points in the room, and on the wall within its gates.
  std::vector<Eigen::Vector3d> pts = roomPoints(120, 23);
  for (const Eigen::Vector3d& q : randomPoints(s.global.ellipsoids, 80, 29)) pts.push_back(q);
  for (const double max_d : {kInf, 0.3}) {
    std::vector<DistanceResult> out(pts.size());
    s.map.distance(pts, out, max_d);
    int inside = 0, beyond = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const SurfaceIndex::Nearest ref = nearestByLoop(s.gates, pts[i], max_d);
      ASSERT_EQ(out[i].ellipsoid, ref.ellipsoid) << i;
      ASSERT_EQ(out[i].distance_m, ref.distance) << i;
      if (ref.ellipsoid < 0) {
        ++beyond;
        EXPECT_EQ(out[i].distance_m, kInf);
        EXPECT_EQ(out[i].gradient, Eigen::Vector3d::Zero());
        continue;
      }
      ASSERT_EQ(out[i].closest_W, ref.closest) << i;
      if (ref.distance == 0) {
        ++inside;
        EXPECT_EQ(out[i].gradient, Eigen::Vector3d::Zero());
      } else {
        // Unit, from the closest surface point to q; the closest point is on that gate's surface.
        EXPECT_NEAR(out[i].gradient.norm(), 1.0, 1e-12);
        // (To the float rounding of the gate's A and frame, each 6e-8 relative: its axes are
        // orthonormal, and its surface m^2 = k^2, to that.)
        EXPECT_NEAR(out[i].gradient.dot(pts[i] - out[i].closest_W), out[i].distance_m,
                    1e-7 * std::max(1.0, out[i].distance_m));
        EXPECT_NEAR(gateDistance2(s.gates[static_cast<std::size_t>(ref.ellipsoid)], out[i].closest_W), 9.0, 1e-5);
      }
    }
    EXPECT_GT(inside, 10);
    if (max_d < kInf) {
      EXPECT_GT(beyond, 10);
    }
  }
}

TEST(QueryMapSurface, CastRaysIsTheFirstGateEntryOverEveryEllipsoid) {
  const BoxRoomMap& s = boxRoom();
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1, 1);
  const std::vector<Eigen::Vector3d> origins = roomPoints(2000, 37);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < origins.size(); ++i) {
    Ray r;
    r.origin_W = origins[i];
    r.direction_W = Eigen::Vector3d(u(rng), u(rng), u(rng) + (i % 2 ? 1.5 : 0.0)) * 3.0;  // any length
    r.max_range_m = i % 4 == 3 ? 0.5 : 8.0;
    rays.push_back(r);
  }
  std::vector<RayHit> out(rays.size());
  s.map.castRays(rays, out);
  int hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Eigen::Vector3d d = unitDirection(rays[i].direction_W);
    const SurfaceIndex::Hit ref = firstHitByLoop(s.gates, rays[i].origin_W, d, rays[i].max_range_m);
    ASSERT_EQ(out[i].ellipsoid, ref.ellipsoid) << i;
    ASSERT_EQ(out[i].hit, ref.ellipsoid >= 0) << i;
    if (!out[i].hit) continue;
    ++hits;
    ASSERT_EQ(out[i].t_m, ref.t) << i;
    EXPECT_EQ(out[i].point_W, rays[i].origin_W + ref.t * d);
    const EllipsoidGate& g = s.gates[static_cast<std::size_t>(ref.ellipsoid)];
    if (ref.t > 0) {
      EXPECT_NEAR(gateDistance2(g, out[i].point_W), 9.0, 1e-6);
      EXPECT_LE(out[i].normal_W.dot(d), 1e-9);  // entering: against the ray
    }
  }
  EXPECT_GT(hits, 200);
}

TEST(QueryMapSurface, CastViewEqualsCastRaysOnEveryPixel) {
  const BoxRoomMap& s = boxRoom();
  const PinholeCamera camera = cameraPreset("tum-default");
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int view = 0; view < 5; ++view) {
    // Inside the room, looking anywhere (the seen wall, the unseen ones, from inside a gate).
    Eigen::Vector3d c(u(rng), 0.8 * u(rng), u(rng));
    if (view == 4) c = s.global.ellipsoids[s.global.ellipsoids.size() / 2].mean;  // in a gate: t = 0
    const Eigen::Vector3d target =
        view < 3 ? Eigen::Vector3d(u(rng), u(rng), 2.0) : Eigen::Vector3d(u(rng), u(rng), u(rng) * 2);
    const Transform T = test::lookAt(c, target);
    const double max_range = view == 2 ? 1.5 : 8.0;
    const std::vector<RayHit> pixels = s.map.castView(camera, T, max_range);
    ASSERT_EQ(pixels.size(), static_cast<std::size_t>(camera.width * camera.height));
    std::vector<Ray> rays;
    for (int v = 0; v < camera.height; ++v)
      for (int x = 0; x < camera.width; ++x) rays.push_back({T.translation(), pixelRay(camera, T, x, v), max_range});
    std::vector<RayHit> ref(rays.size());
    s.map.castRays(rays, ref);
    std::size_t hits = 0;
    for (std::size_t p = 0; p < rays.size(); ++p) {
      ASSERT_TRUE(sameHit(pixels[p], ref[p])) << "view " << view << " pixel " << p;
      hits += ref[p].hit;
    }
    if (view < 2 || view == 4) {
      EXPECT_GT(hits, rays.size() / 4) << view;
    }
  }
}

TEST(QueryMapSurface, SameAnswersOnOneAndTwoThreads) {
  const BoxRoomMap one(1), two(2);
  const std::vector<Eigen::Vector3d> pts = roomPoints(3000, 43);
  std::vector<DistanceResult> d1(pts.size()), d2(pts.size());
  one.map.distance(pts, d1);
  two.map.distance(pts, d2);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < pts.size(); ++i) rays.push_back({pts[i], Eigen::Vector3d(0.1, -0.2, 1.0), 8.0});
  std::vector<RayHit> r1(rays.size()), r2(rays.size());
  one.map.castRays(rays, r1);
  two.map.castRays(rays, r2);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(d1[i].distance_m, d2[i].distance_m);
    ASSERT_EQ(d1[i].closest_W, d2[i].closest_W);
    ASSERT_EQ(d1[i].gradient, d2[i].gradient);
    ASSERT_EQ(d1[i].ellipsoid, d2[i].ellipsoid);
    ASSERT_TRUE(sameHit(r1[i], r2[i]));
  }
  const PinholeCamera camera = cameraPreset("tum-default");
  const Transform T = test::lookAt({0.2, 0.1, 0.3}, {-0.3, 0.2, 2.0});
  const std::vector<RayHit> v1 = one.map.castView(camera, T, 8.0), v2 = two.map.castView(camera, T, 8.0);
  for (std::size_t p = 0; p < v1.size(); ++p) ASSERT_TRUE(sameHit(v1[p], v2[p]));
  std::vector<Sphere> spheres;
  for (std::size_t i = 0; i < 200; ++i) spheres.push_back({pts[i], 0.05, static_cast<int>(i % 7)});
  const auto c1 = one.map.collide(spheres, 0.01), c2 = two.map.collide(spheres, 0.01);
  ASSERT_EQ(c1.size(), c2.size());
  for (std::size_t b = 0; b < c1.size(); ++b) {
    EXPECT_EQ(c1[b].clearance_m, c2[b].clearance_m);
    EXPECT_EQ(c1[b].sphere, c2[b].sphere);
    EXPECT_EQ(c1[b].collides, c2[b].collides);
    EXPECT_EQ(c1[b].touches_unknown, c2[b].touches_unknown);
  }
}

// The wall z = 2 seen by keyframe 0 from 2 m: the distance and the ray range of the analytic wall,
// short by at most the gate's reach k sigma_n (+ 1 mm), sigma_n the sensor's axial spread at 2 m.
TEST(QueryMapSurface, BoxRoomWallDistanceAndRangeAreTheAnalyticOnes) {
  const BoxRoomMap& s = boxRoom();
  const double k = 3.0, sigma_n = nguyenAxialSd(2.0);
  std::mt19937 rng(47);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 500; ++i) pts.push_back({0.3 * u(rng), 0.3 * u(rng), 1.4 + 0.4 * u(rng)});
  std::vector<DistanceResult> out(pts.size());
  s.map.distance(pts, out);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const double analytic = 2.0 - pts[i].z();
    EXPECT_LE(out[i].distance_m, analytic + 0.001) << i;
    EXPECT_GE(out[i].distance_m, analytic - k * sigma_n - 0.001) << i;
    EXPECT_GT(out[i].gradient.z(), -1.0 - 1e-9);
    EXPECT_LT(out[i].gradient.z(), -0.99) << i;  // away from the wall
  }
  // Rays from keyframe 0's centre through the middle of its image.
  const PinholeCamera camera = cameraPreset("tum-default");
  const Transform T = s.graph.keyframe(0).T_W_K;
  std::vector<Ray> rays;
  for (int v = 60; v < 420; v += 7)
    for (int x = 80; x < 560; x += 7) rays.push_back({T.translation(), pixelRay(camera, T, x, v), 8.0});
  std::vector<RayHit> hits(rays.size());
  s.map.castRays(rays, hits);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    ASSERT_TRUE(hits[i].hit) << i;
    const double cos_theta = rays[i].direction_W.normalized().z();
    const double analytic = 2.0 / cos_theta;
    EXPECT_LE(hits[i].t_m, analytic + 0.001) << i;
    EXPECT_GE(hits[i].t_m, analytic - k * sigma_n / cos_theta - 0.001) << i;
  }
}

TEST(QueryMapSurface, ASphereChainCollidesNearTheWallAndNotFarFromIt) {
  const BoxRoomMap& s = boxRoom();
  const double r = 0.05, clearance = 0.02;
  std::vector<Sphere> spheres;
  for (int i = 0; i < 7; ++i) spheres.push_back({{-0.3 + 0.1 * i, 0.0, 1.93}, r, 0});  // 7 cm from the wall
  for (int i = 0; i < 7; ++i) spheres.push_back({{-0.3 + 0.1 * i, 0.0, 1.85}, r, 3});  // 15 cm from it
  for (int i = 0; i < 3; ++i) spheres.push_back({{-0.1 + 0.1 * i, 0.0, -1.0}, r, 1});  // behind the cameras
  const std::vector<BodyCollision> bodies = s.map.collide(spheres, clearance);
  ASSERT_EQ(bodies.size(), 3u);
  EXPECT_EQ(bodies[0].body, 0);
  EXPECT_EQ(bodies[1].body, 1);
  EXPECT_EQ(bodies[2].body, 3);
  std::vector<Eigen::Vector3d> centres;
  for (const Sphere& sp : spheres) centres.push_back(sp.centre_W);
  std::vector<DistanceResult> d(centres.size());
  s.map.distance(centres, d);
  const auto expectBody = [&](const BodyCollision& b, int first, int count) {
    double best = kInf;
    int sphere = -1;
    for (int i = first; i < first + count; ++i)
      if (d[static_cast<std::size_t>(i)].distance_m - r < best)
        best = d[static_cast<std::size_t>(i)].distance_m - r, sphere = i;
    EXPECT_EQ(b.clearance_m, best);
    EXPECT_EQ(b.sphere, sphere);
    EXPECT_EQ(b.closest_W, d[static_cast<std::size_t>(sphere)].closest_W);
    EXPECT_EQ(b.collides, best < clearance);
  };
  expectBody(bodies[0], 0, 7);
  expectBody(bodies[2], 7, 7);
  expectBody(bodies[1], 14, 3);
  EXPECT_TRUE(bodies[0].collides);  // 7 cm - 5 cm - the gate's reach < 2 cm
  EXPECT_NEAR(bodies[0].clearance_m, 0.02, 0.02);
  EXPECT_FALSE(bodies[2].collides);  // 15 cm - 5 cm - reach > 2 cm
  EXPECT_FALSE(bodies[1].collides);
  EXPECT_TRUE(bodies[1].touches_unknown);   // no keyframe sees behind the cameras
  EXPECT_FALSE(bodies[2].touches_unknown);  // free in front of the seen wall
}

TEST(QueryMapSurface, EmptyMapAnswers) {
  const QueryMap empty;
  const std::vector<Eigen::Vector3d> pts = {{0, 0, 0}, {1, 2, 3}};
  std::vector<DistanceResult> d(pts.size());
  empty.distance(pts, d);
  for (const DistanceResult& r : d) {
    EXPECT_EQ(r.distance_m, kInf);
    EXPECT_EQ(r.gradient, Eigen::Vector3d::Zero());
    EXPECT_EQ(r.ellipsoid, -1);
  }
  std::vector<RayHit> h(1);
  empty.castRays(std::vector<Ray>{Ray{}}, h);
  EXPECT_FALSE(h[0].hit);
  PinholeCamera small;
  small.width = 32, small.height = 24, small.cx = 15.5, small.cy = 11.5;
  for (const RayHit& p : empty.castView(small, Transform::Identity(), 8.0)) EXPECT_FALSE(p.hit);
  const auto bodies = empty.collide(std::vector<Sphere>{{{0, 0, 0}, 0.1, 0}}, 0.0);
  ASSERT_EQ(bodies.size(), 1u);
  EXPECT_FALSE(bodies[0].collides);
  EXPECT_EQ(bodies[0].clearance_m, kInf);
  EXPECT_TRUE(bodies[0].touches_unknown);
  EXPECT_TRUE(empty.collide({}, 0.0).empty());
}

TEST(QueryMapSurface, BadInputThrowsNamingTheIndex) {
  const BoxRoomMap& s = boxRoom();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const auto message = [](const auto& f) {
    try {
      f();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no exception");
  };
  std::vector<Eigen::Vector3d> pts = {{0, 0, 1}, {0, nan, 1}};
  std::vector<DistanceResult> d(pts.size());
  EXPECT_NE(message([&] { s.map.distance(pts, d); }).find("point 1"), std::string::npos);
  pts[1] = {kInf, 0, 0};
  EXPECT_NE(message([&] { s.map.distance(pts, d); }).find("point 1"), std::string::npos);
  std::vector<Ray> rays = {Ray{}, Ray{}, {{0, 0, 0}, {0, 0, 0}, 8.0}};
  std::vector<RayHit> h(rays.size());
  EXPECT_NE(message([&] { s.map.castRays(rays, h); }).find("ray 2"), std::string::npos);
  rays[2].direction_W = {nan, 0, 1};
  EXPECT_NE(message([&] { s.map.castRays(rays, h); }).find("ray 2"), std::string::npos);
  rays[2].direction_W = {0, 0, 1};
  rays[1].origin_W = {0, 0, -kInf};
  EXPECT_NE(message([&] { s.map.castRays(rays, h); }).find("ray 1"), std::string::npos);
  std::vector<Sphere> spheres = {{{0, 0, 1}, 0.1, 0}, {{0, 0, 1}, 0.0, 0}};
  EXPECT_NE(message([&] { s.map.collide(spheres, 0.0); }).find("sphere 1"), std::string::npos);
  spheres[1].radius_m = -0.1;
  EXPECT_NE(message([&] { s.map.collide(spheres, 0.0); }).find("sphere 1"), std::string::npos);
  spheres[1].radius_m = nan;
  EXPECT_NE(message([&] { s.map.collide(spheres, 0.0); }).find("sphere 1"), std::string::npos);
  spheres[1] = {{nan, 0, 0}, 0.1, 0};
  EXPECT_NE(message([&] { s.map.collide(spheres, 0.0); }).find("sphere 1"), std::string::npos);
  spheres.pop_back();
  EXPECT_NE(message([&] { s.map.collide(spheres, -0.01); }).find("clearance"), std::string::npos);
  EXPECT_NE(message([&] { s.map.collide(spheres, nan); }).find("clearance"), std::string::npos);
  PinholeCamera camera;
  EXPECT_NE(message([&] { s.map.castView(camera, Transform::Identity(), -1.0); }), "no exception");
  Transform bad = Transform::Identity();
  bad.translation().x() = nan;
  EXPECT_NE(message([&] { s.map.castView(camera, bad, 8.0); }), "no exception");
  // Output spans of the wrong size.
  std::vector<DistanceResult> short_out(1);
  EXPECT_NE(message([&] { s.map.distance(pts, short_out); }), "no exception");
}

}  // namespace
}  // namespace vdmap
