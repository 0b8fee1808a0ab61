#include "render/map_mirror.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include "render/colormap.h"
#include "render/map_scene.h"

namespace vdmap::render {
namespace {

constexpr glm::u8vec3 kSelected{255, 255, 255}, kCurrent{255, 220, 0}, kCamera{255, 60, 60};
constexpr glm::u8vec3 kHighlight{255, 0, 255};

glm::vec3 toVec(const Eigen::Vector3d& p) { return {float(p.x()), float(p.y()), float(p.z())}; }

// A wire diamond around the ellipsoid: its principal axes out to 3 sigma (at least 2 cm, so a
// tiny ellipsoid stays visible) and the octahedron through their tips.
ColoredLines diamond(const Ellipsoid& e) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(e.cov);
  glm::vec3 tip[6];
  for (int k = 0; k < 3; ++k) {
    const double radius = std::max(0.02, 3.0 * std::sqrt(std::max(0.0, eig.eigenvalues()[k])));
    const Eigen::Vector3d axis = eig.eigenvectors().col(k) * radius;
    tip[2 * k] = toVec(e.mean + axis);
    tip[2 * k + 1] = toVec(e.mean - axis);
  }
  ColoredLines lines;
  for (int k = 0; k < 3; ++k) lines.add(tip[2 * k], tip[2 * k + 1], kHighlight);
  for (int a = 0; a < 6; ++a)
    for (int b = a + 1; b < 6; ++b)
      if (a / 2 != b / 2) lines.add(tip[a], tip[b], kHighlight);
  return lines;
}

}  // namespace

GraphLines graphLines(const GraphScene& scene, const MirrorStyle& style) {
  GraphLines out;
  ColoredLines& lines = out.lines;
  for (std::size_t i = 0; i < scene.keyframes.size() && style.frustums; ++i) {
    const int id = static_cast<int>(i);
    const glm::u8vec3 color = id == scene.selected_keyframe  ? kSelected
                              : id == scene.current_keyframe ? kCurrent
                                                             : keyframeColor(id);
    addFrustum(lines, scene.camera, scene.keyframes[i], kKeyframeFrustumDepthM, color);
  }
  if (style.graph) addEdges(lines, scene.keyframes, scene.edges);
  if (!scene.trajectory.empty())
    addFrustum(lines, scene.camera, scene.trajectory.back(), kCameraFrustumDepthM, kCamera);
  if (style.graph) addEdges(out.paths, scene.keyframes, scene.loops, kLoopEdgeColor);
  if (style.groundtruth) addTrajectory(out.paths, scene.groundtruth, kGroundTruthColor);
  if (style.trajectory) addTrajectory(out.paths, scene.trajectory, kTrajectoryColor);
  return out;
}

std::optional<ColorRange> colorRange(std::span<const EllipsoidInstance> ellipsoids, ColorMode mode,
                                     const HeightFrame& height, const HeightSlice& slice) {
  if (ellipsoids.empty() || mode == ColorMode::kRgb || mode == ColorMode::kKeyframe) return std::nullopt;
  if (mode == ColorMode::kHeight) {
    const auto [lo, hi] = heightRange(ellipsoids, height, slice);
    return ColorRange{lo, hi};
  }
  ColorRange range{INFINITY, -INFINITY};
  for (const EllipsoidInstance& e : ellipsoids) {
    float v = static_cast<float>(std::max<std::uint32_t>(1, e.count));
    if (mode == ColorMode::kUncertainty) {
      Eigen::Matrix3f m;
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) m(r, c) = e.cov[c][r];
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> solver;
      solver.computeDirect(m, Eigen::EigenvaluesOnly);
      v = std::sqrt(std::max(solver.eigenvalues()(2), 1e-12f));  // as ellipsoidColors' ramp
    }
    range.lo = std::min(range.lo, v);
    range.hi = std::max(range.hi, v);
  }
  return range;
}

cv::Mat depthToRgb(const cv::Mat& depth, double depth_scale, double max_m) {
  cv::Mat d8, bgr, rgb;
  depth.convertTo(d8, CV_8U, 255.0 / (max_m * depth_scale));
  cv::applyColorMap(d8, bgr, cv::COLORMAP_VIRIDIS);
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  rgb.setTo(cv::Scalar::all(0), depth == 0);
  return rgb;
}

cv::Mat readFramebufferRgb(const Gl& gl, int x, int y, int width, int height) {
  cv::Mat image(height, width, CV_8UC3);
  gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
  gl.ReadPixels(x, y, width, height, GL_RGB, GL_UNSIGNED_BYTE, image.data);
  cv::flip(image, image, 0);
  return image;
}

// The default sphere level 0 draws icosahedra (20 triangles) rather than level-1 spheres (80):
// at 2 sigma an ellipsoid covers a few pixels, and with a software renderer (llvmpipe) the
// view's frame time falls with the triangles (docs/notes/performance.md).
MapMirror::MapMirror(const Gl& gl, int sphere_level)
    : gl_(&gl), ellipsoids_(gl, {.sphere_subdivisions = sphere_level}), points_(gl), lines_(gl), paths_(gl),
      highlight_(gl), container_(gl), legend_(std::make_unique<OverlayRenderer>(gl)), query_slice_renderer_(gl),
      rgb_(gl), depth_(gl), container_image_(gl) {
  lines_.setWidth(1.5f);
  // The trajectories and loop edges are what one compares: drawn over the map, never hidden by
  // it, and wider where the context allows (a core profile draws 1 px).
  paths_.setWidth(3.f);
  paths_.setOnTop(true);
  highlight_.setWidth(2.f);
  highlight_.setOnTop(true);
}

MapMirror::~MapMirror() = default;

void MapMirror::setStyle(const MirrorStyle& style) {
  if (!(style == style_)) ++content_serial_;
  style_ = style;
  if (surface_renderer_) surface_renderer_->setStyle(style.mesh_style);
  ellipsoids_.setStyle({.sigma = style.sigma,
                        .color = style.color,
                        .point_below_px = style.points_below_px,
                        .height = style.height,
                        .slice = style.slice});
  if (style.color != points_style_.color ||
      (style.color == ColorMode::kHeight &&
       (style.height != points_style_.height || style.slice != points_style_.slice))) {
    points_.set(instances_, style.color, style.height, style.slice);
    points_style_ = style;
  }
}

void MapMirror::setMap(int generation, std::span<const Ellipsoid> ellipsoids,
                       std::span<const std::uint32_t> lod_order) {
  if (generation == map_generation_) return;
  map_generation_ = generation;
  instances_ = toInstances(ellipsoids);
  ellipsoids_.set(instances_, lod_order);
  points_.set(instances_, style_.color, style_.height, style_.slice);
  points_style_ = style_;
  ++uploads_.map;
  ++content_serial_;
}

void MapMirror::setGraph(int generation, int selected_keyframe, const std::function<GraphScene()>& build, int variant) {
  const bool toggles_same = style_.frustums == graph_style_.frustums && style_.graph == graph_style_.graph &&
                            style_.trajectory == graph_style_.trajectory &&
                            style_.groundtruth == graph_style_.groundtruth;
  if (generation == graph_generation_ && selected_keyframe == graph_selected_ && variant == graph_variant_ &&
      toggles_same)
    return;
  graph_generation_ = generation;
  graph_selected_ = selected_keyframe;
  graph_variant_ = variant;
  graph_style_ = style_;
  const GraphLines lines = graphLines(build(), style_);
  lines_.set(lines.lines);
  paths_.set(lines.paths);
  ++uploads_.graph;
  ++content_serial_;
}

void MapMirror::setFrame(int generation, const cv::Mat& rgb, const cv::Mat& depth, double depth_scale) {
  if (generation == frame_generation_) return;
  frame_generation_ = generation;
  rgb_.set(rgb);
  if (!depth.empty()) depth_.set(depthToRgb(depth, depth_scale, kDepthRampMaxM));
  ++uploads_.frame;
}

void MapMirror::setContainer(int generation, int keyframe, const cv::Mat& rgb, const PinholeCamera& camera,
                             const Transform& T_W_K, std::span<const Ellipsoid> ellipsoids,
                             const ContainerStyle& style) {
  if (generation == container_generation_ && style == container_style_) return;
  container_generation_ = generation;
  container_style_ = style;
  ++uploads_.container;
  if (keyframe < 0 || rgb.empty()) {
    container_rgb_ = cv::Mat();
    return;
  }
  container_.setKeyframe(rgb, camera, T_W_K);
  container_.setEllipsoids(toInstances(ellipsoids), style);
  if (!container_fb_ || container_fb_->width() != container_.containerWidth() ||
      container_fb_->height() != container_.containerHeight())
    container_fb_ = std::make_unique<Framebuffer>(*gl_, container_.containerWidth(), container_.containerHeight());
  GLint bound = 0, viewport[4];
  gl_->GetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &bound);
  gl_->GetIntegerv(GL_VIEWPORT, viewport);
  container_fb_->bindAndClear(0.f, 0.f, 0.f);
  container_.draw(container_fb_->width(), container_fb_->height());
  container_rgb_ = container_fb_->readRgb();
  container_image_.set(container_rgb_);
  gl_->BindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(bound));
  gl_->Viewport(viewport[0], viewport[1], viewport[2], viewport[3]);
}

void MapMirror::setHighlight(const std::optional<Ellipsoid>& ellipsoid) {
  if (has_highlight_ != ellipsoid.has_value()) ++content_serial_;
  has_highlight_ = ellipsoid.has_value();
  if (!ellipsoid) return;
  if (highlighted_ && highlighted_->mean == ellipsoid->mean && highlighted_->cov == ellipsoid->cov) return;
  highlighted_ = ellipsoid;
  highlight_.set(diamond(*ellipsoid));
  ++content_serial_;
}

void MapMirror::setLegend(const Legend& legend, const glm::vec3& background, int max_width) {
  if (legend == legend_shown_ && background == legend_background_ && max_width == legend_width_) return;
  legend_shown_ = legend;
  legend_background_ = background;
  legend_width_ = max_width;
  ++content_serial_;
  legend_image_ = rasterizeLegend(legend, background, max_width);
  legend_->set(legend_image_);
}

void MapMirror::drawLegend(int height) const {
  if (legend_image_.empty()) return;
  const cv::Point at = legendOrigin(legend_image_, height);
  legend_->draw(at.x, at.y);
}

void MapMirror::drawContainer(int width, int height) const { container_.draw(width, height); }

void MapMirror::draw(const ViewCamera& view, bool with_lines) const {
  if (style_.mesh && surface_renderer_) surface_renderer_->draw(view);
  if (!style_.map) {
  } else if (drawsFast()) {
    ellipsoids_.drawFast(view, fast_budget_);
  } else if (style_.ellipsoids) {
    ellipsoids_.draw(view);
  } else {
    points_.draw(view);
  }
  query_slice_renderer_.draw(view);  // after the opaque map, which hides it where in front
  if (with_lines) lines_.draw(view);
  if (with_lines) paths_.draw(view);
  if (has_highlight_) highlight_.draw(view);
}

void MapMirror::setQuerySlice(std::shared_ptr<const QuerySliceImage> slice) {
  if (slice == query_slice_) return;
  query_slice_ = std::move(slice);
  query_slice_renderer_.set(query_slice_.get());
  ++content_serial_;
}

void MapMirror::setSurfaceMesh(std::shared_ptr<const ColoredMesh> mesh) {
  if (mesh == surface_) return;
  surface_ = std::move(mesh);
  if (!surface_renderer_) surface_renderer_ = std::make_unique<MeshRenderer>(*gl_);
  surface_renderer_->set(surface_ ? *surface_ : ColoredMesh{});
  surface_renderer_->setStyle(style_.mesh_style);
  ++uploads_.mesh;
  ++content_serial_;
}

std::optional<ColorRange> MapMirror::mapColorRange() const {
  return colorRange(instances_, style_.color, style_.height, style_.slice);
}

}  // namespace vdmap::render
