// The Coiffure viewer: connects to the server's WebSocket, draws the scene, drives the tool with the mouse.
import * as THREE from 'three';
import * as P from './protocol';
import { CAMERA_VIEWS, DEFAULT_VIEW, View } from './scene';
import { ForcePlot } from './plot';
import { MouseDevice, TOOL_NAMES, toolModel, toolQuaternion } from './tools';
import { DEFAULT_HAIR_COLOUR, HAIR_COLOURS } from './hairColor';
import { skinUnderHair } from './person';

/** State exposed for the end-to-end tests and for curious users (window.coiffure). */
interface Status {
  webgl2: boolean;
  connected: boolean;
  closeReason: string | null; // why the server closed the connection (its close code and reason), null while open
  sceneLoaded: boolean;
  framesReceived: number;
  framesRendered: number;
  youControl: boolean;
  viewers: number;
  lastForce: number;
  peakForce: number;
  contacts: number;
  maxDisplacement: number;
  wetnessMean: number;
  cutMin: number; // smallest kept fraction of a render strand (kept points / V), 1 before any cut
  keptMean: number; // mean kept points per render strand (STRANDS)
  segmentsDrawn: number; // render strand segments drawn
  keptVersion: number; // changes of the strands' kept points on the server (cuts, resets)
  chainPoints: number; // points of the falling chains in the last frame
  tool: number;
  readonly toolPressed: boolean; // the tool's button as the page last handled it (the mouse's left button, or a test's releaseButton)
  readonly toolTarget: [number, number, number]; // where the mouse puts the device (m, world): the tool proxy follows it
  errors: P.ErrorMsg[];
  recordStopped: string | null; // why `serve --record` stopped recording (ERROR 7), kept in the status bar
  frameTimes: number[];
  gpuFrameMs: number | null; // GPU time of the last measured frame (EXT_disjoint_timer_query_webgl2), null if unavailable
  gpuTimer: boolean; // the timer query extension exists
  readonly hairDrawCalls: number; // draw calls of the strands in the last frame (lit lines and the two shadow passes; 3 at one line, any strand count)
  readonly hairSegmentsPerCall: number; // strand segments the lit draw call drew in the last frame (all strands')
  hairColour: string;
  strands: number;
  /** The SCENE's hair types with their fibre sections (major-axis diameter, m; ellipticity). */
  hairTypes: { name: string; diameter: number; ellipticity: number }[];
  /** The drawn strands: width of one render strand (m; the hairs it stands for side by side), the mean width
   * of one fibre of the current hair type (m) and the hairs a render strand stands for. */
  strandWidth: () => { width: number; fibreWidth: number; hairsPerStrand: number };
  lastFile: { format: number; bytes: number } | null;
  fit: P.FitMsg | null; // how the last loaded hairstyle was placed on the head (FIT)
  device: P.DeviceMsg | null; // the haptic device's stream (DEVICE; null without `serve --device`)
  runaways: number; // runaway-guard resets of the tool proxy since the session started (FRAME; should stay 0)
  treatment: string; // the session's surface treatment as its FRAME reports it (P.TREATMENTS; '' before one)
  toolFriction: number; // the tool-hair friction coefficient the session uses (FRAME; NaN before one)
  toolPosition: [number, number, number]; // the tool proxy of the last FRAME (m, world)
  headPosition: [number, number, number]; // the head pose of the last FRAME (m; head frame to world)
  headQuaternion: [number, number, number, number]; // x, y, z, w
  headMode: boolean; // the mouse turns the head (key H) instead of driving the tool
  /** Turns and nods the head (rad, about z then about the head's x) and moves it (m): sends HEAD. */
  setHead: (yaw: number, pitch: number, position?: [number, number, number]) => void;
  /** Largest lattice-node displacement relative to the head since the scene was loaded, now (m). */
  latticeMotion: () => number;
  /** The camera view (CAMERA_VIEWS in scene.ts; the page's `?view=` sets it at start). */
  view: string;
  setView: (name: string) => void;
  send: (b: ArrayBuffer) => void;
}

const canvas = document.getElementById('view') as HTMLCanvasElement;
const statusEl = document.getElementById('status') as HTMLSpanElement;
const healthEl = document.getElementById('health') as HTMLSpanElement;
const treatmentEl = document.getElementById('treatment') as HTMLSelectElement;
const view = new View(canvas);
const plot = new ForcePlot(document.getElementById('plot') as HTMLCanvasElement);
const device = new MouseDevice(view.camera, canvas);

const status: Status = {
  webgl2: view.renderer.getContext() instanceof WebGL2RenderingContext,
  connected: false, closeReason: null, sceneLoaded: false, framesReceived: 0, framesRendered: 0, youControl: false, viewers: 0,
  runaways: 0, treatment: '', toolFriction: NaN, lastForce: 0, peakForce: 0, contacts: 0, maxDisplacement: 0, wetnessMean: 0, cutMin: 1, keptMean: 0, segmentsDrawn: 0, keptVersion: 0, chainPoints: 0, tool: 0, errors: [], recordStopped: null, frameTimes: [], strands: 0,
  gpuFrameMs: null, gpuTimer: view.gpuTimer.available, hairColour: DEFAULT_HAIR_COLOUR,
  get toolPressed() { return device.pressed; },
  get toolTarget() { return device.target.toArray(); },
  get hairDrawCalls() { return view.hairDrawCalls; },
  get hairSegmentsPerCall() { return view.hairSegmentsPerCall; },
  hairTypes: [], strandWidth: () => ({ width: view.hair?.material.uniforms.strandWidth.value ?? 0, fibreWidth: view.hair?.fibreWidth ?? 0, hairsPerStrand: view.hair?.hairsPerStrand ?? 0 }),
  lastFile: null,
  fit: null,
  device: null,
  toolPosition: [0, 0, 0],
  headPosition: [0, 0, 0], headQuaternion: [0, 0, 0, 1], headMode: false,
  latticeMotion: () => latticeMotion(),
  view: DEFAULT_VIEW,
  setView: (name) => setView(name),
  setHead: (yaw, pitch, position = [0, 0, 0]) => {
    const q = new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(0, 0, 1), yaw)
      .multiply(new THREE.Quaternion().setFromAxisAngle(new THREE.Vector3(1, 0, 0), pitch));
    const angle = 2 * Math.acos(Math.min(1, Math.abs(q.w)));
    const s = Math.sqrt(Math.max(0, 1 - q.w * q.w));
    const sign = q.w < 0 ? -1 : 1;
    const rv: [number, number, number] = s < 1e-9 ? [0, 0, 0] : [sign * q.x / s * angle, sign * q.y / s * angle, sign * q.z / s * angle];
    status.send(P.encodeHead(position, rv));
  },
  send: (b) => { if (ws.readyState === WebSocket.OPEN) ws.send(b); },
};
(window as unknown as { coiffure: Status }).coiffure = status;

// Tool, force arrow, device ghost.
/** Where the nozzle tools' nozzle is behind the tool point, m (SCENE). */
let nozzleStandoff = 0.15;
let toolGroup = toolModel(0);
view.scene.add(toolGroup);
const arrow = new THREE.ArrowHelper(new THREE.Vector3(0, 0, 1), new THREE.Vector3(), 0.05, 0xff5533, 0.012, 0.008);
arrow.visible = false;
view.scene.add(arrow);
const ghost = new THREE.Mesh(new THREE.SphereGeometry(0.003, 12, 8), new THREE.MeshBasicMaterial({ color: 0x88ff88, transparent: true, opacity: 0.5 }));
view.scene.add(ghost);

const url = new URL('/ws', window.location.href);
// The access token the server printed with the page's URL (required when it listens off loopback).
const token = new URLSearchParams(window.location.search).get('token');
if (token) url.searchParams.set('token', token);
url.protocol = url.protocol === 'https:' ? 'wss:' : 'ws:';
const ws = new WebSocket(url);
ws.binaryType = 'arraybuffer';
ws.onopen = () => { status.connected = true; statusEl.textContent = 'connected'; };
ws.onclose = (ev) => {
  status.connected = false;
  status.closeReason = `${ev.code}${ev.reason ? ` ${ev.reason}` : ''}`;
  statusEl.textContent = ev.reason ? `disconnected by the server: ${ev.reason}` : 'disconnected (is coiffure serve running?)';
};
ws.onmessage = (ev) => {
  const buf = ev.data as ArrayBuffer;
  let type: number;
  try { type = P.messageType(buf); } catch (e) {
    statusEl.textContent = `server: ${(e as Error).message}`;
    return;
  }
  switch (type) {
    case P.Server.SCENE: {
      let msg: P.SceneMsg;
      try { msg = P.decodeScene(buf); } catch (e) {
        statusEl.textContent = `cannot show the scene: ${(e as Error).message}`;
        throw e;
      }
      onScene(msg);
      break;
    }
    case P.Server.FRAME: {
      const f = P.decodeFrame(buf);
      onFrame(f);
      // Done with it: the server sends the next (at most two on their way), never a backlog (FRAME_ACK).
      status.send(P.encodeFrameAck(f.seq));
      break;
    }
    case P.Server.STRANDS: onStrands(P.decodeStrands(buf)); break;
    case P.Server.DEVICE: {
      const d = P.decodeDevice(buf);
      status.device = d;
      const el = document.getElementById('device');
      if (el) {
        el.textContent = `device: ${d.state}${d.rejected ? `, ${d.rejected} rejected` : ''}${d.malformed ? `, ${d.malformed} malformed` : ''}${d.lost ? `, lost ${d.lost}x` : ''}`;
        el.className = d.state;
        el.title = `haptic device (UDP): ${d.accepted} poses accepted, ${d.rejected} rejected (NaN, out of range, teleport, out of order, duplicate), ${d.malformed} malformed packets dropped, ${d.foreign} poses from another sender dropped, lost ${d.lost} times, ${d.answered} forces sent`;
      }
      break;
    }
    case P.Server.FIT: {
      const f = P.decodeFit(buf);
      status.fit = f;
      const t = f.translation.map((x) => x.toFixed(3)).join(', ');
      const el = document.getElementById('fit-info');
      if (el) {
        el.textContent = `fit: units ${P.unitsName(f.metersPerUnit)} (${f.unitsSource}), up ${f.up} front ${f.front} (${f.axesSource}), scale ${f.scale.toPrecision(4)}, move [${t}] m; ${(100 * f.rooted).toFixed(0)} % of strands rooted on the scalp (roots median ${(1e3 * f.rootedMedian).toFixed(1)} mm, p95 ${(1e3 * f.rootedP95).toFixed(1)} mm from it)${f.rooted < 0.999 ? `, ${(100 * (1 - f.rooted)).toFixed(0)} % loose` : ''}`;
        el.title = `rotation (file to head frame, rows): ${f.rotation.map((x) => x.toFixed(3)).join(' ')}; all roots to the scalp: median ${(1e3 * f.rootMedian).toFixed(1)} mm, p95 ${(1e3 * f.rootP95).toFixed(1)} mm, max ${(1e3 * f.rootMax).toFixed(1)} mm; ${f.pushedOut} points pushed out of the head`;
      }
      break;
    }
    case P.Server.ERROR: {
      const e = P.decodeError(buf);
      status.errors.push(e);
      if (e.code === 7) status.recordStopped = e.message;
      statusEl.textContent = `server: ${e.message}`;
      break;
    }
    case P.Server.CONTROL: {
      const c = P.decodeControl(buf);
      status.youControl = c.youControl;
      status.viewers = c.viewers;
      statusEl.textContent = `${status.youControl ? 'you control the tool' : 'watching'} (${status.viewers} viewer${status.viewers === 1 ? '' : 's'})${status.recordStopped ? `; ${status.recordStopped}` : ''}`;
      break;
    }
    case P.Server.FILE: {
      const f = P.decodeFile(buf);
      const blob = new Blob([f.bytes]);
      status.lastFile = { format: f.format, bytes: blob.size };
      const a = document.createElement('a');
      a.href = URL.createObjectURL(blob);
      a.download = `hairstyle.${f.extension}`;
      a.click();
      break;
    }
    case P.Server.PONG: break;
    default: statusEl.textContent = `server: unknown message type 0x${type.toString(16)}`;
  }
};

function onScene(msg: P.SceneMsg): void {
  view.load(msg);
  status.strands = msg.strands;
  nv = msg.verticesPerStrand;
  const preset = document.getElementById('preset') as HTMLSelectElement;
  preset.innerHTML = msg.hairTypes.map((n, i) => `<option value="${i}">${n}</option>`).join('');
  preset.value = String(msg.hairType);
  view.setHairType(msg.hairType);
  status.hairTypes = msg.hairTypes.map((name, i) => ({ name, diameter: msg.hairTypeDiameter[i], ellipticity: msg.hairTypeEllipticity[i] }));
  status.sceneLoaded = true;
  restNodes = null;
  if (msg.nozzleStandoff !== nozzleStandoff) {
    nozzleStandoff = msg.nozzleStandoff;
    setTool(status.tool, false);
  }
}

// --- scissors (issue 5): shortened strands ---
let nv = 2;
function onStrands(kept: Uint16Array): void {
  status.segmentsDrawn = view.setKept(kept);
  let sum = 0, min = Infinity;
  for (const k of kept) { sum += k; min = Math.min(min, k); }
  status.keptMean = sum / Math.max(1, kept.length);
  status.cutMin = kept.length ? min / nv : 1;
}

const scratch = new THREE.Vector3();
// The lattice nodes of the first FRAME after a SCENE (head frame), to measure how far the hairstyle moved.
let restNodes: Float32Array | null = null;
let lastNodes: Float32Array | null = null;
/** Largest distance of a lattice node from where it was at the first FRAME after the SCENE, relative to the
 * head (m): how far the whole hairstyle moved. */
function latticeMotion(): number {
  if (!restNodes || !lastNodes) return 0;
  const inv = new THREE.Quaternion(...status.headQuaternion).invert();
  const p = new THREE.Vector3(...status.headPosition), x = new THREE.Vector3();
  let worst = 0;
  for (let i = 0; i + 2 < lastNodes.length; i += 3) {
    x.set(lastNodes[i], lastNodes[i + 1], lastNodes[i + 2]).sub(p).applyQuaternion(inv);
    worst = Math.max(worst, Math.hypot(x.x - restNodes[i], x.y - restNodes[i + 1], x.z - restNodes[i + 2]));
  }
  return worst;
}

function onFrame(f: P.FrameMsg): void {
  status.framesReceived++;
  status.toolPosition = f.toolPosition;
  lastNodes = f.nodes;
  if (!restNodes) {
    // in the head frame
    const inv = new THREE.Quaternion(...f.headQuaternion).invert();
    const p = new THREE.Vector3(...f.headPosition), x = new THREE.Vector3();
    restNodes = new Float32Array(f.nodes.length);
    for (let i = 0; i + 2 < f.nodes.length; i += 3) {
      x.set(f.nodes[i], f.nodes[i + 1], f.nodes[i + 2]).sub(p).applyQuaternion(inv);
      restNodes.set([x.x, x.y, x.z], i);
    }
  }
  status.youControl = f.youControl;
  const hair = view.hair;
  if (hair) {
    hair.setLattice(f.nodes);
    hair.setGuides(f.active, f.samples, f.displacement, f.wetness);
  }
  view.setChains(f.chainCounts, f.chainPoints);
  const hp = f.headPosition, hq = f.headQuaternion;
  if (hp.some((x, i) => x !== status.headPosition[i]) || hq.some((x, i) => x !== status.headQuaternion[i])) {
    view.setHead(hp, hq);
    status.headPosition = hp;
    status.headQuaternion = hq;
  }
  status.keptVersion = f.keptVersion;
  status.chainPoints = f.chainPoints.length / 3;
  for (let i = 0; i < f.displacement.length; i += 3) {
    status.maxDisplacement = Math.max(status.maxDisplacement, Math.hypot(f.displacement[i], f.displacement[i + 1], f.displacement[i + 2]));
  }
  status.wetnessMean = f.wetness.reduce((a, b) => a + b, 0) / Math.max(1, f.wetness.length);
  const fm = Math.hypot(...f.force);
  status.lastForce = fm;
  status.peakForce = Math.max(status.peakForce, fm);
  status.contacts = f.contacts;
  if (f.treatment >= 0) {
    const name = P.TREATMENTS[f.treatment] ?? `treatment ${f.treatment}`;
    if (name !== status.treatment || f.toolFriction !== status.toolFriction) {
      status.treatment = name;
      status.toolFriction = f.toolFriction;
      treatmentEl.title = `surface treatment: ${name}, tool friction ${f.toolFriction.toFixed(3)} (docs/treatment.md)`;
      if (document.activeElement !== treatmentEl) treatmentEl.value = String(f.treatment);
    }
  }
  if (f.runaways !== status.runaways) {
    status.runaways = f.runaways;
    healthEl.textContent = f.runaways > 0 ? `proxy resets: ${f.runaways}` : '';
  }
  plot.push(fm);
  device.setForce(fm);
  if (f.tool !== status.tool) setTool(f.tool, false);
  // Pseudo-haptic cursor: the tool is drawn where the proxy is, which lags behind the mouse under force.
  // The tool appears once something drives it (the pointer on the canvas, or a haptic device): at rest it
  // waits behind the head, where the portrait view would show it floating beside the face.
  toolGroup.visible = ghost.visible = toolDriven || status.device !== null;
  toolGroup.position.set(...f.toolPosition);
  toolGroup.quaternion.set(...f.toolQuaternion);
  ghost.position.set(...f.devicePosition);
  arrow.visible = fm > 1e-4;
  if (arrow.visible) {
    scratch.set(...f.force).normalize();
    arrow.position.set(...f.toolPosition);
    arrow.setDirection(scratch);
    arrow.setLength(Math.min(0.15, 0.02 + 0.3 * fm), 0.012, 0.008);
  }
}

function setTool(t: number, send: boolean): void {
  status.tool = t;
  view.scene.remove(toolGroup);
  toolGroup = toolModel(t, nozzleStandoff);
  view.scene.add(toolGroup);
  document.querySelectorAll<HTMLButtonElement>('#tools button').forEach((b) => b.classList.toggle('active', Number(b.dataset.tool) === t));
  if (send) status.send(P.encodeSelectTool(t));
}

// Camera view: the toolbar's menu and the page's ?view= (e.g. ?view=back for the hanging hair).
const viewEl = document.getElementById('view-select') as HTMLSelectElement | null;
function setView(name: string): void {
  view.setView(name); // throws on an unknown name, naming the known ones
  status.view = name;
  if (viewEl) viewEl.value = name;
}
if (viewEl) {
  viewEl.innerHTML = Object.keys(CAMERA_VIEWS).map((n) => `<option>${n}</option>`).join('');
  viewEl.value = DEFAULT_VIEW;
  viewEl.addEventListener('change', () => setView(viewEl.value));
}
const viewParam = new URLSearchParams(window.location.search).get('view');
if (viewParam !== null) {
  try { setView(viewParam); } catch (e) { statusEl.textContent = (e as Error).message; }
}

// Toolbar.
document.querySelectorAll<HTMLButtonElement>('#tools button').forEach((b) => b.addEventListener('click', () => setTool(Number(b.dataset.tool), true)));
const presetEl = document.getElementById('preset') as HTMLSelectElement;
const curlEl = document.getElementById('curliness') as HTMLInputElement;
const easeEl = document.getElementById('ease') as HTMLInputElement;
const colourEl = document.getElementById('colour') as HTMLSelectElement;
function setColour(name: string): void {
  const m = HAIR_COLOURS[name];
  if (!m) return;
  status.hairColour = name;
  colourEl.value = name;
  view.setColour(m);
}
colourEl.addEventListener('change', () => setColour(colourEl.value));
function sendHair(): void {
  view.setHairType(Number(presetEl.value) || 0);
  const c = Number(curlEl.value);
  if (view.hair) view.hair.material.uniforms.curliness.value = c;
  status.send(P.encodeSetHair(Number(presetEl.value) || 0, c, Number(easeEl.value)));
}
[presetEl, curlEl, easeEl].forEach((e) => e.addEventListener('change', sendHair));
treatmentEl.addEventListener('change', () => status.send(P.encodeSetTreatment(Number(treatmentEl.value) || 0)));
curlEl.addEventListener('input', () => { if (view.hair) view.hair.material.uniforms.curliness.value = Number(curlEl.value); });
document.getElementById('reset')!.addEventListener('click', () => {
  status.send(P.encodeEmpty(P.Client.RESET));
  view.hair?.resetGuides();
  plot.peak = 0;
});
document.getElementById('take')!.addEventListener('click', () => status.send(P.encodeEmpty(P.Client.TAKE_CONTROL)));
document.getElementById('save')!.addEventListener('click', () => {
  status.send(P.encodeSave(Number((document.getElementById('save-format') as HTMLSelectElement).value)));
});
document.getElementById('load')!.addEventListener('change', async (ev) => {
  const file = (ev.target as HTMLInputElement).files?.[0];
  if (!file) return;
  const ext = file.name.split('.').pop()?.toLowerCase() ?? '';
  const format = P.FORMATS.indexOf(ext);
  if (format < 0) { statusEl.textContent = `unknown hair file type .${ext} (use .hair, .data, .tfx or .usda)`; return; }
  const sel = (id: string): number => Number((document.getElementById(id) as HTMLSelectElement).value);
  const opts: P.FitOptions = {
    up: sel('fit-up'), front: sel('fit-front'), metersPerUnit: sel('fit-units'),
    noFit: (document.getElementById('fit-none') as HTMLInputElement).checked,
  };
  const follow = (document.getElementById('fit-follow') as HTMLInputElement).value.trim();
  if (follow !== '') opts.followStrands = Math.max(0, Math.round(Number(follow)));
  status.send(P.encodeLoad(format, await file.arrayBuffer(), opts));
  (ev.target as HTMLInputElement).value = '';
});

// The mouse drives the device.
canvas.addEventListener('contextmenu', (e) => e.preventDefault());
// Each pointer event sends the pose at once (besides every drawn frame): the device's target must not wait
// for a slow frame (software rendering draws a frame every second or two), or a stroke reaches the server as
// a few large jumps.
// Head mode (key H, the paper's Spaceball): a left drag turns (sideways) and nods (up and down) the head.
let headDrag: { x: number; y: number; yaw: number; pitch: number } | null = null;
let headYaw = 0, headPitch = 0;
const headEl = document.getElementById('headmode');
window.addEventListener('keydown', (e) => {
  if (e.key !== 'h' && e.key !== 'H') return;
  status.headMode = !status.headMode;
  if (headEl) headEl.textContent = status.headMode ? 'head mode (H): drag to turn and nod the head' : '';
});
let toolDriven = false;
canvas.addEventListener('pointerenter', () => { toolDriven = true; });
canvas.addEventListener('pointerdown', (e) => {
  toolDriven = true;
  if (e.button !== 0) return;
  canvas.setPointerCapture(e.pointerId);
  if (status.headMode) { headDrag = { x: e.clientX, y: e.clientY, yaw: headYaw, pitch: headPitch }; return; }
  device.down(e); sendPose();
});
canvas.addEventListener('pointerup', (e) => { if (e.button !== 0) return; if (headDrag) { headDrag = null; return; } device.up(e); sendPose(); });
canvas.addEventListener('pointermove', (e) => {
  if (headDrag) {
    headYaw = Math.max(-1.2, Math.min(1.2, headDrag.yaw + 0.005 * (e.clientX - headDrag.x)));
    headPitch = Math.max(-0.5, Math.min(0.5, headDrag.pitch + 0.005 * (e.clientY - headDrag.y)));
    if (status.youControl) status.setHead(headYaw, headPitch);
    return;
  }
  toolDriven = true;
  device.move(e); sendPose();
});

function sendPose(): void {
  if (!status.youControl || ws.readyState !== WebSocket.OPEN) return;
  const q = toolQuaternion(view.camera);
  status.send(P.encodePose(device.target, q, device.pressed ? 1 : 0));
}

const perfEl = document.getElementById('perf') as HTMLSpanElement;
/** While true the frame loop sends the pose but draws nothing (`coiffureDebug.holdFrames`: a test's stroke at a
 * hand's pace in software rendering, whose frames stall the page for up to seconds). */
let framesHeld = false;
let last = performance.now();
function frame(now: number): void {
  status.frameTimes.push(now - last);
  status.gpuFrameMs = view.gpuTimer.lastMs;
  if (status.framesRendered % 15 === 0) {
    perfEl.textContent = `frame ${(now - last).toFixed(1)} ms · GPU ${status.gpuFrameMs === null ? 'n/a' : `${status.gpuFrameMs.toFixed(2)} ms`}`;
  }
  if (status.frameTimes.length > 600) status.frameTimes.shift();
  last = now;
  sendPose();
  if (!framesHeld) {
    view.render();
    plot.draw();
  }
  if (status.sceneLoaded) status.framesRendered++;
  requestAnimationFrame(frame);
}
requestAnimationFrame(frame);
console.log(`coiffure viewer: tools ${TOOL_NAMES.join(', ')}`);

// Hooks for the end-to-end tests: project a world point to client pixels, pixel statistics of the frame.
(window as unknown as { coiffureDebug: unknown }).coiffureDebug = {
  /** Stops (true) or resumes (false) drawing; the session, the pointer and the messages go on. */
  holdFrames(on: boolean): void { framesHeld = on; },
  /** Lets the tool's button go where the tool is (the mouse's release would lift it to the lifted plane): a
   * nozzle stops blowing and stays there. */
  releaseButton(): void { device.pressed = false; sendPose(); },
  /** The carried hair of the last frame (carriedHair.ts, read back from the GPU) checked against its law:
   * the largest distance of a root from its rest root moved rigidly with the head (m), the largest relative
   * change of a segment's length from its rest length, and the largest distance of any vertex from its rest
   * position moved rigidly with the head (m: how far the lattice carried it). With `sample` > 0 the carried hair
   * is computed again now, dry (no wet clumping: a display effect the engine's law leaves out), and the state it
   * was computed on is returned with `sample` strands' vertices (the strands the lattice moves most, then
   * strands spread over the hairstyle), for a point-by-point check against the engine (`POST /debug/carried`):
   * the lattice nodes (world, m, xyz per node), the head rotation (row-major) and translation, the vertices and
   * their carried positions (xyz each). */
  carriedHair(sample = 0): { vertices: number; rootError: number; lengthError: number; largestMove: number; state?: { nodes: number[]; headRotation: number[]; headTranslation: number[]; vertices: number[]; positions: number[] } } {
    const hair = view.hair!;
    const rt = hair.carried.positions;
    const u = hair.material.uniforms;
    if (sample > 0) {
      const wet = u.wetnessOverride.value;
      u.wetnessOverride.value = 0;
      hair.carried.update(view.renderer);
      u.wetnessOverride.value = wet;
    }
    const out = new Float32Array(4 * rt.width * rt.height);
    view.renderer.readRenderTargetPixels(rt, 0, 0, rt.width, rt.height, out);
    const rest = hair.restTexture.image.data as Float32Array;
    const nv = view.verticesPerStrand, n = hair.material.uniforms.vertexCount.value as number;
    const q = new THREE.Quaternion(...status.headQuaternion), t = new THREE.Vector3(...status.headPosition);
    const r = new THREE.Vector3();
    let rootError = 0, lengthError = 0, largestMove = 0;
    for (let v = 0; v < n; v++) {
      r.set(rest[4 * v], rest[4 * v + 1], rest[4 * v + 2]).applyQuaternion(q).add(t);
      const d = Math.hypot(out[4 * v] - r.x, out[4 * v + 1] - r.y, out[4 * v + 2] - r.z);
      largestMove = Math.max(largestMove, d);
      if (v % nv === 0) { rootError = Math.max(rootError, d); continue; }
      const l0 = rest[4 * v + 3] - rest[4 * v - 1];
      const l = Math.hypot(out[4 * v] - out[4 * v - 4], out[4 * v + 1] - out[4 * v - 3], out[4 * v + 2] - out[4 * v - 2]);
      if (l0 > 1e-6) lengthError = Math.max(lengthError, Math.abs(l - l0) / l0);
    }
    if (!(sample > 0)) return { vertices: n, rootError, lengthError, largestMove };
    // The state the texture was computed on (no message was handled since: this runs in one task).
    const strands = n / nv;
    const tipMove = (s: number): number => {
      const v = s * nv + nv - 1;
      r.set(rest[4 * v], rest[4 * v + 1], rest[4 * v + 2]).applyQuaternion(q).add(t);
      return Math.hypot(out[4 * v] - r.x, out[4 * v + 1] - r.y, out[4 * v + 2] - r.z);
    };
    const order = Array.from({ length: strands }, (_, s) => s).sort((a, b) => tipMove(b) - tipMove(a));
    const chosen = new Set(order.slice(0, Math.ceil(sample / 4)));
    for (let s = 0; chosen.size < Math.min(sample, strands); s = (s + Math.max(1, Math.floor(strands / sample))) % strands) chosen.add(s);
    const vertices: number[] = [], positions: number[] = [];
    for (const s of [...chosen].sort((a, b) => a - b)) {
      for (let i = 0; i < nv; i++) {
        const v = s * nv + i;
        vertices.push(v);
        positions.push(out[4 * v], out[4 * v + 1], out[4 * v + 2]);
      }
    }
    const lattice = hair.latticeTexture.image.data as Float32Array;
    const nodes: number[] = [];
    for (let k = 0; k < lattice.length / 4; k++) nodes.push(lattice[4 * k], lattice[4 * k + 1], lattice[4 * k + 2]);
    const m = (u.headRotation.value as THREE.Matrix3).elements; // column-major
    const headRotation = [m[0], m[3], m[6], m[1], m[4], m[7], m[2], m[5], m[8]];
    const headTranslation = (u.headTranslation.value as THREE.Vector3).toArray();
    return { vertices: n, rootError, lengthError, largestMove, state: { nodes, headRotation, headTranslation, vertices, positions } };
  },
  project(x: number, y: number, z: number): [number, number] {
    const v = new THREE.Vector3(x, y, z).project(view.camera);
    const r = canvas.getBoundingClientRect();
    return [r.left + (v.x + 1) / 2 * r.width, r.top + (1 - v.y) / 2 * r.height];
  },
  /** Renders once with and once without the hair; returns the fraction of pixels the hair changes and the
   * fraction of pixels that are not background. */
  hairPixelStats(): { hairFraction: number; nonBackground: number; pixels: number } {
    const read = (): Uint8ClampedArray => {
      view.render();
      const c = document.createElement('canvas');
      c.width = canvas.width; c.height = canvas.height;
      const ctx = c.getContext('2d')!;
      ctx.drawImage(canvas, 0, 0);
      return ctx.getImageData(0, 0, c.width, c.height).data;
    };
    const hairObj = view.hairMesh;
    const withHair = read();
    if (hairObj) hairObj.visible = false;
    const without = read();
    if (hairObj) hairObj.visible = true;
    let changed = 0, nonBg = 0;
    const n = withHair.length / 4;
    for (let i = 0; i < n; i++) {
      const d = Math.abs(withHair[4 * i] - without[4 * i]) + Math.abs(withHair[4 * i + 1] - without[4 * i + 1]) + Math.abs(withHair[4 * i + 2] - without[4 * i + 2]);
      if (d > 24) changed++;
      const b = Math.abs(withHair[4 * i] - 0x1d) + Math.abs(withHair[4 * i + 1] - 0x1f) + Math.abs(withHair[4 * i + 2] - 0x24);
      if (b > 24) nonBg++;
    }
    return { hairFraction: changed / n, nonBackground: nonBg / n, pixels: n };
  },
  /** Renders the scene without the tool with a colour preset, every strand at `wetness`, the key light towards `light` and the
   * debug view (0 shaded, 1 deep-opacity transmittance, 2 highlight only), `clumpStrength` overriding the wet
   * clumping's (HairLookParams); returns the RGBA pixels (base64)
   * and a PNG data URL. Restores the live state afterwards (no server message is handled in between). */
  look(o: { colour?: string; wetness?: number; light?: [number, number, number]; view?: number; camera?: [number, number, number]; target?: [number, number, number]; hideHair?: boolean; lines?: number; clumpStrength?: number }) {
    const hair = view.hair!;
    const u = hair.material.uniforms;
    const oldColour = status.hairColour;
    const oldLight = view.lighting.lightDirection.value.clone();
    const oldCam = view.camera.position.clone(), oldTarget = view.controls.target.clone();
    if (o.colour) setColour(o.colour);
    u.wetnessOverride.value = o.wetness ?? -1;
    const oldClump = u.clumpStrength.value;
    if (o.clumpStrength !== undefined) u.clumpStrength.value = o.clumpStrength;
    if (o.light) view.setLight(new THREE.Vector3(...o.light));
    u.debugView.value = o.view ?? 0;
    if (o.camera) view.camera.position.set(...o.camera);
    if (o.target) view.controls.target.set(...o.target);
    if (o.hideHair && view.hairMesh) view.hairMesh.visible = false;
    const toolsShown = [toolGroup.visible, arrow.visible, ghost.visible];
    toolGroup.visible = arrow.visible = ghost.visible = false;
    view.forceLines = o.lines ?? null;
    const t0 = performance.now();
    view.render();
    const lines = view.lineCount;
    view.forceLines = null;
    const gl = view.renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const px = new Uint8Array(4 * w * h);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const ms = performance.now() - t0;
    const png = canvas.toDataURL('image/png');
    if (view.hairMesh) view.hairMesh.visible = true;
    [toolGroup.visible, arrow.visible, ghost.visible] = toolsShown;
    u.wetnessOverride.value = -1;
    u.clumpStrength.value = oldClump;
    u.debugView.value = 0;
    view.setLight(oldLight);
    setColour(oldColour);
    view.camera.position.copy(oldCam);
    view.controls.target.copy(oldTarget);
    let bin = '';
    for (let i = 0; i < px.length; i += 8192) bin += String.fromCharCode(...px.subarray(i, i + 8192));
    return { width: w, height: h, pixels: btoa(bin), png, ms, lines };
  },
  /** The hair's ink (sum over pixels of every strand fragment's coverage, in pixels; hairCompositor.ink) for
   * each of `views` (camera and target in world m, `hairType`: the strands' width from that SCENE hair type),
   * `fov` the vertical field of view, deg, `lines` forces the parallel lines per strand, `size` a square drawing buffer of that many pixels), all rendered from the
   * same hair state, the person and the tools hidden (so no strand is behind the body).
   * The depth weight is set to 1 and everything is restored afterwards. */
  hairInk(views: { camera: [number, number, number]; target: [number, number, number]; hairType?: number; fov?: number; lines?: number; size?: number }[]) {
    const hair = view.hair!;
    const u = hair.material.uniforms;
    const falloff = u.oitDepthFalloff.value;
    const oldCam = view.camera.position.clone(), oldTarget = view.controls.target.clone();
    const oldType = Number(presetEl.value) || 0;
    const hidden = [view.person?.group, toolGroup, arrow, ghost, view.chains].filter((o) => o) as THREE.Object3D[];
    const shown = hidden.map((o) => o.visible);
    hidden.forEach((o) => { o.visible = false; });
    u.oitDepthFalloff.value = 1e9;
    const fov = view.camera.fov;
    const ink = views.map((v) => {
      view.camera.position.set(...v.camera);
      view.controls.target.set(...v.target);
      view.camera.fov = v.fov ?? fov;
      view.camera.updateProjectionMatrix();
      view.setHairType(v.hairType ?? oldType);
      view.forceLines = v.lines ?? null;
      if (v.size) { view.renderer.setSize(v.size, v.size, false); view.camera.aspect = 1; }
      view.camera.updateProjectionMatrix();
      view.render();
      return { ink: view.compositor.ink(view.renderer), strandWidth: u.strandWidth.value as number, lines: view.lineCount };
    });
    view.forceLines = null;
    view.camera.fov = fov;
    view.resize();
    u.oitDepthFalloff.value = falloff;
    hidden.forEach((o, i) => { o.visible = shown[i]; });
    view.setHairType(oldType);
    view.camera.position.copy(oldCam);
    view.controls.target.copy(oldTarget);
    return ink;
  },
  /** The strands' rest positions (head frame, m; base64 of a Float32Array), counts, the drawing buffer size
   * (px) and the camera's vertical field of view (deg), for computing the expected ink independently. */
  hairRest() {
    const g = view.hairMesh!.geometry;
    const rest = g.getAttribute('rest').array as Float32Array;
    const b = new Uint8Array(rest.buffer, rest.byteOffset, rest.byteLength);
    let bin = '';
    for (let i = 0; i < b.length; i += 8192) bin += String.fromCharCode(...b.subarray(i, i + 8192));
    const size = view.renderer.getDrawingBufferSize(new THREE.Vector2());
    return { rest: btoa(bin), strands: status.strands, verticesPerStrand: nv, width: size.x, height: size.y, fov: view.camera.fov,
      minCoverage: view.hair!.params.minCoverage };
  },
  view,
  personInfo: () => view.person && { maxOutset: view.person.info.maxOutset, maxProjectionError: view.person.info.maxProjectionError },
  /** The displayed skin under the hair: for the strands' rest vertices within `within` (m) of the collision
   * surface, the sculpt's largest outset and inset there (person.ts `skinUnderHair`). */
  skinUnderHair(within: number) {
    const p = view.person, g = view.hairMesh?.geometry;
    if (!p || !g) return null;
    return skinUnderHair(p.metaballs, p.metaballThreshold, g.getAttribute('rest').array as Float32Array, within);
  },
};
