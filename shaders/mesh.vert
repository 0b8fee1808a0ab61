#version 330 core
// Triangle mesh with vertex colours.
layout(location = 0) in vec3 a_pos_W;
layout(location = 1) in vec4 a_color;
uniform mat4 u_view;  // T_C_W
uniform mat4 u_proj;
out vec3 v_color;
out vec3 v_pos_C;
void main() {
  vec4 p_C = u_view * vec4(a_pos_W, 1.0);
  v_pos_C = p_C.xyz;
  v_color = a_color.rgb;
  gl_Position = u_proj * p_C;
}
