//! The viewer's WebSocket protocol (binary, little-endian; docs/protocol.md is the specification).
//!
//! Every message starts with a type byte and a protocol version byte ([`VERSION`]); f32 on the wire.
//! Client messages are parsed by [`parse_client`], which never panics: a short, long or unknown message is an
//! [`WireError`] that the server answers with an [`encode_error`] message while the connection stays up.

use engine::session::{Command, HapticSnapshot, LatticeSnapshot, Scene, Tool};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Protocol version carried by every message.
pub const VERSION: u8 = 1;

/// Client -> server message types.
pub mod client {
    /// Device pose from the mouse: 3 f32 position (m), 4 f32 quaternion (x, y, z, w), u32 buttons.
    pub const POSE: u8 = 0x01;
    /// Ask to control the tool (no payload).
    pub const TAKE_CONTROL: u8 = 0x02;
    /// u8 tool id.
    pub const SELECT_TOOL: u8 = 0x03;
    /// u8 hair type, f32 curliness, f32 combing ease.
    pub const SET_HAIR: u8 = 0x04;
    /// Reset the scene (no payload).
    pub const RESET: u8 = 0x05;
    /// u8 format (bit 7: an 8-byte fit-options block follows), then the file's bytes.
    pub const LOAD: u8 = 0x06;
    /// u8 format: ask for the current hairstyle as a file.
    pub const SAVE: u8 = 0x07;
    /// u32 token: answered by PONG with the same token.
    pub const PING: u8 = 0x08;
    /// Move the head: 3 f32 position of the head frame's origin (m, at most 1 m from the origin), 3 f32
    /// rotation vector (axis times angle, rad, at most pi).
    pub const HEAD: u8 = 0x09;
    /// u8 surface treatment (`tools::treatment::Treatment::id`: 0 virgin, 1 conditioned, 2 bleached, 3
    /// bleached twice).
    pub const SET_TREATMENT: u8 = 0x0A;
    /// u32 sequence number of the last FRAME the viewer has finished with. From a viewer's first FRAME_ACK on,
    /// the server keeps at most [`crate::outbox::FRAME_WINDOW`] FRAMEs unacknowledged on their way to it: a
    /// viewer that falls behind gets the newest frame when it catches up, not a backlog of stale ones.
    pub const FRAME_ACK: u8 = 0x0B;
}

/// Server -> client message types.
pub mod server {
    /// The scene, once at connect (and again after a load).
    pub const SCENE: u8 = 0x81;
    /// One visual frame.
    pub const FRAME: u8 = 0x82;
    /// An error: u16 code, u16 length, UTF-8 text.
    pub const ERROR: u8 = 0x83;
    /// Control state: u8 you-control, u32 viewers connected.
    pub const CONTROL: u8 = 0x84;
    /// A saved file: u8 format, then the bytes.
    pub const FILE: u8 = 0x85;
    /// u32 token echoed.
    pub const PONG: u8 = 0x86;
    // --- STRANDS (issue 5: scissors) ---
    /// Kept points of every render strand: u32 S, S x u16 (at connect and after each cut).
    pub const STRANDS: u8 = 0x87;
    /// How a loaded hairstyle was placed on the head (after its SCENE): transform and root distances.
    pub const FIT: u8 = 0x88;
    /// Haptic device status (`--device`): u8 state, u32 x 6 counters.
    pub const DEVICE: u8 = 0x89;
}

/// Error codes of ERROR messages.
pub mod code {
    /// Too short, too long or a bad value.
    pub const MALFORMED: u16 = 1;
    /// Unknown message type.
    pub const UNKNOWN_TYPE: u16 = 2;
    /// Version byte not [`super::VERSION`].
    pub const BAD_VERSION: u16 = 3;
    /// Only the controlling viewer may do this.
    pub const NOT_CONTROLLER: u16 = 4;
    /// A hairstyle file could not be read or written.
    pub const FILE: u16 = 5;
    /// A text frame (the protocol is binary).
    pub const TEXT: u16 = 6;
    /// Recording (`serve --record`) stopped before the session ended (disk full, file unwritable, the writer
    /// fell behind); the text says why and up to where the record replays. The session goes on.
    pub const RECORD: u16 = 7;
}

/// File formats by wire id (the server's formats).
/// A POSE farther than this from the head frame's origin is out of range (error 1), m.
pub const MAX_POSE_DISTANCE: f64 = 10.0;

pub const FORMATS: [&str; 4] = ["hair", "data", "tfx", "usda"];

/// A parsed client message.
#[derive(Debug, Clone, PartialEq)]
pub enum ClientMessage {
    /// Device pose.
    Pose {
        /// Position, m.
        position: Vector3<f64>,
        /// Rotation (tool frame to world).
        rotation: Matrix3<f64>,
        /// Button bits.
        buttons: u32,
    },
    /// Take control.
    TakeControl,
    /// A session command.
    Command(Command),
    /// Load a hairstyle: format index into [`FORMATS`], fit options, bytes.
    Load(usize, hairstyle::fit::FitOptions, Option<usize>, Vec<u8>),
    /// Save the hairstyle in a format (index into [`FORMATS`]).
    Save(usize),
    /// Ping.
    Ping(u32),
    /// The viewer has finished with the FRAME of this sequence number.
    FrameAck(u32),
}

/// Why a client message was refused.
#[derive(Debug, Clone, PartialEq)]
pub struct WireError {
    /// Error code ([`code`]).
    pub code: u16,
    /// Human-readable explanation.
    pub message: String,
}

fn err(code: u16, message: String) -> WireError {
    WireError { code, message }
}

fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

/// Parses a client message.
pub fn parse_client(b: &[u8]) -> Result<ClientMessage, WireError> {
    if b.len() < 2 {
        return Err(err(code::MALFORMED, format!("message of {} bytes; every message starts with a type byte and a version byte", b.len())));
    }
    let (kind, version, p) = (b[0], b[1], &b[2..]);
    if version != VERSION {
        return Err(err(code::BAD_VERSION, format!("protocol version {version} not supported (this server speaks {VERSION})")));
    }
    let need = |n: usize, name: &str| -> Result<(), WireError> {
        if p.len() != n {
            Err(err(code::MALFORMED, format!("{name} needs a {n}-byte payload, got {}", p.len())))
        } else {
            Ok(())
        }
    };
    match kind {
        client::POSE => {
            need(32, "POSE")?;
            let v: Vec<f64> = (0..7).map(|k| f32_at(p, 4 * k) as f64).collect();
            if v.iter().any(|x| !x.is_finite()) {
                return Err(err(code::MALFORMED, "POSE holds a non-finite number".into()));
            }
            if Vector3::new(v[0], v[1], v[2]).norm() > MAX_POSE_DISTANCE {
                return Err(err(code::MALFORMED, format!("POSE position {:?} m is farther than {MAX_POSE_DISTANCE} m from the head", &v[..3])));
            }
            let q = Quaternion::new(v[6], v[3], v[4], v[5]);
            if q.norm() < 1e-6 {
                return Err(err(code::MALFORMED, "POSE quaternion has zero length".into()));
            }
            let rotation = UnitQuaternion::from_quaternion(q).to_rotation_matrix().into_inner();
            let buttons = u32::from_le_bytes([p[28], p[29], p[30], p[31]]);
            Ok(ClientMessage::Pose { position: Vector3::new(v[0], v[1], v[2]), rotation, buttons })
        }
        client::TAKE_CONTROL => need(0, "TAKE_CONTROL").map(|_| ClientMessage::TakeControl),
        client::SELECT_TOOL => {
            need(1, "SELECT_TOOL")?;
            let t = Tool::from_id(p[0]).ok_or_else(|| err(code::MALFORMED, format!("SELECT_TOOL tool id {} unknown (0-5)", p[0])))?;
            Ok(ClientMessage::Command(Command::SelectTool(t)))
        }
        client::SET_HAIR => {
            need(9, "SET_HAIR")?;
            if p[0] as usize >= strand::HairType::ALL.len() {
                return Err(err(code::MALFORMED, format!("SET_HAIR hair type {} unknown (0-{})", p[0], strand::HairType::ALL.len() - 1)));
            }
            let (c, e) = (f32_at(p, 1) as f64, f32_at(p, 5) as f64);
            if !(c.is_finite() && e.is_finite()) {
                return Err(err(code::MALFORMED, "SET_HAIR holds a non-finite number".into()));
            }
            Ok(ClientMessage::Command(Command::SetHair { hair_type: p[0], curliness: c.clamp(0.0, 1.0), combing_ease: e.clamp(0.0, 1.0) }))
        }
        client::SET_TREATMENT => {
            need(1, "SET_TREATMENT")?;
            let t = tools::treatment::Treatment::from_id(p[0])
                .ok_or_else(|| err(code::MALFORMED, format!("SET_TREATMENT treatment {} unknown (0-{})", p[0], tools::treatment::Treatment::ALL.len() - 1)))?;
            Ok(ClientMessage::Command(Command::SetTreatment(t)))
        }
        client::RESET => need(0, "RESET").map(|_| ClientMessage::Command(Command::Reset)),
        client::LOAD => {
            let format = p.first().map_or(usize::MAX, |f| (f & 0x7f) as usize);
            if format >= FORMATS.len() {
                return Err(err(code::MALFORMED, "LOAD needs a format byte (0 .hair, 1 .data, 2 .tfx, 3 .usda; bit 7 set when fit options follow) and the file".into()));
            }
            if p[0] & 0x80 == 0 {
                return Ok(ClientMessage::Load(format, hairstyle::fit::FitOptions::default(), None, p[1..].to_vec()));
            }
            if p.len() < 9 {
                return Err(err(code::MALFORMED, format!("LOAD with fit options needs 8 option bytes after the format, got {}", p.len() - 1)));
            }
            let axis = |b: u8, name: &str| -> Result<Option<hairstyle::fit::Axis>, WireError> {
                match b {
                    0 => Ok(None),
                    1..=6 => Ok(Some(hairstyle::fit::Axis::ALL[b as usize - 1])),
                    _ => Err(err(code::MALFORMED, format!("LOAD {name} axis {b} unknown (0 detect, 1-6 +x -x +y -y +z -z)"))),
                }
            };
            let (up, front) = (axis(p[1], "up")?, axis(p[2], "front")?);
            if p[3] > 3 || p[4] != 0 {
                return Err(err(code::MALFORMED, format!("LOAD option flags {} and reserved byte {} (flags: bit 0 no fit, bit 1 follow strands given; reserved 0)", p[3], p[4])));
            }
            let units = f32_at(p, 5) as f64;
            if !(units.is_finite() && units >= 0.0) {
                return Err(err(code::MALFORMED, format!("LOAD units {units}: metres per unit must be positive, or 0 to detect")));
            }
            let opts = hairstyle::fit::FitOptions { units: (units > 0.0).then_some(units), up, front, fit: p[3] & 1 == 0 };
            if p[3] & 2 == 0 {
                return Ok(ClientMessage::Load(format, opts, None, p[9..].to_vec()));
            }
            if p.len() < 13 {
                return Err(err(code::MALFORMED, format!("LOAD with follow strands needs a u32 count after the 8 option bytes, got {} bytes", p.len() - 9)));
            }
            let follow = u32::from_le_bytes([p[9], p[10], p[11], p[12]]) as usize;
            Ok(ClientMessage::Load(format, opts, Some(follow), p[13..].to_vec()))
        }
        client::SAVE => {
            need(1, "SAVE")?;
            if p[0] as usize >= FORMATS.len() {
                return Err(err(code::MALFORMED, format!("SAVE format {} unknown (0-3)", p[0])));
            }
            Ok(ClientMessage::Save(p[0] as usize))
        }
        client::HEAD => {
            need(24, "HEAD")?;
            let v: Vec<f64> = (0..6).map(|k| f32_at(p, 4 * k) as f64).collect();
            let (position, rotation) = (Vector3::new(v[0], v[1], v[2]), Vector3::new(v[3], v[4], v[5]));
            if engine::command::head_pose(&position, &rotation).is_none() {
                return Err(err(code::MALFORMED, format!("HEAD pose out of range (finite, position within 1 m, rotation within pi rad): {v:?}")));
            }
            Ok(ClientMessage::Command(Command::SetHead { position, rotation }))
        }
        client::PING => {
            need(4, "PING")?;
            Ok(ClientMessage::Ping(u32::from_le_bytes([p[0], p[1], p[2], p[3]])))
        }
        client::FRAME_ACK => {
            need(4, "FRAME_ACK")?;
            Ok(ClientMessage::FrameAck(u32::from_le_bytes([p[0], p[1], p[2], p[3]])))
        }
        other => Err(err(code::UNKNOWN_TYPE, format!("unknown message type 0x{other:02x}"))),
    }
}

struct W(Vec<u8>);
impl W {
    fn new(kind: u8, cap: usize) -> Self {
        let mut v = Vec::with_capacity(cap + 2);
        v.push(kind);
        v.push(VERSION);
        W(v)
    }
    fn u8(&mut self, x: u8) {
        self.0.push(x);
    }
    fn u16(&mut self, x: u16) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u32(&mut self, x: u32) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn f32(&mut self, x: f64) {
        self.0.extend_from_slice(&(x as f32).to_le_bytes());
    }
    fn v3(&mut self, v: &Vector3<f64>) {
        v.iter().for_each(|&x| self.f32(x));
    }
}

/// ERROR message.
pub fn encode_error(e: &WireError) -> Vec<u8> {
    let text = e.message.as_bytes();
    let n = text.len().min(u16::MAX as usize);
    let mut w = W::new(server::ERROR, 4 + n);
    w.u16(e.code);
    w.u16(n as u16);
    w.0.extend_from_slice(&text[..n]);
    w.0
}

/// CONTROL message.
pub fn encode_control(you: bool, viewers: u32) -> Vec<u8> {
    let mut w = W::new(server::CONTROL, 5);
    w.u8(you as u8);
    w.u32(viewers);
    w.0
}

/// Device states of the DEVICE message.
pub mod device_state {
    /// No pose received yet.
    pub const WAITING: u8 = 0;
    /// Poses arriving (one accepted within the last 50 ms).
    pub const CONNECTED: u8 = 1;
    /// The stream was lost (no accepted pose for 50 ms); zero force until it resumes.
    pub const LOST: u8 = 2;
}

/// DEVICE message (`coiffure serve --device`, about 10 Hz): u8 state ([`device_state`]), then u32 poses
/// accepted, u32 poses rejected (non-finite or out of range, teleport, out of order, duplicate), u32
/// packets dropped as malformed, u32 poses dropped from another sender, u32 times the stream was lost,
/// u32 force packets sent.
pub fn encode_device(c: &haptics::udp::UdpCounts) -> Vec<u8> {
    let mut w = W::new(server::DEVICE, 25);
    w.u8(if c.connected { device_state::CONNECTED } else if c.accepted == 0 { device_state::WAITING } else { device_state::LOST });
    for v in [c.accepted, c.rejected_total(), c.malformed, c.foreign, c.lost, c.answered] {
        w.u32(v.min(u32::MAX as u64) as u32);
    }
    w.0
}

/// PONG message.
pub fn encode_pong(token: u32) -> Vec<u8> {
    let mut w = W::new(server::PONG, 4);
    w.u32(token);
    w.0
}

/// FIT message: how a loaded hairstyle was placed (docs/protocol.md).
pub fn encode_fit(r: &hairstyle::fit::FitReport) -> Vec<u8> {
    let mut w = W::new(server::FIT, 96);
    let t = &r.transform;
    w.f32(t.scale);
    for i in 0..3 {
        for j in 0..3 {
            w.f32(t.rotation[(i, j)]);
        }
    }
    w.v3(&t.translation);
    w.f32(r.meters_per_unit);
    let source = |s: hairstyle::fit::Source| s as u8;
    w.u8(r.up as u8 + 1);
    w.u8(r.front as u8 + 1);
    w.u8(source(r.units_source));
    w.u8(source(r.orientation_source));
    w.f32(r.rooted);
    w.f32(r.root_distance.median);
    w.f32(r.root_distance.p95);
    w.f32(r.root_distance.max);
    w.u32(r.pushed_out as u32);
    w.f32(r.rooted_distance.median);
    w.f32(r.rooted_distance.p95);
    w.f32(r.rooted_distance.max);
    w.0
}

/// FILE message.
pub fn encode_file(format: usize, bytes: &[u8]) -> Vec<u8> {
    let mut w = W::new(server::FILE, 1 + bytes.len());
    w.u8(format as u8);
    w.0.extend_from_slice(bytes);
    w.0
}

/// SCENE message: counts, lattice geometry, hair-type names, head mesh, render strands and their guide
/// binding, the head's metaballs, the hair types' sections, the root hold and the nozzles' standoff
/// `nozzle_standoff` (m, `GlobalParams::nozzle_standoff`) (layout in docs/protocol.md).
pub fn encode_scene(s: &Scene, nozzle_standoff: f64) -> Vec<u8> {
    let r = &s.render;
    let strands = r.strands();
    let f = &s.lattice.ffd;
    let mut w = W::new(server::SCENE, 64 + 12 * (s.head_mesh.positions.len() + r.positions.len()) + 4 * s.head_mesh.indices.len() + 8 * r.guide.len() + 4 * strands);
    w.u32(r.vertices_per_strand as u32);
    w.u32(strands as u32);
    w.u32(r.guides_per_strand as u32);
    w.u32(s.guides.len() as u32);
    w.u32(s.samples() as u32);
    w.u32(f.nx as u32);
    w.u32(f.ny as u32);
    w.u32(f.nz as u32);
    w.v3(&f.origin.coords);
    w.f32(f.h);
    let names = strand::HairType::ALL;
    w.u8(names.len() as u8);
    for h in names {
        w.u8(h.name.len() as u8);
        w.0.extend_from_slice(h.name.as_bytes());
    }
    let current = names.iter().position(|h| h.name == s.hair_type.name).unwrap_or(0);
    w.u8(current as u8);
    while w.0.len() % 4 != 0 {
        w.u8(0);
    }
    w.u32(s.head_mesh.positions.len() as u32);
    w.u32(s.head_mesh.indices.len() as u32);
    for p in &s.head_mesh.positions {
        p.iter().for_each(|&x| w.0.extend_from_slice(&x.to_le_bytes()));
    }
    for i in &s.head_mesh.indices {
        w.u32(*i);
    }
    for p in &r.positions {
        p.iter().for_each(|&x| w.0.extend_from_slice(&x.to_le_bytes()));
    }
    for g in &r.guide {
        w.u32(*g);
    }
    for x in r.weight.iter().chain(r.span.iter()) {
        w.0.extend_from_slice(&x.to_le_bytes());
    }
    // Appended block: the head's metaballs (head frame) for the viewer's push-out of render vertices.
    encode_scene_metaballs(&mut w.0, &s.head, s.lattice.params.metaball.threshold);
    // Appended block: the hair types' fibre sections, for the viewer's strand width.
    encode_scene_hair_types(&mut w.0);
    // Appended block: the root hold (the carried hair's law, `engine::scene::carried`) and where a nozzle is.
    for x in [s.root_hold, nozzle_standoff] {
        w.0.extend_from_slice(&(x as f32).to_le_bytes());
    }
    w.0
}

/// The SCENE's appended hair-type block (docs/protocol.md), after the metaballs: u32 N (the hair types of
/// the names list, in its order), then N x (f32 major-axis diameter (m), f32 ellipticity (major / minor
/// axis, >= 1)) of `strand::HairType::ALL`: the fibre section the physics uses, so the viewer draws strands
/// as wide as the hair type's fibres without a copy of the presets.
fn encode_scene_hair_types(out: &mut Vec<u8>) {
    let types = strand::HairType::ALL;
    out.extend_from_slice(&(types.len() as u32).to_le_bytes());
    for h in types {
        for x in [h.major_diameter, h.ellipticity] {
            out.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
}

/// The SCENE's appended metaball block (docs/protocol.md): u32 M, f32 threshold T, f32 push-out skin (m),
/// then M x (3 x f32 centre, f32 radius) in the head frame, m.
fn encode_scene_metaballs(out: &mut Vec<u8>, head: &lattice::metaball::MetaballSet, threshold: f64) {
    out.extend_from_slice(&(head.balls.len() as u32).to_le_bytes());
    out.extend_from_slice(&(threshold as f32).to_le_bytes());
    out.extend_from_slice(&(lattice::metaball::PUSH_OUT_SKIN as f32).to_le_bytes());
    for b in &head.balls {
        for x in [b.centre.x, b.centre.y, b.centre.z, b.radius] {
            out.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
}

/// Byte offset of the FRAME's sequence number (u32, little-endian), after the 2-byte header.
pub const FRAME_SEQ_OFFSET: usize = 2;
/// Byte offset of the FRAME flags byte (bit 0: the receiving viewer controls the tool), patched per viewer:
/// after the header (2), the sequence number (4), the time (f32, 4) and the tool (u8, 1).
pub const FRAME_FLAGS_OFFSET: usize = 11;

/// The sequence number of a FRAME message's bytes, or None if `frame` is too short to hold one.
pub fn frame_seq(frame: &[u8]) -> Option<u32> {
    Some(u32::from_le_bytes(frame.get(FRAME_SEQ_OFFSET..FRAME_SEQ_OFFSET + 4)?.try_into().ok()?))
}

/// FRAME message: what changed since the last frame (never the render strands).
pub fn encode_frame(seq: u32, lat: &LatticeSnapshot, h: &HapticSnapshot) -> Vec<u8> {
    let nodes = lat.positions.len();
    let guides = lat.wetness.len();
    let chain_points: usize = lat.chains.iter().map(|c| c.len()).sum();
    let mut w = W::new(server::FRAME, 96 + 12 * nodes + 4 * h.active.len() + 12 * h.displacement.len() + 4 * guides + 4 * lat.chains.len() + 12 * chain_points);
    w.u32(seq);
    w.f32(h.time);
    w.u8(h.tool);
    w.u8(0); // flags, patched per viewer
    w.u16(h.contacts.min(u16::MAX as u32) as u16);
    w.v3(&h.tool_position);
    let q = UnitQuaternion::from_matrix(&h.tool_rotation);
    w.f32(q.i);
    w.f32(q.j);
    w.f32(q.k);
    w.f32(q.w);
    w.v3(&h.device_position);
    w.v3(&h.force);
    w.u32(lat.version as u32);
    w.u32(nodes as u32);
    for p in &lat.positions {
        w.v3(&p.coords);
    }
    let samples = if h.active.is_empty() { 0 } else { h.displacement.len() / h.active.len() };
    w.u32(h.active.len() as u32);
    w.u32(samples as u32);
    for g in &h.active {
        w.u32(*g);
    }
    for d in &h.displacement {
        w.v3(d);
    }
    w.u32(guides as u32);
    for x in &lat.wetness {
        w.0.extend_from_slice(&x.to_le_bytes());
    }
    // --- falling cut clusters (issue 5: scissors) ---
    w.u32(lat.kept_version as u32);
    w.u32(lat.chains.len() as u32);
    for c in &lat.chains {
        w.u32(c.len() as u32);
    }
    for p in lat.chains.iter().flatten() {
        p.iter().for_each(|&x| w.0.extend_from_slice(&x.to_le_bytes()));
    }
    // --- the head pose (issue 14): head frame to world ---
    w.v3(&lat.head.translation.vector);
    let q = lat.head.rotation;
    for x in [q.i, q.j, q.k, q.w] {
        w.f32(x);
    }
    // --- proxy health (issue 16): runaway-guard resets since the session started ---
    w.u32(h.runaways.min(u32::MAX as u64) as u32);
    // --- the hair's surface (issue 29): treatment id, the tool-hair friction coefficient in use ---
    w.u8(h.treatment.id());
    w.f32(h.tool_friction);
    w.0
}

/// STRANDS message: the points kept of every render strand (vertices 0..kept of strand i stay on the head).
pub fn encode_strands(kept: &[u16]) -> Vec<u8> {
    let mut w = W::new(server::STRANDS, 4 + 2 * kept.len());
    w.u32(kept.len() as u32);
    for k in kept {
        w.u16(*k);
    }
    w.0
}

#[cfg(test)]
mod properties;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn device_status_has_its_documented_layout() {
        // docs/protocol.md: type, version, u8 state, then six u32 counters, 27 bytes.
        let mut c = haptics::udp::UdpCounts { connected: true, accepted: 7, rejected: [1, 2, 3, 4], malformed: 5, foreign: 6, lost: 8, answered: 9, deferred: 0 };
        let b = encode_device(&c);
        assert_eq!(b.len(), 27);
        assert_eq!((b[0], b[1], b[2]), (server::DEVICE, VERSION, device_state::CONNECTED));
        let u = |i: usize| u32::from_le_bytes(b[3 + 4 * i..7 + 4 * i].try_into().unwrap());
        assert_eq!([u(0), u(1), u(2), u(3), u(4), u(5)], [7, 10, 5, 6, 8, 9]);
        c.connected = false;
        assert_eq!(encode_device(&c)[2], device_state::LOST);
        assert_eq!(encode_device(&haptics::udp::UdpCounts::default())[2], device_state::WAITING);
    }

    #[test]
    fn malformed_and_unknown_messages_are_errors_not_panics() {
        assert_eq!(parse_client(&[]).unwrap_err().code, code::MALFORMED);
        assert_eq!(parse_client(&[0x01]).unwrap_err().code, code::MALFORMED);
        assert_eq!(parse_client(&[0x01, 9]).unwrap_err().code, code::BAD_VERSION);
        assert_eq!(parse_client(&[0x7f, 1]).unwrap_err().code, code::UNKNOWN_TYPE);
        assert_eq!(parse_client(&[client::POSE, 1, 0, 0]).unwrap_err().code, code::MALFORMED);
        assert_eq!(parse_client(&[client::SELECT_TOOL, 1, 6]).unwrap_err().code, code::MALFORMED);
        let mut nan = vec![client::POSE, 1];
        for x in [f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
            nan.extend_from_slice(&x.to_le_bytes());
        }
        nan.extend_from_slice(&0u32.to_le_bytes());
        assert_eq!(parse_client(&nan).unwrap_err().code, code::MALFORMED);
        // Every prefix of a good message fails cleanly.
        let mut good = vec![client::POSE, 1];
        for x in [0.1f32, -0.2, 0.3, 0.0, 0.0, 0.0, 1.0] {
            good.extend_from_slice(&x.to_le_bytes());
        }
        good.extend_from_slice(&1u32.to_le_bytes());
        for n in 0..good.len() {
            assert!(parse_client(&good[..n]).is_err());
        }
        match parse_client(&good).unwrap() {
            ClientMessage::Pose { position, rotation, buttons } => {
                assert!((position - Vector3::new(0.1, -0.2, 0.3)).norm() < 1e-6);
                assert!((rotation - Matrix3::identity()).norm() < 1e-12);
                assert_eq!(buttons, 1);
            }
            m => panic!("{m:?}"),
        }
        // FRAME_ACK: a u32 sequence number, exactly.
        assert_eq!(parse_client(&[client::FRAME_ACK, 1, 7, 1, 0, 0]).unwrap(), ClientMessage::FrameAck(263));
        for n in [0, 3, 5] {
            let e = parse_client(&[vec![client::FRAME_ACK, 1], vec![0; n]].concat()).unwrap_err();
            assert_eq!(e.code, code::MALFORMED);
            assert!(e.message.contains("FRAME_ACK needs a 4-byte payload"), "{}", e.message);
        }
    }

    #[test]
    fn the_frame_header_offsets_name_what_encode_frame_writes_there() {
        // The sequence number and the flags byte (patched per viewer) at their named offsets, for sequence
        // numbers across the u32 range and every tool; a message too short has no sequence number.
        for (seq, tool) in [(0u32, 0u8), (1, 1), (0xdead_beef, 2), (u32::MAX, 3)] {
            let h = HapticSnapshot { tool_rotation: Matrix3::identity(), tool, time: 1.5, ..Default::default() };
            let f = encode_frame(seq, &LatticeSnapshot::default(), &h);
            assert_eq!(frame_seq(&f), Some(seq));
            assert_eq!(f[FRAME_FLAGS_OFFSET], 0, "flags are zero until patched");
            assert_eq!(f[FRAME_FLAGS_OFFSET - 1], tool, "the tool byte comes just before the flags");
            assert_eq!(&f[FRAME_SEQ_OFFSET + 4..FRAME_SEQ_OFFSET + 8], &1.5f32.to_le_bytes(), "the time follows the sequence number");
        }
        assert_eq!(frame_seq(&[server::FRAME, VERSION, 1, 2, 3]), None);
    }

    #[test]
    fn strands_and_frame_layout() {
        let b = encode_strands(&[12, 3]);
        assert_eq!(b, vec![server::STRANDS, VERSION, 2, 0, 0, 0, 12, 0, 3, 0]);
        let lat = LatticeSnapshot { version: 7, positions: vec![nalgebra::Point3::new(1.0, 2.0, 3.0)], wetness: vec![0.5, 0.25], kept_version: 2, chains: vec![vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], vec![[7.0, 8.0, 9.0]]], ..Default::default() };
        let h = HapticSnapshot { tool_rotation: Matrix3::identity(), ..Default::default() };
        let f = encode_frame(1, &lat, &h);
        // Header and fixed part: 2 + 4 + 4 + 1 + 1 + 2 + 12 + 16 + 12 + 12 + 4 + 4 = 74; 1 node; A = 0, K = 0.
        let tail = &f[74 + 12 + 8..];
        let u32_at = |i: usize| u32::from_le_bytes(tail[i..i + 4].try_into().unwrap());
        let f32_at = |i: usize| f32::from_le_bytes(tail[i..i + 4].try_into().unwrap());
        assert_eq!(u32_at(0), 2);
        assert_eq!((f32_at(4), f32_at(8)), (0.5, 0.25));
        assert_eq!((u32_at(12), u32_at(16), u32_at(20), u32_at(24)), (2, 2, 2, 1));
        assert_eq!((f32_at(28), f32_at(28 + 8 * 4)), (1.0, 9.0));
        assert_eq!(tail.len(), 28 + 9 * 4 + 28 + 4 + 5, "chains, the head pose, the runaway count, the hair's surface");
        assert_eq!(u32::from_le_bytes(f[f.len() - 9..f.len() - 5].try_into().unwrap()), 0);
        // The head pose follows the chains: 3 f32 position, 4 f32 quaternion (x, y, z, w); then u32 runaways;
        // then u8 treatment and f32 tool friction.
        let h = HapticSnapshot { runaways: 7, treatment: tools::treatment::Treatment::Bleached, tool_friction: 0.375, ..h };
        let lat = LatticeSnapshot { head: nalgebra::Isometry3::new(Vector3::new(0.01, 0.02, 0.03), Vector3::new(0.0, 0.0, 0.5)), ..lat };
        let f = encode_frame(1, &lat, &h);
        assert_eq!(u32::from_le_bytes(f[f.len() - 9..f.len() - 5].try_into().unwrap()), 7);
        assert_eq!((f[f.len() - 5], f32::from_le_bytes(f[f.len() - 4..].try_into().unwrap())), (2, 0.375));
        let end: Vec<f32> = (0..7).map(|k| f32::from_le_bytes(f[f.len() - 37 + 4 * k..f.len() - 33 + 4 * k].try_into().unwrap())).collect();
        let want = [0.01, 0.02, 0.03, 0.0, 0.0, (0.25f64).sin(), (0.25f64).cos()];
        assert!(end.iter().zip(want).all(|(a, b)| (*a as f64 - b).abs() < 1e-6), "{end:?}");
        // HEAD: 6 f32; a turn of more than pi or a NaN is refused.
        let head = |v: [f32; 6]| { let mut m = vec![client::HEAD, VERSION]; v.iter().for_each(|x| m.extend_from_slice(&x.to_le_bytes())); parse_client(&m) };
        match head([0.0, 0.0, 0.01, 0.0, 0.0, 0.5]).unwrap() {
            ClientMessage::Command(Command::SetHead { position, rotation }) => assert!((position.z - 0.01).abs() < 1e-7 && (rotation.z - 0.5).abs() < 1e-7),
            m => panic!("{m:?}"),
        }
        assert_eq!(head([0.0, 0.0, 0.0, 0.0, 0.0, 4.0]).unwrap_err().code, code::MALFORMED);
        assert_eq!(head([f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]).unwrap_err().code, code::MALFORMED);
        // SET_TREATMENT: one byte, a known treatment id.
        for t in tools::treatment::Treatment::ALL {
            assert_eq!(parse_client(&[client::SET_TREATMENT, VERSION, t.id()]).unwrap(), ClientMessage::Command(Command::SetTreatment(t)));
        }
        assert!(parse_client(&[client::SET_TREATMENT, VERSION, 4]).unwrap_err().message.contains("treatment 4 unknown"));
        assert_eq!(parse_client(&[client::SET_TREATMENT, VERSION]).unwrap_err().code, code::MALFORMED);
        // A finite but absurd POSE (1e30 m) is out of range.
        let mut pose = vec![client::POSE, VERSION];
        [1e30f32, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0].iter().for_each(|x| pose.extend_from_slice(&x.to_le_bytes()));
        pose.extend_from_slice(&0u32.to_le_bytes());
        let e = parse_client(&pose).unwrap_err();
        assert!(e.code == code::MALFORMED && e.message.contains("farther than"), "{}", e.message);
    }

    #[test]
    fn load_with_fit_options_and_the_fit_message() {
        use hairstyle::fit::{Axis, FitOptions};
        assert_eq!(parse_client(&[client::LOAD, VERSION, 2, 9, 9]).unwrap(), ClientMessage::Load(2, FitOptions::default(), None, vec![9, 9]));
        let mut m = vec![client::LOAD, VERSION, 0x80 | 3, 3, 6, 1, 0];
        m.extend_from_slice(&0.01f32.to_le_bytes());
        m.push(7);
        let opts = FitOptions { units: Some(0.01f32 as f64), up: Some(Axis::PosY), front: Some(Axis::NegZ), fit: false };
        assert_eq!(parse_client(&m).unwrap(), ClientMessage::Load(3, opts, None, vec![7]));
        // Bit 1 of the flags: a u32 count of follow strands comes before the file.
        let mut f = m.clone();
        f[5] |= 2;
        f.splice(11..11, 437u32.to_le_bytes());
        assert_eq!(parse_client(&f).unwrap(), ClientMessage::Load(3, opts, Some(437), vec![7]));
        assert!(parse_client(&f[..13]).unwrap_err().message.contains("u32 count"));
        let mut bad = m.clone();
        bad[3] = 7;
        assert!(parse_client(&bad).unwrap_err().message.contains("up axis 7 unknown"));
        assert!(parse_client(&m[..8]).unwrap_err().message.contains("8 option bytes"));
        assert!(parse_client(&[client::LOAD, VERSION, 4]).is_err());
        let r = hairstyle::fit::FitReport {
            meters_per_unit: 0.01,
            units_source: hairstyle::fit::Source::Detected,
            up: Axis::PosY,
            front: Axis::PosZ,
            orientation_source: hairstyle::fit::Source::Option,
            transform: hairstyle::fit::Similarity::identity(),
            rooted: 0.5,
            root_distance: hairstyle::fit::Distances { median: 0.001, p95: 0.002, max: 0.003 },
            rooted_distance: hairstyle::fit::Distances { median: 0.0005, p95: 0.001, max: 0.002 },
            loose_distance: hairstyle::fit::Distances { median: 0.1, p95: 0.2, max: 0.3 },
            pushed_out: 42,
            scores: None,
        };
        let b = encode_fit(&r);
        assert_eq!((b[0], b.len()), (server::FIT, 2 + 4 * 14 + 4 + 4 * 4 + 4 + 3 * 4));
        assert_eq!(&b[2..6], &1f32.to_le_bytes());
        assert_eq!(&b[58..62], &[3, 5, 2, 0]); // up +y, front +z, units detected, orientation option
        assert_eq!(&b[62..66], &0.5f32.to_le_bytes());
        assert_eq!(&b[78..82], &42u32.to_le_bytes());
        assert_eq!(&b[86..90], &0.001f32.to_le_bytes()); // rooted p95
    }

    /// SCENE decoded field by field as docs/protocol.md lays it out: every byte is accounted for, the
    /// appended hair-type block carries each preset's fibre section (`strand::HairType::ALL`) in the order of
    /// the names list, and the last block the scene's root hold and the nozzle standoff.
    #[test]
    fn scene_layout_and_the_hair_types_diameters() {
        let opts = engine::session::SceneOptions { render_strands: 200, guides: 20, hair_type: "asian".into(), ..Default::default() };
        let scene = engine::session::Scene::builtin(&opts).unwrap();
        let b = encode_scene(&scene, 0.15);
        assert_eq!((b[0], b[1]), (server::SCENE, VERSION));
        let mut o = 2;
        let mut u32_ = || { let x = u32::from_le_bytes(b[o..o + 4].try_into().unwrap()); o += 4; x as usize };
        let (v, strands, p, g, k) = (u32_(), u32_(), u32_(), u32_(), u32_());
        assert_eq!((v, strands, p, g, k), (scene.render.vertices_per_strand, 200, scene.render.guides_per_strand, 20, scene.samples()));
        let f = &scene.lattice.ffd;
        assert_eq!((u32_(), u32_(), u32_()), (f.nx, f.ny, f.nz));
        o += 16; // lattice origin and cell size
        let types = b[o] as usize;
        o += 1;
        let mut names = Vec::new();
        for _ in 0..types {
            let n = b[o] as usize;
            names.push(std::str::from_utf8(&b[o + 1..o + 1 + n]).unwrap().to_string());
            o += 1 + n;
        }
        let want: Vec<&str> = strand::HairType::ALL.iter().map(|h| h.name).collect();
        assert_eq!(names, want);
        assert_eq!(names[b[o] as usize], "asian", "the scene's hair type");
        o = (o + 1).div_ceil(4) * 4;
        let u = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap()) as usize;
        let f32_ = |o: usize| f32::from_le_bytes(b[o..o + 4].try_into().unwrap()) as f64;
        let (nh, ni) = (u(o), u(o + 4));
        assert_eq!((nh, ni), (scene.head_mesh.positions.len(), scene.head_mesh.indices.len()));
        o += 8 + 12 * nh + 4 * ni + 12 * strands * v + 8 * strands * p + 4 * strands;
        let m = u(o);
        assert_eq!(m, scene.head.balls.len());
        o += 12 + 16 * m;
        // The hair-type block: one (diameter, ellipticity) per name, and nothing after it.
        assert_eq!(u(o), types);
        o += 4;
        for (i, h) in strand::HairType::ALL.iter().enumerate() {
            let (d, e) = (f32_(o + 8 * i), f32_(o + 8 * i + 4));
            assert!((d / h.major_diameter - 1.0).abs() < 1e-6 && (e / h.ellipticity - 1.0).abs() < 1e-6, "{}: {d} m, {e}", h.name);
            assert!(d > 50e-6 && d < 150e-6 && e >= 1.0, "{}: a human hair's section", h.name);
        }
        o += 8 * types;
        // The root hold and the nozzle standoff, and nothing after them.
        assert!((f32_(o) - scene.root_hold).abs() < 1e-7 && scene.root_hold > 0.0, "root hold {}", f32_(o));
        assert!((f32_(o + 4) - 0.15).abs() < 1e-7, "nozzle standoff {}", f32_(o + 4));
        assert_eq!(o + 8, b.len(), "SCENE ends with the root hold and the nozzle standoff");
    }

    #[test]
    fn error_message_layout() {
        let b = encode_error(&WireError { code: 2, message: "abc".into() });
        assert_eq!(b, vec![server::ERROR, VERSION, 2, 0, 3, 0, b'a', b'b', b'c']);
    }
}
