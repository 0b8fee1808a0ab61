#version 330 core
// A screen-space quad from gl_VertexID (no vertex buffer) covering u_rect (NDC x0, y0, x1, y1).
uniform vec4 u_rect;
void main() {
  vec2 t = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  gl_Position = vec4(mix(u_rect.xy, u_rect.zw, t), 0.0, 1.0);
}
