#version 330 core
// The fast pass while the camera moves (docs/performance.md "Workbench"): one square point per
// ellipsoid of a prefix of the level-of-detail order (render/lod_order.h), flat-coloured, its
// side the projected bounding diameter times u_spread (the prefix's thinning: sqrt(n / K) for
// surfaces), 1..u_max_px pixels. No ellipse is evaluated per fragment.
layout(location = 1) in vec3 i_center;
layout(location = 2) in vec3 i_axis0;
layout(location = 3) in vec3 i_axis1;
layout(location = 4) in vec3 i_axis2;
layout(location = 5) in vec4 i_color;
uniform mat4 u_view;  // T_C_W
uniform mat4 u_proj;
uniform float u_focal_px;
uniform float u_spread;
uniform float u_max_px;
flat out vec3 v_color;
void main() {
  float radius = sqrt(max(max(dot(i_axis0, i_axis0), dot(i_axis1, i_axis1)), dot(i_axis2, i_axis2)));
  vec4 center_C = u_view * vec4(i_center, 1.0);
  // The splats' mean headlight term (2/3, ellipsoid_point.vert), so colours match the full pass.
  v_color = i_color.rgb * (0.35 + 0.65 * 2.0 / 3.0);
  gl_PointSize = center_C.z > 0.0 ? clamp(2.0 * u_focal_px * radius / center_C.z * u_spread, 1.0, u_max_px) : 1.0;
  gl_Position = u_proj * center_C;
}
