#include "render/view_camera.h"

#include <algorithm>
#include <cmath>

namespace vdmap::render {

glm::mat4 ViewCamera::projection() const {
  // clip = P * p_C with w = z; x_ndc = 2 (u + 0.5) / W - 1 and y_ndc = 1 - 2 (v + 0.5) / H, so
  // pixel centres land on GL fragment centres and the read-back flip puts row v = 0 on top.
  glm::mat4 P(0.f);  // column-major: P[col][row]
  const float w = static_cast<float>(width), h = static_cast<float>(height);
  P[0][0] = 2.f * fx / w;
  P[2][0] = 2.f * (cx + 0.5f) / w - 1.f;
  P[1][1] = -2.f * fy / h;
  P[2][1] = 1.f - 2.f * (cy + 0.5f) / h;
  P[2][2] = (far_m + near_m) / (far_m - near_m);
  P[3][2] = -2.f * far_m * near_m / (far_m - near_m);
  P[2][3] = 1.f;
  return P;
}

glm::vec3 ViewCamera::eye() const { return glm::vec3(glm::inverse(T_C_W)[3]); }

ViewCamera ViewCamera::lookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up, float fov_y_deg,
                              int width, int height) {
  ViewCamera v;
  v.width = width;
  v.height = height;
  v.fy = v.fx = 0.5f * height / std::tan(glm::radians(fov_y_deg) * 0.5f);
  v.cx = 0.5f * (width - 1);
  v.cy = 0.5f * (height - 1);
  const glm::vec3 z = glm::normalize(target - eye);
  glm::vec3 x = glm::cross(z, up);
  if (glm::length(x) < 1e-6f) x = glm::cross(z, glm::vec3(1.f, 0.f, 0.f));
  x = glm::normalize(x);
  const glm::vec3 y = glm::cross(z, x);  // down in the image
  glm::mat4 T_W_C(1.f);
  T_W_C[0] = glm::vec4(x, 0.f);
  T_W_C[1] = glm::vec4(y, 0.f);
  T_W_C[2] = glm::vec4(z, 0.f);
  T_W_C[3] = glm::vec4(eye, 1.f);
  v.T_C_W = glm::inverse(T_W_C);
  const float dist = glm::length(target - eye);
  v.near_m = std::max(0.01f, dist * 0.01f);
  v.far_m = std::max(100.f, dist * 10.f);
  return v;
}

ViewCamera ViewCamera::lookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up, float fov_y_deg,
                              int width, int height, bool orthographic) {
  if (!orthographic) return lookAt(eye, target, up, fov_y_deg, width, height);
  const float tan_half = std::tan(glm::radians(fov_y_deg) * 0.5f) / kOrthographicFar;
  const ViewCamera near_eye = lookAt(eye, target, up, fov_y_deg, width, height);
  // The far eye snapped to a grid (its direction to 2^-16, its distance to 1/16 m): 1000 times
  // out, the last bit of the view direction is a millimetre of depth, where overlapping
  // ellipsoids would resolve differently for two cameras equal to float rounding (a view file's
  // eye, and the window's orbit camera made from it). The snap turns the view by at most
  // 1e-5 rad.
  const auto snap = [](float x, float step) { return std::round(x / step) * step; };
  const float distance = glm::length(eye - target);
  const glm::vec3 dir = (eye - target) / distance;
  const glm::vec3 snapped(snap(dir.x, 1.f / 65536.f), snap(dir.y, 1.f / 65536.f), snap(dir.z, 1.f / 65536.f));
  ViewCamera v = lookAt(target + snapped * snap(distance * kOrthographicFar, 1.f / 16.f), target, up,
                        glm::degrees(2.f * std::atan(tan_half)), width, height);
  // The clip planes of the perspective view, moved back with the eye: the depth buffer then
  // resolves the scene as finely as there (planes at 1% and 10x of the far eye's distance would
  // leave centimetres per depth step, and overlapping ellipsoids would fight).
  const float back = distance * (kOrthographicFar - 1.f);
  v.near_m = back + near_eye.near_m;
  v.far_m = back + near_eye.far_m;
  return v;
}

ViewCamera ViewCamera::fromPinhole(const PinholeCamera& camera, const Transform& T_W_C, int width, int height) {
  ViewCamera v;
  v.width = width;
  v.height = height;
  const double sx = static_cast<double>(width) / camera.width;
  const double sy = static_cast<double>(height) / camera.height;
  v.fx = static_cast<float>(camera.fx * sx);
  v.fy = static_cast<float>(camera.fy * sy);
  v.cx = static_cast<float>((camera.cx + 0.5) * sx - 0.5);
  v.cy = static_cast<float>((camera.cy + 0.5) * sy - 0.5);
  v.T_C_W = toGlm(T_W_C.inverse());
  return v;
}

glm::mat4 toGlm(const Transform& T) {
  glm::mat4 m(1.f);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) m[c][r] = static_cast<float>(T.matrix()(r, c));
  return m;
}

void OrbitCamera::orbit(float d_yaw, float d_pitch) {
  yaw += d_yaw;
  const float limit = glm::radians(89.f);
  pitch = std::clamp(pitch + d_pitch, -limit, limit);
}

void OrbitCamera::pan(float right_m, float up_m) {
  const ViewCamera v = view(2, 2);
  const glm::mat4 T_W_C = glm::inverse(v.T_C_W);
  target += glm::vec3(T_W_C[0]) * right_m - glm::vec3(T_W_C[1]) * up_m;
}

void OrbitCamera::dolly(float factor) { distance_m = std::max(1e-3f, distance_m * factor); }

void OrbitCamera::fly(float forward_m, float right_m, float up_m) {
  const glm::vec3 forward = glm::normalize(target - eye());
  const glm::vec3 right = glm::normalize(glm::cross(forward, up));
  target += forward * forward_m + right * right_m + glm::normalize(up) * up_m;
}

namespace {

// A frame with `up` as z: any perpendicular pair (a, b) spans the horizon.
void horizon(const glm::vec3& up, glm::vec3* u, glm::vec3* a, glm::vec3* b) {
  *u = glm::normalize(up);
  *a = glm::normalize(glm::cross(*u, std::abs(u->x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0)));
  *b = glm::cross(*u, *a);
}

}  // namespace

OrbitCamera OrbitCamera::fromLookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up,
                                    float fov_y_deg) {
  OrbitCamera cam;
  cam.target = target;
  cam.up = up;
  cam.fov_y_deg = fov_y_deg;
  cam.distance_m = std::max(1e-3f, glm::length(eye - target));
  glm::vec3 u, a, b;
  horizon(up, &u, &a, &b);
  const glm::vec3 dir = (eye - target) / cam.distance_m;
  const float limit = glm::radians(89.f);
  cam.pitch = std::clamp(std::asin(std::clamp(glm::dot(dir, u), -1.f, 1.f)), -limit, limit);
  cam.yaw = std::atan2(glm::dot(dir, b), glm::dot(dir, a));
  return cam;
}

glm::vec3 OrbitCamera::eye() const {
  glm::vec3 u, a, b;
  horizon(up, &u, &a, &b);
  const glm::vec3 dir = std::cos(pitch) * (std::cos(yaw) * a + std::sin(yaw) * b) + std::sin(pitch) * u;
  return target + distance_m * dir;
}

ViewCamera OrbitCamera::view(int width, int height) const {
  return ViewCamera::lookAt(eye(), target, up, fov_y_deg, width, height, orthographic);
}

glm::vec3 OrbitCamera::imageUp() const {
  const ViewCamera v = ViewCamera::lookAt(eye(), target, up, fov_y_deg, 2, 2);
  return -glm::vec3(glm::inverse(v.T_C_W)[1]);
}

void OrbitCamera::tumble(float d_yaw, float d_pitch) {
  // About the image's up the view has pitch 0, so the orbit's pitch limit never holds it back.
  const bool ortho = orthographic;
  *this = fromLookAt(eye(), target, imageUp(), fov_y_deg);
  orthographic = ortho;
  orbit(d_yaw, d_pitch);
}

void OrbitCamera::fit(const FrameBox& box, float aspect, float margin) {
  // The camera's axes for the held direction: r right, u up in the image, f forward.
  glm::vec3 uu, a, b;
  horizon(up, &uu, &a, &b);
  const glm::vec3 back = std::cos(pitch) * (std::cos(yaw) * a + std::sin(yaw) * b) + std::sin(pitch) * uu;
  const glm::vec3 f = -back;
  glm::vec3 r = glm::cross(f, up);
  if (glm::length(r) < 1e-6f) r = glm::cross(f, glm::vec3(1.f, 0.f, 0.f));
  r = glm::normalize(r);
  const glm::vec3 u = glm::cross(r, f);
  const float tan_y = std::tan(glm::radians(fov_y_deg) * 0.5f);
  const float tan_x = tan_y * std::max(aspect, 1e-3f);
  const float keep = 1.f - std::clamp(margin, 0.f, 0.5f);
  // A box of at least 5 cm, so a single point is framed at a sane distance.
  const glm::vec3 box_mid = 0.5f * (box.lo + box.hi);
  const glm::vec3 half = glm::max(0.5f * (box.hi - box.lo), glm::vec3(0.025f));
  const glm::vec3 mid = box.axes * box_mid;
  glm::vec3 corners[8];
  for (int c = 0; c < 8; ++c)
    corners[c] = box.axes * (box_mid + glm::vec3((c & 1) ? half.x : -half.x, (c & 2) ? half.y : -half.y,
                                                 (c & 4) ? half.z : -half.z));
  // The eye is mid + s_r r + s_u u - d f. A corner q (relative to mid) is inside when
  // |q.r - s_r| <= tan_x (q.f + d) and likewise for u. For a given d the shifts that hold every
  // corner form an interval per axis, non-empty from the d of the widest pair of corners on:
  // d >= (a_i - a_j) / (2 tan) - (f_i + f_j) / 2. The smallest such d over both axes is taken,
  // and each shift is its interval's middle (the projected box centred).
  // Orthographic: the image holds the box's extent along r and u at the target's plane.
  float d = 1e-3f;
  for (int axis = 0; axis < 2 && orthographic; ++axis) {
    const glm::vec3& dir = axis == 0 ? r : u;
    const float t = (axis == 0 ? tan_x : tan_y) * keep;
    for (const glm::vec3& ci : corners)
      for (const glm::vec3& cj : corners) d = std::max(d, glm::dot(ci - cj, dir) / (2.f * t));
  }
  for (int axis = 0; axis < 2 && !orthographic; ++axis) {
    const glm::vec3& dir = axis == 0 ? r : u;
    const float t = (axis == 0 ? tan_x : tan_y) * keep;
    for (const glm::vec3& ci : corners)
      for (const glm::vec3& cj : corners)
        d = std::max(d, glm::dot(ci - cj, dir) / (2.f * t) - 0.5f * (glm::dot(ci - mid, f) + glm::dot(cj - mid, f)));
  }
  glm::vec3 shift(0.f);
  for (int axis = 0; axis < 2; ++axis) {
    const glm::vec3& dir = axis == 0 ? r : u;
    const float t = (axis == 0 ? tan_x : tan_y) * keep;
    float lo = -INFINITY, hi = INFINITY;
    for (const glm::vec3& c : corners) {
      const float a = glm::dot(c - mid, dir), z = orthographic ? d : glm::dot(c - mid, f) + d;
      lo = std::max(lo, a - t * z);
      hi = std::min(hi, a + t * z);
    }
    shift += dir * (0.5f * (lo + hi));
  }
  target = mid + shift;
  distance_m = d;
}

OrbitCamera OrbitCamera::framing(const FrameBox& box, const glm::vec3& up, float aspect) {
  OrbitCamera cam;
  cam.up = up;
  cam.yaw = glm::radians(-60.f);
  cam.pitch = glm::radians(35.f);
  cam.frame(box, aspect);
  return cam;
}

std::optional<glm::vec3> unproject(const ViewCamera& view, float x_px, float y_px, float depth01) {
  if (!std::isfinite(depth01) || !std::isfinite(x_px) || !std::isfinite(y_px) || depth01 >= 1.f) return std::nullopt;
  const glm::vec4 ndc(2.f * (x_px + 0.5f) / static_cast<float>(view.width) - 1.f,
                      1.f - 2.f * (y_px + 0.5f) / static_cast<float>(view.height), 2.f * depth01 - 1.f, 1.f);
  const glm::vec4 p = glm::inverse(view.viewProjection()) * ndc;
  if (!(std::abs(p.w) > 1e-12f)) return std::nullopt;
  return glm::vec3(p) / p.w;
}

PixelRect letterbox(int width, int height, int image_width, int image_height) {
  if (width <= 0 || height <= 0 || image_width <= 0 || image_height <= 0)
    return {0, 0, std::max(width, 0), std::max(height, 0)};
  PixelRect r;
  if (static_cast<long>(width) * image_height <= static_cast<long>(height) * image_width) {
    r.width = width;
    r.height = std::max(1, static_cast<int>(std::lround(static_cast<double>(width) * image_height / image_width)));
  } else {
    r.height = height;
    r.width = std::max(1, static_cast<int>(std::lround(static_cast<double>(height) * image_width / image_height)));
  }
  r.x = (width - r.width) / 2;
  r.y = (height - r.height) / 2;
  return r;
}

std::pair<glm::vec3, glm::vec3> robustBounds(const std::vector<glm::vec3>& points) {
  if (points.empty()) return {glm::vec3(-1.f), glm::vec3(1.f)};
  glm::vec3 lo, hi;
  std::vector<float> v(points.size());
  for (int k = 0; k < 3; ++k) {
    for (std::size_t i = 0; i < points.size(); ++i) v[i] = points[i][k];
    const std::size_t a = v.size() * 2 / 100, b = std::min(v.size() - 1, v.size() * 98 / 100);
    std::nth_element(v.begin(), v.begin() + static_cast<long>(a), v.end());
    lo[k] = v[a];
    std::nth_element(v.begin(), v.begin() + static_cast<long>(b), v.end());
    hi[k] = v[b];
  }
  return {lo, hi};
}

}  // namespace vdmap::render
