//! The server's shared state ([`App`]): the live session and its scene, the connected viewers and who controls
//! the tool, and the latest state a SAVE writes.

use super::access::Access;
use crate::delivery::{DeliveryStats, Frame, PublishLog};
use crate::outbox::Outbox;
use crate::protocol::{self, WireError};
use engine::record::RecordStatus;
use engine::session::{Command, HapticSnapshot, LatticeSnapshot, Scene, SceneOptions, Session, SessionParams};
use haptics::backends::VirtualHandle;
use haptics::device::HapticDevice;
use haptics::udp::{UdpDevice, UdpStatus};
use nalgebra::Vector3;
use std::sync::atomic::AtomicU64;
use std::sync::mpsc::Sender;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::watch;
use triple_buffer::Output;

/// Who is connected and who controls the tool.
pub(super) struct Control {
    /// The viewer in control (its id), if any.
    pub controller: Option<u64>,
    /// Every connected viewer's outgoing queue.
    pub viewers: Vec<Arc<Outbox>>,
}

/// The server's shared state: the live session and its scene, the viewers, the latest state for SAVE.
pub(super) struct App {
    /// The SCENE message of the live scene (sent to every new viewer).
    pub scene_msg: Mutex<Arc<Vec<u8>>>,
    /// The live scene (replaced when a hairstyle is loaded).
    pub scene: Mutex<Arc<Scene>>,
    /// The latest FRAME, published by the frame thread.
    pub frames: watch::Receiver<Arc<Frame>>,
    /// How on time the writers hand FRAMEs on (their pickup delays).
    pub delivery: DeliveryStats,
    /// When the latest FRAMEs were published (for the writers' pickup delays).
    pub published: PublishLog,
    /// The mouse's virtual device of the live session (POSE messages push readings into it).
    pub device: Mutex<VirtualHandle>,
    /// The live session's command queue (tool, wetness, dryer, reset...).
    pub commands: Mutex<Sender<Command>>,
    /// The viewers and who controls the tool.
    pub control: Mutex<Control>,
    /// The next viewer's id.
    pub next_id: AtomicU64,
    /// When the server started (POSE readings' clock).
    pub started: Instant,
    /// The latest lattice nodes (head frame, m), for SAVE.
    pub latest_lattice: Mutex<Vec<[f32; 3]>>,
    /// The head pose of the latest lattice (head frame to world).
    pub latest_head: Mutex<nalgebra::Isometry3<f64>>,
    /// The latest guides' state from the frame thread (for SAVE and new viewers).
    pub latest_guides: Mutex<LatestGuides>,
    /// Options of the built-in scene (head, guides, lattice cell) a loaded hairstyle is put on.
    pub opts: SceneOptions,
    /// Parameters every session of this server starts with.
    pub params: SessionParams,
    /// The running session (replaced when a hairstyle file is loaded).
    pub session: Mutex<Option<Session>>,
    /// A new session's snapshot outputs, for the frame thread to take over.
    pub swap: Mutex<Option<(Output<LatticeSnapshot>, Output<HapticSnapshot>)>>,
    /// `--device`: the UDP device each session reads (a clone on the same socket), and its counters.
    pub udp: Option<(UdpDevice, Arc<UdpStatus>)>,
    /// Who may open `/ws`.
    pub access: Access,
    /// When the last SAVE was served.
    pub last_save: Mutex<Option<Instant>>,
    /// Held while a LOAD reads, fits and builds (one at a time: a second is refused, not queued).
    pub loading: Mutex<()>,
    /// A viewer's time limit (`--viewer-timeout`).
    pub viewer_timeout: Duration,
    /// The record's status with `--record` (its stop is told to every viewer, ERROR 7).
    pub record: Option<Arc<RecordStatus>>,
}

/// Shortest time between two SAVEs (each writes the whole hairstyle).
pub const SAVE_INTERVAL: Duration = Duration::from_secs(1);

impl App {
    /// The device a new session reads: the UDP device's clone with `--device`, else None (the mouse).
    pub fn session_device(&self) -> Result<Option<Box<dyn HapticDevice>>, String> {
        match &self.udp {
            Some((d, _)) => d.try_clone().map(|d| Some(Box::new(d) as Box<dyn HapticDevice>)).map_err(|e| format!("cannot share the device socket: {e}")),
            None => Ok(None),
        }
    }

    /// The viewers now. Messages are posted outside the control lock, which the frame thread also takes:
    /// nobody holds it for long.
    pub fn viewers(&self) -> Vec<Arc<Outbox>> {
        self.control.lock().unwrap().viewers.clone()
    }

    /// Posts `msg` to every viewer.
    pub fn broadcast(&self, msg: &[u8]) {
        for v in self.viewers() {
            v.post(msg.to_vec());
        }
    }

    /// Tells every viewer whether it controls the tool, and how many watch.
    pub fn broadcast_control(&self) {
        let c = self.control.lock().unwrap();
        let n = c.viewers.len() as u32;
        for v in &c.viewers {
            v.post(protocol::encode_control(c.controller == Some(v.id), n));
        }
    }
}

/// The latest guides' state the frame thread saw: what a SAVE needs besides the lattice, and the kept points a
/// new viewer is sent.
#[derive(Debug, Clone)]
pub(super) struct LatestGuides {
    /// Points kept per guide after the scissors (`LatticeSnapshot::kept`; empty before the first frame).
    pub kept: Arc<Vec<u16>>,
    /// The guides simulated by the local layer now.
    pub active: Vec<u32>,
    /// Their displacements from where the lattice carries them, `samples` per active guide, m.
    pub displacement: Vec<Vector3<f64>>,
    /// Samples per active guide (at least 2).
    pub samples: usize,
}

impl Default for LatestGuides {
    fn default() -> Self {
        Self { kept: Arc::new(Vec::new()), active: Vec::new(), displacement: Vec::new(), samples: 2 }
    }
}

/// ERROR 7: recording stopped before the session ended, and why (the session goes on).
pub(super) fn record_stopped(why: &str) -> Vec<u8> {
    protocol::encode_error(&WireError { code: protocol::code::RECORD, message: format!("recording stopped: {why}") })
}
