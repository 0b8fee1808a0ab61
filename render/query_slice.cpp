#include "render/query_slice.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "render/colormap.h"
#include "render/shader_program.h"

namespace vdmap::render {
namespace {

constexpr std::array<const char*, 4> kAxisNames = {"up", "x", "y", "z"};
constexpr std::array<const char*, 2> kColorNames = {"occupancy", "distance"};

}  // namespace

const char* querySliceAxisName(QuerySliceAxis axis) { return kAxisNames[static_cast<std::size_t>(axis)]; }
const char* querySliceColorName(QuerySliceColor color) { return kColorNames[static_cast<std::size_t>(color)]; }

QuerySliceSpec parseQuerySlice(const std::string& text) {
  const std::string form = "'" + text + "': expected AXIS=VALUE (AXIS up, x, y or z; VALUE in metres, e.g. up=1.0)";
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos) throw std::invalid_argument(form);
  QuerySliceSpec spec;
  const std::string axis = text.substr(0, eq), value = text.substr(eq + 1);
  const auto it = std::find(kAxisNames.begin(), kAxisNames.end(), axis);
  if (it == kAxisNames.end()) throw std::invalid_argument(form);
  spec.axis = static_cast<QuerySliceAxis>(it - kAxisNames.begin());
  std::size_t used = 0;
  try {
    spec.offset_m = std::stod(value, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != value.size() || !std::isfinite(spec.offset_m)) throw std::invalid_argument(form);
  return spec;
}

QuerySliceColor parseQuerySliceColor(const std::string& name) {
  const auto it = std::find(kColorNames.begin(), kColorNames.end(), name);
  if (it == kColorNames.end()) throw std::invalid_argument("'" + name + "': expected occupancy or distance");
  return static_cast<QuerySliceColor>(it - kColorNames.begin());
}

QuerySlicePlane querySlicePlane(const QuerySliceSpec& spec, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                const HeightFrame& height) {
  QuerySlicePlane plane;
  Eigen::Vector3d n = Eigen::Vector3d::UnitZ(), u = Eigen::Vector3d::UnitX(), v = Eigen::Vector3d::UnitY();
  switch (spec.axis) {
    case QuerySliceAxis::kX:
      n = Eigen::Vector3d::UnitX(), u = Eigen::Vector3d::UnitY(), v = Eigen::Vector3d::UnitZ();
      break;
    case QuerySliceAxis::kY:
      n = Eigen::Vector3d::UnitY(), u = Eigen::Vector3d::UnitX(), v = Eigen::Vector3d::UnitZ();
      break;
    case QuerySliceAxis::kZ:
      n = Eigen::Vector3d::UnitZ(), u = Eigen::Vector3d::UnitX(), v = Eigen::Vector3d::UnitY();
      break;
    case QuerySliceAxis::kUp: {
      n = Eigen::Vector3d(height.up.x, height.up.y, height.up.z).normalized();
      // In-plane axes from the world axis least along the up axis.
      Eigen::Index k = 0;
      n.cwiseAbs().minCoeff(&k);
      const Eigen::Vector3d helper = Eigen::Vector3d::Unit(k);
      u = (helper - helper.dot(n) * n).normalized();
      v = n.cross(u);
      break;
    }
  }
  plane.normal = n;
  plane.offset = spec.offset_m + (spec.axis == QuerySliceAxis::kUp ? static_cast<double>(height.floor_m) : 0.0);
  if ((lo.array() > hi.array()).any() || spec.samples <= 0) return plane;
  double u0 = INFINITY, u1 = -INFINITY, v0 = INFINITY, v1 = -INFINITY;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    u0 = std::min(u0, p.dot(u)), u1 = std::max(u1, p.dot(u));
    v0 = std::min(v0, p.dot(v)), v1 = std::max(v1, p.dot(v));
  }
  const double side = std::max(u1 - u0, v1 - v0);
  if (!(side > 0)) return plane;
  const double step = side / spec.samples;
  plane.width = std::max(1, static_cast<int>(std::ceil((u1 - u0) / step - 1e-9)));
  plane.height = std::max(1, static_cast<int>(std::ceil((v1 - v0) / step - 1e-9)));
  plane.du = step * u;
  plane.dv = step * v;
  plane.origin = plane.offset * n + u0 * u + v0 * v;
  return plane;
}

QuerySliceImage computeQuerySlice(const QueryMap& map, const QuerySliceSpec& spec, const HeightFrame& height,
                                  const std::optional<QuerySliceBox>& fallback) {
  const auto t0 = std::chrono::steady_clock::now();
  QuerySliceImage out;
  out.spec = spec;
  Eigen::Vector3d lo, hi;
  map.seenBounds(&lo, &hi);
  const bool seen = !(lo.array() > hi.array()).any();
  if (!seen && fallback) lo = fallback->first, hi = fallback->second;
  out.plane = querySlicePlane(spec, lo, hi, height);
  const QuerySlicePlane& plane = out.plane;
  if (plane.empty()) return out;
  const std::size_t n = static_cast<std::size_t>(plane.width) * static_cast<std::size_t>(plane.height);
  std::vector<Eigen::Vector3d> points(n);
  for (int j = 0; j < plane.height; ++j)
    for (int i = 0; i < plane.width; ++i) points[static_cast<std::size_t>(j) * plane.width + i] = plane.sample(i, j);
  std::vector<Classification> classes(n);
  map.classify(points, classes);
  std::vector<DistanceResult> distances;
  if (spec.color == QuerySliceColor::kDistance) {
    distances.resize(n);
    map.distance(points, distances, spec.max_distance_m);
  }
  out.rgba.create(plane.height, plane.width, CV_8UC4);
  for (std::size_t k = 0; k < n; ++k) {
    std::array<std::uint8_t, 4> c{};
    switch (classes[k].state) {
      case Occupancy::kOccupied: ++out.occupied, c = kSliceOccupied; break;
      case Occupancy::kFree: ++out.free, c = kSliceFree; break;
      case Occupancy::kUnknown: ++out.unknown, c = kSliceUnknown; break;
    }
    if (spec.color == QuerySliceColor::kDistance && (classes[k].state != Occupancy::kUnknown || !seen)) {
      const double d = distances[k].distance_m;
      const float t = spec.max_distance_m > 0 ? static_cast<float>(std::min(1.0, d / spec.max_distance_m)) : 1.f;
      const glm::u8vec3 rgb = colormap(t);
      c = {rgb.r, rgb.g, rgb.b, 220};
    }
    std::copy(c.begin(), c.end(), out.rgba.ptr<std::uint8_t>(0) + 4 * k);
  }
  out.compute_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

std::optional<Eigen::Vector3d> intersectPlane(const QuerySlicePlane& plane, const Eigen::Vector3d& origin,
                                              const Eigen::Vector3d& direction) {
  const double denom = plane.normal.dot(direction);
  if (std::abs(denom) < 1e-12) return std::nullopt;
  const double t = (plane.offset - plane.normal.dot(origin)) / denom;
  if (!(t > 0) || !std::isfinite(t)) return std::nullopt;
  return origin + t * direction;
}

QuerySliceRenderer::QuerySliceRenderer(const Gl& gl)
    : gl_(&gl), program_(std::make_unique<ShaderProgram>(gl, "query_slice.vert", "query_slice.frag")), vao_(gl) {
  gl.GenTextures(1, &texture_);
}

QuerySliceRenderer::~QuerySliceRenderer() { gl_->DeleteTextures(1, &texture_); }

void QuerySliceRenderer::set(const QuerySliceImage* image) {
  plane_ = {};
  if (!image || image->plane.empty() || image->rgba.empty()) return;
  CV_Assert(image->rgba.type() == CV_8UC4);
  const cv::Mat rgba = image->rgba.isContinuous() ? image->rgba : image->rgba.clone();
  const Gl& gl = *gl_;
  gl.BindTexture(GL_TEXTURE_2D, texture_);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 1);
  // Row 0 (samples j = 0) is the texture's first row: t = 0 at the plane's origin side.
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, rgba.cols, rgba.rows, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  plane_ = image->plane;
}

void QuerySliceRenderer::draw(const ViewCamera& view) const {
  if (empty()) return;
  const Gl& gl = *gl_;
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthMask(GL_FALSE);
  gl.Enable(GL_BLEND);
  gl.BlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  const auto vec = [](const Eigen::Vector3d& p) { return glm::vec3(p.x(), p.y(), p.z()); };
  program_->use();
  program_->set("u_view_proj", view.viewProjection());
  program_->set("u_origin", vec(plane_.origin));
  program_->set("u_u", vec(plane_.du * plane_.width));
  program_->set("u_v", vec(plane_.dv * plane_.height));
  program_->set("u_image", 0);
  gl.ActiveTexture(GL_TEXTURE0);
  gl.BindTexture(GL_TEXTURE_2D, texture_);
  vao_.bind();
  gl.DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  gl.BindVertexArray(0);
  gl.BindTexture(GL_TEXTURE_2D, 0);
  gl.Disable(GL_BLEND);
  gl.DepthMask(GL_TRUE);
}

}  // namespace vdmap::render
