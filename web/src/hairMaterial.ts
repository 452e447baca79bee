// Hair strands: the geometry (rest positions, guide binding, clump centres), the lit material (Marschner
// lobes, melanin colour, dual scattering with deep opacity map shadows, wet look; one-pixel lines carrying the
// strand's sub-pixel coverage from its width, blended in any order by hairCompositor.ts) and the two
// deep-opacity-map materials, all deforming the strands with the same shader code
// (shaders/hairDeform.glsl.ts): FFD by the lattice and the local strands' displacement on the GPU.
import * as THREE from 'three';
import type { SceneMsg } from './protocol';
import { hairDeformGLSL } from './shaders/hairDeform.glsl';
import { marschnerGLSL } from './shaders/marschner.glsl';
import { dualScatteringGLSL } from './shaders/dualScattering.glsl';
import { domLookupGLSL } from './shaders/deepOpacity.glsl';
import { displayGLSL } from './shaders/display.glsl';
import { strandCoverageGLSL } from './shaders/strandCoverage.glsl';
import { oitOutputGLSL } from './shaders/hairOit.glsl';
import { DEFAULT_HAIR_COLOUR, HAIR_COLOURS, sigmaFromMelanin, type Melanin } from './hairColor';
import { meanFibreWidth } from './fibre';
import type { DeepOpacityMaps } from './deepOpacityMaps';
import { CarriedHair } from './carriedHair';

/** Parameters of the hair's look (one home; documented with meaning, unit and default). */
export interface HairLookParams {
  /** Cuticle scale tilt alpha, rad. Default 2.5 deg (Marschner et al.: R shifted by -5 deg). */
  cuticleTilt: number;
  /** Longitudinal width beta_R of the R lobe, rad. Default 7 deg (TT: half, TRT: twice). */
  roughness: number;
  /** Refractive index of keratin. Default 1.55. */
  fibreIndex: number;
  /** Width of the water film's Gaussian highlight, rad. Default 1.5 deg. */
  waterRoughness: number;
  /** Relative lengthening of the absorbing paths at wetness 1 (wet hair is darker). Default 0.6. */
  wetAbsorption: number;
  /** Fraction of the way a soaked strand's tip moves to its clump's centre. Default 0.8. */
  clumpStrength: number;
  /** Hairs on a human head (each render strand stands for hairsOnHead / strands of them). Default 100,000. */
  hairsOnHead: number;
  /** Dual scattering densities d_f and d_b (Zinke et al. 2008). Default 0.7 each. */
  densityForward: number;
  densityBack: number;
  /** Smallest coverage of a pixel a strand's fragment carries, [0, 1] (shaders/strandCoverage.glsl.ts): keeps
   * a lone strand faintly visible however far the camera. Default 0.01. */
  minCoverage: number;
  /** Most parallel one-pixel lines a strand wider than a pixel is drawn with (each a draw of all the strands,
   * only when the strands near the camera are that wide; shaders/strandCoverage.glsl.ts). Default 4. */
  maxLines: number;
}

export const DEFAULT_HAIR_LOOK: HairLookParams = {
  cuticleTilt: 2.5 * Math.PI / 180, roughness: 7 * Math.PI / 180, fibreIndex: 1.55,
  waterRoughness: 1.5 * Math.PI / 180, wetAbsorption: 0.6, clumpStrength: 0.8, hairsOnHead: 100000,
  densityForward: 0.7, densityBack: 0.7, minCoverage: 0.01, maxLines: 4,
};

// The lit pass shades per vertex (32 or so per strand; a strand is a pixel wide, so its shading varies
// along it only): in software rendering a fragment shader with the full model cost about ten times more.
const litVertex = /* glsl */ `
${hairDeformGLSL}
${marschnerGLSL}
${dualScatteringGLSL}
${domLookupGLSL}
${displayGLSL}
${strandCoverageGLSL}
uniform vec3 lightDirection;  // unit, towards the key light
uniform vec3 lightColor;      // key light irradiance (linear RGB)
uniform vec3 skyColor;        // ambient irradiance from above
uniform vec3 groundColor;     // ambient irradiance from below
uniform vec3 cameraPos;
uniform int debugView;        // 0 shaded; 1 direct transmittance exp(-n) from the deep opacity maps; 2 highlight only
varying vec3 vColour;
varying float vCut;
varying float vCoverage;      // fraction of the pixel the strand covers
varying float vDepth;         // view distance, m
void main() {
  HairVertex h = deformHair();
  vCut = h.u - h.keep - 1e-4;
  vec4 clip = projectionMatrix * modelViewMatrix * vec4(h.position, 1.0);
  vDepth = clip.w;
  vec3 T = h.tangent;
  gl_Position = strandLine(h.position, clip, T, vCoverage);
  vec3 L = normalize(lightDirection);
  vec3 V = normalize(cameraPos - h.position);
  HairAngles a = hairAngles(T, L, V);
  float n = strandsTowardsLight(h.position);
  vec3 highlight;
  vec3 c = lightColor * hairRadiance(a, sigmaA, h.wetness, n, highlight);
  // Ambient: sky and ground light scattered back by the fibre and its neighbours, less deep in the volume.
  FibreAttenuation fa = fibreAttenuation(sigmaA * (1.0 + wetAbsorption * h.wetness));
  vec3 albedo = fa.ab + densityBack * fa.Ab + 0.3 * fa.af;
  float up = 0.5 + 0.5 * sqrt(max(0.0, 1.0 - T.z * T.z));
  c += albedo * mix(groundColor, skyColor, up) * (0.3 + 0.7 * exp(-0.15 * n)) / PI;
  vColour = debugView == 1 ? vec3(exp(-n)) : debugView == 2 ? toDisplay(lightColor * highlight * a.cosThetaI) : toDisplay(c);
}
`;

const shadowVertex = /* glsl */ `
${hairDeformGLSL}
varying float vCut;
void main() {
  HairVertex h = deformHair();
  vCut = h.u - h.keep - 1e-4;
  gl_Position = projectionMatrix * modelViewMatrix * vec4(h.position, 1.0);
}
`;

const litFragment = /* glsl */ `
precision highp float;
${oitOutputGLSL}
varying vec3 vColour;
varying float vCut;
varying float vCoverage;
varying float vDepth;
void main() {
  if (vCut > 0.0 || vCoverage <= 0.0) discard; // cut off by the scissors; a line this strand does not need
  writeOit(vColour, vCoverage, vDepth);
}
`;

export class HairMaterial {
  readonly material: THREE.ShaderMaterial;
  readonly depthMaterial: THREE.ShaderMaterial;
  readonly opacityMaterial: THREE.ShaderMaterial;
  readonly latticeTexture: THREE.DataTexture;
  readonly displacementTexture: THREE.DataTexture;
  readonly stateTexture: THREE.DataTexture;
  readonly clumpTexture: THREE.DataTexture;
  /** Every render vertex's rest position (head frame) and rest arc length from its root, for the carried hair. */
  readonly restTexture: THREE.DataTexture;
  /** Every render strand's primary guide, for the wet clumping of the carried hair. */
  readonly strandGuideTexture: THREE.DataTexture;
  /** The render vertices carried by the head and the lattice, once a frame (`carry`). */
  readonly carried: CarriedHair;
  readonly params: HairLookParams;
  /** Hairs one render strand stands for (>= 1). */
  readonly hairsPerStrand: number;
  private readonly samples: number;
  /** The SCENE's hair types: major-axis diameter (m) and ellipticity of each. */
  private readonly sections: { diameter: Float32Array; ellipticity: Float32Array };
  /** Mean width of one fibre of the current hair type, m (fibre.ts). */
  fibreWidth = 0;

  constructor(scene: SceneMsg, dom: DeepOpacityMaps, lighting: Record<string, THREE.IUniform>, oit: Record<string, THREE.IUniform>, params: Partial<HairLookParams> = {}) {
    this.params = { ...DEFAULT_HAIR_LOOK, ...params };
    const p = this.params;
    if (!(p.minCoverage >= 0 && p.minCoverage <= 1)) throw new Error(`minCoverage must be in [0, 1], got ${p.minCoverage}`);
    if (!(Number.isInteger(p.maxLines) && p.maxLines >= 1)) throw new Error(`maxLines must be an integer >= 1, got ${p.maxLines}`);
    const [nx, ny, nz] = scene.latticeDims;
    this.samples = Math.max(2, scene.samples);
    this.sections = { diameter: scene.hairTypeDiameter, ellipticity: scene.hairTypeEllipticity };
    this.hairsPerStrand = Math.max(1, p.hairsOnHead / Math.max(1, scene.strands));
    this.latticeTexture = floatTexture(nx * ny, nz);
    this.displacementTexture = floatTexture(this.samples, Math.max(1, scene.guides));
    this.stateTexture = floatTexture(Math.max(1, scene.guides), 1);
    this.clumpTexture = clumpCentres(scene);
    this.restTexture = restPositions(scene);
    this.strandGuideTexture = strandGuides(scene, this.restTexture.image.width);
    this.resetGuides();
    const deform: Record<string, THREE.IUniform> = {
      latticeNodes: { value: this.latticeTexture },
      latticeOrigin: { value: new THREE.Vector3(...scene.latticeOrigin) },
      latticeCell: { value: scene.latticeH },
      latticeSize: { value: new THREE.Vector3(nx, ny, nz) },
      guideDisplacement: { value: this.displacementTexture },
      guideState: { value: this.stateTexture },
      guideSamples: { value: this.samples },
      curliness: { value: 0 },
      curlRadius: { value: 0.006 },
      clumpCentres: { value: this.clumpTexture },
      verticesPerStrand: { value: scene.verticesPerStrand },
      clumpStrength: { value: p.clumpStrength },
      wetnessOverride: { value: -1 },
      headRotation: { value: new THREE.Matrix3() },
      headTranslation: { value: new THREE.Vector3() },
      rootHold: { value: scene.rootHold },
      restPositions: { value: this.restTexture },
      restWidth: { value: this.restTexture.image.width },
      strandGuides: { value: this.strandGuideTexture },
      vertexCount: { value: scene.strands * scene.verticesPerStrand },
      carriedPositions: { value: null },
      ...pushOutUniforms(scene),
    };
    this.carried = new CarriedHair(this.restTexture.image.width, this.restTexture.image.height, deform);
    deform.carriedPositions.value = this.carried.positions.texture;
    this.material = new THREE.ShaderMaterial({
      glslVersion: THREE.GLSL3,
      vertexShader: litVertex,
      fragmentShader: litFragment,
      // Order-independent: every fragment adds (hairCompositor.ts); the opaque depth hides strands behind the body.
      depthWrite: false, blending: THREE.CustomBlending, blendEquation: THREE.AddEquation,
      blendSrc: THREE.OneFactor, blendDst: THREE.OneFactor, blendSrcAlpha: THREE.OneFactor, blendDstAlpha: THREE.OneFactor,
      uniforms: {
        ...deform,
        ...dom.uniforms,
        ...oit,
        strandWidth: { value: 0 },
        viewport: { value: new THREE.Vector2(1, 1) },
        minCoverage: { value: p.minCoverage },
        lineIndex: { value: 0 },
        lineCount: { value: 1 },
        sigmaA: { value: new THREE.Vector3() },
        cuticleTilt: { value: p.cuticleTilt },
        roughness: { value: p.roughness },
        fibreIndex: { value: p.fibreIndex },
        waterRoughness: { value: p.waterRoughness },
        wetAbsorption: { value: p.wetAbsorption },
        densityForward: { value: p.densityForward },
        densityBack: { value: p.densityBack },
        ...lighting,
        debugView: { value: 0 },
      },
    });
    [this.depthMaterial, this.opacityMaterial] = dom.materials(shadowVertex, deform);
    this.setColour(HAIR_COLOURS[DEFAULT_HAIR_COLOUR]);
    this.setHairType(scene.hairType, dom);
  }

  /** Hair colour from melanin concentrations. */
  setColour(m: Melanin): void {
    this.material.uniforms.sigmaA.value.set(...sigmaFromMelanin(m));
  }

  /** The strand width (and the shadow maps' coverage) from the fibre section of the SCENE's hair type
   * `index`: a render strand is as wide as the hairs it stands for side by side. */
  setHairType(index: number, dom: DeepOpacityMaps): void {
    const n = this.sections.diameter.length;
    if (!(Number.isInteger(index) && index >= 0 && index < n)) throw new Error(`hair type ${index} unknown (the SCENE has ${n})`);
    this.fibreWidth = meanFibreWidth(this.sections.diameter[index], this.sections.ellipticity[index]);
    this.material.uniforms.strandWidth.value = this.fibreWidth * this.hairsPerStrand;
    dom.setHair(this.hairsPerStrand, this.fibreWidth);
  }

  /** The body's metaballs at rest (head frame), captured before the first head move. */
  private restBalls: THREE.Vector4[] | null = null;

  /** The head pose (head frame to world): the roots move with it (the carried hair's law) and so do the
   * push-out's metaballs (the lattice nodes already come in the world frame). */
  setHead(p: THREE.Vector3, q: THREE.Quaternion): void {
    (this.material.uniforms.headRotation.value as THREE.Matrix3).setFromMatrix4(new THREE.Matrix4().makeRotationFromQuaternion(q));
    (this.material.uniforms.headTranslation.value as THREE.Vector3).copy(p);
    const balls = this.material.uniforms.metaballs.value as THREE.Vector4[];
    if (!this.restBalls) this.restBalls = balls.map((b) => b.clone());
    const c = new THREE.Vector3();
    this.restBalls.forEach((r, i) => {
      c.set(r.x, r.y, r.z).applyQuaternion(q).add(p);
      balls[i].set(c.x, c.y, c.z, r.w);
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

  /** Carries the render vertices for this frame: before any pass that draws the hair. */
  carry(renderer: THREE.WebGLRenderer): void {
    this.carried.update(renderer);
  }

  /** Frees the textures and the materials' programs (a new SCENE replaces them). */
  dispose(): void {
    for (const t of [this.latticeTexture, this.displacementTexture, this.stateTexture, this.clumpTexture, this.restTexture, this.strandGuideTexture]) t.dispose();
    this.carried.dispose();
    for (const m of [this.material, this.depthMaterial, this.opacityMaterial]) m.dispose();
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

/** Clump centres for wet clumping: texel (i, g) is the mean rest position of vertex i over the strands whose
 * primary guide is g (a strand of its own where the guide has none). */
function clumpCentres(scene: SceneMsg): THREE.DataTexture {
  const nv = scene.verticesPerStrand, ns = scene.strands, k = scene.guidesPerStrand, G = Math.max(1, scene.guides);
  const t = floatTexture(nv, G);
  const d = t.image.data as Float32Array;
  const pos = scene.renderPositions;
  for (let s = 0; s < ns; s++) {
    const g = scene.renderGuide[s * k];
    for (let i = 0; i < nv; i++) {
      const o = 4 * (g * nv + i), v = 3 * (s * nv + i);
      d[o] += pos[v]; d[o + 1] += pos[v + 1]; d[o + 2] += pos[v + 2]; d[o + 3] += 1;
    }
  }
  for (let o = 0; o < d.length; o += 4) {
    if (d[o + 3] > 0) { d[o] /= d[o + 3]; d[o + 1] /= d[o + 3]; d[o + 2] /= d[o + 3]; }
  }
  return t;
}

/** Every render vertex's rest position (head frame, m) in xyz and its rest arc length from the strand's root
 * (m) in w: texel (v % width, v / width) for vertex v, width at most 4096 (WebGL2 guarantees textures that wide). */
function restPositions(scene: SceneMsg): THREE.DataTexture {
  const nv = scene.verticesPerStrand;
  const n = Math.max(1, scene.strands * nv);
  const w = Math.min(4096, n);
  const t = floatTexture(w, Math.ceil(n / w));
  const d = t.image.data as Float32Array;
  const pos = scene.renderPositions;
  let arc = 0;
  for (let v = 0; v < pos.length / 3; v++) {
    if (v % nv === 0) arc = 0;
    else arc += Math.hypot(pos[3 * v] - pos[3 * v - 3], pos[3 * v + 1] - pos[3 * v - 2], pos[3 * v + 2] - pos[3 * v - 1]);
    d[4 * v] = pos[3 * v]; d[4 * v + 1] = pos[3 * v + 1]; d[4 * v + 2] = pos[3 * v + 2]; d[4 * v + 3] = arc;
  }
  return t;
}

/** Every render strand's primary guide (the guide its wet clump gathers to): texel (s % width, s / width). */
function strandGuides(scene: SceneMsg, width: number): THREE.DataTexture {
  const t = floatTexture(width, Math.max(1, Math.ceil(scene.strands / width)));
  const d = t.image.data as Float32Array;
  for (let s = 0; s < scene.strands; s++) d[4 * s] = scene.renderGuide[s * scene.guidesPerStrand];
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

/** The same strands for the deep opacity maps: shares the attributes, draws every `stride`-th strand. */
export function shadowGeometry(g: THREE.BufferGeometry, stride: number, strands: number, nv: number): THREE.BufferGeometry {
  const s = new THREE.BufferGeometry();
  for (const name of ['position', 'rest', 'restTangent', 'guides', 'weights', 'arc']) s.setAttribute(name, g.getAttribute(name));
  s.setIndex(new THREE.BufferAttribute(new Uint32Array(Math.ceil(strands / stride) * 2 * Math.max(1, nv - 1)), 1));
  s.userData.stride = stride;
  return s;
}

// --- scissors (issue 5) ---
/** Draws only the kept part of every strand: segments (j, j + 1) with j + 1 < kept[s] (STRANDS message).
 * Returns the number of segments drawn. `shadow` (optional) gets every stride-th strand's kept segments. */
export function setKept(g: THREE.BufferGeometry, nv: number, kept: Uint16Array, shadow?: THREE.BufferGeometry): number {
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
  if (shadow) fillShadowIndex(shadow, nv, kept);
  return n / 2;
}

/** Every stride-th strand's segments (all of them when `kept` is absent). */
export function fillShadowIndex(shadow: THREE.BufferGeometry, nv: number, kept: Uint16Array | null, strands = 0): void {
  const stride = shadow.userData.stride as number;
  const index = shadow.getIndex()!;
  const a = index.array as Uint32Array;
  const ns = kept ? kept.length : strands;
  let n = 0;
  for (let s = 0; s < ns; s += stride) {
    const k = kept ? Math.min(nv, kept[s]) : nv;
    for (let i = 0; i + 1 < k && n + 1 < a.length; i++) { a[n++] = s * nv + i; a[n++] = s * nv + i + 1; }
  }
  shadow.setDrawRange(0, n);
  index.needsUpdate = true;
}
