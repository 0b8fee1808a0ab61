#include "render/mesh_renderer.h"

#include <stdexcept>
#include <string>

namespace vdmap::render {

MeshRenderer::MeshRenderer(const Gl& gl)
    : gl_(&gl), program_(std::make_unique<ShaderProgram>(gl, "mesh.vert", "mesh.frag")), vao_(gl), positions_(gl),
      colors_(gl), indices_(gl, GL_ELEMENT_ARRAY_BUFFER) {
  vao_.bind();
  positions_.upload(nullptr, 0);
  positions_.attribute(0, 3, GL_FLOAT, false, sizeof(glm::vec3), 0);
  colors_.upload(nullptr, 0);
  colors_.attribute(1, 3, GL_UNSIGNED_BYTE, true, sizeof(glm::u8vec3), 0);
  indices_.upload(nullptr, 0);
  gl.BindVertexArray(0);
}

MeshRenderer::~MeshRenderer() = default;

void MeshRenderer::set(const ColoredMesh& mesh) {
  if (mesh.colors.size() != mesh.positions.size())
    throw std::invalid_argument("mesh has " + std::to_string(mesh.positions.size()) + " vertices but " +
                                std::to_string(mesh.colors.size()) + " colours");
  for (const auto& t : mesh.triangles)
    if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() || t.z >= mesh.positions.size())
      throw std::invalid_argument("mesh triangle indexes a vertex that does not exist");
  vao_.bind();
  positions_.upload(mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
  colors_.upload(mesh.colors.data(), mesh.colors.size() * sizeof(glm::u8vec3));
  indices_.upload(mesh.triangles.data(), mesh.triangles.size() * sizeof(glm::uvec3));
  gl_->BindVertexArray(0);
  index_count_ = static_cast<GLsizei>(mesh.triangles.size() * 3);
}

void MeshRenderer::draw(const ViewCamera& view) const {
  if (index_count_ == 0) return;
  const Gl& gl = *gl_;
  program_->useWithView(view);
  // u_mode: 0 the raw colour, 1 lit colour, 2 lit grey, 3 flat light grey (the wireframe's edges).
  const bool wire = shaded_ && style_ == MeshStyle::kWireframe;
  program_->set("u_mode", !shaded_ ? 0 : style_ == MeshStyle::kColour ? 1 : style_ == MeshStyle::kShaded ? 2 : 3);
  vao_.bind();
  if (wire) {  // 1 px edges, whatever width the last lines were drawn at
    gl.LineWidth(1.f);
    gl.PolygonMode(GL_FRONT_AND_BACK, GL_LINE);
  }
  gl.DrawElements(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr);
  if (wire) gl.PolygonMode(GL_FRONT_AND_BACK, GL_FILL);
  gl.BindVertexArray(0);
}

}  // namespace vdmap::render
