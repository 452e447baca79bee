// The render strands' deformation, shared by every pass that draws hair (the lit pass and both passes of the
// deep opacity maps), so the shadows follow exactly the strands that are drawn:
//  1-2. the strand wet-clumped, then carried by the head and the lattice (the one law of
//     engine::scene::carry_strand), computed once a frame for every vertex by carriedHair.ts
//     (shaders/carriedHair.glsl.ts) and read here from its texture; the tangent is the last segment;
//  3. the local strands' displacement (guide displacement texture, interpolated along the guide);
//  4. curliness: a helical offset about the strand, growing from the root;
//  5. push-out of the body (SCENE's metaballs), as MetaballSet::push_out does on the CPU.
// Entry point: `HairVertex deformHair()`.

export const hairDeformGLSL = /* glsl */ `
precision highp float;
precision highp sampler2D;
uniform sampler2D guideDisplacement; // texel (sample, guide): displacement of the guide from its reference, m
uniform sampler2D guideState;     // texel (guide, 0): r wetness [0,1], g kept length fraction [0,1]
uniform int guideSamples;
uniform float curliness;          // [0,1]
uniform float curlRadius;         // m at curliness 1
uniform int verticesPerStrand;
uniform float wetnessOverride;    // >= 0: every strand has this wetness (test and preview hook); < 0: off
attribute vec3 rest;              // rest position (head frame), m
attribute vec3 restTangent;       // rest position of the next vertex minus the previous one, m
attribute vec3 guides;            // the strand's three guides (indices; weight 0 for unused slots)
attribute vec3 weights;           // their weights, summing to 1
uniform mat3 headRotation;        // head pose (head frame to world): rotation
uniform sampler2D carriedPositions; // texel (v % restWidth, v / restWidth): render vertex v carried (world, m; carriedHair.ts)
uniform int restWidth;            // texels per row of the per-vertex textures
attribute vec2 arc;               // x: fraction u of the guides' length at this vertex, y: curl phase

struct HairVertex {
  vec3 position;  // world, m
  vec3 tangent;   // unit, world
  float wetness;  // [0,1]
  float keep;     // kept length fraction of the primary guide
  float u;        // fraction of the guides' length
  float v;        // vertex index / (V - 1): root 0, tip 1
};

vec3 carriedAt(int v) {
  return texelFetch(carriedPositions, ivec2(v % restWidth, v / restWidth), 0).xyz;
}
#define MAX_METABALLS 16
uniform vec4 metaballs[MAX_METABALLS]; // xyz centre, w radius R, m
uniform int metaballCount;
uniform float metaballThreshold;       // T, dimensionless
uniform float pushOutSkin;             // m
// A vertex inside the body {F > T}, or within the skin of its surface, moves along the outward normal
// -grad F/|grad F| onto the surface offset by the skin (Newton steps on the first-order distance (T - F)/|grad F|).
vec3 pushOut(vec3 p) {
  for (int it = 0; it < 3; it++) {
    float f = 0.0;
    vec3 g = vec3(0.0);
    for (int b = 0; b < MAX_METABALLS; b++) {
      if (b >= metaballCount) break;
      vec3 r = p - metaballs[b].xyz;
      float r2inv = 1.0 / (metaballs[b].w * metaballs[b].w);
      float q = 1.0 - dot(r, r) * r2inv;
      if (q > 0.0) { f += q * q; g -= 4.0 * q * r2inv * r; }
    }
    float gn = length(g);
    if (f <= 0.0 || gn < 1e-9) return p;
    float d = (metaballThreshold - f) / gn;
    if (d >= pushOutSkin * 0.999) return p;
    p -= (pushOutSkin - d) * g / gn;
  }
  return p;
}
vec3 guideOffset(int g, float u) {
  float x = u * float(guideSamples - 1);
  int a = int(floor(x));
  int b = min(a + 1, guideSamples - 1);
  vec3 da = texelFetch(guideDisplacement, ivec2(a, g), 0).xyz;
  vec3 db = texelFetch(guideDisplacement, ivec2(b, g), 0).xyz;
  return mix(da, db, x - float(a));
}
HairVertex deformHair() {
  HairVertex h;
  int g = int(guides.x + 0.5);
  int i = gl_VertexID % verticesPerStrand;
  float u = arc.x;
  h.u = u;
  h.v = float(i) / float(max(1, verticesPerStrand - 1));
  vec4 st = texelFetch(guideState, ivec2(g, 0), 0);
  h.wetness = wetnessOverride >= 0.0 ? wetnessOverride : st.r;
  h.keep = st.g;
  // 1-2. wet clumping, carried by the head and the lattice (carriedHair.ts); the tangent is the last segment
  // (restTangent spans two vertices: the same scale for the curl's derivative below); 3. local strands.
  vec3 p = carriedAt(gl_VertexID);
  vec3 jt = i > 0 ? 2.0 * (p - carriedAt(gl_VertexID - 1)) : headRotation * restTangent;
  p += weights.x * guideOffset(g, u) + weights.y * guideOffset(int(guides.y + 0.5), u)
     + weights.z * guideOffset(int(guides.z + 0.5), u);
  // 4. curliness: helix of radius curlRadius sqrt(u) about the rest tangent, 40 rad over the guide.
  vec3 t = normalize(restTangent);
  vec3 side = normalize(cross(t, abs(t.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
  vec3 side2 = cross(t, side);
  float ang = u * 40.0 + arc.y;
  float amp = curliness * curlRadius * sqrt(u);
  p += amp * (cos(ang) * side + sin(ang) * side2);
  // d(helix)/d(vertex) = amp * 40 du * (-sin, cos); restTangent spans two vertices.
  float du = i > 0 ? u / float(i) : 0.0;
  jt += 2.0 * amp * 40.0 * du * (-sin(ang) * side + cos(ang) * side2);
  // 5. push-out.
  h.position = pushOut(p);
  h.tangent = normalize(jt + 1e-9 * t);
  return h;
}
`;
