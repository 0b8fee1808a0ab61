#pragma once
#include <memory>

#include "render/gpu_buffer.h"
#include "render/scene_types.h"
#include "render/shader_program.h"
#include "render/view_camera.h"

namespace vdmap::render {

/// A triangle mesh with vertex colours. Shaded for viewing (in a MeshStyle: its colours, grey, or
/// its edges), or unshaded for synthetic images; into a Framebuffer with a float target it also
/// writes camera z (m) and |cos incidence|.
class MeshRenderer {
 public:
  explicit MeshRenderer(const Gl& gl);
  ~MeshRenderer();
  /// Uploads the mesh (throws std::invalid_argument when an index is out of range).
  void set(const ColoredMesh& mesh);
  void setShaded(bool shaded) { shaded_ = shaded; }
  /// How a shaded mesh is drawn (default kColour).
  void setStyle(MeshStyle style) { style_ = style; }
  std::size_t triangles() const { return static_cast<std::size_t>(index_count_ / 3); }
  void draw(const ViewCamera& view) const;

 private:
  const Gl* gl_;
  std::unique_ptr<ShaderProgram> program_;
  VertexArray vao_;
  GpuBuffer positions_, colors_, indices_;
  GLsizei index_count_ = 0;
  bool shaded_ = true;
  MeshStyle style_ = MeshStyle::kColour;
};

}  // namespace vdmap::render
