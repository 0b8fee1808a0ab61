#version 330 core
// The container's background: the keyframe image in the middle (nearest texel), dark grey
// around it, and optionally a line on the first pixel row/column of every cell; drawn a second
// time with u_bounds_only after the ellipses, the image's outline.
uniform vec2 u_viewport;      // output pixels
uniform vec2 u_container;     // container pixels (2W, 2H)
uniform vec2 u_image_offset;  // (W/2, H/2)
uniform int u_cell_size;      // 0: no grid
uniform int u_bounds_only;    // 1: only the image's outline (drawn over the ellipses), else discard
uniform sampler2D u_image;
out vec4 frag_color;
// Within 0.75 output pixels of the image's outline (its pixels' outer edges).
bool onBounds(vec2 c) {
  vec2 per_px = u_container / u_viewport;  // container pixels per output pixel
  vec2 lo = u_image_offset - 0.5, hi = u_image_offset + vec2(textureSize(u_image, 0)) - 0.5;
  vec2 d = min(abs(c - lo), abs(c - hi)) / per_px;
  bool inside_x = c.x >= lo.x - per_px.x && c.x <= hi.x + per_px.x;
  bool inside_y = c.y >= lo.y - per_px.y && c.y <= hi.y + per_px.y;
  return (d.x <= 0.75 && inside_y) || (d.y <= 0.75 && inside_x);
}

void main() {
  // Container pixel at this fragment (the output may be scaled; rows read back flipped).
  vec2 c = vec2(gl_FragCoord.x / u_viewport.x, 1.0 - gl_FragCoord.y / u_viewport.y) * u_container - 0.5;
  if (u_bounds_only == 1) {
    if (!onBounds(c)) discard;
    frag_color = vec4(1.0, 220.0 / 255.0, 0.0, 1.0);
    return;
  }
  ivec2 px = ivec2(floor(c + 0.5));
  ivec2 uv = px - ivec2(u_image_offset);
  ivec2 size = textureSize(u_image, 0);
  vec3 color = vec3(0.15);
  if (all(greaterThanEqual(uv, ivec2(0))) && all(lessThan(uv, size))) color = texelFetch(u_image, uv, 0).rgb;
  if (u_cell_size > 0 && (px.x % u_cell_size == 0 || px.y % u_cell_size == 0)) color = mix(color, vec3(0.0), 0.5);
  frag_color = vec4(color, 1.0);
}
