#include "render/view_draw.h"

#include "render/framebuffer.h"

namespace vdmap::render {

MirrorStyle mirrorStyle(const ViewSpec& spec, const HeightFrame& height) {
  return {.color = spec.color,
          .sigma = spec.sigma,
          .ellipsoids = spec.ellipsoids,
          .map = !spec.map_hidden,
          .frustums = spec.layers.frustums,
          .graph = spec.layers.graph,
          .trajectory = spec.layers.trajectory,
          .groundtruth = spec.layers.groundtruth,
          .points_below_px = spec.points_below_px,
          .height = height,
          .slice = spec.slice,
          .mesh = spec.layers.mesh,
          .mesh_style = spec.mesh_style};
}

void drawMapView(const Gl& gl, const MapMirror& mirror, const FramedView& view, const glm::vec3& background,
                 const PixelRect& viewport, bool with_lines, bool legend, const MeshRenderer* mesh) {
  const PixelRect& r = view.image;  // within the viewport, row 0 on top
  const int image_y = viewport.y + (viewport.height - r.y - r.height);
  gl.Enable(GL_SCISSOR_TEST);
  const bool letterboxed = r.width != viewport.width || r.height != viewport.height;
  if (letterboxed) {
    gl.Scissor(viewport.x, viewport.y, viewport.width, viewport.height);
    gl.ClearColor(kLetterboxColor.r, kLetterboxColor.g, kLetterboxColor.b, 1.f);
    gl.Clear(GL_COLOR_BUFFER_BIT);
  }
  gl.Scissor(viewport.x + r.x, image_y, r.width, r.height);
  gl.ClearColor(background.r, background.g, background.b, 1.f);
  gl.ClearDepth(1.0);
  gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  gl.Disable(GL_SCISSOR_TEST);
  gl.Viewport(viewport.x + r.x, image_y, r.width, r.height);
  if (mesh) mesh->draw(view.camera);
  mirror.draw(view.camera, with_lines);
  // The legend sits at the image's bottom-left (inside a letterboxed keyframe view, as render
  // draws it), then the viewport is restored for the caller.
  if (legend) mirror.drawLegend(r.height);
  gl.Viewport(viewport.x, viewport.y, viewport.width, viewport.height);
}

cv::Mat renderView(const Gl& gl, MapMirror& mirror, const ViewSpec& spec, const ViewScene& scene, int width, int height,
                   const MeshRenderer* mesh) {
  mirror.setStyle(mirrorStyle(spec, scene.height));
  Framebuffer fb(gl, width, height);
  if (spec.kind == ViewKind::kContainer) {
    fb.bindAndClear(0.f, 0.f, 0.f);
    mirror.drawContainer(width, height);
    return fb.readRgb();
  }
  fb.bindAndClear(spec.background.r, spec.background.g, spec.background.b);
  drawMapView(gl, mirror, viewCamera(spec, scene, width, height), spec.background, {0, 0, width, height},
              spec.kind == ViewKind::kGlobal, spec.layers.legend, mesh);
  return fb.readRgb();
}

}  // namespace vdmap::render
