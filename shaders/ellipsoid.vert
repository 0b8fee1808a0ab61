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
uniform float u_focal_px;  // max(fx, fy) of the view
uniform float u_point_below_px;  // instances projecting smaller than this radius: ellipsoid_point.vert
out vec3 v_color;
out vec3 v_normal_C;
out vec3 v_pos_C;
void main() {
  // Level of detail: an instance whose bounding sphere projects to a radius below
  // u_point_below_px is drawn as one point by the other pass; here its triangles are put beyond
  // the far plane, so the rasteriser rejects them before any setup.
  float radius = sqrt(max(max(dot(i_axis0, i_axis0), dot(i_axis1, i_axis1)), dot(i_axis2, i_axis2)));
  vec4 center_C = u_view * vec4(i_center, 1.0);
  if (center_C.z > 0.0 && u_focal_px * radius < u_point_below_px * center_C.z) {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);
    v_color = vec3(0.0);
    v_normal_C = vec3(0.0, 0.0, 1.0);
    v_pos_C = vec3(0.0, 0.0, 1.0);
    return;
  }
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
