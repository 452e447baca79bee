// The hair laid over the opaque picture with weighted blended order-independent transparency
// (shaders/hairOit.glsl.ts): strands have sub-pixel coverage (shaders/strandCoverage.glsl.ts), so they are
// blended, and blended in any order (100k strands cannot be sorted every frame).
//  1. the opaque scene's depth is drawn into the accumulation target (colour writes off);
//  2. the strands (one draw call) add their weighted colour and opacity there, tested against that depth;
//  3. a full-screen pass blends the hair's mean colour with its opacity over the opaque picture on the canvas.
import * as THREE from 'three';
import { oitCompositeFragment, oitCompositeVertex } from './shaders/hairOit.glsl';

/** Parameters of the hair's compositing (one home; meaning, unit, default). */
export interface HairCompositeParams {
  /** Depth over which a strand's weight in the hair's colour falls by e behind the front of the hair, m.
   * Default 5 mm (about a dozen strands of 100k at 10 % coverage each: how deep front-to-back compositing sees). */
  depthFalloff: number;
}

export const DEFAULT_HAIR_COMPOSITE: HairCompositeParams = { depthFalloff: 0.005 };

export class HairCompositor {
  readonly params: HairCompositeParams;
  /** Attachment 0: weighted colour and weight; attachment 1: optical depth. Depth buffer for the opaque scene.
   * 32-bit floats where they can be blended (EXT_float_blend), else half floats. */
  readonly target: THREE.WebGLRenderTarget;
  /** Shared with the strands' material (oitOutputGLSL). */
  readonly uniforms: Record<string, THREE.IUniform>;
  private readonly depthOnly = new THREE.MeshBasicMaterial({ colorWrite: false });
  private readonly composite = new THREE.Scene();
  private readonly screen = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
  private readonly size = new THREE.Vector2();
  private readonly clear = new THREE.Color();

  constructor(renderer: THREE.WebGLRenderer, params: Partial<HairCompositeParams> = {}) {
    this.params = { ...DEFAULT_HAIR_COMPOSITE, ...params };
    if (!(this.params.depthFalloff > 0)) throw new Error(`depthFalloff must be > 0 m, got ${this.params.depthFalloff}`);
    const full = renderer.extensions.has('EXT_float_blend');
    this.target = new THREE.WebGLRenderTarget(1, 1, {
      count: 2, type: full ? THREE.FloatType : THREE.HalfFloatType, depthBuffer: true,
      minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
    });
    this.uniforms = {
      oitDepthReference: { value: 0 },
      oitDepthFalloff: { value: this.params.depthFalloff },
      // A weight's product with a coverage near minCoverage must stay a normal float of the target.
      oitMinWeight: { value: full ? 1e-30 : 1e-3 },
    };
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.BufferAttribute(new Float32Array([-1, -1, 0, 3, -1, 0, -1, 3, 0]), 3));
    const m = new THREE.ShaderMaterial({
      vertexShader: oitCompositeVertex, fragmentShader: oitCompositeFragment,
      uniforms: { oitAccumTexture: { value: this.target.textures[0] }, oitRevealTexture: { value: this.target.textures[1] } },
      depthTest: false, depthWrite: false, transparent: true, blending: THREE.CustomBlending,
      blendEquation: THREE.AddEquation, blendSrc: THREE.OneFactor, blendDst: THREE.OneMinusSrcAlphaFactor,
      blendSrcAlpha: THREE.OneFactor, blendDstAlpha: THREE.OneMinusSrcAlphaFactor,
    });
    const tri = new THREE.Mesh(g, m);
    tri.frustumCulled = false;
    this.composite.add(tri);
  }

  /** Draws `hair` over the picture of `opaque` already on the canvas. `bounds` holds every strand (world, m):
   * the depth weight is 1 at its front. */
  render(renderer: THREE.WebGLRenderer, opaque: THREE.Scene, hair: THREE.Scene, camera: THREE.Camera, bounds: THREE.Sphere): void {
    renderer.getDrawingBufferSize(this.size);
    if (this.target.width !== this.size.x || this.target.height !== this.size.y) this.target.setSize(this.size.x, this.size.y);
    const near = (camera as THREE.PerspectiveCamera).near ?? 0;
    this.uniforms.oitDepthReference.value = Math.max(near, camera.position.distanceTo(bounds.center) - bounds.radius);
    const oldTarget = renderer.getRenderTarget();
    const oldAuto = renderer.autoClear;
    renderer.getClearColor(this.clear);
    const oldAlpha = renderer.getClearAlpha();
    renderer.autoClear = false;
    renderer.setClearColor(0x000000, 0);
    renderer.setRenderTarget(this.target);
    renderer.clear(true, true, false);
    const override = opaque.overrideMaterial;
    opaque.overrideMaterial = this.depthOnly;
    renderer.render(opaque, camera);
    opaque.overrideMaterial = override;
    renderer.render(hair, camera);
    renderer.setRenderTarget(oldTarget);
    renderer.setClearColor(this.clear, oldAlpha);
    renderer.render(this.composite, this.screen);
    renderer.autoClear = oldAuto;
  }

  /** The hair's ink of the last render: the sum over pixels of accum.a (with the depth weight 1, i.e.
   * oitDepthFalloff set very large, the sum of every strand fragment's coverage, in pixels). */
  ink(renderer: THREE.WebGLRenderer): number {
    const { width, height } = this.target;
    const px = new Float32Array(4 * width * height);
    if (this.target.texture.type === THREE.FloatType) {
      renderer.readRenderTargetPixels(this.target, 0, 0, width, height, px, 0);
    } else {
      const h = new Uint16Array(4 * width * height);
      renderer.readRenderTargetPixels(this.target, 0, 0, width, height, h, 0);
      for (let i = 0; i < h.length; i++) px[i] = THREE.DataUtils.fromHalfFloat(h[i]);
    }
    let s = 0;
    for (let i = 3; i < px.length; i += 4) s += px[i];
    return s;
  }

  dispose(): void {
    this.target.dispose();
    this.depthOnly.dispose();
  }
}
