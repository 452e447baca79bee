// Tools: their display meshes, and the mouse as a virtual device. The device point moves in a plane facing
// the camera; holding the left button presses the tool into the hair (the plane closer to the head) and
// sets button bit 0 (scissors cut, dryer and sprayer blow, clip closes). Pseudo-haptics: mouse motion is
// scaled down as the force grows, so the cursor (the tool, drawn at the proxy) slows as the hair resists.
import * as THREE from 'three';

export const TOOL_NAMES = ['comb', 'brush', 'scissors', 'dryer', 'sprayer', 'clip'];

/** Distance from the head's centre (the scene's origin) to the device plane, m: pressed into the hair, and
 * lifted. Pressed, a comb's teeth (2.5 cm, pointing into the screen) end at least 9.5 cm from the centre, 5 mm
 * outside the 9 cm cranium: they go through the hair, not into the scalp (the plane used to be measured from
 * the orbit target, 5 cm below the centre, and put the teeth 1.4 cm inside the head). */
export const PRESSED_DEPTH = 0.12;
export const LIFTED_DEPTH = 0.18;
/** The head's centre, m (scene frame). */
const HEAD_CENTRE = new THREE.Vector3(0, 0, 0);
/** Force at which the pseudo-haptic gain halves, N. */
export const PSEUDO_HAPTIC_FORCE = 0.05;

function box(w: number, h: number, d: number, x: number, y: number, z: number, color: number): THREE.Mesh {
  const m = new THREE.Mesh(new THREE.BoxGeometry(w, h, d), new THREE.MeshStandardMaterial({ color, roughness: 0.5 }));
  m.position.set(x, y, z);
  return m;
}

/** A display model of each tool in its own frame (x along the spine, teeth along -z, as the server's shapes).
 * The dryer and the sprayer are drawn at their nozzle, `nozzleStandoff` m (SCENE) behind the tool point along
 * +z, their jet along -z; the tool point, where the jet aims, is air: a small translucent marker shows it. */
export function toolModel(tool: number, nozzleStandoff = 0.15): THREE.Group {
  const g = new THREE.Group();
  switch (tool) {
    case 0: // comb: spine and 25 teeth
      g.add(box(0.13, 0.004, 0.006, 0, 0, 0.004, 0x222222));
      for (let i = 0; i < 25; i++) g.add(box(0.0012, 0.0012, 0.025, -0.06 + 0.005 * i, 0, -0.0125, 0x333333));
      break;
    case 1: // brush: pad and bristles
      g.add(box(0.06, 0.03, 0.01, 0, 0, 0.005, 0x6b3b1f));
      for (let i = 0; i < 8; i++) for (let j = 0; j < 4; j++) g.add(box(0.001, 0.001, 0.02, -0.025 + 0.007 * i, -0.01 + 0.007 * j, -0.01, 0x111111));
      break;
    case 2: // scissors: two blades
      g.add(box(0.08, 0.003, 0.003, 0, 0.0015, 0, 0xb0b0b8));
      g.add(box(0.08, 0.003, 0.003, 0, -0.0015, 0, 0x9090a0));
      break;
    case 3: // dryer: nozzle pointing along -z
    case 4: { // sprayer
      const colour = tool === 3 ? 0x5566cc : 0x33aadd;
      const cone = new THREE.Mesh(new THREE.ConeGeometry(0.02, 0.05, 16), new THREE.MeshStandardMaterial({ color: colour }));
      cone.rotation.x = Math.PI / 2;
      cone.position.z = nozzleStandoff + 0.02;
      g.add(cone);
      const aim = new THREE.Mesh(new THREE.SphereGeometry(0.004, 12, 8), new THREE.MeshBasicMaterial({ color: colour, transparent: true, opacity: 0.4, depthWrite: false }));
      g.add(aim);
      break;
    }
    default: // clip
      g.add(box(0.03, 0.008, 0.006, 0, 0, 0, 0xcc4477));
  }
  return g;
}

/** The tool's orientation for the camera: x along the screen's right, teeth (-z) pointing into the screen. */
export function toolQuaternion(camera: THREE.Camera): THREE.Quaternion {
  const forward = new THREE.Vector3();
  camera.getWorldDirection(forward);
  const z = forward.clone().negate();
  const x = new THREE.Vector3().crossVectors(forward, camera.up).normalize();
  const y = new THREE.Vector3().crossVectors(z, x);
  return new THREE.Quaternion().setFromRotationMatrix(new THREE.Matrix4().makeBasis(x, y, z));
}

/** The mouse as a virtual device. */
export class MouseDevice {
  /** Device target, m (world). */
  readonly target = new THREE.Vector3(0, -0.3, 0);
  pressed = false;
  private lastHit: THREE.Vector3 | null = null;
  private readonly raycaster = new THREE.Raycaster();
  /** Current pseudo-haptic gain in (0, 1]. */
  gain = 1;

  constructor(private readonly camera: THREE.Camera, private readonly canvas: HTMLCanvasElement) {}

  private plane(): THREE.Plane {
    const forward = new THREE.Vector3();
    this.camera.getWorldDirection(forward);
    const depth = this.pressed ? PRESSED_DEPTH : LIFTED_DEPTH;
    const p = HEAD_CENTRE.clone().addScaledVector(forward, -depth);
    return new THREE.Plane().setFromNormalAndCoplanarPoint(forward.clone().negate(), p);
  }

  private hit(ev: { clientX: number; clientY: number }): THREE.Vector3 | null {
    const r = this.canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((ev.clientX - r.left) / r.width) * 2 - 1, -((ev.clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    return this.raycaster.ray.intersectPlane(this.plane(), new THREE.Vector3());
  }

  /** Sets the pseudo-haptic gain from the force magnitude, N. */
  setForce(f: number): void {
    this.gain = 1 / (1 + f / PSEUDO_HAPTIC_FORCE);
  }

  down(ev: PointerEvent): void {
    this.pressed = true;
    const h = this.hit(ev);
    if (h) { this.target.copy(h); this.lastHit = h; }
  }

  up(ev: PointerEvent): void {
    this.pressed = false;
    const h = this.hit(ev);
    if (h) { this.target.copy(h); this.lastHit = h; }
  }

  move(ev: PointerEvent): void {
    const h = this.hit(ev);
    if (!h) return;
    if (this.lastHit && this.pressed) {
      this.target.addScaledVector(h.clone().sub(this.lastHit), this.gain);
      // Stay on the pressed plane.
      const pl = this.plane();
      this.target.sub(pl.normal.clone().multiplyScalar(pl.distanceToPoint(this.target)));
    } else {
      this.target.copy(h);
    }
    this.lastHit = h;
  }
}
