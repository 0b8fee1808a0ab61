#version 330 core
// Output 0: colour (headlight-shaded, or the raw vertex colour for synthetic images).
// Output 1 (when the framebuffer has a float target): camera z in metres, the exact
// perspective-correct depth of the surface at the pixel centre, and |cos| of the angle between
// the viewing ray and the face normal (for the grazing-angle cut of the sensor model).
in vec3 v_color;
in vec3 v_pos_C;
uniform int u_shaded;
layout(location = 0) out vec4 frag_color;
layout(location = 1) out vec2 frag_depth;
void main() {
  vec3 n = normalize(cross(dFdx(v_pos_C), dFdy(v_pos_C)));
  float cos_incidence = abs(dot(n, normalize(-v_pos_C)));
  vec3 c = u_shaded == 1 ? v_color * (0.35 + 0.65 * cos_incidence) : v_color;
  frag_color = vec4(c, 1.0);
  frag_depth = vec2(v_pos_C.z, cos_incidence);
}
