// The three.js scene: renderer, camera with orbit controls (right drag), lights, the head mesh and the hair.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import type { SceneMsg } from './protocol';
import { HairMaterial, hairGeometry, setKept } from './hairMaterial';

export class View {
  readonly renderer: THREE.WebGLRenderer;
  readonly scene = new THREE.Scene();
  readonly camera: THREE.PerspectiveCamera;
  readonly controls: OrbitControls;
  hair: HairMaterial | null = null;
  private hairMesh: THREE.LineSegments | null = null;
  private verticesPerStrand = 2;
  /** Falling cut pieces (the clusters' chains), redrawn every frame. */
  readonly chains: THREE.LineSegments;
  private chainPositions = new Float32Array(3 * 4096);
  private headMesh: THREE.Mesh | null = null;

  constructor(readonly canvas: HTMLCanvasElement) {
    this.renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
    this.renderer.setClearColor(0x1d1f24);
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.01, 10);
    this.camera.up.set(0, 0, 1); // z up, as in the simulation
    // Default view: from behind and a little above, where the hair hangs.
    this.camera.position.set(0.3, -0.9, 0.22);
    this.controls = new OrbitControls(this.camera, canvas);
    this.controls.target.set(0, 0, -0.05);
    // Left button is the tool's; right button orbits; wheel zooms.
    this.controls.mouseButtons = { LEFT: null, MIDDLE: THREE.MOUSE.DOLLY, RIGHT: THREE.MOUSE.ROTATE };
    this.controls.update();
    this.scene.add(new THREE.HemisphereLight(0xdde4ff, 0x30261e, 1.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(0.4, -0.6, 0.7);
    this.scene.add(sun);
    this.resize();
    window.addEventListener('resize', () => this.resize());
    const cg = new THREE.BufferGeometry();
    cg.setAttribute('position', new THREE.BufferAttribute(this.chainPositions, 3));
    this.chains = new THREE.LineSegments(cg, new THREE.LineBasicMaterial({ color: 0x8a5a33 }));
    this.chains.frustumCulled = false;
    cg.setDrawRange(0, 0);
    this.scene.add(this.chains);
  }

  /** Shortens the strands to their kept points (STRANDS message); returns the segments drawn. */
  setKept(kept: Uint16Array): number {
    if (!this.hairMesh) return 0;
    return setKept(this.hairMesh.geometry, this.verticesPerStrand, kept);
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

  /** Builds the head mesh and the hair from the SCENE message (replacing earlier ones). */
  load(msg: SceneMsg): void {
    if (this.hairMesh) { this.scene.remove(this.hairMesh); this.hairMesh.geometry.dispose(); }
    if (this.headMesh) { this.scene.remove(this.headMesh); this.headMesh.geometry.dispose(); }
    const hg = new THREE.BufferGeometry();
    hg.setAttribute('position', new THREE.BufferAttribute(msg.headPositions, 3));
    hg.setIndex(new THREE.BufferAttribute(msg.headIndices, 1));
    hg.computeVertexNormals();
    this.headMesh = new THREE.Mesh(hg, new THREE.MeshStandardMaterial({ color: 0xd9b59a, roughness: 0.7 }));
    this.scene.add(this.headMesh);
    // Head radius: the highest point of the mesh above the head's centre (the crown).
    let r = 0;
    for (let i = 0; i < msg.headPositions.length; i += 3) r = Math.max(r, msg.headPositions[i + 2]);
    this.hair = new HairMaterial(msg, r || 0.09);
    this.hairMesh = new THREE.LineSegments(hairGeometry(msg), this.hair.material);
    this.hairMesh.frustumCulled = false;
    this.verticesPerStrand = msg.verticesPerStrand;
    this.scene.add(this.hairMesh);
  }

  render(): void {
    this.controls.update();
    if (this.hair) this.hair.material.uniforms.cameraPos.value.copy(this.camera.position);
    this.renderer.render(this.scene, this.camera);
  }
}
