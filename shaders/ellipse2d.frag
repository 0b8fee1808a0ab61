#version 330 core
in vec3 v_color;
in vec2 v_offset;
flat in vec3 v_inv_cov;
uniform float u_sigma;
out vec4 frag_color;
void main() {
  vec2 d = v_offset;
  float m2 = v_inv_cov.x * d.x * d.x + 2.0 * v_inv_cov.y * d.x * d.y + v_inv_cov.z * d.y * d.y;
  if (m2 > u_sigma * u_sigma) discard;
  frag_color = vec4(v_color, 1.0);
}
