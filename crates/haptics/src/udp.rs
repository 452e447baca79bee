//! The UDP device protocol (docs/protocol.md): a program on the machine with the real device (written with
//! CHAI3D, OpenHaptics or the Force Dimension SDK) sends pose packets; Coiffure answers each with a force
//! packet. All numbers little-endian.
//!
//! Pose packet, 116 bytes: `b"CFP1"`, u32 sequence, f64 time (s), f64 x 3 position (m), f64 x 9 rotation
//! (row-major, tool frame to world), u32 buttons.
//! Force packet, 64 bytes: `b"CFF1"`, u32 sequence (of the pose answered), f64 x 3 force (N), f64 x 3 torque
//! (N m), u32 flags (bit 0: the pose was rejected, force is zero), u32 reserved (0).
//! Version 2: a pose sent as `b"CFP2"` (same layout) is answered by `b"CFF2"`, the same 64 bytes followed by
//! the local force model ([`crate::local_model`], 352 bytes in all); version-1 clients are answered as before.

use crate::device::{DeviceCommand, DeviceProfile, DeviceReading, HapticDevice};
use crate::local_model::{model_feed, FedModel, ModelFeed, ModelTap, WireModel};
use crate::workspace::Workspace;
use nalgebra::{Matrix3, Vector3};
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use thiserror::Error;

/// Size of a pose packet, bytes.
pub const POSE_BYTES: usize = 116;
/// Size of a force packet, bytes.
pub const FORCE_BYTES: usize = 64;
/// Size of a version-2 force packet (the answer to a `CFP2` pose), bytes.
pub const FORCE_V2_BYTES: usize = FORCE_BYTES + crate::local_model::MODEL_BYTES;

/// A malformed packet.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PacketError {
    /// Wrong size.
    #[error("packet of {0} bytes; expected {1}")]
    Size(usize, usize),
    /// Wrong magic.
    #[error("bad magic {0:?}")]
    Magic([u8; 4]),
}

fn f64_at(b: &[u8], i: usize) -> f64 {
    f64::from_le_bytes(b[i..i + 8].try_into().unwrap())
}
fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes(b[i..i + 4].try_into().unwrap())
}

/// Encodes a pose packet (version 1: `CFP1`).
pub fn encode_pose(seq: u32, r: &DeviceReading) -> [u8; POSE_BYTES] {
    encode_pose_version(seq, r, 1)
}

/// Encodes a pose packet of protocol `version` (1: `CFP1`, answered by `CFF1`; 2: `CFP2`, answered by `CFF2`
/// with the local force model).
pub fn encode_pose_version(seq: u32, r: &DeviceReading, version: u8) -> [u8; POSE_BYTES] {
    let mut b = [0u8; POSE_BYTES];
    b[0..4].copy_from_slice(if version >= 2 { b"CFP2" } else { b"CFP1" });
    b[4..8].copy_from_slice(&seq.to_le_bytes());
    b[8..16].copy_from_slice(&r.time.to_le_bytes());
    for k in 0..3 {
        b[16 + 8 * k..24 + 8 * k].copy_from_slice(&r.position[k].to_le_bytes());
    }
    for i in 0..3 {
        for j in 0..3 {
            let o = 40 + 8 * (3 * i + j);
            b[o..o + 8].copy_from_slice(&r.rotation[(i, j)].to_le_bytes());
        }
    }
    b[112..116].copy_from_slice(&r.buttons.to_le_bytes());
    b
}

/// Decodes a pose packet of either version: (sequence, reading).
pub fn decode_pose(b: &[u8]) -> Result<(u32, DeviceReading), PacketError> {
    decode_pose_version(b).map(|(s, r, _)| (s, r))
}

/// Decodes a pose packet: (sequence, reading, protocol version 1 or 2).
pub fn decode_pose_version(b: &[u8]) -> Result<(u32, DeviceReading, u8), PacketError> {
    if b.len() != POSE_BYTES {
        return Err(PacketError::Size(b.len(), POSE_BYTES));
    }
    let version = match &b[0..4] {
        b"CFP1" => 1,
        b"CFP2" => 2,
        _ => return Err(PacketError::Magic(b[0..4].try_into().unwrap())),
    };
    let position = Vector3::new(f64_at(b, 16), f64_at(b, 24), f64_at(b, 32));
    let rotation = Matrix3::from_fn(|i, j| f64_at(b, 40 + 8 * (3 * i + j)));
    Ok((u32_at(b, 4), DeviceReading { time: f64_at(b, 8), position, rotation, buttons: u32_at(b, 112) }, version))
}

/// Encodes a force packet.
pub fn encode_force(seq: u32, c: &DeviceCommand, flags: u32) -> [u8; FORCE_BYTES] {
    let mut b = [0u8; FORCE_BYTES];
    b[0..4].copy_from_slice(b"CFF1");
    b[4..8].copy_from_slice(&seq.to_le_bytes());
    for k in 0..3 {
        b[8 + 8 * k..16 + 8 * k].copy_from_slice(&c.force[k].to_le_bytes());
        b[32 + 8 * k..40 + 8 * k].copy_from_slice(&c.torque[k].to_le_bytes());
    }
    b[56..60].copy_from_slice(&flags.to_le_bytes());
    b
}

/// Encodes a version-2 force packet: the version-1 packet (magic `CFF2`) followed by `model`.
pub fn encode_force_v2(seq: u32, c: &DeviceCommand, flags: u32, model: &WireModel) -> [u8; FORCE_V2_BYTES] {
    let mut b = [0u8; FORCE_V2_BYTES];
    b[..FORCE_BYTES].copy_from_slice(&encode_force(seq, c, flags));
    b[0..4].copy_from_slice(b"CFF2");
    model.encode_into(&mut b[FORCE_BYTES..]);
    b
}

/// Decodes a force packet of either version: (sequence, command, flags, the model of a version-2 packet).
pub fn decode_answer(b: &[u8]) -> Result<(u32, DeviceCommand, u32, Option<WireModel>), PacketError> {
    if b.len() == FORCE_V2_BYTES && &b[0..4] == b"CFF2" {
        let mut v1 = [0u8; FORCE_BYTES];
        v1.copy_from_slice(&b[..FORCE_BYTES]);
        v1[0..4].copy_from_slice(b"CFF1");
        let (s, c, f) = decode_force(&v1)?;
        return Ok((s, c, f, Some(WireModel::decode(&b[FORCE_BYTES..]))));
    }
    decode_force(b).map(|(s, c, f)| (s, c, f, None))
}

/// Decodes a version-1 force packet: (sequence, command, flags).
pub fn decode_force(b: &[u8]) -> Result<(u32, DeviceCommand, u32), PacketError> {
    if b.len() != FORCE_BYTES {
        return Err(PacketError::Size(b.len(), FORCE_BYTES));
    }
    if &b[0..4] != b"CFF1" {
        return Err(PacketError::Magic(b[0..4].try_into().unwrap()));
    }
    let force = Vector3::new(f64_at(b, 8), f64_at(b, 16), f64_at(b, 24));
    let torque = Vector3::new(f64_at(b, 32), f64_at(b, 40), f64_at(b, 48));
    Ok((u32_at(b, 4), DeviceCommand { force, torque }, u32_at(b, 56)))
}

/// Force packet flag: the pose answered was rejected (non-finite or out of range, teleport, out of order,
/// duplicate); the force is zero.
pub const FLAG_REJECTED: u32 = 1;
/// Force packet flag: the simulation's force was not finite and was withheld; the force is zero.
pub const FLAG_WITHHELD: u32 = 2;

/// Parameters of the UDP device (docs/protocol.md, "Timing" and "Faults").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UdpParams {
    /// No accepted pose for this long: the device is lost (the loop gets no reading, so zero force; the
    /// stream's owner is released and the next valid sender takes over), s. Default 0.05.
    pub lost_after: f64,
    /// Most datagrams read in one haptic step; the rest wait for the next step, so a flood cannot stall the
    /// loop. Default 16 (a 4 kHz device into a 1 kHz loop sends 4 a step).
    pub max_packets_per_step: usize,
    /// Fastest believable hand, m/s (device frame): a pose farther from the last accepted one than
    /// `max_speed` times their time difference plus `teleport_slack` is a teleport. Default 5 (the profiles').
    pub max_speed: f64,
    /// Allowance of the teleport check for sensor noise and clock jitter, m. Default 0.002.
    pub teleport_slack: f64,
    /// Largest distance of a pose from the device's origin, m (device frame; farther is out of range).
    /// Default 1 (every desktop device's reach).
    pub max_reach: f64,
    /// Largest deviation of the rotation from orthonormal (max |R^T R - I| entry). Default 0.01.
    pub rotation_tolerance: f64,
    /// Device workspace to head frame. Default [`Workspace::for_profile`] of the Phantom Omni.
    pub workspace: Workspace,
    /// Clock of the lost timer: the wall clock (true, the default: a loop catching up after a stall runs
    /// steps faster than real time and must not find the device lost), or the loop's clock, the `time`
    /// given to [`HapticDevice::read`] (false: for tests that step the device by hand).
    pub wall_clock: bool,
}

impl UdpParams {
    /// Defaults for a device profile (its speed limit and default workspace).
    pub fn for_profile(p: &DeviceProfile) -> Self {
        Self { lost_after: 0.05, max_packets_per_step: 16, max_speed: p.max_speed, teleport_slack: 0.002, max_reach: 1.0, rotation_tolerance: 0.01, workspace: Workspace::for_profile(p), wall_clock: true }
    }

    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), String> {
        for (k, v) in [("lost_after", self.lost_after), ("max_speed", self.max_speed), ("max_reach", self.max_reach), ("rotation_tolerance", self.rotation_tolerance)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("udp device: {k} must be finite and > 0, got {v}"));
            }
        }
        if !(self.teleport_slack.is_finite() && self.teleport_slack >= 0.0) {
            return Err(format!("udp device: teleport_slack must be finite and >= 0 m, got {}", self.teleport_slack));
        }
        if self.max_packets_per_step == 0 {
            return Err("udp device: max_packets_per_step must be > 0".into());
        }
        Ok(())
    }
}

/// Why a pose was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reject {
    /// A non-finite number, a position beyond `max_reach`, or a rotation that is not one.
    Invalid = 0,
    /// Farther from the last accepted pose than the hand can move in the time between them.
    Teleport = 1,
    /// Sequence number or time before the last accepted pose's.
    OutOfOrder = 2,
    /// The last accepted pose's sequence number again.
    Duplicate = 3,
}

/// Counters of a UDP device, shared with other threads (the server shows them to the viewers).
#[derive(Debug, Default)]
pub struct UdpStatus {
    connected: AtomicBool,
    accepted: AtomicU64,
    rejected: [AtomicU64; 4],
    malformed: AtomicU64,
    foreign: AtomicU64,
    lost: AtomicU64,
    answered: AtomicU64,
    deferred: AtomicU64,
}

/// A copy of a device's counters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct UdpCounts {
    /// A valid pose arrived within `lost_after`.
    pub connected: bool,
    /// Poses accepted.
    pub accepted: u64,
    /// Poses rejected, by [`Reject`] (invalid, teleport, out of order, duplicate).
    pub rejected: [u64; 4],
    /// Datagrams of the wrong size or magic, dropped.
    pub malformed: u64,
    /// Poses from another sender while the stream had an owner, dropped.
    pub foreign: u64,
    /// Times the stream was lost (no accepted pose for `lost_after`).
    pub lost: u64,
    /// Force packets sent.
    pub answered: u64,
    /// Steps that left datagrams for the next step (more than `max_packets_per_step` waiting).
    pub deferred: u64,
}

impl UdpCounts {
    /// Poses rejected for any reason.
    pub fn rejected_total(&self) -> u64 {
        self.rejected.iter().sum()
    }
}

impl UdpStatus {
    /// The counters now.
    pub fn counts(&self) -> UdpCounts {
        let l = |a: &AtomicU64| a.load(Ordering::Relaxed);
        UdpCounts {
            connected: self.connected.load(Ordering::Relaxed),
            accepted: l(&self.accepted),
            rejected: [l(&self.rejected[0]), l(&self.rejected[1]), l(&self.rejected[2]), l(&self.rejected[3])],
            malformed: l(&self.malformed),
            foreign: l(&self.foreign),
            lost: l(&self.lost),
            answered: l(&self.answered),
            deferred: l(&self.deferred),
        }
    }
}

/// The Coiffure side of the protocol: a non-blocking UDP socket read once per haptic step.
///
/// [`HapticDevice::read`] takes at most `max_packets_per_step` datagrams: malformed ones are counted and
/// dropped; the first sender of a valid pose owns the stream until it is lost (others are counted and
/// dropped); each pose is checked (finite and in range, not a teleport, in order, not a duplicate) and
/// either becomes the latest reading or is rejected. It returns the latest accepted pose mapped to the head
/// frame (held between packets), or None once no pose was accepted for `lost_after`.
/// [`HapticDevice::write`] answers every pose read in that step: accepted ones with the step's force,
/// rejected ones with zero force and [`FLAG_REJECTED`].
pub struct UdpDevice {
    socket: UdpSocket,
    params: UdpParams,
    status: Arc<UdpStatus>,
    owner: Option<SocketAddr>,
    last: Option<(u32, DeviceReading)>,
    /// Loop time of the last accepted pose, s.
    last_valid: Option<f64>,
    /// Poses read this step and not answered yet: (sender, sequence, rejected, protocol version).
    pending: Vec<(SocketAddr, u32, bool, u8)>,
    /// The local force model the device loop feeds ([`HapticDevice::model_feed`]), for version-2 answers.
    tap: Option<ModelTap>,
    /// Origin of the wall clock.
    epoch: std::time::Instant,
}

impl UdpDevice {
    /// Binds `addr` (e.g. "127.0.0.1:0" for any free port) with the defaults of a Phantom Omni.
    pub fn bind(addr: &str) -> std::io::Result<Self> {
        Self::bind_with(addr, UdpParams::for_profile(&DeviceProfile::PHANTOM_OMNI))
    }

    /// Binds `addr` with `params` (checked: an invalid field is an `InvalidInput` error naming it).
    pub fn bind_with(addr: &str, params: UdpParams) -> std::io::Result<Self> {
        params.validate().map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))?;
        let socket = UdpSocket::bind(addr)?;
        socket.set_nonblocking(true)?;
        Ok(Self::on(socket, params, Arc::new(UdpStatus::default())))
    }

    fn on(socket: UdpSocket, params: UdpParams, status: Arc<UdpStatus>) -> Self {
        let pending = Vec::with_capacity(params.max_packets_per_step);
        Self { socket, params, status, owner: None, last: None, last_valid: None, pending, tap: None, epoch: std::time::Instant::now() }
    }

    /// A second device on the same socket and counters, with a fresh stream state (no owner, no pose): for
    /// a new session taking over (the next valid pose re-anchors the tool).
    pub fn try_clone(&self) -> std::io::Result<Self> {
        Ok(Self::on(self.socket.try_clone()?, self.params, self.status.clone()))
    }

    /// The bound address.
    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// The shared counters.
    pub fn status(&self) -> Arc<UdpStatus> {
        self.status.clone()
    }

    /// The parameters.
    pub fn params(&self) -> &UdpParams {
        &self.params
    }

    /// Checks a pose against the last accepted one.
    fn check(&self, seq: u32, r: &DeviceReading) -> Result<(), Reject> {
        let p = &self.params;
        let finite = r.time.is_finite() && r.position.iter().chain(r.rotation.iter()).all(|x| x.is_finite());
        if !finite || r.position.norm() > p.max_reach {
            return Err(Reject::Invalid);
        }
        let off = (r.rotation.transpose() * r.rotation - Matrix3::identity()).amax();
        if off > p.rotation_tolerance {
            return Err(Reject::Invalid);
        }
        if let Some((last_seq, last)) = &self.last {
            let ahead = seq.wrapping_sub(*last_seq) as i32;
            if ahead == 0 {
                return Err(Reject::Duplicate);
            }
            if ahead < 0 || r.time < last.time {
                return Err(Reject::OutOfOrder);
            }
            if (r.position - last.position).norm() > p.max_speed * (r.time - last.time) + p.teleport_slack {
                return Err(Reject::Teleport);
            }
        }
        Ok(())
    }

    /// Handles one datagram from `from` read at loop time `now` (s).
    fn take(&mut self, bytes: &[u8], from: SocketAddr, now: f64) {
        let (seq, r, version) = match decode_pose_version(bytes) {
            Ok(p) => p,
            Err(_) => {
                self.status.malformed.fetch_add(1, Ordering::Relaxed);
                return;
            }
        };
        if self.owner.is_some_and(|o| o != from) {
            self.status.foreign.fetch_add(1, Ordering::Relaxed);
            return;
        }
        match self.check(seq, &r) {
            Ok(()) => {
                self.owner = Some(from);
                self.last = Some((seq, r));
                self.last_valid = Some(now);
                self.status.accepted.fetch_add(1, Ordering::Relaxed);
                self.status.connected.store(true, Ordering::Relaxed);
                self.pending.push((from, seq, false, version));
            }
            Err(why) => {
                self.status.rejected[why as usize].fetch_add(1, Ordering::Relaxed);
                self.pending.push((from, seq, true, version));
            }
        }
    }
}

impl HapticDevice for UdpDevice {
    /// `time`: the loop's clock, s (the lost timer runs on it if `UdpParams::wall_clock` is false).
    fn read(&mut self, time: f64) -> Option<DeviceReading> {
        let time = if self.params.wall_clock { self.epoch.elapsed().as_secs_f64() } else { time };
        if self.last_valid.is_some_and(|t| time - t > self.params.lost_after) {
            self.owner = None;
            self.last = None;
            self.last_valid = None;
            self.status.connected.store(false, Ordering::Relaxed);
            self.status.lost.fetch_add(1, Ordering::Relaxed);
        }
        let mut buf = [0u8; 2048];
        let mut n = 0;
        while n < self.params.max_packets_per_step {
            match self.socket.recv_from(&mut buf) {
                Ok((len, from)) => self.take(&buf[..len], from, time),
                // WouldBlock: nothing more waiting. Other errors (e.g. ICMP port unreachable from an earlier
                // answer on some systems) end this step's reading; the next step tries again.
                Err(_) => break,
            }
            n += 1;
        }
        if n == self.params.max_packets_per_step {
            self.status.deferred.fetch_add(1, Ordering::Relaxed);
        }
        self.last.map(|(_, r)| self.params.workspace.to_head(&r))
    }

    fn write(&mut self, command: &DeviceCommand) {
        let ok = command.force.iter().chain(command.torque.iter()).all(|x| x.is_finite());
        let mut model: Option<WireModel> = None;
        for (to, seq, rejected, version) in std::mem::take(&mut self.pending) {
            let (c, flags) = match (rejected, ok) {
                (true, _) => (DeviceCommand::default(), FLAG_REJECTED),
                (false, false) => (DeviceCommand::default(), FLAG_WITHHELD),
                (false, true) => (*command, 0),
            };
            let sent = if version >= 2 {
                // The model in the device frame (none yet, or no feed: no hair, number 0).
                let m = *model.get_or_insert_with(|| {
                    let fed = self.tap.as_mut().and_then(|t| t.latest()).unwrap_or(FedModel { number: 0, valid_for: 0.0, hair: crate::coupling::HairReaction::none(), coupling: crate::coupling::CouplingParams::for_profile(&DeviceProfile::PHANTOM_OMNI) });
                    WireModel::to_device(&fed, &self.params.workspace)
                });
                self.socket.send_to(&encode_force_v2(seq, &c, flags, &m), to)
            } else {
                self.socket.send_to(&encode_force(seq, &c, flags), to)
            };
            if sent.is_ok() {
                self.status.answered.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    fn model_feed(&mut self) -> Option<ModelFeed> {
        let (feed, tap) = model_feed();
        self.tap = Some(tap);
        Some(feed)
    }
}

/// Reference client (what a device program does): sends poses, receives forces. Used by the tests and
/// `coiffure device-sim`.
pub struct UdpClient {
    socket: UdpSocket,
    seq: u32,
    version: u8,
}

impl UdpClient {
    /// Connects to a Coiffure UDP device at `server` (from any free port on loopback, or on any interface
    /// when the server is not on loopback).
    pub fn connect(server: SocketAddr) -> std::io::Result<Self> {
        let local = if server.ip().is_loopback() { "127.0.0.1:0" } else { "0.0.0.0:0" };
        let socket = UdpSocket::bind(local)?;
        socket.connect(server)?;
        socket.set_read_timeout(Some(std::time::Duration::from_millis(200)))?;
        Ok(Self { socket, seq: 0, version: 1 })
    }

    /// Sends a pose with the next sequence number; returns it.
    pub fn send(&mut self, r: &DeviceReading) -> std::io::Result<u32> {
        self.seq = self.seq.wrapping_add(1);
        self.send_seq(self.seq, r)?;
        Ok(self.seq)
    }

    /// Sends a pose with the sequence number `seq` (to test out-of-order and duplicate packets).
    pub fn send_seq(&mut self, seq: u32, r: &DeviceReading) -> std::io::Result<()> {
        self.socket.send(&encode_pose_version(seq, r, self.version)).map(|_| ())
    }

    /// Speaks protocol `version` from now on (1, the default: `CFP1`; 2: `CFP2`, answered with the local force
    /// model, read by [`UdpClient::receive_model`]).
    pub fn set_version(&mut self, version: u8) {
        self.version = version;
    }

    /// Waits (up to the read timeout, 200 ms unless set) for a force packet: (sequence, command, flags).
    pub fn receive(&mut self) -> std::io::Result<(u32, DeviceCommand, u32)> {
        self.receive_model().map(|(s, c, f, _)| (s, c, f))
    }

    /// [`UdpClient::receive`], with the local force model of a version-2 answer.
    pub fn receive_model(&mut self) -> std::io::Result<(u32, DeviceCommand, u32, Option<WireModel>)> {
        let mut buf = [0u8; 512];
        let n = self.socket.recv(&mut buf)?;
        decode_answer(&buf[..n]).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
    }

    /// Sets how long [`UdpClient::receive`] waits (None: forever).
    pub fn set_timeout(&self, t: Option<std::time::Duration>) -> std::io::Result<()> {
        self.socket.set_read_timeout(t)
    }

    /// Makes [`UdpClient::receive`] return `WouldBlock` at once when nothing is waiting (or wait again).
    pub fn set_nonblocking(&self, on: bool) -> std::io::Result<()> {
        self.socket.set_nonblocking(on)
    }

    /// Sends raw bytes (to test malformed input).
    pub fn send_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.socket.send(bytes).map(|_| ())
    }

    /// The client's own address.
    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        self.socket.local_addr()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packets_round_trip() {
        let r = DeviceReading { time: 1.25, position: Vector3::new(0.1, -0.2, 0.3), rotation: Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0), buttons: 5 };
        let b = encode_pose(42, &r);
        assert_eq!(decode_pose(&b).unwrap(), (42, r));
        assert!(matches!(decode_pose(&b[..100]), Err(PacketError::Size(100, POSE_BYTES))));
        let mut bad = b;
        bad[0] = b'X';
        assert!(matches!(decode_pose(&bad), Err(PacketError::Magic(_))));
        let c = DeviceCommand { force: Vector3::new(1.0, 2.0, 3.0), torque: Vector3::new(-1.0, 0.5, 0.0) };
        assert_eq!(decode_force(&encode_force(7, &c, FLAG_REJECTED)).unwrap(), (7, c, FLAG_REJECTED));
    }

    #[test]
    fn round_trip_over_loopback() {
        // A client streams poses to the UDP device over 127.0.0.1; the device answers each with the force
        // computed from it (here: a spring towards the origin), echoing the sequence number. A malformed
        // packet is dropped and counted, and the stream goes on.
        let identity = UdpParams { workspace: Workspace { scale: 1.0, offset: Vector3::zeros() }, wall_clock: false, ..UdpParams::for_profile(&DeviceProfile::PHANTOM_OMNI) };
        let mut dev = UdpDevice::bind_with("127.0.0.1:0", identity).unwrap();
        let mut client = UdpClient::connect(dev.local_addr().unwrap()).unwrap();
        for i in 0..50 {
            if i == 10 {
                client.send_raw(b"garbage").unwrap();
            }
            let r = DeviceReading { time: i as f64 * 1e-3, position: Vector3::new(0.001 * i as f64, 0.0, 0.0), rotation: Matrix3::identity(), buttons: 0 };
            let seq = client.send(&r).unwrap();
            let mut got = None;
            for _ in 0..200 {
                got = dev.read(r.time);
                if got.map(|g| g.time) == Some(r.time) {
                    break;
                }
                std::thread::sleep(std::time::Duration::from_micros(200));
            }
            let got = got.expect("pose received");
            assert_eq!(got, r);
            dev.write(&DeviceCommand { force: -got.position * 100.0, torque: Vector3::zeros() });
            let (s, cmd, flags) = client.receive().unwrap();
            assert_eq!(s, seq);
            assert_eq!(flags, 0);
            assert!((cmd.force.x + 0.1 * i as f64).abs() < 1e-12);
        }
        assert_eq!(dev.status().counts().malformed, 1);
        assert_eq!(dev.status().counts().answered, 50);
    }
}
