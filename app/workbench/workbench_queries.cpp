// The workbench's point queries (docs/workbench.md "Queries"; docs/method.md 13): the probe under
// the cursor and the query slice, read from the QueryMap the worker publishes with every global map.
#include <chrono>
#include <cmath>
#include <cstdio>

#include "app/workbench/workbench.h"
#include "render/view_camera.h"

namespace vdmap::app::gui {

std::string ProbeResult::text() const {
  char text[256];
  const char* name = occupancyName(state.state);
  // p below 0.0005 (free well in front of a surface) would print as 0.000: say "<0.001".
  const double p = state.p_occupied;
  int n = p < 0.0005 ? std::snprintf(text, sizeof text, "%s p<0.001", name)
                              : std::snprintf(text, sizeof text, "%s p=%.3f", name, p);
  const auto more = [&](const char* format, auto... args) {
    if (n >= 0 && n < static_cast<int>(sizeof text)) n += std::snprintf(text + n, sizeof text - n, format, args...);
  };
  if (std::isfinite(distance.distance_m)) more(" \u00b7 %.3f m to surface", distance.distance_m);
  else more(" \u00b7 no surface");
  if (state.state == Occupancy::kFree && state.keyframe >= 0) more(" (kf %d)", state.keyframe);
  more(" \u00b7 %.3f %.3f %.3f", static_cast<double>(point.x), static_cast<double>(point.y),
       static_cast<double>(point.z));
  std::string out = text;
  if (on_slice) out += " (slice)";
  if (!note.empty()) out += " \u00b7 " + note;
  return out;
}

std::shared_ptr<const QuerySnapshot> Workbench::query() const { return worker_ ? worker_->query() : nullptr; }

std::optional<glm::vec3> Workbench::probePoint(float x_px, float y_px, int width, int height,
                                               const std::optional<glm::vec3>& surface) const {
  const ViewportView v = view(width, height);
  const float x = x_px - static_cast<float>(v.image.x), y = y_px - static_cast<float>(v.image.y);
  const glm::vec3 eye = v.camera.eye();
  if (const auto slice = querySlice(); slice && !slice->plane.empty()) {
    // The cursor's ray through the slice's plane (unproject at any depth gives a point on it).
    const std::optional<glm::vec3> far = render::unproject(v.camera, x, y, 0.5f);
    if (!far) return std::nullopt;
    const glm::vec3 d = *far - eye;
    const auto hit = render::intersectPlane(slice->plane, Eigen::Vector3d(eye.x, eye.y, eye.z),
                                            Eigen::Vector3d(d.x, d.y, d.z));
    if (!hit) return std::nullopt;
    return glm::vec3(static_cast<float>(hit->x()), static_cast<float>(hit->y()), static_cast<float>(hit->z()));
  }
  if (!surface) return std::nullopt;
  const glm::vec3 to_eye = eye - *surface;
  const float length = glm::length(to_eye);
  if (!(length > 0.f)) return surface;
  // Back toward the camera, but never behind it.
  return *surface + to_eye * (std::min(ui_.probe_offset_m, 0.99f * length) / length);
}

ProbeResult Workbench::probe(const glm::vec3& p, bool on_slice) const {
  ProbeResult r;
  r.point = p;
  r.on_slice = on_slice;
  const auto q = query();
  if (!q) {
    r.note = "point queries being built";
    return r;
  }
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::Vector3d point(p.x, p.y, p.z);
  q->map->classify({&point, 1}, {&r.state, 1});
  q->map->distance({&point, 1}, {&r.distance, 1});
  r.query_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  r.generation = q->generation;
  r.note = q->note;
  const auto global = worker_->global();
  if (global && global->generation != q->generation && r.note.empty()) r.note = "queries of the previous map";
  return r;
}

bool Workbench::probeAt(float x_px, float y_px, int width, int height, const std::optional<glm::vec3>& surface) {
  const std::string before = ui_.probe_result ? ui_.probe_result->text() : "";
  const std::optional<glm::vec3> p = probePoint(x_px, y_px, width, height, surface);
  if (p) ui_.probe_result = probe(*p, querySlice() != nullptr);
  else ui_.probe_result.reset();
  return (ui_.probe_result ? ui_.probe_result->text() : "") != before;
}

void Workbench::syncQueries() {
  if (!worker_) return;
  worker_->wantQueries(ui_.probe || ui_.query_slice);
  if (!ui_.probe) ui_.probe_result.reset();
  // A finished slice replaces the one shown.
  if (slice_job_.valid() && slice_job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    slice_image_ = slice_job_.get();
    slice_key_ = slice_job_key_;
  }
  const auto q = worker_->query();
  if (!q) slice_image_.reset(), slice_key_ = {};  // another session's, or queries turned off
  if (!ui_.query_slice || slice_job_.valid() || !q) return;
  const SliceKey key{q->map, ui_.query_slice_spec,
                     ui_.query_slice_spec.axis == render::QuerySliceAxis::kUp ? heightFrame() : render::HeightFrame{}};
  if (key == slice_key_ && slice_image_) return;
  slice_job_key_ = key;
  // A map file's keyframes see nothing: the slice spans the map's robust box instead.
  std::optional<render::QuerySliceBox> fallback;
  if (const auto global = worker_->global(); global && q->map->keyframes() == 0) {
    std::vector<glm::vec3> means;
    means.reserve(global->map.ellipsoids.size());
    for (const Ellipsoid& e : global->map.ellipsoids) means.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
    const auto [lo, hi] = render::robustBounds(means);
    fallback = render::QuerySliceBox{{lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z}};
  }
  // Off the UI thread; QueryMap is immutable and computeQuerySlice uses its own threads.
  slice_job_ = std::async(std::launch::async, [q, key, fallback, wake = on_change_] {
    auto image = std::make_shared<const render::QuerySliceImage>(
        render::computeQuerySlice(*q->map, key.spec, key.height, fallback));
    if (wake) wake();
    return image;
  });
}

void Workbench::waitQuerySlice() {
  syncQueries();
  if (slice_job_.valid()) slice_job_.wait();
  syncQueries();
}

}  // namespace vdmap::app::gui
