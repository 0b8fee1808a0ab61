#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "render/gpu_buffer.h"
#include "render/scene_types.h"
#include "render/shader_program.h"
#include "render/view_camera.h"

namespace vdmap::render {

struct EllipsoidStyle {
  float sigma = 2.f;  ///< drawn surface at this many standard deviations
  ColorMode color = ColorMode::kRgb;
  int sphere_subdivisions = 1;  ///< icosphere level of the instanced mesh (42 vertices at 1)
  /// Level of detail: an ellipsoid whose bounding sphere projects to a radius below this many
  /// pixels is drawn as a flat-shaded splat of its exact projected ellipse instead of the mesh
  /// (0: always the mesh). Decided per instance and per frame in the shaders. At 4 px the
  /// mesh's shading gradient is a few pixels wide and hardly visible, and splats draw a million
  /// ellipsoids in view far faster under llvmpipe (docs/performance.md).
  float point_below_px = 4.f;
  /// ColorMode::kHeight: heights above `height`'s floor along its up axis, the ramp over the
  /// slice when it is on, else over the instances' 2-98 % height range (ellipsoidColors).
  HeightFrame height{};
  HeightSlice slice{};
};

/// Draws ellipsoids as instanced, shaded icospheres scaled by the covariance's principal axes,
/// and those that project smaller than EllipsoidStyle::point_below_px as splats (one point
/// sprite covering the projected ellipse). Geometry (centre + three scaled axes, 48 bytes) and
/// colour (4 bytes) live in separate GPU buffers: a colour-mode change re-sends colours only.
/// With the splat level on, draw() also sends the instances that
/// may need the mesh (near or large ones), so far ones cost no vertex work per triangle; it
/// re-selects them only when the view or the instances changed. For that the geometry and
/// colours are mirrored on the CPU (52 bytes per ellipsoid).
class EllipsoidRenderer {
 public:
  EllipsoidRenderer(const Gl& gl, const EllipsoidStyle& style = {});
  ~EllipsoidRenderer();
  /// Replaces the whole set. `lod_order`: lodOrder of the set's means when the caller has it
  /// (computed off the UI thread); empty: computed here.
  void set(std::span<const EllipsoidInstance> ellipsoids, std::span<const std::uint32_t> lod_order = {});
  /// Changes sigma (re-sends geometry) or colour mode (re-sends colours) when they differ.
  void setStyle(const EllipsoidStyle& style);
  void draw(const ViewCamera& view) const;
  /// The fast pass while the camera moves: the first min(budget, n) instances of the map's
  /// level-of-detail order (lodOrder, computed in set()) as flat square points, no mesh.
  void drawFast(const ViewCamera& view, std::size_t budget) const;
  std::size_t size() const { return instances_.size(); }
  /// The level-of-detail order of the instances set (a permutation of 0..n-1).
  const std::vector<std::uint32_t>& lodOrder() const { return lod_order_cpu_; }

  /// What the last draw() or drawFast() drew (the bench and tests count it).
  struct DrawStats {
    bool fast = false;
    std::size_t mesh_instances = 0;   ///< sent to the mesh pass (near or large ones)
    std::size_t point_instances = 0;  ///< sent to the splat pass, or the fast pass's points
    double select_ms = 0;             ///< the mesh selection's CPU time (0 when it was reused)
  };
  const DrawStats& lastDraw() const { return last_draw_; }

 private:
  // What decides the mesh-pass selection: the view's camera-z row, focal length, near plane and
  // the splat threshold.
  struct MeshSelectionKey {
    glm::mat4 T_C_W;
    glm::vec4 intrinsics;  // fx, fy, cx, cy
    glm::ivec2 size;
    float near_m, threshold_px;
    bool operator==(const MeshSelectionKey&) const = default;
  };
  // Instances that may need the mesh pass in this view, sent to near_geometry_/near_colors_,
  // and those the splat pass may draw (in front of the near plane, not certainly meshes, their
  // splat within reach of the image), sent to far_indices_; unless they were already selected
  // for the same key. Returns the mesh count.
  std::size_t selectMeshInstances(const ViewCamera& view) const;

  const Gl* gl_;
  EllipsoidStyle style_;
  std::vector<EllipsoidInstance> instances_;  // kept to re-derive geometry/colours on a style change
  std::vector<float> geometry_cpu_;           // what geometry_ and colors_ hold
  std::vector<glm::u8vec4> colors_cpu_;
  std::unique_ptr<ShaderProgram> program_, point_program_, fast_program_;
  VertexArray vao_, near_vao_, point_vao_, fast_vao_;
  GpuBuffer sphere_vertices_, sphere_indices_, geometry_, colors_, lod_order_;
  std::vector<std::uint32_t> lod_order_cpu_;
  mutable DrawStats last_draw_;
  mutable GpuBuffer near_geometry_, near_colors_;
  mutable std::vector<float> near_geometry_cpu_;
  mutable std::vector<glm::u8vec4> near_colors_cpu_;
  mutable GpuBuffer far_indices_;  // element buffer of point_vao_
  mutable std::vector<std::uint32_t> far_indices_cpu_;
  mutable std::optional<MeshSelectionKey> near_key_;  // empty: geometry or colours changed since
  GLsizei index_count_ = 0;
};

}  // namespace vdmap::render
