#include "mapping/tracking/ndt_refinement.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "mapping/local_map/sensor_model.h"

namespace vdmap {

double NdtRefinementResult::translationConditioning() const {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(translation_information);
  return es.eigenvalues()(0) / std::max(es.eigenvalues()(2), 1e-300);
}

Transform stepTransform(const Eigen::Matrix<double, 6, 1>& xi) {
  Transform step = Transform::Identity();
  const Eigen::Vector3d phi = xi.tail<3>();
  if (phi.norm() > 0) step.linear() = Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix();
  step.translation() = xi.head<3>();
  return step;
}

PhotometricImage photometricImage(const cv::Mat& rgb) {
  PhotometricImage out;
  if (rgb.empty()) return out;
  cv::Mat grey, half;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  cv::resize(grey, half, cv::Size(rgb.cols / 2, rgb.rows / 2), 0, 0, cv::INTER_AREA);
  half.convertTo(half, CV_32F);
  cv::GaussianBlur(half, out.grey, cv::Size(5, 5), 1.0, 1.0, cv::BORDER_REPLICATE);
  cv::Sobel(out.grey, out.gx, CV_32F, 1, 0, 1, 0.5, 0.0, cv::BORDER_REPLICATE);
  cv::Sobel(out.grey, out.gy, CV_32F, 0, 1, 1, 0.5, 0.0, cv::BORDER_REPLICATE);
  return out;
}

DensePoints sampleDensePoints(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range,
                              int stride_px) {
  DensePoints out;
  if (frame.depth.empty() || stride_px < 1) return out;
  const double inv_scale = 1.0 / camera.depth_scale;
  for (int v = stride_px / 2; v < frame.depth.rows; v += stride_px) {
    const auto* row = frame.depth.ptr<std::uint16_t>(v);
    for (int u = stride_px / 2; u < frame.depth.cols; u += stride_px) {
      const double d = row[u] * inv_scale;
      if (row[u] == 0 || !range.contains(d)) continue;
      out.points_C.push_back(camera.backProject(u, v, d).cast<float>());
    }
  }
  return out;
}

PhotometricPoints samplePhotometricPoints(const RgbdFrame& frame, const PinholeCamera& camera, const DepthRange& range,
                                          int stride_px) {
  PhotometricPoints out;
  const PhotometricImage image = photometricImage(frame.rgb);
  if (image.empty() || frame.depth.size() != frame.rgb.size() || stride_px < 1) return out;
  const int block = std::max(1, stride_px / 2);
  const float min_g2 = kMinPhotometricGradient * kMinPhotometricGradient;
  const double inv_scale = 1.0 / camera.depth_scale;
  for (int by = 0; by + block <= image.grey.rows; by += block) {
    for (int bx = 0; bx + block <= image.grey.cols; bx += block) {
      int best_x = -1, best_y = -1;
      float best = min_g2;
      for (int y = by; y < by + block; ++y)
        for (int x = bx; x < bx + block; ++x) {
          const float gx = image.gx.at<float>(y, x), gy = image.gy.at<float>(y, x);
          if (gx * gx + gy * gy >= best) best = gx * gx + gy * gy, best_x = x, best_y = y;
        }
      if (best_x < 0) continue;
      double lo = 1e300, hi = 0, sum = 0;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const std::uint16_t raw = frame.depth.at<std::uint16_t>(2 * best_y + dy, 2 * best_x + dx);
          const double d = raw * inv_scale;
          if (raw == 0 || !range.contains(d)) lo = 0;
          lo = std::min(lo, d), hi = std::max(hi, d), sum += d;
        }
      if (lo <= 0 || hi > 1.02 * lo) continue;
      out.points_C.push_back(camera.backProject(2 * best_x + 0.5, 2 * best_y + 0.5, sum / 4).cast<float>());
      out.intensity.push_back(image.grey.at<float>(best_y, best_x));
    }
  }
  return out;
}

namespace {

// A cell's distribution (CellDistribution), computed on first use and kept while the cell is
// unchanged.
struct CellInfo {
  std::uint64_t container = 0;  ///< KeyframeContainer::id() it was computed for (0: never)
  std::uint32_t n = 0;          ///< the cell's count then: a cell changes only by gaining points
  CellDistribution d;
};

// Per-thread cache, one entry per stored cell (by its index in cells()) of the container last
// refined against: tracking refines every frame against the current keyframe, whose cells
// mostly did not change since the previous frame.
// Entries depend on the parameters they were computed with: other parameters clear them.
struct Scratch {
  std::vector<CellInfo> cells;
  int min_cell_points = -1;
  double min_variance_m2 = -1, in_plane_inflation = -1;
  bool axial_noise = true;
  void use(const KeyframeContainer& map, const NdtRefinementParams& p) {
    if (cells.size() < map.size()) cells.resize(map.size());
    if (p.min_cell_points == min_cell_points && p.min_variance_m2 == min_variance_m2 &&
        p.in_plane_inflation == in_plane_inflation && p.axial_noise == axial_noise)
      return;
    for (CellInfo& c : cells) c.container = 0;
    min_cell_points = p.min_cell_points, min_variance_m2 = p.min_variance_m2, in_plane_inflation = p.in_plane_inflation;
    axial_noise = p.axial_noise;
  }
};

CellDistribution distributionOf(const StoredCell& cell, const NdtRefinementParams& params) {
  CellDistribution out;
  out.usable = cell.n >= static_cast<std::uint32_t>(std::max(params.min_cell_points, 2));
  if (!out.usable) return out;
  out.mean = cell.mean;
  // The cell's covariance plus the sensor's axial noise at its depth (a single frame's points
  // scatter that much about the surface), or without it (NdtRefinementParams::axial_noise: taken
  // out along the ray, negative variances clamped to 0), plus the floor that keeps a noise-free
  // plane invertible; then the in-plane axes inflated. One eigen-decomposition: adding the
  // isotropic terms moves every eigenvalue and no eigenvector.
  const double sd = nguyenAxialSd(cell.mean.z());
  const std::array<float, 6>& s = cell.scatter;
  const double inv_n1 = 1.0 / (cell.n - 1.0);
  Eigen::Matrix3d sigma;
  sigma << s[0] * inv_n1, s[1] * inv_n1, s[2] * inv_n1,  //
      s[1] * inv_n1, s[3] * inv_n1, s[4] * inv_n1,       //
      s[2] * inv_n1, s[4] * inv_n1, s[5] * inv_n1;
  double isotropic = params.min_variance_m2;
  if (params.axial_noise) {
    isotropic += sd * sd;
  } else {
    const Eigen::Vector3d ray = cell.mean.cast<double>().normalized();
    sigma -= sd * sd * ray * ray.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(sigma);
  Eigen::Vector3d lambda = es.eigenvalues().cwiseMax(0.0).array() + isotropic;  // ascending
  lambda(1) *= params.in_plane_inflation;
  lambda(2) *= params.in_plane_inflation;
  const Eigen::Matrix3d o = es.eigenvectors() * lambda.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
  const float values[6] = {float(o(0, 0)), float(o(0, 1)), float(o(0, 2)),
                           float(o(1, 1)), float(o(1, 2)), float(o(2, 2))};
  std::copy(values, values + 6, out.omega);
  return out;
}

const CellDistribution& cellInfo(const StoredCell& cell, CellInfo* info, std::uint64_t container,
                                 const NdtRefinementParams& params) {
  if (info->container != container || info->n != cell.n) {
    info->container = container;
    info->n = cell.n;
    info->d = distributionOf(cell, params);
  }
  return info->d;
}

struct Linearisation {
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
  int associated = 0;
  int inliers = 0;
  double inlier_m2 = 0.0;
  double support = 0.0;  ///< sum over the points of 1 - rho / rho_max (Tukey): a soft inlier count
  /// H's translation block before the photometric terms were added (unset without them).
  std::optional<Eigen::Matrix3d> H_tt_before_photometric;
  int photometric_points = 0;
  double photometric_sigma = 0.0;
};

// `distribution(cell)`: the CellDistribution of a stored cell of `map`.
template <typename Distribution>
Linearisation linearise(const KeyframeContainer& map, const DensePoints& frame, const Transform& T_K_C,
                        const NdtRefinementParams& params, double robust_k, const Distribution& distribution,
                        std::uint8_t* inlier_flags = nullptr) {
  const PinholeCamera& cam = map.camera();
  const Eigen::Matrix3f R = T_K_C.linear().cast<float>();
  const Eigen::Vector3f t = T_K_C.translation().cast<float>();
  const float gate2 = static_cast<float>(params.max_distance_m * params.max_distance_m);
  const float inv_k2 = static_cast<float>(1.0 / (robust_k * robust_k));
  // Float sums of one point's terms are exact enough (1e-7 relative); the frame's sums are double.
  double H[21] = {}, g[6] = {}, inlier_m2 = 0.0, support = 0.0;
  int associated = 0, inliers = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const Eigen::Vector3f q = R * frame.points_C[i] + t;
    if (q.z() <= 0.0f) continue;
    const float inv_z = 1.0f / q.z();
    const int index = map.gridIndexOfPixel(cam.fx * q.x() * inv_z + cam.cx, cam.fy * q.y() * inv_z + cam.cy);
    if (index < 0) continue;
    const StoredCell* cell = map.find(index);
    if (!cell) continue;
    const CellDistribution& c = distribution(cell);
    if (!c.usable) continue;
    const Eigen::Vector3f r = q - c.mean;
    if (r.squaredNorm() > gate2) continue;
    ++associated;
    const float* o = c.omega;
    // a = Omega r
    const float ax = o[0] * r.x() + o[1] * r.y() + o[2] * r.z();
    const float ay = o[1] * r.x() + o[3] * r.y() + o[4] * r.z();
    const float az = o[2] * r.x() + o[4] * r.y() + o[5] * r.z();
    const float m2 = r.x() * ax + r.y() * ay + r.z() * az;
    // Tukey's biweight (NdtRefinementParams::robust_k).
    const float u = m2 * inv_k2;
    if (u >= 1.0f) continue;
    if (inlier_flags) inlier_flags[i] = 1;
    ++inliers;
    inlier_m2 += m2;
    const float w = (1.0f - u) * (1.0f - u);
    support += w * (1.0f - u);  // 1 - rho/rho_max with rho = k^2/6 (1 - (1 - u)^3)
    // J = [I, -[q]x] (q(xi) = exp(xi) q). J^T Omega r = (a, q x a); J^T Omega J has the blocks
    // Omega, -Omega [q]x and [q]x^T Omega [q]x.
    const float qx = q.x(), qy = q.y(), qz = q.z();
    const float gx = qy * az - qz * ay, gy = qz * ax - qx * az, gz = qx * ay - qy * ax;
    g[0] += w * ax, g[1] += w * ay, g[2] += w * az, g[3] += w * gx, g[4] += w * gy, g[5] += w * gz;
    // B = Omega [q]x^T = -Omega [q]x, column j of [q]x^T is q x e_j... written out:
    // [q]x = [[0,-qz,qy],[qz,0,-qx],[-qy,qx,0]]; B = Omega * [q]x^T.
    const float b00 = o[1] * -qz + o[2] * qy, b01 = o[0] * qz + o[2] * -qx, b02 = o[0] * -qy + o[1] * qx;
    const float b10 = o[3] * -qz + o[4] * qy, b11 = o[1] * qz + o[4] * -qx, b12 = o[1] * -qy + o[3] * qx;
    const float b20 = o[4] * -qz + o[5] * qy, b21 = o[2] * qz + o[5] * -qx, b22 = o[2] * -qy + o[4] * qx;
    // C = [q]x B (= [q]x Omega [q]x^T), symmetric: rows of [q]x times columns of B.
    const float c00 = -qz * b10 + qy * b20, c01 = -qz * b11 + qy * b21, c02 = -qz * b12 + qy * b22;
    const float c11 = qz * b01 - qx * b21, c12 = qz * b02 - qx * b22;
    const float c22 = -qy * b02 + qx * b12;
    const float terms[21] = {o[0], o[1], o[2], b00, b01, b02,  //
                             o[3], o[4], b10,  b11, b12,       //
                             o[5], b20,  b21,  b22,            //
                             c00,  c01,  c02,  c11, c12, c22};
    for (int k = 0; k < 21; ++k) H[k] += w * terms[k];
  }
  Linearisation lin;
  int k = 0;
  for (int row = 0; row < 6; ++row)
    for (int col = row; col < 6; ++col) lin.H(row, col) = lin.H(col, row) = H[k++];
  for (int j = 0; j < 6; ++j) lin.g(j) = g[j];
  lin.associated = associated;
  lin.inliers = inliers;
  lin.inlier_m2 = inlier_m2;
  lin.support = support;
  return lin;
}

// Adds the reprojection terms of the features to `lin`. T_C_K' = T_C_K exp(-xi) for the
// perturbation T_K_C' = exp(xi) T_K_C, so y = T_C_K X moves by -R (rho + phi x X).
void addFeatureTerms(std::span<const FeatureObservation> features, const PinholeCamera& cam, const Transform& T_K_C,
                     const NdtRefinementParams& params, double anneal, Linearisation* lin) {
  const Transform T_C_K = T_K_C.inverse();
  const Eigen::Matrix3d R = T_C_K.linear();
  const double info = 1.0 / (params.feature_sigma_px * params.feature_sigma_px);
  const double inv_k2 = 1.0 / (anneal * anneal * params.feature_robust_k * params.feature_robust_k);
  for (const FeatureObservation& f : features) {
    const Eigen::Vector3d y = T_C_K * f.X_K;
    if (y.z() <= 0.0) continue;
    const double iz = 1.0 / y.z();
    const Eigen::Vector2d e = Eigen::Vector2d(cam.fx * y.x() * iz + cam.cx, cam.fy * y.y() * iz + cam.cy) - f.pixel;
    const double u = e.squaredNorm() * info * inv_k2;
    if (u >= 1.0) continue;
    const double w = info * (1.0 - u) * (1.0 - u);
    lin->support += (1.0 - u) * (1.0 - u) * (1.0 - u);  // a feature counts like a point
    Eigen::Matrix<double, 2, 3> P;
    P << cam.fx * iz, 0, -cam.fx * y.x() * iz * iz, 0, cam.fy * iz, -cam.fy * y.y() * iz * iz;
    Eigen::Matrix<double, 3, 6> dy;
    dy.leftCols<3>() = -R;
    Eigen::Matrix3d skew_X;
    skew_X << 0, -f.X_K.z(), f.X_K.y(), f.X_K.z(), 0, -f.X_K.x(), -f.X_K.y(), f.X_K.x(), 0;
    dy.rightCols<3>() = R * skew_X;
    const Eigen::Matrix<double, 2, 6> J = P * dy;
    lin->H.noalias() += w * J.transpose() * J;
    lin->g.noalias() += w * J.transpose() * e;
  }
}

// Bilinear sample of a CV_32F image at (x, y); false outside the image's inner area.
bool bilinear(const cv::Mat& image, float x, float y, float* value) {
  if (!(x >= 0.0f && y >= 0.0f && x < image.cols - 1.0f && y < image.rows - 1.0f)) return false;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const float ax = x - x0, ay = y - y0;
  const float* r0 = image.ptr<float>(y0) + x0;
  const float* r1 = image.ptr<float>(y0 + 1) + x0;
  *value = (1 - ay) * ((1 - ax) * r0[0] + ax * r0[1]) + ay * ((1 - ax) * r1[0] + ax * r1[1]);
  return true;
}

// Adds the photometric terms of the frame's photometric points to `lin`: r = I_K(pi(q)) - I_C - b
// with q = T_K_C p, b the median of the differences (an exposure change), weighted by the
// differences' own spread (NdtRefinementParams::photometric_min_sigma), and for the
// perturbation exp(xi) T_K_C, dq = [I, -[q]x] xi, so with a = dpi/dq^T grad I_K the Jacobian is
// (a, q x a).
void addPhotometricTerms(const PhotometricTerm& term, const PinholeCamera& cam, const Transform& T_K_C,
                         const NdtRefinementParams& params, double anneal, Linearisation* lin) {
  const PhotometricPoints& frame = term.frame;
  const PhotometricImage& image = term.keyframe;
  lin->H_tt_before_photometric = lin->H.topLeftCorner<3, 3>();
  const Eigen::Matrix3f R = T_K_C.linear().cast<float>();
  const Eigen::Vector3f t = T_K_C.translation().cast<float>();
  // Half-resolution pixel of full-resolution coordinate u: (u - 0.5) / 2.
  const float fx = static_cast<float>(cam.fx / 2), fy = static_cast<float>(cam.fy / 2);
  const float cx = static_cast<float>((cam.cx - 0.5) / 2), cy = static_cast<float>((cam.cy - 0.5) / 2);
  struct Sample {
    Eigen::Vector3f q;
    float x, y, r;
  };
  std::vector<Sample> samples;
  samples.reserve(frame.points_C.size());
  for (std::size_t i = 0; i < frame.points_C.size(); ++i) {
    const Eigen::Vector3f q = R * frame.points_C[i] + t;
    if (q.z() <= 0.0f) continue;
    const float x = fx * q.x() / q.z() + cx, y = fy * q.y() / q.z() + cy;
    float value;
    if (!bilinear(image.grey, x, y, &value)) continue;
    samples.push_back({q, x, y, value - frame.intensity[i]});
  }
  if (samples.empty()) return;
  std::vector<float> r(samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) r[i] = samples[i].r;
  std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2), r.end());
  const float offset = r[r.size() / 2];
  // The noise: the median absolute deviation of the differences, as a sigma, floored.
  for (float& v : r) v = std::abs(v - offset);
  std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(r.size() / 2), r.end());
  const double sigma = std::max(params.photometric_min_sigma, 1.4826 * r[r.size() / 2]);
  const double info = 1.0 / (sigma * sigma);
  lin->photometric_points = static_cast<int>(samples.size());
  lin->photometric_sigma = sigma;
  const double inv_k2 = 1.0 / (anneal * anneal * params.photometric_robust_k * params.photometric_robust_k);
  for (const Sample& p : samples) {
    const double e = p.r - offset;
    const double u = e * e * info * inv_k2;
    if (u >= 1.0) continue;
    float gx, gy;
    bilinear(image.gx, p.x, p.y, &gx);
    bilinear(image.gy, p.x, p.y, &gy);
    const Eigen::Vector3d q = p.q.cast<double>();
    const double iz = 1.0 / q.z();
    const Eigen::Vector3d a(gx * fx * iz, gy * fy * iz, -(gx * fx * q.x() + gy * fy * q.y()) * iz * iz);
    Eigen::Matrix<double, 6, 1> J;
    J << a, q.cross(a);
    const double w = info * (1.0 - u) * (1.0 - u);
    lin->H.noalias() += w * J * J.transpose();
    lin->g.noalias() += w * e * J;
  }
}

// The lookup linearise() takes for `map`: the per-thread cache.
auto cachedDistributions(const KeyframeContainer& map, const NdtRefinementParams& params) {
  static thread_local Scratch scratch;
  scratch.use(map, params);
  return [&map, &params, base = map.cells().data(),
          cells = scratch.cells.data()](const StoredCell* cell) -> const CellDistribution& {
    return cellInfo(*cell, &cells[static_cast<std::size_t>(cell - base)], map.id(), params);
  };
}

NdtRefinementResult resultOf(const Linearisation& lin, std::size_t points) {
  NdtRefinementResult result;
  result.points = static_cast<int>(points);
  result.associated = lin.associated;
  result.inliers = lin.inliers;
  result.rms_mahalanobis = lin.inliers > 0 ? std::sqrt(lin.inlier_m2 / lin.inliers) : 0.0;
  result.support = lin.support;
  result.information = lin.H;
  result.translation_information = lin.H_tt_before_photometric.value_or(lin.H.topLeftCorner<3, 3>());
  result.gradient = lin.g;
  result.photometric_points = lin.photometric_points;
  result.photometric_sigma = lin.photometric_sigma;
  return result;
}

}  // namespace

NdtRefinementResult refineAgainstLocalMap(const KeyframeContainer& map, const DensePoints& frame,
                                          std::span<const FeatureObservation> features, Transform* T_K_C,
                                          const NdtRefinementParams& params, const PhotometricTerm* photometric) {
  const auto distribution = cachedDistributions(map, params);
  int iterations = 0;
  // Annealing: the first steps take points up to annealing_factor times farther (the basin of
  // a Tukey weight at robust_k sigmas of a clean surface is millimetres), each step halves the
  // threshold down to robust_k, where the last steps and the final measurement are made.
  const auto anneal = [&params](int it) { return std::max(1.0, params.annealing_factor / std::pow(2.0, it)); };
  // Every term at the current pose, thresholds scaled by the annealing factor a.
  const auto measure = [&](double a) {
    Linearisation out = linearise(map, frame, *T_K_C, params, a * params.robust_k, distribution);
    addFeatureTerms(features, map.camera(), *T_K_C, params, a, &out);
    if (photometric) addPhotometricTerms(*photometric, map.camera(), *T_K_C, params, a, &out);
    return out;
  };
  Linearisation lin;
  for (int it = 0; it <= params.iterations; ++it) {
    const double a = it == params.iterations ? 1.0 : anneal(it);
    lin = measure(a);
    // The last pass only measures the pose the previous step reached.
    if (it == params.iterations || lin.associated < 6) break;
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(lin.H);
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 1e-12).all()) break;
    const Eigen::Matrix<double, 6, 1> xi = -ldlt.solve(lin.g);
    if (!xi.allFinite()) break;
    *T_K_C = stepTransform(xi) * *T_K_C;
    ++iterations;
    if (a == 1.0 && xi.head<3>().norm() < params.converged_m && xi.tail<3>().norm() < params.converged_rad) {
      lin = measure(1.0);
      break;
    }
  }
  NdtRefinementResult result = resultOf(lin, frame.size());
  result.iterations = iterations;
  return result;
}

NdtRefinementResult lineariseAgainstLocalMap(const KeyframeContainer& map, std::span<const CellDistribution> cells,
                                             const DensePoints& frame, const Transform& T_K_C,
                                             const NdtRefinementParams& params, std::vector<std::uint8_t>* inliers) {
  const auto distribution = [&cells, base = map.cells().data()](const StoredCell* cell) -> const CellDistribution& {
    return cells[static_cast<std::size_t>(cell - base)];
  };
  if (inliers) inliers->assign(frame.size(), 0);
  return resultOf(
      linearise(map, frame, T_K_C, params, params.robust_k, distribution, inliers ? inliers->data() : nullptr),
      frame.size());
}

std::vector<CellDistribution> cellDistributions(const KeyframeContainer& map, const NdtRefinementParams& params) {
  std::vector<CellDistribution> out;
  out.reserve(map.size());
  for (const StoredCell& c : map.cells()) out.push_back(distributionOf(c, params));
  return out;
}

}  // namespace vdmap
