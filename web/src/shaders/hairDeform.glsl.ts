// The render strands' deformation, shared by every pass that draws hair (the lit pass and both passes of the
// deep opacity maps), so the shadows follow exactly the strands that are drawn:
//  1. wet clumping: the rest position moves towards its clump's centre (the mean rest shape of the strands
//     bound to the same primary guide), more at the tips and the wetter the guide;
//  2. quadratic B-spline FFD of the rest position by the lattice (nodes in a float texture), with its
//     Jacobian applied to the rest tangent;
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
vec3 bsplineDerivative(float t) {
  return vec3(t - 1.0, 1.0 - 2.0 * t, t);
}
// FFD(p) and the directional derivative J(p) d (both world, m; jd is zero with HAIR_NO_TANGENT).
vec3 ffd(vec3 p, vec3 d, out vec3 jd) {
  vec3 s = clamp((p - latticeOrigin) / latticeCell, vec3(0.5), latticeSize - 1.5);
  ivec3 c = ivec3(floor(s + 0.5));
  vec3 t = s - vec3(c) + 0.5;
  vec3 bx = bspline(t.x), by = bspline(t.y), bz = bspline(t.z);
  vec3 dx = bsplineDerivative(t.x), dy = bsplineDerivative(t.y), dz = bsplineDerivative(t.z);
  vec3 ds = d / latticeCell;
  vec3 x = vec3(0.0);
  jd = vec3(0.0);
  for (int k = 0; k < 3; k++) {
    for (int j = 0; j < 3; j++) {
      for (int i = 0; i < 3; i++) {
        vec3 n = node(c.x + i - 1, c.y + j - 1, c.z + k - 1);
        x += bx[i] * by[j] * bz[k] * n;
#ifndef HAIR_NO_TANGENT
        jd += (dx[i] * by[j] * bz[k] * ds.x + bx[i] * dy[j] * bz[k] * ds.y + bx[i] * by[j] * dz[k] * ds.z) * n;
#endif
      }
    }
  }
  return x;
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
  // 1. wet clumping (rest frame): roots stay, tips gather.
  vec3 centre = texelFetch(clumpCentres, ivec2(i, g), 0).xyz;
  vec3 r = mix(rest, centre, clumpStrength * h.wetness * smoothstep(0.05, 0.7, h.v));
  // 2. FFD with the tangent through its Jacobian; 3. local strands.
  vec3 jt;
  vec3 p = ffd(r, restTangent, jt);
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
