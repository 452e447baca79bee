// Strands drawn as camera-facing strips as wide as the hairs they stand for (the hair type's fibre width from
// SCENE times the hairs per render strand). Every strand vertex is stored twice (even: one edge, odd: the
// other); the vertex shader moves each copy half the strip's width to its side, across the strand's projected
// tangent. A strip is never drawn thinner than `minStrandPixels`: a thinner strand keeps that width and
// covers the pixels it crosses by its true width over the drawn one, so its weight in the picture follows its
// width continuously as the camera moves (no popping, no strands vanishing between pixels). Half a pixel of
// edge filter on each side (a box filter across the strip) anti-aliases the edges without multisampling.
// When every strand is far thinner than a pixel (stripMode 0: the viewer decides per frame from the distance),
// the same vertices are drawn as one-pixel lines with the same coverage: half the vertex work of strips and
// the same ink per unit length, so switching between the two does not change the picture's weight.

export const hairStripGLSL = /* glsl */ `
uniform vec2 viewport;          // drawing buffer size, px
uniform float strandWidth;      // true width of a render strand (its fibres side by side), m
uniform float minStrandPixels;  // strips are drawn at least this wide, px
uniform float stripMode;        // 1: strips (two vertices across); 0: one-pixel lines through the even copies
varying float vAcross;          // signed distance from the strand's axis, px
varying float vWidthPixels;     // the strand's true width on screen, px

// Clip-space position of the strip vertex at world point p (tangent t, unit) on the edge side (-1 or +1).
vec4 strandStrip(vec3 p, vec3 t, float side) {
  vec4 c = projectionMatrix * modelViewMatrix * vec4(p, 1.0);
  vec4 c1 = projectionMatrix * modelViewMatrix * vec4(p + 1e-3 * t, 1.0);
  vec2 d = (c1.xy / c1.w - c.xy / c.w) * viewport;
  vec2 n = dot(d, d) > 1e-12 ? normalize(vec2(-d.y, d.x)) : vec2(1.0, 0.0);
  // Width on screen: the projection's y scale (perspective: divided by the distance c.w).
  vWidthPixels = strandWidth * projectionMatrix[1][1] * 0.5 * viewport.y / c.w;
  float halfWidth = 0.5 * max(vWidthPixels, minStrandPixels) + 0.5;
  vAcross = stripMode * side * halfWidth;
  c.xy += n * (vAcross * 2.0 / viewport) * c.w;
  return c;
}
`;

/** Fragment side: the fraction of the pixel the strand covers. */
export const hairStripCoverageGLSL = /* glsl */ `
uniform float minStrandPixels;
uniform float stripMode;
varying float vAcross;
varying float vWidthPixels;
float strandCoverage() {
  if (stripMode < 0.5) return min(vWidthPixels, 1.0);
  float drawn = max(vWidthPixels, minStrandPixels);
  return clamp(0.5 * drawn + 0.5 - abs(vAcross), 0.0, 1.0) * vWidthPixels / drawn;
}
`;
