#version 330 core
// An RGBA image (row 0 on top) placed pixel for pixel: texel = this fragment's pixel minus the
// image's bottom-left corner, rows flipped; blended by its alpha.
uniform vec2 u_origin;  // the image's bottom-left corner, window pixels (GL convention)
uniform sampler2D u_image;
out vec4 frag_color;
void main() {
  ivec2 size = textureSize(u_image, 0);
  ivec2 p = ivec2(floor(gl_FragCoord.xy - u_origin));
  if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, size))) discard;
  frag_color = texelFetch(u_image, ivec2(p.x, size.y - 1 - p.y), 0);
}
