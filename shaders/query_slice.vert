#version 330 core
// The query slice's quad from gl_VertexID (no vertex buffer): origin + s u + t v, (s, t) in [0, 1]^2.
uniform mat4 u_view_proj;
uniform vec3 u_origin, u_u, u_v;
out vec2 v_uv;
void main() {
  v_uv = vec2(gl_VertexID & 1, gl_VertexID >> 1);
  gl_Position = u_view_proj * vec4(u_origin + v_uv.x * u_u + v_uv.y * u_v, 1.0);
}
