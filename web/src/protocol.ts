// The WebSocket protocol (docs/protocol.md): binary, little-endian, [type u8][version u8] then the payload.

export const VERSION = 1;

export const Client = {
  POSE: 0x01,
  TAKE_CONTROL: 0x02,
  SELECT_TOOL: 0x03,
  SET_HAIR: 0x04,
  RESET: 0x05,
  LOAD: 0x06,
  SAVE: 0x07,
  PING: 0x08,
  HEAD: 0x09,
  SET_TREATMENT: 0x0A,
  FRAME_ACK: 0x0B,
} as const;

/** The hair's surface treatments by wire id (SET_TREATMENT, FRAME; `tools::treatment::Treatment::ALL`). */
export const TREATMENTS = ['virgin', 'conditioned', 'bleached', 'bleached-twice'] as const;

export const Server = {
  SCENE: 0x81,
  FRAME: 0x82,
  ERROR: 0x83,
  CONTROL: 0x84,
  FILE: 0x85,
  PONG: 0x86,
  // --- STRANDS (issue 5: scissors) ---
  STRANDS: 0x87,
  FIT: 0x88,
  DEVICE: 0x89,
} as const;

/** DEVICE (`coiffure serve --device`): the haptic device's stream (docs/protocol.md). */
export interface DeviceMsg {
  state: 'waiting' | 'connected' | 'lost';
  accepted: number; // poses accepted
  rejected: number; // poses rejected (non-finite or out of range, teleport, out of order, duplicate)
  malformed: number; // datagrams of the wrong size or magic
  foreign: number; // poses from another sender, dropped
  lost: number; // times the stream was lost (no pose for 50 ms)
  answered: number; // force packets sent
}

export function decodeDevice(buf: ArrayBuffer): DeviceMsg {
  const v = new DataView(buf);
  const u = (i: number): number => v.getUint32(3 + 4 * i, true);
  const states = ['waiting', 'connected', 'lost'] as const;
  return { state: states[v.getUint8(2)] ?? 'lost', accepted: u(0), rejected: u(1), malformed: u(2), foreign: u(3), lost: u(4), answered: u(5) };
}

/** Axis names of LOAD's options and FIT (index 1-6; 0 = detect). */
export const AXES = ['detect', '+x', '-x', '+y', '-y', '+z', '-z'];
/** Where a fit choice came from (FIT). */
export const FIT_SOURCES = ['option', 'metadata', 'detected', 'assumed'];

/** FIT: how a loaded hairstyle was placed on the head (docs/protocol.md). */
export interface FitMsg {
  scale: number; // m per file unit
  rotation: number[]; // 3x3 row-major, file to head frame
  translation: [number, number, number]; // m
  metersPerUnit: number;
  up: string;
  front: string;
  unitsSource: string;
  axesSource: string;
  rooted: number; // fraction of strands rooted on the scalp
  rootMedian: number; // m, all roots to the scalp
  rootP95: number; // m
  rootMax: number; // m
  pushedOut: number;
  rootedMedian: number; // m, the rooted strands' roots to the scalp
  rootedP95: number; // m
  rootedMax: number; // m
}

export function decodeFit(buf: ArrayBuffer): FitMsg {
  const v = new DataView(buf);
  const f = (i: number): number => v.getFloat32(2 + 4 * i, true);
  return {
    scale: f(0),
    rotation: [1, 2, 3, 4, 5, 6, 7, 8, 9].map(f),
    translation: [f(10), f(11), f(12)],
    metersPerUnit: f(13),
    up: AXES[v.getUint8(58)] ?? '?',
    front: AXES[v.getUint8(59)] ?? '?',
    unitsSource: FIT_SOURCES[v.getUint8(60)] ?? '?',
    axesSource: FIT_SOURCES[v.getUint8(61)] ?? '?',
    rooted: v.getFloat32(62, true),
    rootMedian: v.getFloat32(66, true),
    rootP95: v.getFloat32(70, true),
    rootMax: v.getFloat32(74, true),
    pushedOut: v.getUint32(78, true),
    rootedMedian: v.getFloat32(82, true),
    rootedP95: v.getFloat32(86, true),
    rootedMax: v.getFloat32(90, true),
  };
}

/** Overrides of the fit sent with LOAD. */
export interface FitOptions {
  up: number; // 0 detect, 1-6 +x -x +y -y +z -z
  front: number; // same
  noFit: boolean;
  metersPerUnit: number; // 0 detect
  followStrands?: number; // follow strands per strand of the file; undefined: the server's default
}

/** Metres per file unit for people (the rule of `hairstyle::fit::units_name`): a named unit when within 1e-6 of it
 * ("cm (0.01 m)"; a file's f32 holds 0.009999999776 for 0.01), else 4 significant digits. */
export function unitsName(m: number): string {
  const named: [string, number][] = [['m', 1], ['dm', 0.1], ['cm', 0.01], ['mm', 0.001], ['in', 0.0254], ['ft', 0.3048]];
  for (const [name, v] of named) {
    if (Math.abs(m / v - 1) < 1e-6) return name === 'm' ? 'm' : `${name} (${v} m)`;
  }
  return `${Number(m.toPrecision(4))} m`;
}

export const FORMATS = ['hair', 'data', 'tfx', 'usda'];

export interface SceneMsg {
  verticesPerStrand: number;
  strands: number;
  guidesPerStrand: number;
  guides: number;
  samples: number;
  latticeDims: [number, number, number];
  latticeOrigin: [number, number, number];
  latticeH: number;
  hairTypes: string[];
  hairType: number;
  headPositions: Float32Array;
  headIndices: Uint32Array;
  renderPositions: Float32Array;
  /** Appended to SCENE: the head's metaballs (head frame) for the shader's push-out; empty if absent. */
  metaballs: Float32Array; // M x (cx, cy, cz, R), m
  metaballThreshold: number;
  pushOutSkin: number; // m
  rootHold: number; // m: length of hair from the root the head holds (engine::scene::carried); 0 from older servers
  nozzleStandoff: number; // m: the nozzle of the dryer and the sprayer, behind the tool point along the tool's +z
  renderGuide: Uint32Array; // guidesPerStrand per strand, nearest first
  renderWeight: Float32Array; // guidesPerStrand per strand, summing to 1
  renderSpan: Float32Array; // per strand: fraction of the guides' length it spans
  /** Appended to SCENE after the metaballs: each hair type's fibre section (same order as hairTypes). */
  hairTypeDiameter: Float32Array; // major-axis diameter, m
  hairTypeEllipticity: Float32Array; // major / minor axis, >= 1
}

export interface FrameMsg {
  seq: number;
  time: number;
  tool: number;
  youControl: boolean;
  contacts: number;
  toolPosition: [number, number, number];
  toolQuaternion: [number, number, number, number];
  devicePosition: [number, number, number];
  force: [number, number, number];
  latticeVersion: number;
  nodes: Float32Array; // 3 per node
  active: Uint32Array;
  samples: number;
  displacement: Float32Array; // 3 per sample, active.length * samples samples
  wetness: Float32Array;
  // --- falling cut clusters (issue 5: scissors) ---
  keptVersion: number; // changes of the strands' kept points (cuts, resets); STRANDS follows each
  chainCounts: Uint32Array; // points of each falling chain
  chainPoints: Float32Array; // 3 per point, chain after chain (world, m)
  // --- the head pose (issue 14): head frame to world ---
  headPosition: [number, number, number]; // m
  headQuaternion: [number, number, number, number]; // x, y, z, w
  // --- proxy health (issue 16) ---
  runaways: number; // steps in which the runaway guard put the tool proxy back on the device (0 from older servers)
  // --- the hair's surface (issue 29) ---
  treatment: number; // the session's surface treatment (index into TREATMENTS; -1 from older servers)
  toolFriction: number; // the tool-hair friction coefficient in use (NaN from older servers)
}

export interface ErrorMsg { code: number; message: string }

/** Copies `n` little-endian f32 starting at byte `at` (handles unaligned offsets). */
function f32s(buf: ArrayBuffer, at: number, n: number): Float32Array {
  return new Float32Array(buf.slice(at, at + 4 * n));
}
function u32s(buf: ArrayBuffer, at: number, n: number): Uint32Array {
  return new Uint32Array(buf.slice(at, at + 4 * n));
}

export function decodeScene(buf: ArrayBuffer): SceneMsg {
  const v = new DataView(buf);
  let o = 2;
  const u32 = () => { const x = v.getUint32(o, true); o += 4; return x; };
  const f32 = () => { const x = v.getFloat32(o, true); o += 4; return x; };
  const verticesPerStrand = u32(), strands = u32(), guidesPerStrand = u32(), guides = u32(), samples = u32();
  const latticeDims: [number, number, number] = [u32(), u32(), u32()];
  const latticeOrigin: [number, number, number] = [f32(), f32(), f32()];
  const latticeH = f32();
  const nTypes = v.getUint8(o++);
  const hairTypes: string[] = [];
  for (let i = 0; i < nTypes; i++) {
    const len = v.getUint8(o++);
    hairTypes.push(new TextDecoder().decode(new Uint8Array(buf, o, len)));
    o += len;
  }
  const hairType = v.getUint8(o++);
  while (o % 4 !== 0) o++;
  const nHead = u32(), nIdx = u32();
  const headPositions = f32s(buf, o, 3 * nHead); o += 12 * nHead;
  const headIndices = u32s(buf, o, nIdx); o += 4 * nIdx;
  const nv = strands * verticesPerStrand;
  const renderPositions = f32s(buf, o, 3 * nv); o += 12 * nv;
  const nb = strands * guidesPerStrand;
  const renderGuide = u32s(buf, o, nb); o += 4 * nb;
  const renderWeight = f32s(buf, o, nb); o += 4 * nb;
  const renderSpan = f32s(buf, o, strands); o += 4 * strands;
  // Appended block (older servers end here): metaballs of the head for the push-out.
  let metaballs: Float32Array = new Float32Array(0), metaballThreshold = 0.25, pushOutSkin = 0;
  if (o + 12 <= buf.byteLength) {
    const m = u32();
    metaballThreshold = f32();
    pushOutSkin = f32();
    metaballs = f32s(buf, o, 4 * m); o += 16 * m;
  }
  // Appended block: the hair types' fibre sections (the server's presets; the viewer keeps no copy).
  if (o + 4 + 8 * nTypes > buf.byteLength || v.getUint32(o, true) !== nTypes) {
    throw new Error(`SCENE without the fibre sections of its ${nTypes} hair types (a server older than this viewer?)`);
  }
  o += 4;
  const sections = f32s(buf, o, 2 * nTypes); o += 8 * nTypes;
  const hairTypeDiameter = new Float32Array(nTypes), hairTypeEllipticity = new Float32Array(nTypes);
  for (let i = 0; i < nTypes; i++) { hairTypeDiameter[i] = sections[2 * i]; hairTypeEllipticity[i] = sections[2 * i + 1]; }
  // Appended block (older servers end here): the root hold and the nozzle standoff.
  let rootHold = 0, nozzleStandoff = 0.15;
  if (o + 8 <= buf.byteLength) { rootHold = f32(); nozzleStandoff = f32(); }
  return { verticesPerStrand, strands, guidesPerStrand, guides, samples, latticeDims, latticeOrigin, latticeH, hairTypes, hairType, headPositions, headIndices, renderPositions, renderGuide, renderWeight, renderSpan, metaballs, metaballThreshold, pushOutSkin, hairTypeDiameter, hairTypeEllipticity, rootHold, nozzleStandoff };
}

export function decodeFrame(buf: ArrayBuffer): FrameMsg {
  const v = new DataView(buf);
  let o = 2;
  const u32 = () => { const x = v.getUint32(o, true); o += 4; return x; };
  const f32 = () => { const x = v.getFloat32(o, true); o += 4; return x; };
  const seq = u32();
  const time = f32();
  const tool = v.getUint8(o++);
  const youControl = (v.getUint8(o++) & 1) === 1;
  const contacts = v.getUint16(o, true); o += 2;
  const toolPosition: [number, number, number] = [f32(), f32(), f32()];
  const toolQuaternion: [number, number, number, number] = [f32(), f32(), f32(), f32()];
  const devicePosition: [number, number, number] = [f32(), f32(), f32()];
  const force: [number, number, number] = [f32(), f32(), f32()];
  const latticeVersion = u32();
  const nNodes = u32();
  const nodes = f32s(buf, o, 3 * nNodes); o += 12 * nNodes;
  const nActive = u32();
  const samples = u32();
  const active = u32s(buf, o, nActive); o += 4 * nActive;
  const displacement = f32s(buf, o, 3 * nActive * samples); o += 12 * nActive * samples;
  const nGuides = u32();
  const wetness = f32s(buf, o, nGuides); o += 4 * nGuides;
  // --- falling cut clusters (issue 5: scissors) ---
  const keptVersion = u32();
  const nChains = u32();
  const chainCounts = u32s(buf, o, nChains); o += 4 * nChains;
  const nPoints = chainCounts.reduce((a, b) => a + b, 0);
  const chainPoints = f32s(buf, o, 3 * nPoints); o += 12 * nPoints;
  // --- the head pose (issue 14) ---
  const headPosition: [number, number, number] = [f32(), f32(), f32()];
  const headQuaternion: [number, number, number, number] = [f32(), f32(), f32(), f32()];
  // --- proxy health (issue 16): older servers end at the head pose ---
  const runaways = o + 4 <= buf.byteLength ? u32() : 0;
  // --- the hair's surface (issue 29): older servers end at the runaways ---
  const surface = o + 5 <= buf.byteLength;
  const treatment = surface ? new DataView(buf).getUint8(o++) : -1;
  const toolFriction = surface ? f32() : NaN;
  return { seq, time, tool, youControl, contacts, toolPosition, toolQuaternion, devicePosition, force, latticeVersion, nodes, active, samples, displacement, wetness, keptVersion, chainCounts, chainPoints, headPosition, headQuaternion, runaways, treatment, toolFriction };
}

// --- STRANDS (issue 5: scissors) ---
/** STRANDS: the points kept of every render strand (vertices 0..kept-1 of strand i stay on the head). */
export function decodeStrands(buf: ArrayBuffer): Uint16Array {
  const n = new DataView(buf).getUint32(2, true);
  return new Uint16Array(buf.slice(6, 6 + 2 * n));
}

export function decodeError(buf: ArrayBuffer): ErrorMsg {
  const v = new DataView(buf);
  const code = v.getUint16(2, true);
  const len = v.getUint16(4, true);
  return { code, message: new TextDecoder().decode(new Uint8Array(buf, 6, len)) };
}

/** The type byte of a server message (`Server`), after checking its header: at least [type][version], and this
 *  protocol's version. Throws naming what is wrong. */
export function messageType(buf: ArrayBuffer): number {
  if (buf.byteLength < 2) throw new Error(`a server message of ${buf.byteLength} bytes has no header`);
  const v = new DataView(buf);
  if (v.getUint8(1) !== VERSION) throw new Error(`server message 0x${v.getUint8(0).toString(16)} has protocol version ${v.getUint8(1)}, the viewer speaks ${VERSION}`);
  return v.getUint8(0);
}

/** CONTROL: whether this viewer controls the tool, and how many viewers are connected. */
export interface ControlMsg { youControl: boolean; viewers: number }

export function decodeControl(buf: ArrayBuffer): ControlMsg {
  if (buf.byteLength < 7) throw new Error(`CONTROL of ${buf.byteLength} bytes, expected 7`);
  const v = new DataView(buf);
  return { youControl: v.getUint8(2) === 1, viewers: v.getUint32(3, true) };
}

/** FILE (the answer to SAVE): the hairstyle file's format (index in `FORMATS`, its extension) and bytes. */
export interface FileMsg { format: number; extension: string; bytes: ArrayBuffer }

export function decodeFile(buf: ArrayBuffer): FileMsg {
  if (buf.byteLength < 3) throw new Error(`FILE of ${buf.byteLength} bytes has no format byte`);
  const format = new DataView(buf).getUint8(2);
  const extension = FORMATS[format];
  if (extension === undefined) throw new Error(`FILE in unknown format ${format}`);
  return { format, extension, bytes: buf.slice(3) };
}

function header(type: number, payload: number): [ArrayBuffer, DataView] {
  const b = new ArrayBuffer(2 + payload);
  const v = new DataView(b);
  v.setUint8(0, type);
  v.setUint8(1, VERSION);
  return [b, v];
}

export function encodePose(p: { x: number; y: number; z: number }, q: { x: number; y: number; z: number; w: number }, buttons: number): ArrayBuffer {
  const [b, v] = header(Client.POSE, 32);
  [p.x, p.y, p.z, q.x, q.y, q.z, q.w].forEach((x, i) => v.setFloat32(2 + 4 * i, x, true));
  v.setUint32(30, buttons, true);
  return b;
}

/** HEAD: the head frame's origin (m) and its rotation vector (axis times angle, rad). */
export function encodeHead(p: [number, number, number], rotation: [number, number, number]): ArrayBuffer {
  const [b, v] = header(Client.HEAD, 24);
  [...p, ...rotation].forEach((x, i) => v.setFloat32(2 + 4 * i, x, true));
  return b;
}

export function encodeEmpty(type: number): ArrayBuffer {
  return header(type, 0)[0];
}

export function encodeSelectTool(tool: number): ArrayBuffer {
  const [b, v] = header(Client.SELECT_TOOL, 1);
  v.setUint8(2, tool);
  return b;
}

export function encodeSetHair(type: number, curliness: number, ease: number): ArrayBuffer {
  const [b, v] = header(Client.SET_HAIR, 9);
  v.setUint8(2, type);
  v.setFloat32(3, curliness, true);
  v.setFloat32(7, ease, true);
  return b;
}

/** SET_TREATMENT: the hair's surface treatment (index into TREATMENTS). */
export function encodeSetTreatment(treatment: number): ArrayBuffer {
  const [b, v] = header(Client.SET_TREATMENT, 1);
  v.setUint8(2, treatment);
  return b;
}

/** FRAME_ACK: the viewer has finished with FRAME `seq`; the server then keeps at most two FRAMEs on their way to
 * it, so that a page that falls behind gets the newest frame, not a backlog of stale ones. */
export function encodeFrameAck(seq: number): ArrayBuffer {
  const [b, v] = header(Client.FRAME_ACK, 4);
  v.setUint32(2, seq, true);
  return b;
}

export function encodeSave(format: number): ArrayBuffer {
  const [b, v] = header(Client.SAVE, 1);
  v.setUint8(2, format);
  return b;
}

export function encodeLoad(format: number, file: ArrayBuffer, opts?: FitOptions): ArrayBuffer {
  if (!opts) {
    const [b, v] = header(Client.LOAD, 1 + file.byteLength);
    v.setUint8(2, format);
    new Uint8Array(b, 3).set(new Uint8Array(file));
    return b;
  }
  const follow = opts.followStrands !== undefined;
  const [b, v] = header(Client.LOAD, 9 + (follow ? 4 : 0) + file.byteLength);
  v.setUint8(2, format | 0x80);
  v.setUint8(3, opts.up);
  v.setUint8(4, opts.front);
  v.setUint8(5, (opts.noFit ? 1 : 0) | (follow ? 2 : 0));
  v.setUint8(6, 0);
  v.setFloat32(7, opts.metersPerUnit, true);
  if (follow) v.setUint32(11, opts.followStrands!, true);
  new Uint8Array(b, follow ? 15 : 11).set(new Uint8Array(file));
  return b;
}
