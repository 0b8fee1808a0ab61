#include "mapping/local_map/local_map_integrator.h"

#include <cassert>
#include <cmath>
#include <stdexcept>

namespace vdmap {
namespace {

void checkInputs(const RgbdFrame& frame, const PinholeCamera& camera, const Transform& T_W_K) {
  if (!isValidTransform(T_W_K))
    throw std::invalid_argument("keyframe pose T_W_K is not a finite rigid transform");
  if (!isValidTransform(frame.T_W_C))
    throw std::invalid_argument("pose of frame " + std::to_string(frame.index) +
                                " is not a finite rigid transform (NaN or not a rotation)");
  if (frame.depth.type() != CV_16UC1 || frame.depth.cols != camera.width ||
      frame.depth.rows != camera.height)
    throw std::invalid_argument(
        "depth image of frame " + std::to_string(frame.index) + " is " +
        std::to_string(frame.depth.cols) + "x" + std::to_string(frame.depth.rows) +
        (frame.depth.type() == CV_16UC1 ? "" : " and not 16-bit single channel") +
        "; the camera expects 16-bit " + std::to_string(camera.width) + "x" +
        std::to_string(camera.height));
  if (!frame.rgb.empty() && (frame.rgb.type() != CV_8UC3 || frame.rgb.size() != frame.depth.size()))
    throw std::invalid_argument("colour image of frame " + std::to_string(frame.index) +
                                " is not 8-bit RGB of the depth image's size");
}

}  // namespace

void LocalMapIntegrator::integrateFrame(const RgbdFrame& frame, const PinholeCamera& camera,
                                        const Transform& T_W_K, KeyframeContainer* container,
                                        std::vector<int>* touched_cells) {
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
  col_of_.resize(2 * kcam.width);
  row_of_.resize(2 * kcam.height);
  for (int i = 0; i < 2 * kcam.width; ++i) col_of_[i] = i / s;
  for (int i = 0; i < 2 * kcam.height; ++i) row_of_[i] = (i / s) * container->cols();
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

  // Projection into container pixel coordinates shifted by +0.5, so that the integer part is
  // the container pixel and [0, 2W) x [0, 2H) is the container.
  const double kfx = kcam.fx, kfy = kcam.fy;
  const double kcx = kcam.cx + container->offsetU() + 0.5, kcy = kcam.cy + container->offsetV() + 0.5;
  const double u_end = 2.0 * kcam.width, v_end = 2.0 * kcam.height;
  const bool has_rgb = !frame.rgb.empty();
  const double tx = t.x(), ty = t.y(), tz = t.z();

  FrameSums* acc = nullptr;
  // Runs of neighbouring pixels of a row that fall into the same cell are summed in registers
  // and added to the cell's frame sums once per run (a 5 px cell gives runs of ~5 pixels).
  auto flush = [&](double n, const double* q, const double* Q, const double* c) {
    acc->n += n;
    for (int k = 0; k < 3; ++k) acc->q[k] += q[k];
    for (int k = 0; k < 6; ++k) acc->Q[k] += Q[k];
    for (int k = 0; k < 3; ++k) acc->c[k] += c[k];
  };

  for (int v = 0; v < height; ++v) {
    const auto* drow = frame.depth.ptr<std::uint16_t>(v);
    const auto* crow = has_rgb ? frame.rgb.ptr<std::uint8_t>(v) : nullptr;
    const double yf = (v - camera.cy) / camera.fy;
    const double bx = yf * R(0, 1) + R(0, 2), by = yf * R(1, 1) + R(1, 2), bz = yf * R(2, 1) + R(2, 2);
    int current = -1;
    double ox = 0, oy = 0, oz = 0;
    double rn = 0, q[3] = {0, 0, 0}, Q[6] = {0, 0, 0, 0, 0, 0}, c[3] = {0, 0, 0};
    for (int u = 0; u < width; ++u) {
      const unsigned raw = drow[u];
      if (raw < raw_min || raw > raw_max) continue;
      const double d = raw * inv_scale;
      const double x = d * (ray_x_[u] + bx) + tx;
      const double y = d * (ray_y_[u] + by) + ty;
      const double z = d * (ray_z_[u] + bz) + tz;
      if (!(z > 0.0)) continue;
      const double iz = 1.0 / z;
      const double up = kfx * x * iz + kcx, vp = kfy * y * iz + kcy;
      if (!(up >= 0.0 && vp >= 0.0 && up < u_end && vp < v_end)) continue;
      const int cell = row_of_[static_cast<int>(vp)] + col_of_[static_cast<int>(up)];
      if (cell != current) {
        if (current >= 0) flush(rn, q, Q, c);
        current = cell;
        std::int32_t& slot = sums_slot_[cell];
        if (slot < 0) {
          slot = static_cast<std::int32_t>(used_cells_.size());
          used_cells_.push_back(cell);
          sums_[slot] = FrameSums{{x, y, z}, 0, {0, 0, 0}, {0, 0, 0, 0, 0, 0}, {0, 0, 0}};
        }
        acc = &sums_[slot];
        ox = acc->origin[0], oy = acc->origin[1], oz = acc->origin[2];
        rn = 0;
        q[0] = q[1] = q[2] = 0;
        Q[0] = Q[1] = Q[2] = Q[3] = Q[4] = Q[5] = 0;
        c[0] = c[1] = c[2] = 0;
      }
      const double dx = x - ox, dy = y - oy, dz = z - oz;
      rn += 1.0;
      q[0] += dx, q[1] += dy, q[2] += dz;
      Q[0] += dx * dx, Q[1] += dx * dy, Q[2] += dx * dz;
      Q[3] += dy * dy, Q[4] += dy * dz, Q[5] += dz * dz;
      if (crow) {
        c[0] += crow[3 * u], c[1] += crow[3 * u + 1], c[2] += crow[3 * u + 2];
      } else {
        c[0] += 255.0, c[1] += 255.0, c[2] += 255.0;
      }
    }
    if (current >= 0) flush(rn, q, Q, c);
  }

  // Merge each cell's batch into the container (SPEC section 2 step 4) and reset the scratch.
  for (std::size_t i = 0; i < used_cells_.size(); ++i) {
    const int cell = used_cells_[i];
    const FrameSums& f = sums_[i];
    PointBatch batch;
    batch.n = f.n;
    const Eigen::Vector3d o(f.origin[0], f.origin[1], f.origin[2]), qv(f.q[0], f.q[1], f.q[2]);
    batch.sum = f.n * o + qv;
    batch.scatter << f.Q[0], f.Q[1], f.Q[2], f.Q[1], f.Q[3], f.Q[4], f.Q[2], f.Q[4], f.Q[5];
    batch.scatter -= qv * qv.transpose() / f.n;
    batch.color_sum = Eigen::Vector3d(f.c[0], f.c[1], f.c[2]);
    StoredCell& stored = container->findOrCreate(cell);
    CellStats stats = stored.toStats();
    mergeBatch(batch, &stats);
    stored.fromStats(stats);
    sums_slot_[cell] = -1;
  }
  if (touched_cells) touched_cells->assign(used_cells_.begin(), used_cells_.end());
}

}  // namespace vdmap
