#version 330 core
// Headlight shading: ambient plus diffuse from a light at the eye, two-sided.
in vec3 v_color;
in vec3 v_normal_C;
in vec3 v_pos_C;
out vec4 frag_color;
void main() {
  float lambert = abs(dot(normalize(v_normal_C), normalize(-v_pos_C)));
  frag_color = vec4(v_color * (0.35 + 0.65 * lambert), 1.0);
}
