// Sub-pixel strands: a strand is drawn as one-pixel lines whose fragments carry the fraction of the pixel the
// strand really covers. A strand of width w (m; its fibres side by side) at view depth z is
//   W = w f / z  pixels wide  (f = P[1][1] H / 2, the focal length in pixels, H the drawing buffer's height),
// and a one-pixel line lights one pixel per pixel of its major axis, so a segment of screen direction
// (dx, dy) spans E = W |d| / max(|dx|, |dy|) pixels across its major axis (1 to sqrt 2 times W). Below a
// pixel (E <= 1) one line carries coverage E; a wider strand (E > 1, a close camera or a render strand
// standing for many hairs) is drawn as m = ceil(E) parallel lines one pixel apart across the major axis
// (`lineCount` draws of the same strands, chosen per frame; at most m of them used by a strand), each with
// coverage E / m. Either way the strand's ink, the sum of its fragments' coverage, is its width times its
// projected length: it follows the camera and the hair type continuously (no popping). Coverage is at least
// minCoverage; a strand wider than lineCount pixels is under-drawn (coverage clamped to 1).

export const strandCoverageGLSL = /* glsl */ `
uniform float strandWidth;   // width of a render strand (its fibres side by side), m
uniform vec2 viewport;       // drawing buffer size, px
uniform float minCoverage;   // smallest coverage drawn, [0,1]
uniform float lineIndex;     // this draw's line, 0 .. lineCount - 1
uniform float lineCount;     // parallel lines drawn per strand this frame (>= 1)
// Clip position of this draw's line of the strand at world point p (clip position c, unit world tangent t),
// and the coverage of the pixels it lights (0: the strand needs no such line here).
vec4 strandLine(vec3 p, vec4 c, vec3 t, out float coverage) {
  float widthPixels = strandWidth * projectionMatrix[1][1] * 0.5 * viewport.y / c.w;
  vec4 c1 = projectionMatrix * modelViewMatrix * vec4(p + 1e-3 * t, 1.0);
  vec2 d = (c1.xy / c1.w - c.xy / c.w) * viewport;
  float major = max(abs(d.x), abs(d.y));
  float extent = widthPixels * (major > 1e-9 ? length(d) / major : 1.0);
  float lines = clamp(ceil(extent), 1.0, lineCount);
  coverage = lineIndex < lines ? clamp(extent / lines, minCoverage, 1.0) : 0.0;
  vec2 across = abs(d.x) >= abs(d.y) ? vec2(0.0, 1.0) : vec2(1.0, 0.0);
  return vec4(c.xy + across * (lineIndex - 0.5 * (lines - 1.0)) * 2.0 / viewport * c.w, c.zw);
}
`;
