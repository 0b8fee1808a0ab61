#pragma once
#include <memory>

#include "render/gpu_buffer.h"
#include "render/scene_types.h"
#include "render/shader_program.h"
#include "render/view_camera.h"

namespace vdmap::render {

/// A triangle mesh with vertex colours. Shaded for viewing, or unshaded for synthetic images;
/// into a Framebuffer with a float target it also writes camera z (m) and |cos incidence|.
class MeshRenderer {
 public:
  explicit MeshRenderer(const Gl& gl);
  ~MeshRenderer();
  /// Uploads the mesh (throws std::invalid_argument when an index is out of range).
  void set(const ColoredMesh& mesh);
  void setShaded(bool shaded) { shaded_ = shaded; }
  void draw(const ViewCamera& view) const;

 private:
  const Gl* gl_;
  std::unique_ptr<ShaderProgram> program_;
  VertexArray vao_;
  GpuBuffer positions_, colors_, indices_;
  GLsizei index_count_ = 0;
  bool shaded_ = true;
};

}  // namespace vdmap::render
