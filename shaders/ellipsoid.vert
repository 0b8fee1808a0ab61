#version 330 core
// Instanced ellipsoid: a unit icosphere vertex mapped by M = [a0 a1 a2] (principal axes scaled
// by sigma * sqrt(lambda)) around the centre. Frames: W world, C camera (x right, y down, z fwd).
layout(location = 0) in vec3 a_unit;
layout(location = 1) in vec3 i_center;
layout(location = 2) in vec3 i_axis0;
layout(location = 3) in vec3 i_axis1;
layout(location = 4) in vec3 i_axis2;
layout(location = 5) in vec4 i_color;
uniform mat4 u_view;  // T_C_W
uniform mat4 u_proj;
out vec3 v_color;
out vec3 v_normal_C;
out vec3 v_pos_C;
void main() {
  mat3 M = mat3(i_axis0, i_axis1, i_axis2);
  vec3 p_W = i_center + M * a_unit;
  // The normal maps by M^-T = M diag(1 / |a_k|^2) because the axes are orthogonal.
  vec3 s2 = max(vec3(dot(i_axis0, i_axis0), dot(i_axis1, i_axis1), dot(i_axis2, i_axis2)), vec3(1e-30));
  vec3 n_W = M * (a_unit / s2);
  vec4 p_C = u_view * vec4(p_W, 1.0);
  v_pos_C = p_C.xyz;
  v_normal_C = mat3(u_view) * n_W;
  v_color = i_color.rgb;
  gl_Position = u_proj * p_C;
}
