// Deep opacity maps from the key light (shaders/deepOpacity.glsl.ts): a light camera fitted around the head and
// hair, a depth pass and a layered opacity pass over a sub-sample of the strands, redrawn every frame with the
// same deformation as the lit strands, so the shadows follow the moving hair.
import * as THREE from 'three';
import { domDepthFragment, domOpacityFragment } from './shaders/deepOpacity.glsl';

/** Parameters of the deep opacity maps. */
export interface DomParams {
  /** Texels per side of the maps. Default 512. */
  resolution: number;
  /** Ends of the four layers behind the first surface, m. Default 5, 15, 35, 80 mm. */
  layers: [number, number, number, number];
  /** At most this many strands are drawn into the maps (every k-th strand, weighted by k). Default 8,000. */
  maxStrands: number;
  /** Depth bias against the first layer shadowing itself, m. Default 4 mm. */
  bias: number;
  /** Expected hair hits of a ray through the body (opaque). Default 40. */
  bodyHits: number;
}

export const DEFAULT_DOM_PARAMS: DomParams = {
  resolution: 512, layers: [0.005, 0.015, 0.035, 0.08], maxStrands: 8000, bias: 0.004, bodyHits: 40,
};

export class DeepOpacityMaps {
  readonly params: DomParams;
  readonly camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0.1, 3);
  readonly depthTarget: THREE.WebGLRenderTarget;
  readonly opacityTarget: THREE.WebGLRenderTarget;
  /** Shared by the lit materials that look the maps up (domLookupGLSL) and by the opacity pass. */
  readonly uniforms: Record<string, THREE.IUniform>;
  readonly depthScene = new THREE.Scene();
  readonly opacityScene = new THREE.Scene();
  private centre = new THREE.Vector3(0, 0, -0.05);
  private radius = 0.4;
  private readonly clear = new THREE.Color();

  constructor(params: Partial<DomParams> = {}) {
    this.params = { ...DEFAULT_DOM_PARAMS, ...params };
    const r = this.params.resolution;
    this.depthTarget = new THREE.WebGLRenderTarget(r, r, { depthBuffer: true, depthTexture: new THREE.DepthTexture(r, r) });
    this.depthTarget.depthTexture!.minFilter = THREE.NearestFilter;
    this.depthTarget.depthTexture!.magFilter = THREE.NearestFilter;
    this.opacityTarget = new THREE.WebGLRenderTarget(r, r, { type: THREE.HalfFloatType, depthBuffer: false, minFilter: THREE.LinearFilter, magFilter: THREE.LinearFilter });
    this.uniforms = {
      domDepth: { value: this.depthTarget.depthTexture },
      domOpacity: { value: this.opacityTarget.texture },
      domMatrix: { value: new THREE.Matrix4() },
      domLayers: { value: new THREE.Vector4(...this.params.layers) },
      domDepthRange: { value: 1 },
      domCoverage: { value: 0.03 },
      domBias: { value: this.params.bias },
      domResolution: { value: r },
      domWeight: { value: 1 },
      bodyWeight: { value: 1000 },
    };
  }

  /** Fits the light camera around a sphere (centre, radius in m) holding the head and the hair. */
  fit(centre: THREE.Vector3, radius: number): void {
    this.centre.copy(centre);
    this.radius = radius;
  }

  /** Sets the hairs one map fragment stands for and the coverage of one hair (its diameter, m). */
  setHair(weight: number, diameter: number): void {
    this.uniforms.domWeight.value = weight;
    const texel = 2 * this.radius / this.params.resolution;
    this.uniforms.domCoverage.value = diameter / texel;
    this.uniforms.bodyWeight.value = this.params.bodyHits * texel / diameter;
  }

  /** A depth-pass material and an opacity-pass material for a vertex shader that sets vCut (> 0: cut). */
  materials(vertexShader: string, uniforms: Record<string, THREE.IUniform>): [THREE.ShaderMaterial, THREE.ShaderMaterial] {
    const depth = new THREE.ShaderMaterial({ vertexShader, fragmentShader: domDepthFragment, uniforms, colorWrite: false });
    const opacity = new THREE.ShaderMaterial({
      vertexShader, fragmentShader: domOpacityFragment, uniforms: { ...uniforms, ...this.uniforms },
      transparent: true, depthTest: false, depthWrite: false, blending: THREE.CustomBlending,
      blendEquation: THREE.AddEquation, blendSrc: THREE.OneFactor, blendDst: THREE.OneFactor,
      blendSrcAlpha: THREE.OneFactor, blendDstAlpha: THREE.OneFactor, side: THREE.FrontSide,
    });
    return [depth, opacity];
  }

  /** Renders both passes from the light in direction `towardsLight` (unit, world). */
  update(renderer: THREE.WebGLRenderer, towardsLight: THREE.Vector3): void {
    const R = this.radius;
    const cam = this.camera;
    cam.left = -R; cam.right = R; cam.top = R; cam.bottom = -R; cam.near = 0.5 * R; cam.far = 2.5 * R;
    cam.position.copy(this.centre).addScaledVector(towardsLight, 1.5 * R);
    cam.up.set(0, 0, 1);
    if (Math.abs(towardsLight.z) > 0.95) cam.up.set(0, 1, 0);
    cam.lookAt(this.centre);
    cam.updateProjectionMatrix();
    cam.updateMatrixWorld();
    this.uniforms.domMatrix.value.multiplyMatrices(cam.projectionMatrix, cam.matrixWorldInverse);
    this.uniforms.domDepthRange.value = cam.far - cam.near;
    const oldTarget = renderer.getRenderTarget();
    renderer.getClearColor(this.clear);
    const oldAlpha = renderer.getClearAlpha();
    renderer.setClearColor(0x000000, 0);
    renderer.setRenderTarget(this.depthTarget);
    renderer.clear(true, true, false);
    renderer.render(this.depthScene, cam);
    renderer.setRenderTarget(this.opacityTarget);
    renderer.clear(true, false, false);
    renderer.render(this.opacityScene, cam);
    renderer.setRenderTarget(oldTarget);
    renderer.setClearColor(this.clear, oldAlpha);
  }

  dispose(): void {
    this.depthTarget.dispose();
    this.opacityTarget.dispose();
  }
}
