#version 330 core
// Output 0: colour (u_mode 1: the vertex colour headlight-shaded by the face normal; 2: grey so
// shaded; 3: flat light grey, the wireframe's edges; 0: the raw vertex colour, synthetic images).
// Output 1 (when the framebuffer has a float target): camera z in metres, the exact
// perspective-correct depth of the surface at the pixel centre, and |cos| of the angle between
// the viewing ray and the face normal (for the grazing-angle cut of the sensor model).
in vec3 v_color;
in vec3 v_pos_C;
uniform int u_mode;
layout(location = 0) out vec4 frag_color;
layout(location = 1) out vec2 frag_depth;
void main() {
  vec3 n = normalize(cross(dFdx(v_pos_C), dFdy(v_pos_C)));
  float cos_incidence = abs(dot(n, normalize(-v_pos_C)));
  float light = 0.35 + 0.65 * cos_incidence;
  vec3 c = u_mode == 1 ? v_color * light : u_mode == 2 ? vec3(0.8 * light) : u_mode == 3 ? vec3(0.85) : v_color;
  frag_color = vec4(c, 1.0);
  frag_depth = vec2(v_pos_C.z, cos_incidence);
}
