#include "mapping/query/ellipsoid_geometry.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

namespace vdmap {

namespace {

// Bisection to the last bit: at most digits - min_exponent halvings of a double interval.
constexpr int kMaxBisections = std::numeric_limits<double>::digits - std::numeric_limits<double>::min_exponent;

double robustLength(double a, double b) {
  const double m = std::max(std::abs(a), std::abs(b));
  if (m == 0) return 0;
  return m * std::sqrt((a / m) * (a / m) + (b / m) * (b / m));
}

double robustLength(double a, double b, double c) {
  const double m = std::max({std::abs(a), std::abs(b), std::abs(c)});
  if (m == 0) return 0;
  return m * std::sqrt((a / m) * (a / m) + (b / m) * (b / m) + (c / m) * (c / m));
}

// The root of the decreasing convex g(s) = sum_i (n_i / (s + r_i))^2 - 1 in [s0, s1], g(s0) >= 0 >=
// g(s1) (Eberly's GetRoot), to the last bit: Newton steps from s0, which approach the root from the
// left (the tangents of a convex decreasing function stay below it), kept inside the bracket and
// replaced by bisection when rounding puts them outside; until the bracket cannot shrink. A few
// steps where bisection takes 60 to 100.
template <int N>
double getRoot(const double n[N], const double r[N], double s0, double s1) {
  double s = s0;
  for (int i = 0; i < kMaxBisections; ++i) {
    double g = -1, slope = 0;
    for (int k = 0; k < N; ++k) {
      const double ratio = n[k] / (s + r[k]);
      g += ratio * ratio;
      slope -= 2 * ratio * ratio / (s + r[k]);
    }
    if (g > 0) s0 = s;
    else if (g < 0 && i > 0) s1 = s;  // (at s0 only by rounding of s0 + r_i: keep the bracket)
    else if (g == 0) break;
    double next = s - g / slope;
    if (!(next > s0 && next < s1)) next = 0.5 * (s0 + s1);
    if (next == s0 || next == s1) break;
    s = next;
  }
  return s;
}

// Root s of (r0 z0 / (s + r0))^2 + (z1 / (s + 1))^2 = 1 (Eberly's GetRoot, 2-D).
double getRoot2(double r0, double z0, double z1, double g) {
  const double n[2] = {r0 * z0, z1}, r[2] = {r0, 1};
  return getRoot<2>(n, r, z1 - 1, g < 0 ? 0 : robustLength(n[0], z1) - 1);
}

// The 3-D GetRoot.
double getRoot3(double r0, double r1, double z0, double z1, double z2, double g) {
  const double n[3] = {r0 * z0, r1 * z1, z2}, r[3] = {r0, r1, 1};
  return getRoot<3>(n, r, z2 - 1, g < 0 ? 0 : robustLength(n[0], n[1], z2) - 1);
}

// Ellipse e0 >= e1 > 0, y0, y1 >= 0.
double distanceEllipse(double e0, double e1, double y0, double y1, double* x0, double* x1) {
  if (y1 > 0) {
    if (y0 > 0) {
      const double z0 = y0 / e0, z1 = y1 / e1, g = z0 * z0 + z1 * z1 - 1;
      if (g != 0) {
        const double r0 = (e0 / e1) * (e0 / e1), sbar = getRoot2(r0, z0, z1, g);
        *x0 = r0 * y0 / (sbar + r0);
        *x1 = y1 / (sbar + 1);
        return std::sqrt((*x0 - y0) * (*x0 - y0) + (*x1 - y1) * (*x1 - y1));
      }
      *x0 = y0, *x1 = y1;
      return 0;
    }
    *x0 = 0, *x1 = e1;
    return std::abs(y1 - e1);
  }
  const double numer0 = e0 * y0, denom0 = e0 * e0 - e1 * e1;
  if (numer0 < denom0) {
    const double xde0 = numer0 / denom0;
    *x0 = e0 * xde0;
    *x1 = e1 * std::sqrt(std::max(0.0, 1 - xde0 * xde0));
    return std::sqrt((*x0 - y0) * (*x0 - y0) + *x1 * *x1);
  }
  *x0 = e0, *x1 = 0;
  return std::abs(y0 - e0);
}

// Ellipsoid e0 >= e1 >= e2 > 0, y >= 0 componentwise.
double distanceEllipsoid(const double e[3], const double y[3], double x[3]) {
  if (y[2] > 0) {
    if (y[1] > 0) {
      if (y[0] > 0) {
        const double z0 = y[0] / e[0], z1 = y[1] / e[1], z2 = y[2] / e[2];
        const double g = z0 * z0 + z1 * z1 + z2 * z2 - 1;
        if (g != 0) {
          const double r0 = (e[0] / e[2]) * (e[0] / e[2]), r1 = (e[1] / e[2]) * (e[1] / e[2]);
          const double sbar = getRoot3(r0, r1, z0, z1, z2, g);
          x[0] = r0 * y[0] / (sbar + r0);
          x[1] = r1 * y[1] / (sbar + r1);
          x[2] = y[2] / (sbar + 1);
          return std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) +
                           (x[2] - y[2]) * (x[2] - y[2]));
        }
        x[0] = y[0], x[1] = y[1], x[2] = y[2];
        return 0;
      }
      x[0] = 0;
      return distanceEllipse(e[1], e[2], y[1], y[2], &x[1], &x[2]);
    }
    x[1] = 0;
    if (y[0] > 0) return distanceEllipse(e[0], e[2], y[0], y[2], &x[0], &x[2]);
    x[0] = 0, x[2] = e[2];
    return std::abs(y[2] - e[2]);
  }
  const double denom0 = e[0] * e[0] - e[2] * e[2], denom1 = e[1] * e[1] - e[2] * e[2];
  const double numer0 = e[0] * y[0], numer1 = e[1] * y[1];
  if (numer0 < denom0 && numer1 < denom1) {
    const double xde0 = numer0 / denom0, xde1 = numer1 / denom1;
    const double discr = 1 - xde0 * xde0 - xde1 * xde1;
    if (discr > 0) {
      x[0] = e[0] * xde0, x[1] = e[1] * xde1, x[2] = e[2] * std::sqrt(discr);
      return std::sqrt((x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) + x[2] * x[2]);
    }
  }
  x[2] = 0;
  return distanceEllipse(e[0], e[1], y[0], y[1], &x[0], &x[1]);
}

// Each of v[0..n) rounded to the nearest float. Through a volatile float: GCC 12 at -O3 left
// coefficients unrounded here when written as v[i] = float(v[i]) (or through a float array).
void roundToFloat(double* v, int n) {
  for (int i = 0; i < n; ++i) {
    const volatile float f = static_cast<float>(v[i]);
    v[i] = f;
  }
}

}  // namespace

EllipsoidGate makeGate(const Ellipsoid& e, double gate_sigma, double min_sigma_m) {
  EllipsoidGate g;
  g.mean = e.mean;
  g.k2 = gate_sigma * gate_sigma;
  Eigen::Matrix3d cov = 0.5 * (e.cov + e.cov.transpose());
  cov.diagonal().array() += min_sigma_m * min_sigma_m;
  g.A = cov.inverse();
  g.A = 0.5 * (g.A + g.A.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  // Eigen gives ascending eigenvalues; the distance wants the longest axis first.
  for (int i = 0; i < 3; ++i) {
    g.axes.col(i) = eig.eigenvectors().col(2 - i);
    g.semi_axes[i] = gate_sigma * std::sqrt(std::max(eig.eigenvalues()[2 - i], min_sigma_m * min_sigma_m));
  }
  // Eigenvalues round: keep the order the distance needs.
  g.semi_axes[1] = std::min(g.semi_axes[1], g.semi_axes[0]);
  g.semi_axes[2] = std::min(g.semi_axes[2], g.semi_axes[1]);
  g.half_extent = gate_sigma * cov.diagonal().cwiseSqrt();
  // The shape in float (rounding is monotone: the order of the semi-axes and A's symmetry stay);
  // the frame as a rotation's quaternion in float (a mirrored frame flips its shortest axis).
  roundToFloat(g.A.data(), 9), roundToFloat(g.semi_axes.data(), 3);
  if (g.axes.determinant() < 0) g.axes.col(2) = -g.axes.col(2);
  const Eigen::Quaterniond q(g.axes);
  double c[4] = {q.x(), q.y(), q.z(), q.w()};
  roundToFloat(c, 4);
  g.rotation = Eigen::Vector4d(c[0], c[1], c[2], c[3]).cast<float>();
  g.axes = axesFromQuaternion(g.rotation.data());
  return g;
}

double distanceToEllipsoidSurface(const Eigen::Vector3d& semi_axes, const Eigen::Vector3d& y,
                                  Eigen::Vector3d* closest) {
  const double e[3] = {semi_axes[0], semi_axes[1], semi_axes[2]};
  const double ya[3] = {std::abs(y[0]), std::abs(y[1]), std::abs(y[2])};
  double x[3];
  const double d = distanceEllipsoid(e, ya, x);
  if (closest) *closest = {std::copysign(x[0], y[0]), std::copysign(x[1], y[1]), std::copysign(x[2], y[2])};
  return d;
}

double distanceToGate(const double mean[3], const double a[6], double k2, const Eigen::Matrix3d& axes,
                      const Eigen::Vector3d& semi_axes, const Eigen::Vector3d& q, Eigen::Vector3d* closest) {
  if (gateQuadratic(q.x() - mean[0], q.y() - mean[1], q.z() - mean[2], a[0], a[1], a[2], a[3], a[4], a[5]) <= k2) {
    if (closest) *closest = q;
    return 0;
  }
  const Eigen::Vector3d m(mean[0], mean[1], mean[2]);
  const Eigen::Vector3d y = axes.transpose() * (q - m);
  Eigen::Vector3d x;
  const double d = distanceToEllipsoidSurface(semi_axes, y, closest ? &x : nullptr);
  if (closest) *closest = m + axes * x;
  return d;
}

Eigen::Vector3d gateNormal(const EllipsoidGate& g, const Eigen::Vector3d& p) { return gateNormal(g.A, g.mean, p); }

Eigen::Vector3d gateNormal(const Eigen::Matrix3d& A, const Eigen::Vector3d& mean, const Eigen::Vector3d& p) {
  const Eigen::Vector3d n = A * (p - mean);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

bool gateImageBounds(const EllipsoidGate& g, const PinholeCamera& camera, const Transform& T_C_W, double margin_px,
                     int* u0, int* u1, int* v0, int* v1) {
  const Eigen::Vector3d c = T_C_W * g.mean;
  // k^2 (Sigma + s0^2 I) in the camera frame, from the principal axes (no inversion).
  const Eigen::Matrix3d B = T_C_W.linear() * g.axes;
  const Eigen::Matrix3d M = B * g.semi_axes.cwiseAbs2().asDiagonal() * B.transpose();
  const double z_half = std::sqrt(M(2, 2));
  if (!(c.z() + z_half > 0)) return false;  // behind the camera plane: no ray with t >= 0 reaches it
  *u0 = 0, *u1 = camera.width - 1, *v0 = 0, *v1 = camera.height - 1;
  if (!(c.z() - z_half > 0)) return true;  // straddles the camera plane: its silhouette is unbounded
  // Pixel column u sees the gate when the plane through the camera centre fx x + (cx - u) z = 0
  // cuts it; the bounds are the two tangent planes: with w = cx - u,
  // (fx c0 + w c2)^2 = n^T M n, n = (fx, 0, w): a w^2 + 2 b w + cc = 0.
  const auto bounds = [&](double f, double centre, int axis, int size, int* lo, int* hi) {
    const double a = c.z() * c.z() - M(2, 2), b = f * (c[axis] * c.z() - M(axis, 2)),
                 cc = f * f * (c[axis] * c[axis] - M(axis, axis));
    const double disc = b * b - a * cc;
    if (!(disc >= 0) || !(a > 0)) return true;  // rounding at the edge of the case above: keep the whole range
    const double r = std::sqrt(disc);
    const double w_lo = (-b - r) / a, w_hi = (-b + r) / a;
    const double p_lo = centre - w_hi - margin_px, p_hi = centre - w_lo + margin_px;
    if (!(p_hi >= 0) || !(p_lo <= size - 1)) return false;
    *lo = std::max(0, static_cast<int>(std::floor(std::max(p_lo, -1.0))));
    *hi = std::min(size - 1, static_cast<int>(std::ceil(std::min(p_hi, static_cast<double>(size)))));
    return true;
  };
  return bounds(camera.fx, camera.cx, 0, camera.width, u0, u1) &&
         bounds(camera.fy, camera.cy, 1, camera.height, v0, v1);
}

}  // namespace vdmap
