#pragma once
// Geometry of one ellipsoid's k-sigma gate (docs/method.md 13.4-13.6), shared by the fast query
// paths and the plain references in the tests so that both give the same answers bit for bit:
// the gate matrix, the squared gate distance, the exact Euclidean distance to the gate's surface,
// a ray's first entry into the gate and the ray through a camera pixel's centre.
#include <cmath>
#include <limits>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"
#include "mapping/local_map/ellipsoid_filter.h"

namespace vdmap {

/// An ellipsoid's gate {x : (x - mean)^T A (x - mean) <= k^2}, A = (Sigma + s0^2 I)^-1. A,
/// semi_axes and the frame's quaternion are float values (rounded, 6e-8 relative: far below what a
/// covariance of a few hundred noisy points knows), so that the query map stores them in float and
/// answers as the gate.
struct EllipsoidGate {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  /// Principal frame of Sigma + s0^2 I: columns are unit axes, longest first (a rotation:
  /// axesFromQuaternion(rotation)); semi_axes[i] = k sqrt(lambda_i) along column i (descending).
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
  Eigen::Vector4f rotation = Eigen::Vector4f(0, 0, 0, 1);  ///< axes as a quaternion x, y, z, w
  Eigen::Vector3d semi_axes = Eigen::Vector3d::Zero();
  /// Half-extent of the gate's axis-aligned bounding box: k sqrt(Sigma_ii + s0^2).
  Eigen::Vector3d half_extent = Eigen::Vector3d::Zero();
  double k2 = 0;  ///< k^2
};

/// The rotation matrix of the quaternion q = (x, y, z, w), normalised in double: a gate's axes
/// from the 4 floats the query map keeps of them (instead of 9).
inline Eigen::Matrix3d axesFromQuaternion(const float q[4]) {
  return Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized().toRotationMatrix();
}

/// The gate of `e` at k = gate_sigma with covariance floor min_sigma_m (docs/method.md 13).
EllipsoidGate makeGate(const Ellipsoid& e, double gate_sigma, double min_sigma_m);

/// r^T A r for symmetric A given by its upper triangle (the one expression every gate test uses,
/// so that a compact copy of A gives the same bits).
inline double gateQuadratic(double x, double y, double z, double a00, double a11, double a22, double a01, double a02,
                            double a12) {
  return a00 * x * x + a11 * y * y + a22 * z * z + 2.0 * (a01 * x * y + a02 * x * z + a12 * y * z);
}

/// (q - mean)^T A (q - mean): inside the gate when <= k^2.
inline double gateDistance2(const EllipsoidGate& g, const Eigen::Vector3d& q) {
  const Eigen::Matrix3d& A = g.A;
  return gateQuadratic(q.x() - g.mean.x(), q.y() - g.mean.y(), q.z() - g.mean.z(), A(0, 0), A(1, 1), A(2, 2), A(0, 1),
                       A(0, 2), A(1, 2));
}

/// Euclidean distance from y to the surface of the axis-aligned ellipsoid with semi-axes
/// e0 >= e1 >= e2 > 0 centred at the origin (Eberly, "Distance from a point to an ellipse, an
/// ellipsoid, or a hyperellipsoid": the root of the 1-D equation to the last bit, by Newton steps
/// kept inside its bracket). `closest` (optional) receives the nearest surface point. Works inside and outside.
double distanceToEllipsoidSurface(const Eigen::Vector3d& semi_axes, const Eigen::Vector3d& y,
                                  Eigen::Vector3d* closest = nullptr);

/// A's upper triangle A00, A11, A22, A01, A02, A12: the packed form every kernel reads, so that a
/// compact copy of a gate gives the same bits as the EllipsoidGate.
inline void gateUpper(const EllipsoidGate& g, double a[6]) {
  a[0] = g.A(0, 0), a[1] = g.A(1, 1), a[2] = g.A(2, 2), a[3] = g.A(0, 1), a[4] = g.A(0, 2), a[5] = g.A(1, 2);
}

/// distanceToGate of the gate given by its parts (mean, A's upper triangle, k^2, principal frame).
double distanceToGate(const double mean[3], const double a[6], double k2, const Eigen::Matrix3d& axes,
                      const Eigen::Vector3d& semi_axes, const Eigen::Vector3d& q, Eigen::Vector3d* closest);

/// Distance from q to the gate's surface: 0 inside the gate (gateDistance2 <= k^2, closest = q),
/// else the exact Euclidean distance to {x : (x - mean)^T A (x - mean) = k^2}.
inline double distanceToGate(const EllipsoidGate& g, const Eigen::Vector3d& q, Eigen::Vector3d* closest = nullptr) {
  double a[6];
  gateUpper(g, a);
  return distanceToGate(g.mean.data(), a, g.k2, g.axes, g.semi_axes, q, closest);
}

/// What a ray's gate entry needs of its origin o alone (so a view computes it once per ellipsoid).
struct GateRayOrigin {
  Eigen::Vector3d A_oc = Eigen::Vector3d::Zero();  ///< A (o - mean)
  double gamma = 0;                                ///< (o - mean)^T A (o - mean) - k^2
};

/// gateRayOrigin of the gate given by its mean, A's upper triangle and k^2.
inline GateRayOrigin gateRayOrigin(const double mean[3], const double a[6], double k2, const Eigen::Vector3d& o) {
  GateRayOrigin r;
  const double x = o.x() - mean[0], y = o.y() - mean[1], z = o.z() - mean[2];
  r.A_oc = {a[0] * x + a[3] * y + a[4] * z, a[3] * x + a[1] * y + a[5] * z, a[4] * x + a[5] * y + a[2] * z};
  r.gamma = x * r.A_oc.x() + y * r.A_oc.y() + z * r.A_oc.z() - k2;
  return r;
}

inline GateRayOrigin gateRayOrigin(const EllipsoidGate& g, const Eigen::Vector3d& o) {
  double a[6];
  gateUpper(g, a);
  return gateRayOrigin(g.mean.data(), a, g.k2, o);
}

/// The smallest t >= 0 at which o + t d (d unit) enters the gate, t = 0 when o is inside; +inf when
/// the ray misses it or enters it beyond max_t. alpha = d^T A d, beta = d^T A (o - mean), the root
/// gamma / (sqrt(beta^2 - alpha gamma) - beta) (the smaller root, without cancellation).
/// True when gamma / (-2 beta) > max_t by more than rounding (beta < 0).
inline bool gateEntryBeyond(double gamma, double beta, double max_t) {
  return gamma > max_t * (-2.0 * beta) * (1 + 1e-9);
}

inline double gateRayEntry(const double a[6], const GateRayOrigin& o, const Eigen::Vector3d& d, double max_t) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (o.gamma <= 0) return 0.0;
  const double beta = d.x() * o.A_oc.x() + d.y() * o.A_oc.y() + d.z() * o.A_oc.z();
  if (beta >= 0) return kInf;  // moving away from the gate's centre while outside: no entry ahead
  // sqrt(disc) <= -beta, so t >= gamma / (-2 beta): beyond max_t (with slack for rounding) it is a
  // miss without the rest. Gives the same answers, sooner, when a nearer hit is known.
  if (gateEntryBeyond(o.gamma, beta, max_t)) return kInf;
  const double alpha = gateQuadratic(d.x(), d.y(), d.z(), a[0], a[1], a[2], a[3], a[4], a[5]);
  const double disc = beta * beta - alpha * o.gamma;
  if (disc < 0) return kInf;
  const double t = o.gamma / (std::sqrt(disc) - beta);
  return t <= max_t ? t : kInf;
}

/// gateRayEntry with the gate's A (its upper triangle a = A00, A11, A22, A01, A02, A12: the same
/// bits from a packed copy).
inline double gateRayEntry(const EllipsoidGate& g, const GateRayOrigin& o, const Eigen::Vector3d& d, double max_t) {
  double a[6];
  gateUpper(g, a);
  return gateRayEntry(a, o, d, max_t);
}

/// Outward unit normal of the gate's surface at p: A (p - mean) normalised.
Eigen::Vector3d gateNormal(const EllipsoidGate& g, const Eigen::Vector3d& p);
/// The same from the gate's A and mean alone.
Eigen::Vector3d gateNormal(const Eigen::Matrix3d& A, const Eigen::Vector3d& mean, const Eigen::Vector3d& p);

/// A ray direction as every query uses it: d / |d|. Throws nothing; the caller checks d.
inline Eigen::Vector3d unitDirection(const Eigen::Vector3d& d) { return d / d.norm(); }

/// The unit world direction of the ray through the centre of pixel (u, v) of a camera at T_W_C
/// (its origin is T_W_C.translation()).
inline Eigen::Vector3d pixelRay(const PinholeCamera& camera, const Transform& T_W_C, int u, int v) {
  const Eigen::Vector3d d_C((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
  return unitDirection(T_W_C.linear() * d_C);
}

/// Pixel box [u0, u1] x [v0, v1] (inclusive, clamped to the image) that holds every pixel whose
/// centre ray can meet the gate of `g` seen by a camera at T_C_W's inverse: the exact bounds of the
/// gate's silhouette (its dual quadric), grown by margin_px; the whole image when the gate reaches
/// behind the camera's z = 0 plane. False when no pixel can see it (entirely behind the camera or
/// outside the image).
bool gateImageBounds(const EllipsoidGate& g, const PinholeCamera& camera, const Transform& T_C_W, double margin_px,
                     int* u0, int* u1, int* v0, int* v1);

}  // namespace vdmap
