#include "mapping/local_map/local_map_integrator.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>

namespace vdmap {
namespace {

using detail::FrameSums;
using detail::V4d;

void checkInputs(const RgbdFrame& frame, const PinholeCamera& camera, const Transform& T_W_K) {
  if (!isValidTransform(T_W_K)) throw std::invalid_argument("keyframe pose T_W_K is not a finite rigid transform");
  if (!isValidTransform(frame.T_W_C))
    throw std::invalid_argument("pose of frame " + std::to_string(frame.index) +
                                " is not a finite rigid transform (NaN or not a rotation)");
  if (frame.depth.type() != CV_16UC1 || frame.depth.cols != camera.width || frame.depth.rows != camera.height)
    throw std::invalid_argument(
        "depth image of frame " + std::to_string(frame.index) + " is " + std::to_string(frame.depth.cols) + "x" +
        std::to_string(frame.depth.rows) + (frame.depth.type() == CV_16UC1 ? "" : " and not 16-bit single channel") +
        "; the camera expects 16-bit " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (!frame.rgb.empty() && (frame.rgb.type() != CV_8UC3 || frame.rgb.size() != frame.depth.size()))
    throw std::invalid_argument("colour image of frame " + std::to_string(frame.index) +
                                " is not 8-bit RGB of the depth image's size");
}

// What pass 1 needs for one row: per-column ray parts ((u - cx) / fx) R.col(0), the row's part
// b = ((v - cy) / fy) R.col(1) + R.col(2), translation t of T_K_C, the keyframe projection
// shifted by +0.5 px into container pixels (so that [0, 2W) x [0, 2H) is the container).
struct RowGeometry {
  const double* ray_x;
  const double* ray_y;
  const double* ray_z;
  double b[3], t[3], f[2], c[2], end[2];
  double inv_scale, inv_cell;
  unsigned raw_min, raw_max;
  int cols, rows;
};

// Pass 1 of a row, branch-free so that it vectorises; built for AVX-512, AVX2 and the baseline ISA
// with runtime dispatch, so the binary stays portable. The cell is floor(container px / s),
// computed as a product with 1/s: it may differ from integer division only for points within
// 1e-13 px of a cell border (a measure-zero set; the cell is clamped to the grid).
__attribute__((target_clones("arch=x86-64-v4", "avx2", "default"))) void computeRow(
    const RowGeometry& g, const std::uint16_t* __restrict depth, int width, double* __restrict px,
    double* __restrict py, double* __restrict pz, int* __restrict cell) {
  const double* __restrict ray_x = g.ray_x;
  const double* __restrict ray_y = g.ray_y;
  const double* __restrict ray_z = g.ray_z;
  const double bx = g.b[0], by = g.b[1], bz = g.b[2], tx = g.t[0], ty = g.t[1], tz = g.t[2];
  const double fx = g.f[0], fy = g.f[1], cx = g.c[0], cy = g.c[1], u_end = g.end[0], v_end = g.end[1];
  const double inv_scale = g.inv_scale, inv_cell = g.inv_cell;
  const int raw_min = static_cast<int>(g.raw_min), raw_max = static_cast<int>(g.raw_max);
  const int cols = g.cols, last_col = g.cols - 1, last_row = g.rows - 1;
  for (int u = 0; u < width; ++u) {
    const int raw = depth[u];
    const double d = raw * inv_scale;
    const double rx = d * (ray_x[u] + bx), ry = d * (ray_y[u] + by), rz = d * (ray_z[u] + bz);
    const double x = rx + tx, y = ry + ty, z = rz + tz;
    const double iz = 1.0 / z;
    const double up = fx * x * iz + cx, vp = fy * y * iz + cy;
    const bool ok =
        (raw >= raw_min) & (raw <= raw_max) & (z > 0.0) & (up >= 0.0) & (vp >= 0.0) & (up < u_end) & (vp < v_end);
    const int col = std::min(static_cast<int>((ok ? up : 0.0) * inv_cell), last_col);
    const int row = std::min(static_cast<int>((ok ? vp : 0.0) * inv_cell), last_row);
    px[u] = rx, py[u] = ry, pz[u] = rz;
    cell[u] = ok ? row * cols + col : -1;
  }
}

// Pass 2 of a row: runs of neighbouring pixels in the same cell are summed in registers and
// added to the cell's frame sums once per run (~5 pixels for 5 px cells). With p = (x, y, z, 1)
// the four-wide sums of p, x p and y p give n, s and five scatter entries in three vector
// operations; zz is the sixth. `cell` ends with a -1 sentinel. A cell's first run of the frame
// initialises its sums.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void sumRuns(
    const double* __restrict px, const double* __restrict py, const double* __restrict pz,
    const std::uint8_t* __restrict rgb, int rgb_step, const int* __restrict cell, int width,
    std::int32_t* __restrict slots, FrameSums* __restrict sums, std::vector<int>* used_cells) {
  int u = 0;
  while (u < width) {
    const int c = cell[u];
    if (c < 0) {
      ++u;
      continue;
    }
    V4d q = {0, 0, 0, 0}, xp = q, yp = q;
    double zz = 0;
    std::uint32_t r = 0, g = 0, b = 0;
    for (; cell[u] == c; ++u) {
      const double x = px[u], y = py[u], z = pz[u];
      const V4d p = {x, y, z, 1.0};
      q += p, xp += p * x, yp += p * y, zz += z * z;
      const std::uint8_t* col = rgb + rgb_step * u;
      r += col[0], g += col[1], b += col[2];
    }
    std::int32_t& slot = slots[c];
    if (slot < 0) {
      slot = static_cast<std::int32_t>(used_cells->size());
      used_cells->push_back(c);
      sums[slot] = FrameSums{q, xp, yp, zz, {r, g, b}};
      continue;
    }
    FrameSums& f = sums[slot];
    f.q += q, f.xp += xp, f.yp += yp, f.zz += zz;
    f.c[0] += r, f.c[1] += g, f.c[2] += b;
  }
}

}  // namespace

void LocalMapIntegrator::integrateFrame(const RgbdFrame& frame, const PinholeCamera& camera, const Transform& T_W_K,
                                        KeyframeContainer* container, std::vector<int>* touched_cells) {
  assert(container != nullptr);
  if (touched_cells) touched_cells->clear();
  checkInputs(frame, camera, T_W_K);
  const PinholeCamera& kcam = container->camera();
  const int width = camera.width, height = camera.height;
  const int grid_size = container->cols() * container->rows();
  const int s = container->cellSizePx();

  // Scratch, sized once per container layout (no per-frame allocation when warm).
  if (static_cast<int>(sums_slot_.size()) != grid_size) {
    sums_slot_.assign(grid_size, -1);
    sums_.resize(grid_size);
  }
  used_cells_.clear();

  const Transform T_K_C = T_W_K.inverse(Eigen::Isometry) * frame.T_W_C;
  const Eigen::Matrix3d R = T_K_C.linear();
  const Eigen::Vector3d t = T_K_C.translation();
  ray_x_.resize(width);
  ray_y_.resize(width);
  ray_z_.resize(width);
  for (int u = 0; u < width; ++u) {
    const double xf = (u - camera.cx) / camera.fx;
    ray_x_[u] = xf * R(0, 0);
    ray_y_[u] = xf * R(1, 0);
    ray_z_[u] = xf * R(2, 0);
  }

  // Valid raw depth values: the depth range in sensor units (0 is never valid).
  const double inv_scale = 1.0 / camera.depth_scale;
  const double raw_min_d = std::max(1.0, std::ceil(params_.depth_range.min_m * camera.depth_scale - 1e-9));
  const double raw_max_d = std::floor(params_.depth_range.max_m * camera.depth_scale + 1e-9);
  if (raw_max_d < raw_min_d) return;
  const unsigned raw_min = static_cast<unsigned>(raw_min_d);
  const unsigned raw_max = static_cast<unsigned>(std::min(raw_max_d, 65535.0));

  // Two passes per row. Pass 1 is branch-free arithmetic the compiler vectorises: each pixel's
  // p_K - t and its cell (-1 when the pixel is invalid, behind the keyframe or outside its
  // container). Pass 2 walks the row: runs of neighbouring pixels in the same cell are summed
  // in registers and added to the cell's frame sums once per run (~5 pixels for 5 px cells).
  RowGeometry g;
  g.ray_x = ray_x_.data(), g.ray_y = ray_y_.data(), g.ray_z = ray_z_.data();
  g.t[0] = t.x(), g.t[1] = t.y(), g.t[2] = t.z();
  g.f[0] = kcam.fx, g.f[1] = kcam.fy;
  g.c[0] = kcam.cx + container->offsetU() + 0.5, g.c[1] = kcam.cy + container->offsetV() + 0.5;
  g.end[0] = 2.0 * kcam.width, g.end[1] = 2.0 * kcam.height;
  g.inv_scale = inv_scale, g.inv_cell = 1.0 / s;
  g.raw_min = raw_min, g.raw_max = raw_max;
  g.cols = container->cols(), g.rows = container->rows();
  row_x_.resize(width), row_y_.resize(width), row_z_.resize(width), row_cell_.resize(width + 1);
  double *const px = row_x_.data(), *const py = row_y_.data(), *const pz = row_z_.data();
  int* const pcell = row_cell_.data();
  std::int32_t* const slots = sums_slot_.data();
  FrameSums* const sums = sums_.data();
  static const std::uint8_t kWhite[3] = {255, 255, 255};
  const bool has_rgb = !frame.rgb.empty();

  for (int v = 0; v < height; ++v) {
    const double yf = (v - camera.cy) / camera.fy;
    g.b[0] = yf * R(0, 1) + R(0, 2), g.b[1] = yf * R(1, 1) + R(1, 2), g.b[2] = yf * R(2, 1) + R(2, 2);
    computeRow(g, frame.depth.ptr<std::uint16_t>(v), width, px, py, pz, pcell);
    pcell[width] = -1;  // sentinel: ends the last run without a bounds test
    sumRuns(px, py, pz, has_rgb ? frame.rgb.ptr<std::uint8_t>(v) : kWhite, has_rgb ? 3 : 0, pcell, width, slots, sums,
            &used_cells_);
  }

  // Merge each cell's batch into the container (docs/method.md 2: the arithmetic of mergeBatch
  // written out on the float storage: this loop runs for every touched cell).
  for (std::size_t i = 0; i < used_cells_.size(); ++i) {
    const int cell = used_cells_[i];
    const FrameSums& f = sums_[i];
    StoredCell& c = container->findOrCreate(cell);
    const double N = f.q[3], M = c.n, total = M + N;
    // Batch mean relative to the camera centre t, and the batch scatter S_N = Q - q q^T / N.
    const double mx = f.q[0] / N, my = f.q[1] / N, mz = f.q[2] / N;
    const double SN[6] = {f.xp[0] - f.q[0] * mx, f.xp[1] - f.q[0] * my, f.xp[2] - f.q[0] * mz,
                          f.yp[1] - f.q[1] * my, f.yp[2] - f.q[1] * mz, f.zz - f.q[2] * mz};
    // delta = batch mean - stored mean (zero weight when the cell is new).
    const double dx = t.x() + mx - c.mean[0], dy = t.y() + my - c.mean[1], dz = t.z() + mz - c.mean[2];
    const double w = N / total, k = M * N / total;
    c.mean[0] = static_cast<float>(c.mean[0] + dx * w);
    c.mean[1] = static_cast<float>(c.mean[1] + dy * w);
    c.mean[2] = static_cast<float>(c.mean[2] + dz * w);
    const double dd[6] = {dx * dx, dx * dy, dx * dz, dy * dy, dy * dz, dz * dz};
    for (int j = 0; j < 6; ++j) c.scatter[j] = static_cast<float>(c.scatter[j] + SN[j] + dd[j] * k);
    for (int j = 0; j < 3; ++j) c.color[j] = static_cast<float>((M * c.color[j] + f.c[j]) / total);
    c.n += static_cast<std::uint32_t>(N);
    sums_slot_[cell] = -1;
  }
  if (touched_cells) touched_cells->assign(used_cells_.begin(), used_cells_.end());
}

}  // namespace vdmap
