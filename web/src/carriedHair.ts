// The render strands carried by the head and the lattice (engine::scene::carry_strand, the one law of the
// carried hair), computed on the GPU once per frame for every render vertex (shaders/carriedHair.glsl.ts):
// targets, then follow the leader, each into a float texture with one texel per render vertex. The hair's
// drawing passes read their vertex from `positions` (shaders/hairDeform.glsl.ts).
import * as THREE from 'three';
import { carriedChainFragment, carriedQuadVertex, carriedTargetsFragment } from './shaders/carriedHair.glsl';

export class CarriedHair {
  /** Texel (v % width, v / width): render vertex v carried by the head and the lattice (world, m). */
  readonly positions: THREE.WebGLRenderTarget;
  private readonly targets: THREE.WebGLRenderTarget;
  private readonly targetsMaterial: THREE.ShaderMaterial;
  private readonly chainMaterial: THREE.ShaderMaterial;
  private readonly quad: THREE.Mesh;
  private readonly scene = new THREE.Scene();
  private readonly camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);

  /** `width` x `height` texels (at least one per render vertex, as the rest-position texture); `uniforms`: the
   * hair's deformation uniforms (shared objects, so the lattice, head pose and wetness set on them apply). */
  constructor(width: number, height: number, uniforms: Record<string, THREE.IUniform>) {
    const target = () => new THREE.WebGLRenderTarget(width, height, {
      type: THREE.FloatType, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
      depthBuffer: false, generateMipmaps: false,
    });
    this.targets = target();
    this.positions = target();
    const material = (fragmentShader: string, extra: Record<string, THREE.IUniform>) => new THREE.ShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: carriedQuadVertex, fragmentShader, uniforms: { ...uniforms, ...extra },
      depthTest: false, depthWrite: false, blending: THREE.NoBlending,
    });
    this.targetsMaterial = material(carriedTargetsFragment, {});
    this.chainMaterial = material(carriedChainFragment, { carriedTargets: { value: this.targets.texture } });
    this.quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), this.targetsMaterial);
    this.quad.frustumCulled = false;
    this.scene.add(this.quad);
  }

  /** Runs both passes (before any pass that draws the hair). */
  update(renderer: THREE.WebGLRenderer): void {
    const previous = renderer.getRenderTarget();
    for (const [material, out] of [[this.targetsMaterial, this.targets], [this.chainMaterial, this.positions]] as const) {
      this.quad.material = material;
      renderer.setRenderTarget(out);
      renderer.render(this.scene, this.camera);
    }
    renderer.setRenderTarget(previous);
  }

  dispose(): void {
    this.targets.dispose();
    this.positions.dispose();
    this.targetsMaterial.dispose();
    this.chainMaterial.dispose();
    this.quad.geometry.dispose();
  }
}
