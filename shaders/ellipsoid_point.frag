#version 330 core
// A splat: the inside of the projected ellipse d^T S^-1 d <= 1. gl_PointCoord runs along the
// image's u and v (origin at the sprite's top-left; rows are read back flipped).
flat in vec3 v_color;
flat in mat2 v_conic;
flat in float v_size;
out vec4 frag_color;
void main() {
  vec2 d = (gl_PointCoord - 0.5) * v_size;
  if (dot(d, v_conic * d) > 1.0) discard;
  frag_color = vec4(v_color, 1.0);
}
