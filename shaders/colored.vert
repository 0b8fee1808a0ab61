#version 330 core
// Points and lines with per-vertex colour.
layout(location = 0) in vec3 a_pos_W;
layout(location = 1) in vec4 a_color;
uniform mat4 u_view_proj;
uniform float u_point_size;
out vec3 v_color;
void main() {
  v_color = a_color.rgb;
  gl_PointSize = u_point_size;
  gl_Position = u_view_proj * vec4(a_pos_W, 1.0);
}
