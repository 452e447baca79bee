//! The UDP device protocol (docs/protocol.md): a program on the machine with the real device (written with
//! CHAI3D, OpenHaptics or the Force Dimension SDK) sends pose packets; Coiffure answers each with a force
//! packet. All numbers little-endian.
//!
//! Pose packet, 116 bytes: `b"CFP1"`, u32 sequence, f64 time (s), f64 x 3 position (m), f64 x 9 rotation
//! (row-major, tool frame to world), u32 buttons.
//! Force packet, 64 bytes: `b"CFF1"`, u32 sequence (of the pose answered), f64 x 3 force (N), f64 x 3 torque
//! (N m), u32 flags (bit 0: the pose was rejected, force is zero), u32 reserved (0).

use crate::device::{DeviceCommand, DeviceReading, HapticDevice};
use nalgebra::{Matrix3, Vector3};
use std::net::{SocketAddr, UdpSocket};
use thiserror::Error;

/// Size of a pose packet, bytes.
pub const POSE_BYTES: usize = 116;
/// Size of a force packet, bytes.
pub const FORCE_BYTES: usize = 64;

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

/// Encodes a pose packet.
pub fn encode_pose(seq: u32, r: &DeviceReading) -> [u8; POSE_BYTES] {
    let mut b = [0u8; POSE_BYTES];
    b[0..4].copy_from_slice(b"CFP1");
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

/// Decodes a pose packet: (sequence, reading).
pub fn decode_pose(b: &[u8]) -> Result<(u32, DeviceReading), PacketError> {
    if b.len() != POSE_BYTES {
        return Err(PacketError::Size(b.len(), POSE_BYTES));
    }
    if &b[0..4] != b"CFP1" {
        return Err(PacketError::Magic(b[0..4].try_into().unwrap()));
    }
    let position = Vector3::new(f64_at(b, 16), f64_at(b, 24), f64_at(b, 32));
    let rotation = Matrix3::from_fn(|i, j| f64_at(b, 40 + 8 * (3 * i + j)));
    Ok((u32_at(b, 4), DeviceReading { time: f64_at(b, 8), position, rotation, buttons: u32_at(b, 112) }))
}

/// Encodes a force packet.
pub fn encode_force(seq: u32, c: &DeviceCommand, rejected: bool) -> [u8; FORCE_BYTES] {
    let mut b = [0u8; FORCE_BYTES];
    b[0..4].copy_from_slice(b"CFF1");
    b[4..8].copy_from_slice(&seq.to_le_bytes());
    for k in 0..3 {
        b[8 + 8 * k..16 + 8 * k].copy_from_slice(&c.force[k].to_le_bytes());
        b[32 + 8 * k..40 + 8 * k].copy_from_slice(&c.torque[k].to_le_bytes());
    }
    b[56..60].copy_from_slice(&(rejected as u32).to_le_bytes());
    b
}

/// Decodes a force packet: (sequence, command, rejected).
pub fn decode_force(b: &[u8]) -> Result<(u32, DeviceCommand, bool), PacketError> {
    if b.len() != FORCE_BYTES {
        return Err(PacketError::Size(b.len(), FORCE_BYTES));
    }
    if &b[0..4] != b"CFF1" {
        return Err(PacketError::Magic(b[0..4].try_into().unwrap()));
    }
    let force = Vector3::new(f64_at(b, 8), f64_at(b, 16), f64_at(b, 24));
    let torque = Vector3::new(f64_at(b, 32), f64_at(b, 40), f64_at(b, 48));
    Ok((u32_at(b, 4), DeviceCommand { force, torque }, u32_at(b, 56) & 1 == 1))
}

/// The Coiffure side: a non-blocking UDP socket; `read` takes the newest valid pose received, `write` answers
/// the last sender. Malformed packets are counted and dropped.
pub struct UdpDevice {
    socket: UdpSocket,
    peer: Option<SocketAddr>,
    last: Option<(u32, DeviceReading)>,
    /// Malformed packets dropped so far.
    pub malformed: u64,
}

impl UdpDevice {
    /// Binds `addr` (e.g. "127.0.0.1:0" for any free port).
    pub fn bind(addr: &str) -> std::io::Result<Self> {
        let socket = UdpSocket::bind(addr)?;
        socket.set_nonblocking(true)?;
        Ok(Self { socket, peer: None, last: None, malformed: 0 })
    }

    /// The bound address.
    pub fn local_addr(&self) -> std::io::Result<SocketAddr> {
        self.socket.local_addr()
    }
}

impl HapticDevice for UdpDevice {
    fn read(&mut self, _time: f64) -> Option<DeviceReading> {
        let mut buf = [0u8; 512];
        loop {
            match self.socket.recv_from(&mut buf) {
                Ok((n, from)) => match decode_pose(&buf[..n]) {
                    Ok(p) => {
                        self.last = Some(p);
                        self.peer = Some(from);
                    }
                    Err(_) => self.malformed += 1,
                },
                Err(_) => break,
            }
        }
        self.last.map(|(_, r)| r)
    }

    fn write(&mut self, command: &DeviceCommand) {
        if let (Some(peer), Some((seq, _))) = (self.peer, self.last) {
            let ok = command.force.iter().chain(command.torque.iter()).all(|x| x.is_finite());
            let safe = if ok { *command } else { DeviceCommand::default() };
            let _ = self.socket.send_to(&encode_force(seq, &safe, !ok), peer);
        }
    }
}

/// Reference client (what a device program does): sends poses, receives forces. Used by the tests.
pub struct UdpClient {
    socket: UdpSocket,
    seq: u32,
}

impl UdpClient {
    /// Connects to a Coiffure UDP device at `server`.
    pub fn connect(server: SocketAddr) -> std::io::Result<Self> {
        let socket = UdpSocket::bind("127.0.0.1:0")?;
        socket.connect(server)?;
        socket.set_read_timeout(Some(std::time::Duration::from_millis(200)))?;
        Ok(Self { socket, seq: 0 })
    }

    /// Sends a pose; returns its sequence number.
    pub fn send(&mut self, r: &DeviceReading) -> std::io::Result<u32> {
        self.seq = self.seq.wrapping_add(1);
        self.socket.send(&encode_pose(self.seq, r))?;
        Ok(self.seq)
    }

    /// Waits (up to 200 ms) for a force packet.
    pub fn receive(&mut self) -> std::io::Result<(u32, DeviceCommand, bool)> {
        let mut buf = [0u8; 128];
        let n = self.socket.recv(&mut buf)?;
        decode_force(&buf[..n]).map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidData, e))
    }

    /// Sends raw bytes (to test malformed input).
    pub fn send_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.socket.send(bytes).map(|_| ())
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
        assert_eq!(decode_force(&encode_force(7, &c, true)).unwrap(), (7, c, true));
    }

    #[test]
    fn round_trip_over_loopback() {
        // A client streams poses to the UDP device over 127.0.0.1; the device answers each with the force
        // computed from it (here: a spring towards the origin), echoing the sequence number. A malformed
        // packet is dropped and counted, and the stream goes on.
        let mut dev = UdpDevice::bind("127.0.0.1:0").unwrap();
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
            let (s, cmd, rejected) = client.receive().unwrap();
            assert_eq!(s, seq);
            assert!(!rejected);
            assert!((cmd.force.x + 0.1 * i as f64).abs() < 1e-12);
        }
        assert_eq!(dev.malformed, 1);
    }
}
