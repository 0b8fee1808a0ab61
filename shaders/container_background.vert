#version 330 core
// A full-viewport quad from gl_VertexID (no vertex buffer).
void main() {
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1) * 2.0 - 1.0;
  gl_Position = vec4(corner, 0.0, 1.0);
}
