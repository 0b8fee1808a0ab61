#version 330 core
// One filled 2-D ellipse per instance: a bounding quad in container pixels; the fragment
// shader keeps the pixels within u_sigma of the centre in the Mahalanobis metric.
layout(location = 0) in vec2 i_center;   // container pixels
layout(location = 1) in vec3 i_inv_cov;  // [[a b][b c]] = Sigma_2d^-1, pixels^-2
layout(location = 2) in vec2 i_half;     // bounding half extents, pixels
layout(location = 3) in float i_depth;   // m, nearer ellipses cover farther ones
layout(location = 4) in vec4 i_color;
uniform vec2 u_container;
out vec3 v_color;
out vec2 v_offset;
flat out vec3 v_inv_cov;
void main() {
  vec2 corner = vec2(gl_VertexID & 1, gl_VertexID >> 1) * 2.0 - 1.0;
  v_offset = corner * i_half;
  vec2 c = i_center + v_offset;
  v_color = i_color.rgb;
  v_inv_cov = i_inv_cov;
  float z = clamp(i_depth / 1000.0, 0.0, 1.0) * 2.0 - 1.0;
  gl_Position = vec4(2.0 * (c.x + 0.5) / u_container.x - 1.0, 1.0 - 2.0 * (c.y + 0.5) / u_container.y, z, 1.0);
}
