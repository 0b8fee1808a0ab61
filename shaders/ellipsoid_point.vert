#version 330 core
// The far level of detail of an ellipsoid: a splat. For instances whose bounding sphere projects
// to a radius below u_point_below_px (the complement of the mesh pass in ellipsoid.vert), one
// point sprite covers the ellipse the sigma surface projects to (J Sigma J^T through the
// pinhole's Jacobian at the centre, as in the container view), flat-shaded. Same instance
// buffers as the mesh pass, one vertex per ellipsoid.
layout(location = 1) in vec3 i_center;
layout(location = 2) in vec3 i_axis0;  // the shortest axis (eigenvalues ascend)
layout(location = 3) in vec3 i_axis1;
layout(location = 4) in vec3 i_axis2;
layout(location = 5) in vec4 i_color;
uniform mat4 u_view;  // T_C_W
uniform mat4 u_proj;
uniform float u_focal_px;
uniform float u_point_below_px;
uniform vec2 u_f_px;  // fx, fy
flat out vec3 v_color;
flat out mat2 v_conic;  // inverse of the 2-D covariance of the ellipse, image pixels
flat out float v_size;  // point size, pixels
// A camera-frame axis a at the centre c, projected to image pixels (first-order).
vec2 project(vec3 a, vec3 c) { return u_f_px * (a.xy - c.xy * (a.z / c.z)) / c.z; }
void main() {
  float radius = sqrt(max(max(dot(i_axis0, i_axis0), dot(i_axis1, i_axis1)), dot(i_axis2, i_axis2)));
  vec4 center_C = u_view * vec4(i_center, 1.0);
  v_color = vec3(0.0);
  v_conic = mat2(1.0);
  v_size = 1.0;
  if (center_C.z <= 0.0 || u_focal_px * radius >= u_point_below_px * center_C.z) {
    gl_Position = vec4(0.0, 0.0, 2.0, 1.0);  // drawn by the mesh pass
    gl_PointSize = 1.0;
    return;
  }
  mat3 R = mat3(u_view);
  vec3 c = center_C.xyz;
  vec2 p0 = project(R * i_axis0, c), p1 = project(R * i_axis1, c), p2 = project(R * i_axis2, c);
  // + 0.5 px^2 on the diagonal: a sub-pixel splat still covers the pixel nearest its centre.
  mat2 S = outerProduct(p0, p0) + outerProduct(p1, p1) + outerProduct(p2, p2) + mat2(0.5);
  float half_trace = 0.5 * (S[0][0] + S[1][1]);
  float lambda_max = half_trace + sqrt(max(half_trace * half_trace - determinant(S), 0.0));
  v_conic = inverse(S);
  v_size = 2.0 * sqrt(lambda_max) + 1.0;
  gl_PointSize = v_size;
  // A flat ellipsoid is lit by the normal of its shortest axis, as the mesh's faces are; a
  // round one by the mean of the sphere's headlight term over its disc (2/3).
  float lambert = 2.0 / 3.0;
  float shortest = length(i_axis0), longest = length(i_axis2);
  if (shortest > 0.0 && longest > 0.0)
    lambert = mix(abs(dot(normalize(R * i_axis0), normalize(-c))), lambert, shortest / longest);
  v_color = i_color.rgb * (0.35 + 0.65 * lambert);
  gl_Position = u_proj * center_C;
}
