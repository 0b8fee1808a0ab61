#version 330 core
// The container's background: the keyframe image in the middle (nearest texel), dark grey
// around it, and optionally a line on the first pixel row/column of every cell.
uniform vec2 u_viewport;      // output pixels
uniform vec2 u_container;     // container pixels (2W, 2H)
uniform vec2 u_image_offset;  // (W/2, H/2)
uniform int u_cell_size;      // 0: no grid
uniform sampler2D u_image;
out vec4 frag_color;
void main() {
  // Container pixel at this fragment (the output may be scaled; rows read back flipped).
  vec2 c = vec2(gl_FragCoord.x / u_viewport.x, 1.0 - gl_FragCoord.y / u_viewport.y) * u_container - 0.5;
  ivec2 px = ivec2(floor(c + 0.5));
  ivec2 uv = px - ivec2(u_image_offset);
  ivec2 size = textureSize(u_image, 0);
  vec3 color = vec3(0.15);
  if (all(greaterThanEqual(uv, ivec2(0))) && all(lessThan(uv, size))) color = texelFetch(u_image, uv, 0).rgb;
  if (u_cell_size > 0 && (px.x % u_cell_size == 0 || px.y % u_cell_size == 0)) color = mix(color, vec3(0.0), 0.5);
  frag_color = vec4(color, 1.0);
}
