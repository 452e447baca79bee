// The three.js scene: renderer, camera with orbit controls (right drag), the key light and sky, the person
// (body mesh sculpted into a face, shoulders and shirt) and the hair, with deep opacity maps from the key light.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import type { SceneMsg } from './protocol';
import { HairMaterial, fillShadowIndex, hairGeometry, setKept, shadowGeometry } from './hairMaterial';
import { DeepOpacityMaps } from './deepOpacityMaps';
import { Person } from './person';
import { GpuTimer } from './gpuTimer';
import { HairCompositor } from './hairCompositor';
import { DEFAULT_HAIR_COLOUR, HAIR_COLOURS, sigmaFromMelanin, type Melanin } from './hairColor';

/** Camera views (world, m; the head's centre is the origin, x to the person's left, y forward, z up), each
 * with its key light (a direction towards it, any length). */
export const CAMERA_VIEWS = {
  /** The default: three-quarter front, a little above the eyes: the face and the hairstyle; the key light in
   * front, right of the camera and above (no hard nose shadow), the R highlight band on the crown. */
  portrait: { position: [0.43, 0.6, 0.2], target: [0, 0, 0.02], light: [0.45, 0.8, 0.35] },
  /** From behind and a little above, where the hair hangs (the comb tests' view); the light from behind,
   * right and above, so the hanging hair shows its R highlight band. */
  back: { position: [0.3, -0.9, 0.22], target: [0, 0, -0.05], light: [0.7, -0.55, 0.3] },
  /** From above and a little behind, looking down at the crown (a nozzle held there blows down on it). */
  above: { position: [0.12, -0.3, 0.72], target: [0, 0, 0.03], light: [0.3, -0.4, 0.85] },
} as const satisfies Record<string, { position: readonly [number, number, number]; target: readonly [number, number, number]; light: readonly [number, number, number] }>;
export type CameraView = keyof typeof CAMERA_VIEWS;
export const DEFAULT_VIEW: CameraView = 'portrait';
/** Default direction towards the key light (unit): the default view's. */
export const DEFAULT_LIGHT = new THREE.Vector3().fromArray(CAMERA_VIEWS[DEFAULT_VIEW].light).normalize();

const UNIT_SCALE = new THREE.Vector3(1, 1, 1);

export class View {
  readonly renderer: THREE.WebGLRenderer;
  readonly scene = new THREE.Scene();
  readonly camera: THREE.PerspectiveCamera;
  readonly controls: OrbitControls;
  hair: HairMaterial | null = null;
  /** The strands (one draw call, one-pixel lines with sub-pixel coverage), drawn by `compositor` over the
   * opaque `scene`. */
  hairMesh: THREE.LineSegments | null = null;
  readonly hairScene = new THREE.Scene();
  /** Draws 2 .. maxLines of the same strands (parallel lines for strands wider than a pixel), shown per frame. */
  private hairLines: THREE.LineSegments[] = [];
  /** Rest positions of up to 256 strand vertices (head frame, m): the nearest hair's depth for the line count. */
  private hairSamples = new Float32Array(0);
  /** Parallel lines per strand in the last frame (1 unless strands near the camera are wider than a pixel). */
  lineCount = 1;
  /** Forces the line count (tests, benchmarks); null: chosen per frame. */
  forceLines: number | null = null;
  /** Draw calls of the strands in the last frame (lit lines and both deep-opacity passes), each drawing every
   * strand: 3 at one line per strand, whatever the number of strands. */
  hairDrawCalls = 0;
  /** Strand segments one lit draw call drew in the last frame (every strand's: the index range of the hair). */
  hairSegmentsPerCall = 0;
  private readonly countHairDraw = (_r: THREE.WebGLRenderer, _s: THREE.Scene, _c: THREE.Camera, g: THREE.BufferGeometry): void => {
    this.hairDrawCalls++;
    if (g === this.hairMesh?.geometry) this.hairSegmentsPerCall = Math.min(g.drawRange.count, g.index ? g.index.count : Infinity) / 2;
  };
  readonly compositor: HairCompositor;
  /** Holds every strand at rest with room to move (head frame, m): the front of the hair for the compositing's
   * depth weight. */
  private readonly hairRestBounds = new THREE.Sphere(new THREE.Vector3(), 1);
  private readonly hairBounds = new THREE.Sphere(new THREE.Vector3(), 1);
  private readonly headMatrix = new THREE.Matrix4();
  person: Person | null = null;
  readonly dom = new DeepOpacityMaps();
  readonly gpuTimer: GpuTimer;
  /** Lighting shared by the hair and the skin (linear RGB irradiance). */
  readonly lighting: Record<string, THREE.IUniform> = {
    lightDirection: { value: DEFAULT_LIGHT.clone() },
    lightColor: { value: new THREE.Vector3(3.2, 3.0, 2.8) },
    skyColor: { value: new THREE.Vector3(0.8, 0.85, 1.0) },
    groundColor: { value: new THREE.Vector3(0.2, 0.17, 0.15) },
    cameraPos: { value: new THREE.Vector3() },
    exposure: { value: 1.0 },
  };
  private shadowHair: THREE.BufferGeometry | null = null;
  verticesPerStrand = 2;
  private colour: Melanin = HAIR_COLOURS[DEFAULT_HAIR_COLOUR];
  private readonly sun: THREE.DirectionalLight;
  /** Falling cut pieces (the clusters' chains), redrawn every frame. */
  readonly chains: THREE.LineSegments;
  private chainPositions = new Float32Array(3 * 4096);

  constructor(readonly canvas: HTMLCanvasElement) {
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    this.renderer.setClearColor(0x1d1f24);
    this.gpuTimer = new GpuTimer(this.renderer.getContext() as WebGL2RenderingContext);
    this.compositor = new HairCompositor(this.renderer);
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 10);
    this.camera.up.set(0, 0, 1); // z up, as in the simulation
    this.controls = new OrbitControls(this.camera, canvas);
    // Left button is the tool's; right button orbits; wheel zooms.
    this.controls.mouseButtons = { LEFT: null, MIDDLE: THREE.MOUSE.DOLLY, RIGHT: THREE.MOUSE.ROTATE };
    this.controls.update();
    // Lights for the tools' standard materials (the hair and skin use `lighting`).
    this.scene.add(new THREE.HemisphereLight(0xdde4ff, 0x30261e, 1.2));
    this.sun = new THREE.DirectionalLight(0xffffff, 1.6);
    this.sun.position.copy(DEFAULT_LIGHT);
    this.scene.add(this.sun);
    this.setView(DEFAULT_VIEW);
    this.resize();
    window.addEventListener('resize', () => this.resize());
    const cg = new THREE.BufferGeometry();
    cg.setAttribute('position', new THREE.BufferAttribute(this.chainPositions, 3));
    this.chains = new THREE.LineSegments(cg, new THREE.LineBasicMaterial({ color: 0x8a5a33 }));
    this.chains.frustumCulled = false;
    cg.setDrawRange(0, 0);
    this.scene.add(this.chains);
  }

  /** Puts the camera at one of CAMERA_VIEWS and the key light where that view has it (an unknown name is an
   * error naming the known ones). */
  setView(name: string): void {
    if (!Object.hasOwn(CAMERA_VIEWS, name)) throw new Error(`unknown view "${name}" (known: ${Object.keys(CAMERA_VIEWS).join(', ')})`);
    const v = CAMERA_VIEWS[name as CameraView];
    this.camera.position.fromArray(v.position);
    this.controls.target.fromArray(v.target);
    this.controls.update();
    this.setLight(new THREE.Vector3().fromArray(v.light));
  }

  /** Shortens the strands to their kept points (STRANDS message); returns the segments drawn. */
  setKept(kept: Uint16Array): number {
    if (!this.hairMesh) return 0;
    return setKept(this.hairMesh.geometry, this.verticesPerStrand, kept, this.shadowHair ?? undefined);
  }

  /** The falling chains: `counts[c]` points each, 3 floats per point in `points` (world, m). */
  setChains(counts: Uint32Array, points: Float32Array): void {
    let segs = 0;
    for (const c of counts) segs += Math.max(0, c - 1);
    if (6 * segs > this.chainPositions.length) {
      this.chainPositions = new Float32Array(6 * segs * 2);
      this.chains.geometry.setAttribute('position', new THREE.BufferAttribute(this.chainPositions, 3));
    }
    const d = this.chainPositions;
    let n = 0, p = 0;
    for (const c of counts) {
      for (let i = 0; i + 1 < c; i++) {
        for (let k = 0; k < 3; k++) d[n++] = points[3 * (p + i) + k];
        for (let k = 0; k < 3; k++) d[n++] = points[3 * (p + i + 1) + k];
      }
      p += c;
    }
    this.chains.geometry.setDrawRange(0, n / 3);
    (this.chains.geometry.getAttribute('position') as THREE.BufferAttribute).needsUpdate = true;
  }

  resize(): void {
    const w = this.canvas.clientWidth || window.innerWidth, h = this.canvas.clientHeight || window.innerHeight;
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / Math.max(1, h);
    this.camera.updateProjectionMatrix();
  }

  /** Hair colour from melanin (and the eyebrows'). */
  setColour(m: Melanin): void {
    this.colour = m;
    this.hair?.setColour(m);
    this.person?.setBrows(sigmaFromMelanin(m));
  }

  /** Direction towards the key light (any length). */
  setLight(towards: THREE.Vector3): void {
    this.lighting.lightDirection.value.copy(towards).normalize();
    this.sun.position.copy(this.lighting.lightDirection.value);
  }

  /** The head pose from FRAME (head frame to world): the person, its shadow-pass bodies and the hair's push-out
   * out of the body follow it. */
  setHead(p: [number, number, number], q: [number, number, number, number]): void {
    this.headPosition.set(...p);
    this.headQuaternion.set(...q);
    for (const o of [this.person?.group, this.person?.depthBody, this.person?.opacityBody]) {
      if (!o) continue;
      o.position.copy(this.headPosition);
      o.quaternion.copy(this.headQuaternion);
    }
    this.hair?.setHead(this.headPosition, this.headQuaternion);
  }
  readonly headPosition = new THREE.Vector3();
  readonly headQuaternion = new THREE.Quaternion();

  /** Builds the person and the hair from the SCENE message (replacing earlier ones). */
  load(msg: SceneMsg): void {
    if (this.hairMesh) { this.hairScene.remove(this.hairMesh, ...this.hairLines); this.hairMesh.geometry.dispose(); }
    this.hairLines = [];
    this.shadowHair?.dispose(); // shares the hair's attributes (disposed with them just above)
    this.hair?.dispose();
    if (this.person) { this.scene.remove(this.person.group); this.person.dispose(); }
    this.dom.depthScene.clear();
    this.dom.opacityScene.clear();
    // Light camera around the head and the hair (rest positions plus room to move).
    const box = new THREE.Box3().setFromArray(msg.renderPositions).union(new THREE.Box3().setFromArray(msg.headPositions));
    const sphere = box.getBoundingSphere(new THREE.Sphere());
    this.dom.fit(sphere.center, sphere.radius + 0.05);
    this.hairRestBounds.set(sphere.center.clone(), sphere.radius + 0.05);
    this.person = new Person(msg, this.dom, this.lighting);
    this.person.setBrows(sigmaFromMelanin(this.colour));
    this.scene.add(this.person.group);
    this.dom.depthScene.add(this.person.depthBody);
    this.dom.opacityScene.add(this.person.opacityBody);
    this.hair = new HairMaterial(msg, this.dom, this.lighting, this.compositor.uniforms);
    this.hair.setColour(this.colour);
    const g = hairGeometry(msg);
    this.hairMesh = new THREE.LineSegments(g, this.hair.material);
    this.hairMesh.frustumCulled = false;
    this.verticesPerStrand = msg.verticesPerStrand;
    this.hairScene.add(this.hairMesh);
    const material = this.hair.material;
    const lineDraw = (i: number) => () => { material.uniforms.lineIndex.value = i; material.uniformsNeedUpdate = true; };
    this.hairMesh.onBeforeRender = lineDraw(0);
    this.hairMesh.onAfterRender = this.countHairDraw;
    for (let i = 1; i < this.hair.params.maxLines; i++) {
      const l = new THREE.LineSegments(g, material);
      l.frustumCulled = false;
      l.onBeforeRender = lineDraw(i);
      l.onAfterRender = this.countHairDraw;
      l.visible = false;
      this.hairLines.push(l);
      this.hairScene.add(l);
    }
    const n = msg.renderPositions.length / 3, step = Math.max(1, Math.floor(n / 256));
    this.hairSamples = new Float32Array(3 * Math.ceil(n / step));
    for (let k = 0, v = 0; v < n; v += step, k++) this.hairSamples.set(msg.renderPositions.subarray(3 * v, 3 * v + 3), 3 * k);
    const stride = Math.max(1, Math.ceil(msg.strands / this.dom.params.maxStrands));
    this.shadowHair = shadowGeometry(g, stride, msg.strands, msg.verticesPerStrand);
    fillShadowIndex(this.shadowHair, msg.verticesPerStrand, null, msg.strands);
    this.dom.setHair(this.hair.hairsPerStrand * stride, this.hair.fibreWidth);
    for (const [m, s] of [[this.hair.depthMaterial, this.dom.depthScene], [this.hair.opacityMaterial, this.dom.opacityScene]] as const) {
      const l = new THREE.LineSegments(this.shadowHair, m);
      l.frustumCulled = false;
      l.onAfterRender = this.countHairDraw;
      s.add(l);
    }
  }

  /** Sets the strand width from the fibre section of the SCENE's hair type `index`. */
  setHairType(index: number): void {
    if (!this.hair) return;
    const stride = (this.shadowHair?.userData.stride as number) ?? 1;
    this.hair.setHairType(index, this.dom);
    this.dom.setHair(this.hair.hairsPerStrand * stride, this.hair.fibreWidth);
  }

  /** Parallel lines per strand for this frame: the width in pixels (rounded up, at most maxLines) of a strand
   * at the nearest sampled hair vertex (rest positions moved with the head). */
  private linesNeeded(height: number): number {
    if (!this.hair) return 1;
    const f = 0.5 * height * this.camera.projectionMatrix.elements[5];
    const view = this.camera.matrixWorldInverse, p = this.scratch;
    let nearest = Infinity;
    for (let k = 0; k < this.hairSamples.length; k += 3) {
      p.fromArray(this.hairSamples, k).applyQuaternion(this.headQuaternion).add(this.headPosition).applyMatrix4(view);
      nearest = Math.min(nearest, -p.z);
    }
    const width = this.hair.material.uniforms.strandWidth.value * f / Math.max(this.camera.near, nearest);
    return Math.min(this.hair.params.maxLines, Math.max(1, Math.ceil(width)));
  }
  private readonly scratch = new THREE.Vector3();

  render(): void {
    this.controls.update();
    this.lighting.cameraPos.value.copy(this.camera.position);
    this.gpuTimer.begin();
    this.hairDrawCalls = 0;
    if (this.hair) {
      this.hair.carry(this.renderer);
      this.dom.update(this.renderer, this.lighting.lightDirection.value);
    }
    this.renderer.render(this.scene, this.camera);
    if (this.hair && this.hairMesh) {
      const viewport = this.renderer.getDrawingBufferSize(this.hair.material.uniforms.viewport.value as THREE.Vector2);
      this.lineCount = this.forceLines ?? this.linesNeeded(viewport.y);
      this.hair.material.uniforms.lineCount.value = this.lineCount;
      this.hairLines.forEach((l, i) => { l.visible = this.hairMesh!.visible && i + 1 < this.lineCount; });
      this.hairBounds.copy(this.hairRestBounds).applyMatrix4(this.headMatrix.compose(this.headPosition, this.headQuaternion, UNIT_SCALE));
      this.compositor.render(this.renderer, this.scene, this.hairScene, this.camera, this.hairBounds);
    }
    this.gpuTimer.end();
  }
}
