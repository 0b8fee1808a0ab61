#include "app/workbench/query_controller.h"

#include <chrono>

#include "render/view_camera.h"

namespace vdmap::app::gui {

std::shared_ptr<const QuerySnapshot> QueryController::snapshot() const { return worker_ ? worker_->query() : nullptr; }

std::optional<glm::vec3> QueryController::probePoint(float x_px, float y_px, int width, int height,
                                                     const std::optional<glm::vec3>& surface) const {
  const ViewportView v = view_.viewport(width, height);
  const float x = x_px - static_cast<float>(v.image.x), y = y_px - static_cast<float>(v.image.y);
  const glm::vec3 eye = v.camera.eye();
  if (const auto shown = slice(); shown && !shown->plane.empty()) {
    // The cursor's ray through the slice's plane (unproject at any depth gives a point on it).
    const std::optional<glm::vec3> far = render::unproject(v.camera, x, y, 0.5f);
    if (!far) return std::nullopt;
    const glm::vec3 d = *far - eye;
    const auto hit =
        render::intersectPlane(shown->plane, Eigen::Vector3d(eye.x, eye.y, eye.z), Eigen::Vector3d(d.x, d.y, d.z));
    if (!hit) return std::nullopt;
    return glm::vec3(static_cast<float>(hit->x()), static_cast<float>(hit->y()), static_cast<float>(hit->z()));
  }
  if (!surface) return std::nullopt;
  const glm::vec3 to_eye = eye - *surface;
  const float length = glm::length(to_eye);
  if (!(length > 0.f)) return surface;
  // Back toward the camera, but never behind it.
  return *surface + to_eye * (std::min(ui_.settings.probe_offset_m, 0.99f * length) / length);
}

ProbeResult QueryController::probe(const glm::vec3& p, bool on_slice) const {
  ProbeResult r;
  r.point = p;
  r.on_slice = on_slice;
  const auto q = snapshot();
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

bool QueryController::probeAt(float x_px, float y_px, int width, int height, const std::optional<glm::vec3>& surface) {
  const std::string before = ui_.probe_result ? ui_.probe_result->text() : "";
  const std::optional<glm::vec3> p = probePoint(x_px, y_px, width, height, surface);
  if (p) ui_.probe_result = probe(*p, slice() != nullptr);
  else ui_.probe_result.reset();
  return (ui_.probe_result ? ui_.probe_result->text() : "") != before;
}

void QueryController::sync() {
  if (!worker_) return;
  worker_->wantQueries(ui_.settings.probe || ui_.settings.query_slice);
  if (!ui_.settings.probe) ui_.probe_result.reset();
  // A finished slice replaces the one shown.
  if (slice_job_.valid() && slice_job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
    slice_image_ = slice_job_.get();
    slice_key_ = slice_job_key_;
  }
  const auto q = worker_->query();
  if (!q) slice_image_.reset(), slice_key_ = {};  // another session's, or queries turned off
  if (!ui_.settings.query_slice || slice_job_.valid() || !q) return;
  const SliceKey key{
      q->map, ui_.settings.query_slice_spec,
      ui_.settings.query_slice_spec.axis == render::QuerySliceAxis::kUp ? view_.heightFrame() : render::HeightFrame{}};
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
  slice_job_ = std::async(std::launch::async, [q, key, fallback, wake = state_.on_change] {
    auto image = std::make_shared<const render::QuerySliceImage>(
        render::computeQuerySlice(*q->map, key.spec, key.height, fallback));
    if (wake) wake();
    return image;
  });
}

void QueryController::waitSlice() {
  sync();
  if (slice_job_.valid()) slice_job_.wait();
  sync();
}

}  // namespace vdmap::app::gui
