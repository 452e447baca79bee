// The carried hair (engine::scene::carry_strand) computed once per frame for every render vertex, in two
// full-screen passes over a float texture with one texel per render vertex (texel (v % restWidth, v / restWidth)
// for vertex v = strand * verticesPerStrand + i):
//  1. targets: each vertex's target, the head's rigid motion of its (wet-clumped) rest position blended into the
//     quadratic B-spline FFD by the lattice by smoothstep(0, rootHold, rest arc length from the root);
//  2. chain: follow the leader from the root (held rigidly by the head), each vertex at its rest distance from
//     the previous one, towards its target: the strand keeps its length.
// Every pass that draws hair (the lit lines and both deep-opacity passes, shaders/hairDeform.glsl.ts) then reads
// its vertex from the chain's texture: the FFD runs once per vertex a frame, not once per vertex, per earlier
// vertex of its strand and per pass.

/** Uniforms and helpers both passes share. */
const carriedCommonGLSL = /* glsl */ `
precision highp float;
precision highp int;
precision highp sampler2D;
uniform mat3 headRotation;        // head pose (head frame to world): rotation
uniform vec3 headTranslation;     // and translation, m
uniform sampler2D restPositions;  // texel of vertex v: xyz rest position (head frame), m; w rest arc length from the root, m
uniform int restWidth;            // texels per row of the per-vertex textures
uniform int verticesPerStrand;
uniform int vertexCount;          // render vertices (strands x verticesPerStrand)
layout(location = 0) out highp vec4 carriedOut;
ivec2 vertexTexel(int v) { return ivec2(v % restWidth, v / restWidth); }
vec4 restAt(int v) { return texelFetch(restPositions, vertexTexel(v), 0); }
// The render vertex this fragment computes (-1 past the last).
int fragmentVertex() {
  int v = int(gl_FragCoord.y) * restWidth + int(gl_FragCoord.x);
  return v < vertexCount ? v : -1;
}
`;

/** The full-screen triangle pair's vertex shader (clip-space positions of a 2 x 2 plane). */
export const carriedQuadVertex = /* glsl */ `
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }
`;

/** Pass 1: the target of every render vertex (world, m). */
export const carriedTargetsFragment = /* glsl */ `
${carriedCommonGLSL}
uniform sampler2D latticeNodes;   // node (i,j,k) at texel (i + nx*j, k): world position, m
uniform vec3 latticeOrigin;       // rest position of node (0,0,0), m
uniform float latticeCell;        // node spacing, m
uniform vec3 latticeSize;         // nx, ny, nz (node counts, as floats)
uniform float rootHold;           // length of hair from the root the head holds, m (0: the FFD alone)
uniform sampler2D strandGuides;   // texel (s % restWidth, s / restWidth): primary guide of render strand s
uniform sampler2D guideState;     // texel (guide, 0): r wetness [0,1], g kept length fraction [0,1]
uniform sampler2D clumpCentres;   // texel (vertex index, guide): mean rest position of the guide's strands, m
uniform float clumpStrength;      // fraction of the way to the clump centre at the tip of a soaked strand, [0,1]
uniform float wetnessOverride;    // >= 0: every strand has this wetness (test and preview hook); < 0: off
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
void main() {
  int v = fragmentVertex();
  if (v < 0) { carriedOut = vec4(0.0); return; }
  int i = v % verticesPerStrand;
  int s = v / verticesPerStrand;
  int g = int(texelFetch(strandGuides, vertexTexel(s), 0).r + 0.5);
  float wetness = wetnessOverride >= 0.0 ? wetnessOverride : texelFetch(guideState, ivec2(g, 0), 0).r;
  // Wet clumping (rest frame): roots stay, tips gather.
  float last = float(max(1, verticesPerStrand - 1));
  vec4 r = restAt(v);
  vec3 centre = texelFetch(clumpCentres, ivec2(i, g), 0).xyz;
  vec3 rest = mix(r.xyz, centre, clumpStrength * wetness * smoothstep(0.05, 0.7, float(i) / last));
  carriedOut = vec4(carried(rest, r.w), 1.0);
}
`;

/** Pass 2: follow the leader from the root towards the targets (world, m). */
export const carriedChainFragment = /* glsl */ `
${carriedCommonGLSL}
uniform sampler2D carriedTargets; // pass 1's texture
void main() {
  int v = fragmentVertex();
  if (v < 0) { carriedOut = vec4(0.0); return; }
  int i = v % verticesPerStrand;
  int first = v - i;
  vec3 prev = restAt(first).xyz;
  vec3 p = headRotation * prev + headTranslation;
  for (int k = 1; k <= i; k++) {
    vec3 rk = restAt(first + k).xyz;
    float len = length(rk - prev);
    vec3 d = texelFetch(carriedTargets, vertexTexel(first + k), 0).xyz - p;
    float dl = length(d);
    vec3 dir = dl > 1e-12 ? d / dl : headRotation * (rk - prev) / max(len, 1e-12);
    p += dir * len;
    prev = rk;
  }
  carriedOut = vec4(p, 1.0);
}
`;
