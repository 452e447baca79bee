// The render strands' deformation, shared by every pass that draws hair (the lit pass and both passes of the
// deep opacity maps), so the shadows follow exactly the strands that are drawn:
//  1. wet clumping: the rest position moves towards its clump's centre (the mean rest shape of the strands
//     bound to the same primary guide), more at the tips and the wetter the guide;
//  2. the strand carried by the head and the lattice, the one law of engine::scene::carry_strand: each vertex's
//     target is the head's rigid motion of its rest position blended into the quadratic B-spline FFD by the
//     lattice (nodes in a float texture) by smoothstep(0, rootHold, rest arc length from the root); then follow
//     the leader from the root (each vertex at its rest distance from the previous one, towards its target:
//     the strand keeps its length), the rest positions of the strand's vertices read from a texture; the
//     tangent is the last segment;
//  3. the local strands' displacement (guide displacement texture, interpolated along the guide);
//  4. curliness: a helical offset about the strand, growing from the root;
//  5. push-out of the body (SCENE's metaballs), as MetaballSet::push_out does on the CPU.
// Entry point: `HairVertex deformHair()`.

export const hairDeformGLSL = /* glsl */ `
precision highp float;
precision highp sampler2D;
uniform sampler2D latticeNodes;   // node (i,j,k) at texel (i + nx*j, k): world position, m
uniform vec3 latticeOrigin;       // rest position of node (0,0,0), m
uniform float latticeCell;        // node spacing, m
uniform vec3 latticeSize;         // nx, ny, nz (node counts, as floats)
uniform sampler2D guideDisplacement; // texel (sample, guide): displacement of the guide from its reference, m
uniform sampler2D guideState;     // texel (guide, 0): r wetness [0,1], g kept length fraction [0,1]
uniform int guideSamples;
uniform float curliness;          // [0,1]
uniform float curlRadius;         // m at curliness 1
uniform sampler2D clumpCentres;   // texel (vertex index, guide): mean rest position of the guide's strands, m
uniform int verticesPerStrand;
uniform float clumpStrength;      // fraction of the way to the clump centre at the tip of a soaked strand, [0,1]
uniform float wetnessOverride;    // >= 0: every strand has this wetness (test and preview hook); < 0: off
attribute vec3 rest;              // rest position (head frame), m
attribute vec3 restTangent;       // rest position of the next vertex minus the previous one, m
attribute vec3 guides;            // the strand's three guides (indices; weight 0 for unused slots)
attribute vec3 weights;           // their weights, summing to 1
uniform mat3 headRotation;        // head pose (head frame to world): rotation
uniform vec3 headTranslation;     // and translation, m
uniform float rootHold;           // length of hair from the root the head holds, m (0: the FFD alone)
uniform sampler2D restPositions;  // texel (v % restWidth, v / restWidth): rest position of render vertex v (head frame), m
uniform int restWidth;
attribute vec2 arc;               // x: fraction u of the guides' length at this vertex, y: curl phase

struct HairVertex {
  vec3 position;  // world, m
  vec3 tangent;   // unit, world
  float wetness;  // [0,1]
  float keep;     // kept length fraction of the primary guide
  float u;        // fraction of the guides' length
  float v;        // vertex index / (V - 1): root 0, tip 1
};

vec3 node(int i, int j, int k) {
  return texelFetch(latticeNodes, ivec2(i + int(latticeSize.x + 0.5) * j, k), 0).xyz;
}
vec3 bspline(float t) {
  float u = 1.0 - t;
  return vec3(0.5 * u * u, 0.5 * (-2.0 * t * t + 2.0 * t + 1.0), 0.5 * t * t);
}
// FFD(p), world, m (FfdLattice::deform_clamped).
vec3 ffd(vec3 p) {
  vec3 s = clamp((p - latticeOrigin) / latticeCell, vec3(0.5), latticeSize - 1.5);
  ivec3 c = ivec3(floor(s + 0.5));
  vec3 t = s - vec3(c) + 0.5;
  vec3 bx = bspline(t.x), by = bspline(t.y), bz = bspline(t.z);
  vec3 x = vec3(0.0);
  for (int k = 0; k < 3; k++) {
    for (int j = 0; j < 3; j++) {
      for (int i = 0; i < 3; i++) {
        x += bx[i] * by[j] * bz[k] * node(c.x + i - 1, c.y + j - 1, c.z + k - 1);
      }
    }
  }
  return x;
}
// engine::scene::carried: the rest point r (head frame) at rest arc length sArc from its root, now (world).
vec3 carried(vec3 r, float sArc) {
  vec3 rigid = headRotation * r + headTranslation;
  float w = rootHold > 0.0 ? smoothstep(0.0, rootHold, sArc) : 1.0;
  return w > 0.0 ? rigid + (ffd(r) - rigid) * w : rigid;
}
vec3 restAt(int v) {
  return texelFetch(restPositions, ivec2(v % restWidth, v / restWidth), 0).xyz;
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
  // 1. wet clumping (rest frame): roots stay, tips gather (each vertex of the strand, for step 2).
  float clump = clumpStrength * h.wetness;
  float last = float(max(1, verticesPerStrand - 1));
  // 2. carried by the head and the lattice (engine::scene::carry_strand): from the root (held by the head)
  // each vertex at its rest distance from the previous one, towards its target; 3. local strands.
  int first = gl_VertexID - i;
  vec3 prev = restAt(first);
  vec3 p = headRotation * prev + headTranslation;
  vec3 jt = headRotation * restTangent;
  float sArc = 0.0;
  for (int k = 1; k <= i; k++) {
    vec3 rk = k == i ? rest : restAt(first + k);
    float len = length(rk - prev);
    sArc += len;
    vec3 ck = texelFetch(clumpCentres, ivec2(k, g), 0).xyz;
    vec3 target = carried(mix(rk, ck, clump * smoothstep(0.05, 0.7, float(k) / last)), sArc);
    vec3 d = target - p;
    float dl = length(d);
    vec3 dir = dl > 1e-12 ? d / dl : headRotation * (rk - prev) / max(len, 1e-12);
    jt = 2.0 * dir * len; // restTangent spans two vertices: the same scale for the curl's derivative below
    p += dir * len;
    prev = rk;
  }
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
