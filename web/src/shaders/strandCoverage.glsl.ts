// Sub-pixel strands: a strand is drawn as a one-pixel line whose fragments carry the fraction of the pixel
// the strand really covers. A strand of width w (m; its fibres side by side) at view depth z is
//   W = w f / z  pixels wide  (f = P[1][1] H / 2, the focal length in pixels, H the drawing buffer's height),
// and a one-pixel line lights one pixel per pixel of its major axis, so a segment of screen direction
// (dx, dy) covers per lit pixel the area W |d| / max(|dx|, |dy|) (1 to sqrt 2 times W). The strand's ink, the
// sum of its fragments' coverage, is thus its width times its projected length: it follows the camera and
// the hair type continuously (no popping). Coverage is clamped to [minCoverage, 1]: a strand wider than a
// pixel is drawn opaque but one pixel wide (under-drawn; see docs/rendering.md).

export const strandCoverageGLSL = /* glsl */ `
uniform float strandWidth;   // width of a render strand (its fibres side by side), m
uniform vec2 viewport;       // drawing buffer size, px
uniform float minCoverage;   // smallest coverage drawn, [0,1]
// Coverage of the pixels the line lights at world point p (clip position c), unit world tangent t.
float strandCoverage(vec3 p, vec4 c, vec3 t) {
  float widthPixels = strandWidth * projectionMatrix[1][1] * 0.5 * viewport.y / c.w;
  vec4 c1 = projectionMatrix * modelViewMatrix * vec4(p + 1e-3 * t, 1.0);
  vec2 d = (c1.xy / c1.w - c.xy / c.w) * viewport;
  float major = max(abs(d.x), abs(d.y));
  float lineFactor = major > 1e-9 ? length(d) / major : 1.0;
  return clamp(widthPixels * lineFactor, minCoverage, 1.0);
}
`;
