// The person under the hair: the SCENE's body mesh (surface nets of the metaballs the physics collides with)
// refined twice (3 mm edges), put back on the metaball iso-surface, then sculpted into a face (eye sockets,
// brows, nose, lips, chin, cheekbones) and ears by displacements along the normal, with eyeballs, painted
// lips, brows and a shirt. The sculpt carves the face into the collision surface (the face region sinks by
// 7 mm, the nose rises from it), so only the nose tip stands out by more than a few millimetres, by at most
// PERSON_MAX_OUTSET (m) beyond the surface the hair rests on, in the face the hair leaves free; the ears, under
// the hair, stand out by at most 3 mm, so the hair resting on the surface does not sink into them.
import * as THREE from 'three';
import type { SceneMsg } from './protocol';
import { skinFragmentBody, skinVertex } from './shaders/skin.glsl';
import { domLookupGLSL } from './shaders/deepOpacity.glsl';
import { displayGLSL } from './shaders/display.glsl';
import type { DeepOpacityMaps } from './deepOpacityMaps';

/** Largest outward displacement of the sculpt beyond the collision surface, m (checked in web/test/look.test.mjs). */
export const PERSON_MAX_OUTSET = 0.009;

/** The metaball field F and its gradient (the SCENE's balls: F = sum (1 - |x - c|^2 / R^2)^2 inside each). */
export function metaballField(balls: Float32Array, x: number, y: number, z: number): [number, number, number, number] {
  let f = 0, gx = 0, gy = 0, gz = 0;
  for (let b = 0; b + 3 < balls.length; b += 4) {
    const rx = x - balls[b], ry = y - balls[b + 1], rz = z - balls[b + 2];
    const r2inv = 1 / (balls[b + 3] * balls[b + 3]);
    const q = 1 - (rx * rx + ry * ry + rz * rz) * r2inv;
    if (q > 0) { f += q * q; const s = -4 * q * r2inv; gx += s * rx; gy += s * ry; gz += s * rz; }
  }
  return [f, gx, gy, gz];
}

type V3 = [number, number, number];
/** A Gaussian bump: amplitude (m, + outwards) and radii (m) about a centre; mirrored in x if `mirror`. */
interface Bump { c: V3; r: V3; a: number; mirror?: boolean }

// Head frame: x to the person's right, y forwards (face), z up; the cranium is a 0.09 m sphere about 0.
const FACE: Bump[] = [
  { c: [0, 0.1, -0.045], r: [0.045, 0.06, 0.042], a: -0.007 },          // the face region sinks
  { c: [0.031, 0.09, -0.006], r: [0.016, 0.03, 0.011], a: -0.007, mirror: true }, // eye sockets
  { c: [0.03, 0.095, 0.011], r: [0.022, 0.03, 0.006], a: 0.0025, mirror: true },  // brow ridges
  { c: [0, 0.1, 0.002], r: [0.008, 0.05, 0.005], a: -0.002 },            // nasion
  { c: [0, 0.1, -0.014], r: [0.0055, 0.05, 0.016], a: 0.0065 },          // nose bridge
  { c: [0, 0.1, -0.035], r: [0.009, 0.05, 0.008], a: 0.0135 },           // nose tip
  { c: [0.011, 0.095, -0.038], r: [0.006, 0.04, 0.0055], a: 0.0055, mirror: true }, // alae
  { c: [0, 0.1, -0.049], r: [0.003, 0.05, 0.004], a: -0.001 },           // philtrum
  { c: [0, 0.1, -0.057], r: [0.018, 0.05, 0.005], a: 0.0038 },           // upper lip
  { c: [0, 0.1, -0.068], r: [0.016, 0.05, 0.0055], a: 0.0042 },          // lower lip
  { c: [0, 0.1, -0.0625], r: [0.021, 0.05, 0.0013], a: -0.0028 },        // mouth line
  { c: [0.021, 0.09, -0.063], r: [0.004, 0.04, 0.004], a: -0.002, mirror: true },   // mouth corners
  { c: [0, 0.1, -0.078], r: [0.015, 0.05, 0.004], a: -0.0015 },          // under the lip
  { c: [0, 0.1, -0.09], r: [0.014, 0.05, 0.01], a: 0.004 },              // chin
  { c: [0.046, 0.08, -0.022], r: [0.018, 0.04, 0.014], a: 0.003, mirror: true },    // cheekbones
];

function bumps(list: Bump[], x: number, y: number, z: number): number {
  let d = 0;
  for (const b of list) {
    for (const sx of b.mirror ? [1, -1] : [1]) {
      const u = (x - sx * b.c[0]) / b.r[0], v = (y - b.c[1]) / b.r[1], w = (z - b.c[2]) / b.r[2];
      const e = u * u + v * v + w * w;
      if (e < 16) d += b.a * Math.exp(-e);
    }
  }
  return d;
}

const EAR = { y: -0.008, z: -0.024, halfWidth: 0.016, halfHeight: 0.029 };
/** Relief of the ears (m, outwards) on the sides of the head: a groove round the root sinks the head's side so
 * that the rim (helix), at most 3 mm out of the collision surface, stands about 5 mm above its surround; the
 * concha is carved, the lobe raised. The hair hangs over the ears and rests on the collision surface, so an ear
 * standing out further would show through it (web/test/look.test.mjs bounds the skin under the hair to 3 mm). */
function ears(x: number, y: number, z: number): number {
  if (Math.abs(x) < 0.055) return 0;
  const v = (y - EAR.y) / EAR.halfWidth, w = (z - EAR.z) / EAR.halfHeight;
  const rho = Math.hypot(v, w);
  if (rho > 1.6) return 0;
  const back = 0.6 + 0.4 * THREE.MathUtils.smoothstep(-v, -0.4, 0.6); // the helix stands out more at the back
  const groove = -0.0022 * Math.exp(-(((rho - 1.12) / 0.14) ** 2));
  const plateau = 0.0008 * (1 - THREE.MathUtils.smoothstep(rho, 0.85, 1.05));
  const rim = 0.0019 * back * Math.exp(-(((rho - 0.86) / 0.11) ** 2));
  const concha = -0.0035 * Math.exp(-((v - 0.15) ** 2 + (w + 0.05) ** 2) / 0.16);
  const lobe = 0.0006 * Math.exp(-((v + 0.05) ** 2 / 0.2 + (w + 0.85) ** 2 / 0.05));
  return groove + plateau + rim + concha + lobe;
}

/** Outward displacement of the body surface at a surface point (m). */
export function sculpt(x: number, y: number, z: number): number {
  return (y > 0.02 ? bumps(FACE, x, y, z) : 0) + ears(x, y, z);
}

// Colours (linear RGB albedo).
const SKIN: V3 = [0.68, 0.42, 0.32];
const LIPS: V3 = [0.5, 0.2, 0.18];
const SHIRT: V3 = [0.05, 0.075, 0.12];

/** Albedo, surface kind (0 skin, 1 cloth) and eyebrow weight (the brows take the hair's colour in the shader). */
function paint(x: number, y: number, z: number): [V3, number, number] {
  // A crew-neck shirt: below the shoulders' top, and on the shoulders away from the neck.
  const fromNeck = Math.hypot(x, (y + 0.009) * (y > -0.009 ? 0.8 : 1.1));
  const neckline = -0.165 - (y > 0 ? 0.012 * Math.exp(-((x / 0.04) ** 2)) : 0);
  if (z < neckline || (z < -0.125 && fromNeck > 0.062)) return [SHIRT, 1, 0];
  let c: V3 = [...SKIN];
  let brow = 0;
  const mix = (t: V3, k: number) => { for (let i = 0; i < 3; i++) c[i] += (t[i] - c[i]) * k; };
  if (y > 0.02) {
    const lips = Math.exp(-((x / 0.019) ** 2) - (((z + 0.0625) / 0.0095) ** 2)) * (y > 0.07 ? 1 : 0);
    mix(LIPS, Math.min(1, 1.6 * lips) * 0.8);
    const cheek = Math.exp(-(((Math.abs(x) - 0.045) / 0.02) ** 2) - (((z + 0.035) / 0.018) ** 2));
    mix([0.7, 0.33, 0.27], 0.25 * cheek);
    const b = Math.exp(-(((Math.abs(x) - 0.031) / 0.017) ** 4) - (((z - 0.0125 + 0.004 * ((Math.abs(x) - 0.031) / 0.017) ** 2) / 0.0032) ** 2));
    brow = 0.85 * b * (y > 0.06 ? 1 : 0);
    const nostril = Math.exp(-(((Math.abs(x) - 0.0065) / 0.003) ** 2) - (((z + 0.0425) / 0.0022) ** 2));
    mix([0.12, 0.05, 0.04], 0.9 * nostril);
  }
  if (Math.abs(x) > 0.06) { // ears a little redder
    const v = (y - EAR.y) / EAR.halfWidth, w = (z - EAR.z) / EAR.halfHeight;
    if (Math.hypot(v, w) < 1.1) mix([0.66, 0.33, 0.27], 0.35);
  }
  return [c, 0, brow];
}

/** Splits every triangle into four (shared edge midpoints). */
function subdivide(pos: number[], idx: number[]): [number[], number[]] {
  const mid = new Map<number, number>();
  const out: number[] = [];
  const nv0 = pos.length / 3;
  const m = (a: number, b: number): number => {
    const key = a < b ? a * 4194304 + b : b * 4194304 + a;
    let v = mid.get(key);
    if (v === undefined) {
      v = pos.length / 3;
      pos.push(0.5 * (pos[3 * a] + pos[3 * b]), 0.5 * (pos[3 * a + 1] + pos[3 * b + 1]), 0.5 * (pos[3 * a + 2] + pos[3 * b + 2]));
      mid.set(key, v);
    }
    return v;
  };
  void nv0;
  for (let t = 0; t < idx.length; t += 3) {
    const a = idx[t], b = idx[t + 1], c = idx[t + 2];
    const ab = m(a, b), bc = m(b, c), ca = m(c, a);
    out.push(a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca);
  }
  return [pos, out];
}

/** Newton steps along the gradient onto the iso-surface F = T (as head.rs `Head::project`). */
function project(balls: Float32Array, T: number, p: number[], i: number): V3 {
  let x = p[3 * i], y = p[3 * i + 1], z = p[3 * i + 2];
  let g: [number, number, number, number] = metaballField(balls, x, y, z);
  for (let it = 0; it < 6; it++) {
    const gn = Math.hypot(g[1], g[2], g[3]);
    if (gn < 1e-9) break;
    const d = Math.max(-0.01, Math.min(0.01, (T - g[0]) / gn));
    x += d * g[1] / gn; y += d * g[2] / gn; z += d * g[3] / gn;
    g = metaballField(balls, x, y, z);
    if (Math.abs(d) < 1e-7) break;
  }
  const gn = Math.hypot(g[1], g[2], g[3]) || 1;
  p[3 * i] = x; p[3 * i + 1] = y; p[3 * i + 2] = z;
  return [-g[1] / gn, -g[2] / gn, -g[3] / gn];
}

/** How the displayed skin sits under the hair: the hair rests on the metaball surface (the physics' body), the
 * skin is that surface moved by `sculpt` along the normal. */
export interface SkinUnderHair {
  /** Points (hair vertices) within `within` of the collision surface: the hair lying on the body. */
  near: number;
  /** Points tested. */
  points: number;
  /** Largest outward displacement of the skin under those points (m): hair sinks into the skin by this much. */
  maxOutset: number;
  /** Largest inward displacement (m, positive): hair floats above the skin by this much more than on the surface. */
  maxInset: number;
}

/** For every point (head frame, m; 3 floats each) whose distance to the collision surface F = T is below
 * `within` (m, first-order |F - T| / |grad F|, either side), the sculpt at its projection onto the surface:
 * how far the displayed skin is from the surface the hair rests on there. */
export function skinUnderHair(balls: Float32Array, T: number, points: Float32Array, within: number): SkinUnderHair {
  let near = 0, maxOutset = 0, maxInset = 0;
  const p = [0, 0, 0];
  for (let i = 0; i < points.length / 3; i++) {
    const [f, gx, gy, gz] = metaballField(balls, points[3 * i], points[3 * i + 1], points[3 * i + 2]);
    const gn = Math.hypot(gx, gy, gz);
    if (gn < 1e-9 || Math.abs(f - T) / gn > within) continue;
    p[0] = points[3 * i]; p[1] = points[3 * i + 1]; p[2] = points[3 * i + 2];
    project(balls, T, p, 0);
    const d = sculpt(p[0], p[1], p[2]);
    near++;
    maxOutset = Math.max(maxOutset, d);
    maxInset = Math.max(maxInset, -d);
  }
  return { near, points: points.length / 3, maxOutset, maxInset };
}

export interface PersonGeometry {
  geometry: THREE.BufferGeometry;
  /** Largest outward displacement beyond the collision surface, m. */
  maxOutset: number;
  /** Largest |F - T| / |grad F| of the refined vertices before sculpting, m. */
  maxProjectionError: number;
}

/** The body mesh refined (`levels` times split in four), projected and sculpted. */
export function personGeometry(msg: SceneMsg, levels = 2): PersonGeometry {
  let pos = Array.from(msg.headPositions);
  let idx = Array.from(msg.headIndices);
  for (let l = 0; l < levels; l++) [pos, idx] = subdivide(pos, idx);
  const balls = msg.metaballs, T = msg.metaballThreshold;
  const n = pos.length / 3;
  const albedo = new Float32Array(3 * n), surface = new Float32Array(n), brows = new Float32Array(n);
  let maxOutset = 0, maxProjectionError = 0;
  const haveBalls = balls.length >= 4;
  for (let i = 0; i < n; i++) {
    let nrm: V3 = [0, 0, 1];
    if (haveBalls) {
      nrm = project(balls, T, pos, i);
      const g = metaballField(balls, pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
      maxProjectionError = Math.max(maxProjectionError, Math.abs(g[0] - T) / (Math.hypot(g[1], g[2], g[3]) || 1));
    }
    const x = pos[3 * i], y = pos[3 * i + 1], z = pos[3 * i + 2];
    const d = haveBalls ? sculpt(x, y, z) : 0;
    maxOutset = Math.max(maxOutset, d);
    pos[3 * i] += d * nrm[0]; pos[3 * i + 1] += d * nrm[1]; pos[3 * i + 2] += d * nrm[2];
    const [c, s, b] = paint(x, y, z);
    albedo.set(c, 3 * i);
    surface[i] = s;
    brows[i] = b;
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(new Float32Array(pos), 3));
  g.setAttribute('albedo', new THREE.BufferAttribute(albedo, 3));
  g.setAttribute('surface', new THREE.BufferAttribute(surface, 1));
  g.setAttribute('brow', new THREE.BufferAttribute(brows, 1));
  g.setIndex(new THREE.BufferAttribute(new Uint32Array(idx), 1));
  g.computeVertexNormals();
  return { geometry: g, maxOutset, maxProjectionError };
}

/** An eyeball (radius m) looking along +y: sclera, iris and pupil painted per vertex. */
function eyeGeometry(radius: number): THREE.BufferGeometry {
  const g = new THREE.SphereGeometry(radius, 32, 24);
  const p = g.getAttribute('position');
  const albedo = new Float32Array(3 * p.count), surface = new Float32Array(p.count).fill(2);
  for (let i = 0; i < p.count; i++) {
    const c = p.getY(i) / radius; // cosine of the angle from the gaze
    const ang = Math.acos(Math.max(-1, Math.min(1, c)));
    const stripes = 0.85 + 0.15 * Math.sin(14 * Math.atan2(p.getZ(i), p.getX(i)));
    const col: V3 = ang < 0.2 ? [0.01, 0.01, 0.01] : ang < 0.48 ? [0.13 * stripes, 0.075 * stripes, 0.035 * stripes] : ang < 0.52 ? [0.05, 0.04, 0.03] : [0.62, 0.58, 0.55];
    albedo.set(col, 3 * i);
  }
  g.setAttribute('albedo', new THREE.BufferAttribute(albedo, 3));
  g.setAttribute('surface', new THREE.BufferAttribute(surface, 1));
  g.setAttribute('brow', new THREE.BufferAttribute(new Float32Array(p.count), 1));
  return g;
}

/** The outermost surface point along +y at (x, z), m. */
function frontSurface(balls: Float32Array, T: number, x: number, z: number): number {
  let y = 0.25;
  while (y > 0 && metaballField(balls, x, y, z)[0] < T) y -= 0.0005;
  return y;
}

export class Person {
  readonly group = new THREE.Group();
  readonly material: THREE.ShaderMaterial;
  readonly body: THREE.Mesh;
  readonly info: PersonGeometry;
  readonly opacityBody: THREE.Mesh;
  readonly depthBody: THREE.Mesh;
  /** The SCENE's metaballs (head frame; cx, cy, cz, R in m) and iso-value: the surface the hair rests on. */
  readonly metaballs: Float32Array;
  readonly metaballThreshold: number;

  constructor(msg: SceneMsg, dom: DeepOpacityMaps, shared: Record<string, THREE.IUniform>) {
    this.info = personGeometry(msg);
    this.metaballs = msg.metaballs;
    this.metaballThreshold = msg.metaballThreshold;
    this.material = new THREE.ShaderMaterial({
      vertexShader: skinVertex,
      fragmentShader: `precision highp float;\n${domLookupGLSL}\n${displayGLSL}\n${skinFragmentBody}`,
      uniforms: { ...dom.uniforms, ...shared, scatterWrap: { value: new THREE.Vector3(0.45, 0.2, 0.12) }, browColour: { value: new THREE.Vector3(0.1, 0.05, 0.03) } },
    });
    this.body = new THREE.Mesh(this.info.geometry, this.material);
    this.group.add(this.body);
    if (msg.metaballs.length >= 4) {
      const r = 0.0118;
      for (const sx of [1, -1]) {
        const x = sx * 0.031, z = -0.005;
        const y = frontSurface(msg.metaballs, msg.metaballThreshold, x, z) - 0.0035 - r;
        const eye = new THREE.Mesh(eyeGeometry(r), this.material);
        eye.position.set(x, y, z);
        this.group.add(eye);
      }
    }
    // The body in the deep opacity maps (opaque: a ray through it meets params.bodyHits hairs' worth).
    this.depthBody = new THREE.Mesh(this.info.geometry, new THREE.MeshBasicMaterial({ colorWrite: false }));
    this.opacityBody = new THREE.Mesh(this.info.geometry, new THREE.ShaderMaterial({
      vertexShader: 'varying float vCut; void main() { vCut = -1.0; gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }',
      fragmentShader: dom.materials('void main() {}', {})[1].fragmentShader,
      uniforms: { ...dom.uniforms, domWeight: dom.uniforms.bodyWeight },
      transparent: true, depthTest: false, depthWrite: false, blending: THREE.CustomBlending,
      blendEquation: THREE.AddEquation, blendSrc: THREE.OneFactor, blendDst: THREE.OneFactor,
      blendSrcAlpha: THREE.OneFactor, blendDstAlpha: THREE.OneFactor,
    }));
  }

  /** Eyebrows in the hair's colour: a rough albedo from the absorption (sigma_a, per unit radius). */
  setBrows(sigma: [number, number, number]): void {
    this.material.uniforms.browColour.value.set(...sigma.map((s) => 0.35 * Math.exp(-2 * s)));
  }

  dispose(): void {
    this.info.geometry.dispose();
    this.material.dispose();
    (this.opacityBody.material as THREE.Material).dispose();
    (this.depthBody.material as THREE.Material).dispose();
    this.group.traverse((o) => { if ((o as THREE.Mesh).isMesh && (o as THREE.Mesh).geometry !== this.info.geometry) (o as THREE.Mesh).geometry.dispose(); });
  }
}
