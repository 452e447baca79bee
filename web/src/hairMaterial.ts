// Hair strands: geometry with the rest positions and the guide binding, and a shader that does the
// quadratic B-spline FFD on the GPU (lattice nodes in a float data texture), adds the local strands'
// displacement (guide displacement texture), and shades with Kajiya-Kay, depth-based self-shadowing and
// a wet look (darker, sharper highlight).
import * as THREE from 'three';
import type { SceneMsg } from './protocol';

const vertexShader = /* glsl */ `
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
attribute vec3 rest;              // rest position (head frame), m
attribute vec3 restTangent;
attribute vec3 guides;            // the strand's three guides (indices; weight 0 for unused slots)
attribute vec3 weights;           // their weights, summing to 1
attribute vec2 arc;               // x: fraction u of the guides' length at this vertex, y: curl phase
varying vec3 vTangent;
varying vec3 vPosition;
varying float vWet;
varying float vKeep;
varying float vU;
varying float vDepth;

vec3 node(int i, int j, int k) {
  return texelFetch(latticeNodes, ivec2(i + int(latticeSize.x + 0.5) * j, k), 0).xyz;
}
vec3 bspline(float t) {
  float u = 1.0 - t;
  return vec3(0.5 * u * u, 0.5 * (-2.0 * t * t + 2.0 * t + 1.0), 0.5 * t * t);
}
vec3 ffd(vec3 p) {
  vec3 s = clamp((p - latticeOrigin) / latticeCell, vec3(0.5), latticeSize - 1.5);
  ivec3 c = ivec3(floor(s + 0.5));
  vec3 t = s - vec3(c) + 0.5;
  vec3 bx = bspline(t.x), by = bspline(t.y), bz = bspline(t.z);
  vec3 x = vec3(0.0);
  for (int k = 0; k < 3; k++) {
    for (int j = 0; j < 3; j++) {
      float wjk = by[j] * bz[k];
      x += wjk * (bx[0] * node(c.x - 1, c.y + j - 1, c.z + k - 1)
                + bx[1] * node(c.x,     c.y + j - 1, c.z + k - 1)
                + bx[2] * node(c.x + 1, c.y + j - 1, c.z + k - 1));
    }
  }
  return x;
}
// Push-out (SCENE's appended metaballs, head frame = the viewer's world): a vertex inside the body
// {F > T}, or within the skin of its surface, is moved along the outward normal -grad F/|grad F| onto the
// surface offset by the skin (Newton steps on the first-order distance (T - F)/|grad F|), as
// MetaballSet::push_out does on the CPU.
#define MAX_METABALLS 16
uniform vec4 metaballs[MAX_METABALLS]; // xyz centre, w radius R, m
uniform int metaballCount;
uniform float metaballThreshold;       // T, dimensionless
uniform float pushOutSkin;             // m
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
void main() {
  int g = int(guides.x + 0.5);
  float u = arc.x;
  vec3 p = ffd(rest) + weights.x * guideOffset(g, u) + weights.y * guideOffset(int(guides.y + 0.5), u)
         + weights.z * guideOffset(int(guides.z + 0.5), u);
  vec3 t = normalize(restTangent);
  // Curliness: a helical offset about the strand, growing from the root.
  vec3 side = normalize(cross(t, abs(t.z) < 0.9 ? vec3(0.0, 0.0, 1.0) : vec3(1.0, 0.0, 0.0)));
  vec3 side2 = cross(t, side);
  float ang = u * 40.0 + arc.y;
  p += curliness * curlRadius * sqrt(u) * (cos(ang) * side + sin(ang) * side2);
  p = pushOut(p);
  vec4 st = texelFetch(guideState, ivec2(g, 0), 0);
  vWet = st.r;
  vKeep = st.g;
  vU = u;
  vTangent = t;
  vPosition = p;
  vDepth = length(rest);
  gl_Position = projectionMatrix * modelViewMatrix * vec4(p, 1.0);
}
`;

const fragmentShader = /* glsl */ `
precision highp float;
uniform vec3 hairColor;
uniform vec3 lightDirection;     // towards the light
uniform vec3 cameraPos;
uniform float headRadius;        // m
varying vec3 vTangent;
varying vec3 vPosition;
varying float vWet;
varying float vKeep;
varying float vU;
varying float vDepth;
void main() {
  if (vU > vKeep + 1e-4) discard; // cut off by the scissors
  vec3 T = normalize(vTangent);
  vec3 L = normalize(lightDirection);
  vec3 V = normalize(cameraPos - vPosition);
  vec3 H = normalize(L + V);
  float tl = dot(T, L), th = dot(T, H);
  // Kajiya-Kay: diffuse ~ sin(T, L), specular ~ sin(T, H)^n.
  float diffuse = sqrt(max(0.0, 1.0 - tl * tl));
  float exponent = mix(40.0, 160.0, vWet);
  float specular = pow(sqrt(max(0.0, 1.0 - th * th)), exponent) * mix(0.35, 0.8, vWet);
  // Self-shadowing: hair near the scalp (deep in the volume) and on the side away from the light is darker.
  float depth = smoothstep(headRadius, headRadius + 0.025, vDepth);
  float facing = 0.55 + 0.45 * max(0.0, dot(normalize(vPosition), L));
  float shadow = mix(0.35, 1.0, depth) * facing;
  vec3 base = hairColor * mix(1.0, 0.45, vWet);
  vec3 c = base * (0.25 + 0.75 * diffuse) * shadow + vec3(specular) * shadow;
  gl_FragColor = vec4(c, 1.0);
}
`;

export class HairMaterial {
  readonly material: THREE.ShaderMaterial;
  readonly latticeTexture: THREE.DataTexture;
  readonly displacementTexture: THREE.DataTexture;
  readonly stateTexture: THREE.DataTexture;
  private readonly samples: number;

  constructor(scene: SceneMsg, headRadius: number) {
    const [nx, ny, nz] = scene.latticeDims;
    this.samples = Math.max(2, scene.samples);
    this.latticeTexture = floatTexture(nx * ny, nz);
    this.displacementTexture = floatTexture(this.samples, Math.max(1, scene.guides));
    this.stateTexture = floatTexture(Math.max(1, scene.guides), 1);
    this.resetGuides();
    this.material = new THREE.ShaderMaterial({
      vertexShader,
      fragmentShader,
      uniforms: {
        latticeNodes: { value: this.latticeTexture },
        latticeOrigin: { value: new THREE.Vector3(...scene.latticeOrigin) },
        latticeCell: { value: scene.latticeH },
        latticeSize: { value: new THREE.Vector3(nx, ny, nz) },
        guideDisplacement: { value: this.displacementTexture },
        guideState: { value: this.stateTexture },
        guideSamples: { value: this.samples },
        curliness: { value: 0 },
        curlRadius: { value: 0.006 },
        hairColor: { value: new THREE.Color(0.42, 0.27, 0.15) },
        lightDirection: { value: new THREE.Vector3(0.4, -0.6, 0.7) },
        cameraPos: { value: new THREE.Vector3() },
        headRadius: { value: headRadius },
        ...pushOutUniforms(scene),
      },
    });
  }

  /** Lattice node positions, 3 floats per node in flat order i + nx (j + ny k). */
  setLattice(nodes: Float32Array): void {
    const d = this.latticeTexture.image.data as Float32Array;
    const n = Math.min(nodes.length / 3, d.length / 4);
    for (let i = 0; i < n; i++) {
      d[4 * i] = nodes[3 * i];
      d[4 * i + 1] = nodes[3 * i + 1];
      d[4 * i + 2] = nodes[3 * i + 2];
    }
    this.latticeTexture.needsUpdate = true;
  }

  /** Displacements of the active guides (rows of the others are kept: styling persists). */
  setGuides(active: Uint32Array, samples: number, displacement: Float32Array, wetness: Float32Array): void {
    const d = this.displacementTexture.image.data as Float32Array;
    const w = this.displacementTexture.image.width;
    for (let a = 0; a < active.length; a++) {
      const g = active[a];
      for (let s = 0; s < Math.min(samples, w); s++) {
        const src = 3 * (a * samples + s), dst = 4 * (g * w + s);
        d[dst] = displacement[src];
        d[dst + 1] = displacement[src + 1];
        d[dst + 2] = displacement[src + 2];
      }
    }
    this.displacementTexture.needsUpdate = true;
    const st = this.stateTexture.image.data as Float32Array;
    for (let g = 0; g < Math.min(wetness.length, st.length / 4); g++) {
      st[4 * g] = wetness[g];
    }
    this.stateTexture.needsUpdate = true;
  }

  resetGuides(): void {
    (this.displacementTexture.image.data as Float32Array).fill(0);
    const st = this.stateTexture.image.data as Float32Array;
    for (let i = 0; i < st.length; i += 4) { st[i] = 0; st[i + 1] = 1; }
    this.displacementTexture.needsUpdate = true;
    this.stateTexture.needsUpdate = true;
  }
}

/** The push-out uniforms from SCENE's metaballs (at most 16; none: no push-out). */
function pushOutUniforms(scene: SceneMsg): Record<string, THREE.IUniform> {
  const count = Math.min(16, Math.floor((scene.metaballs?.length ?? 0) / 4));
  const balls: THREE.Vector4[] = [];
  for (let b = 0; b < 16; b++) {
    balls.push(b < count
      ? new THREE.Vector4(scene.metaballs[4 * b], scene.metaballs[4 * b + 1], scene.metaballs[4 * b + 2], scene.metaballs[4 * b + 3])
      : new THREE.Vector4(0, 0, 0, 1));
  }
  return {
    metaballs: { value: balls },
    metaballCount: { value: count },
    metaballThreshold: { value: scene.metaballThreshold ?? 0.25 },
    pushOutSkin: { value: scene.pushOutSkin ?? 0.0005 },
  };
}

function floatTexture(w: number, h: number): THREE.DataTexture {
  const t = new THREE.DataTexture(new Float32Array(4 * w * h), w, h, THREE.RGBAFormat, THREE.FloatType);
  t.minFilter = THREE.NearestFilter;
  t.magFilter = THREE.NearestFilter;
  t.needsUpdate = true;
  return t;
}

/** Line segments for every strand: rest positions, rest tangents and the guide binding per vertex. */
export function hairGeometry(scene: SceneMsg): THREE.BufferGeometry {
  const nv = scene.verticesPerStrand, ns = scene.strands, k = scene.guidesPerStrand;
  const pos = scene.renderPositions;
  const tangent = new Float32Array(pos.length);
  const guides = new Float32Array(3 * nv * ns);
  const weights = new Float32Array(3 * nv * ns);
  const arc = new Float32Array(2 * nv * ns);
  const index = new Uint32Array(2 * (nv - 1) * ns);
  let n = 0;
  for (let s = 0; s < ns; s++) {
    const phase = ((s * 2654435761) >>> 0) / 4294967296 * 6.2832;
    for (let i = 0; i < nv; i++) {
      const v = s * nv + i;
      const a = s * nv + Math.max(0, i - 1), b = s * nv + Math.min(nv - 1, i + 1);
      for (let c = 0; c < 3; c++) tangent[3 * v + c] = pos[3 * b + c] - pos[3 * a + c];
      for (let m = 0; m < Math.min(3, k); m++) {
        guides[3 * v + m] = scene.renderGuide[s * k + m];
        weights[3 * v + m] = scene.renderWeight[s * k + m];
      }
      arc[2 * v] = scene.renderSpan[s] * i / (nv - 1);
      arc[2 * v + 1] = phase;
      if (i + 1 < nv) { index[n++] = v; index[n++] = v + 1; }
    }
  }
  const g = new THREE.BufferGeometry();
  // 'position' is required by three.js (bounding volumes); the shader uses 'rest'.
  g.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('rest', new THREE.BufferAttribute(pos, 3));
  g.setAttribute('restTangent', new THREE.BufferAttribute(tangent, 3));
  g.setAttribute('guides', new THREE.BufferAttribute(guides, 3));
  g.setAttribute('weights', new THREE.BufferAttribute(weights, 3));
  g.setAttribute('arc', new THREE.BufferAttribute(arc, 2));
  g.setIndex(new THREE.BufferAttribute(index, 1));
  return g;
}

// --- scissors (issue 5) ---
/** Draws only the kept part of every strand: segments (j, j + 1) with j + 1 < kept[s] (STRANDS message).
 * Returns the number of segments drawn. */
export function setKept(g: THREE.BufferGeometry, nv: number, kept: Uint16Array): number {
  const index = g.getIndex();
  if (!index) return 0;
  const a = index.array as Uint32Array;
  let n = 0;
  for (let s = 0; s < kept.length; s++) {
    const k = Math.min(nv, kept[s]);
    for (let i = 0; i + 1 < k; i++) { a[n++] = s * nv + i; a[n++] = s * nv + i + 1; }
  }
  g.setDrawRange(0, n);
  index.needsUpdate = true;
  return n / 2;
}
