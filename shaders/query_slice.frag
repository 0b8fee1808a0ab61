#version 330 core
// The query slice's samples, nearest, blended by their alpha.
uniform sampler2D u_image;
in vec2 v_uv;
out vec4 frag_color;
void main() {
  frag_color = texture(u_image, v_uv);
  if (frag_color.a <= 0.0) discard;
}
