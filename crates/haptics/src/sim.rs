//! A simulated device and hand speaking the UDP protocol (`coiffure device-sim`, the end-to-end tests): the
//! end-effector follows a scripted path (given in the head frame, mapped into the device's workspace), either
//! exactly or pulled by a hand modelled as a spring-damper, with the device's own mass and damping and the
//! force Coiffure sends back acting on it. Every pose sent is kept with what came back.
//!
//! Dynamics of the end-effector (device frame, semi-implicit Euler at the stream's rate):
//! `m a = k_h (x_path - x) + b_h (v_path - v) - b_d v + F`, with `m`, `b_d` the profile's `mass` and
//! `damping`, `k_h`, `b_h` the hand's stiffness and damping, and `F` the force the hand feels: the latest force
//! received (zero when none arrived for 50 ms, as a device program must do), or with [`SimParams::render`] the
//! device's own rendering at its rate of the local force model the answers carry (protocol version 2,
//! [`crate::local_model`]): the same [`Coupling`] as the server's, against the latest model, which holds until
//! a newer one comes or expires 50 ms after its answer (then no hair: the proxy settles on the device and the
//! force fades through the coupling); each new model is phased in over its validity ([`crate::model_blend`]).
//!
//! The device samples on its own clock, as a device's servo loop does: pose `k` is the path at `k / rate` s,
//! stamped with that time, sent when the loop gets to it (late on a loaded host, several at once after a stall).

use crate::coupling::{Coupling, HairReaction};
use crate::device::{DeviceProfile, DeviceReading};
use crate::local_model::WireModel;
use crate::model_blend::ModelBlend;
use crate::udp::{encode_pose_version, UdpClient};
use crate::workspace::Workspace;
use nalgebra::Vector3;
use std::net::SocketAddr;
use std::time::{Duration, Instant};

/// How the hand moves the end-effector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Hand {
    /// Exactly along the path (a hand infinitely stiff).
    Rigid,
    /// Pulled towards the path by a spring (N/m) and damper (N s/m).
    Spring {
        /// Hand stiffness, N/m.
        stiffness: f64,
        /// Hand damping, N s/m.
        damping: f64,
    },
}

/// Hand stiffness of `--hand spring`, N/m (a relaxed grip: 200-500 N/m).
pub const DEFAULT_HAND_STIFFNESS: f64 = 300.0;
/// Hand damping of `--hand spring`, N s/m.
pub const DEFAULT_HAND_DAMPING: f64 = 3.0;

/// Faults injected into the stream (times in s from the start).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Faults {
    /// Fraction of poses not sent, at random, in [0, 1). Default 0.
    pub loss: f64,
    /// Seed of the loss's random numbers.
    pub seed: u64,
    /// One pose with a NaN position at each of these times.
    pub nan_at: Vec<f64>,
    /// One pose 10 m away at each of these times.
    pub teleport_at: Vec<f64>,
    /// The previous packet sent again at each of these times.
    pub duplicate_at: Vec<f64>,
    /// No poses from `start` for `length` s, for each (start, length).
    pub pause: Vec<(f64, f64)>,
}

/// Parameters of a simulated device run.
#[derive(Debug, Clone, PartialEq)]
pub struct SimParams {
    /// Poses sent per second, Hz, in (0, 10000]. Default 1000.
    pub rate_hz: f64,
    /// Length of the run, s.
    pub duration: f64,
    /// The hand. Default [`Hand::Rigid`].
    pub hand: Hand,
    /// The device (mass and damping of its end-effector).
    pub profile: DeviceProfile,
    /// The map between the device's workspace and the head frame the path is given in.
    pub workspace: Workspace,
    /// Injected faults.
    pub faults: Faults,
    /// Speak protocol version 2 and render the local force model at the stream's rate (the hand feels the
    /// device's own coupling against the latest model) instead of holding the latest force received. Default
    /// false.
    pub render: bool,
}

impl SimParams {
    /// Checks every field; the error names the bad one.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0 && self.rate_hz <= 10_000.0) {
            return Err(format!("rate must be in (0, 10000] Hz, got {}", self.rate_hz));
        }
        if !(self.duration.is_finite() && self.duration > 0.0 && self.duration <= 3600.0) {
            return Err(format!("duration must be in (0, 3600] s, got {}", self.duration));
        }
        if let Hand::Spring { stiffness, damping } = self.hand {
            if !(stiffness.is_finite() && stiffness > 0.0 && damping.is_finite() && damping >= 0.0) {
                return Err(format!("hand stiffness must be > 0 N/m and damping >= 0 N s/m, got {stiffness}, {damping}"));
            }
            if !(self.profile.mass > 0.0) {
                return Err(format!("the {} profile has no mass: use the rigid hand", self.profile.name));
            }
        }
        if !(0.0..1.0).contains(&self.faults.loss) {
            return Err(format!("loss must be in [0, 1), got {}", self.faults.loss));
        }
        let f = &self.faults;
        if !f.nan_at.iter().chain(&f.teleport_at).chain(&f.duplicate_at).chain(f.pause.iter().flat_map(|p| [&p.0, &p.1])).all(|x| x.is_finite() && *x >= 0.0) {
            return Err("fault times must be finite and >= 0 s".into());
        }
        self.workspace.check(&self.profile)
    }
}

/// What a pose was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sent {
    /// A pose of the path.
    Pose,
    /// A pose with a NaN position.
    Nan,
    /// A pose 10 m away.
    Teleport,
    /// The previous packet again.
    Duplicate,
}

/// One pose sent and its answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimRow {
    /// The pose's time on the device's clock, s from the start (its `time` field: the tick it was sampled at).
    pub t: f64,
    /// Sequence number.
    pub seq: u32,
    /// What was sent.
    pub kind: Sent,
    /// End-effector position sent, m (device frame).
    pub position: Vector3<f64>,
    /// Force received in answer, N (device frame); NaN if none came.
    pub force: Vector3<f64>,
    /// Time from sending to the answer, s; NaN if none came.
    pub latency: f64,
    /// Force the hand felt while this pose was sent, N (device frame): the latest force received, or the
    /// rendered one ([`SimParams::render`]).
    pub felt: Vector3<f64>,
    /// Flags of the answer (docs/protocol.md); 0 if none came.
    pub flags: u32,
}

impl SimRow {
    /// True if an answer came.
    pub fn answered(&self) -> bool {
        self.latency.is_finite()
    }
}

/// The CSV header of [`to_csv`].
pub const CSV_HEADER: &str = "t,x,y,z,fx,fy,fz,latency_us,flags,hx,hy,hz";

/// Rows as CSV (`t,x,y,z,fx,fy,fz,latency_us,flags,hx,hy,hz`: s, m device frame, the force answered in N,
/// microseconds, the answer's flags, the force the hand felt in N; `NaN` where no answer came). The time and
/// forces are exact (shortest decimals reading back to the same f64).
pub fn to_csv(rows: &[SimRow]) -> String {
    let mut s = String::with_capacity(64 * rows.len() + 64);
    s.push_str(CSV_HEADER);
    s.push('\n');
    for r in rows {
        let (p, f) = (r.position, r.force);
        let h = r.felt;
        // Time and forces exactly (shortest round-trip decimals): a record's replay is compared with them bit for bit.
        s.push_str(&format!("{},{:.7},{:.7},{:.7},{:e},{:e},{:e},{:.1},{},{:e},{:e},{:e}\n", r.t, p.x, p.y, p.z, f.x, f.y, f.z, r.latency * 1e6, r.flags, h.x, h.y, h.z));
    }
    s
}

/// Records an answer: on the earliest unanswered packet with its sequence number among the last 1024 (a
/// duplicate has its own row after the original's); its force becomes the one felt.
fn answer(rows: &mut [SimRow], sent_at: &[Instant], seq: u32, c: &crate::device::DeviceCommand, flags: u32, force: &mut Vector3<f64>, force_at: &mut Option<Instant>, model: Option<WireModel>, latest: &mut Option<(WireModel, Instant)>) {
    let now = Instant::now();
    let from = rows.len().saturating_sub(1024);
    if let Some(i) = (from..rows.len()).find(|&i| rows[i].seq == seq && !rows[i].answered()) {
        let r = &mut rows[i];
        r.force = c.force;
        r.flags = flags;
        r.latency = (now - sent_at[i]).as_secs_f64();
    }
    *force = if c.force.iter().all(|x| x.is_finite()) { c.force } else { Vector3::zeros() };
    *force_at = Some(now);
    if let Some(m) = model {
        *latest = Some((m, now));
    }
}

/// How long a force or model received holds without a newer one, s (docs/protocol.md "Timing").
const HOLD: Duration = Duration::from_millis(50);

fn due(times: &[f64], t0: f64, t1: f64) -> bool {
    times.iter().any(|&x| x >= t0 && x < t1)
}

/// Runs the device against the Coiffure UDP device at `server` for `p.duration` s, moving along `path`
/// (head-frame readings at a time from the start: position, rotation, buttons), then waits 50 ms for the
/// last answers. Returns one row per packet sent.
pub fn run(server: SocketAddr, path: &dyn Fn(f64) -> DeviceReading, p: &SimParams) -> Result<Vec<SimRow>, String> {
    p.validate()?;
    let mut client = UdpClient::connect(server).map_err(|e| format!("cannot open a UDP socket towards {server}: {e}"))?;
    client.set_nonblocking(true).map_err(|e| e.to_string())?;
    let version = if p.render { 2 } else { 1 };
    client.set_version(version);
    // The device's own rendering (`render`): its coupling (device frame) and the latest model with its arrival.
    let mut model: Option<(WireModel, Instant)> = None;
    let mut coupling: Option<Coupling> = None;
    // The model rendered: the newest phased in over its validity's device steps, as the server's device loop
    // does (`crate::model_blend`), and the number of the newest.
    let mut rendered = ModelBlend::new(HairReaction::none());
    let mut rendered_number: Option<u32> = None;
    let dt = 1.0 / p.rate_hz;
    let ws = p.workspace;
    let (m, b_d) = (p.profile.mass, p.profile.damping);
    let mut x = ws.to_device(&path(0.0).position);
    let mut v = Vector3::zeros();
    let mut last_target = x;
    let mut force = Vector3::zeros();
    let mut force_at: Option<Instant> = None;
    let mut rng = p.faults.seed ^ 0x9e37_79b9_7f4a_7c15;
    let mut rows: Vec<SimRow> = Vec::with_capacity((p.duration * p.rate_hz) as usize + 16);
    let mut sent_at: Vec<Instant> = Vec::with_capacity(rows.capacity());
    let mut last_packet: Option<(u32, DeviceReading)> = None;
    let start = Instant::now();
    let take = |client: &mut UdpClient, rows: &mut Vec<SimRow>, sent_at: &[Instant], force: &mut Vector3<f64>, force_at: &mut Option<Instant>, model: &mut Option<(WireModel, Instant)>| {
        while let Ok((seq, c, flags, m)) = client.receive_model() {
            answer(rows, sent_at, seq, &c, flags, force, force_at, m, model);
        }
    };
    let mut k = 0u64;
    loop {
        let nominal = k as f64 * dt;
        if nominal > p.duration {
            break;
        }
        // Wait for the tick on the socket, so that answers are timed when they arrive.
        let tick = start + Duration::from_secs_f64(nominal);
        take(&mut client, &mut rows, &sent_at, &mut force, &mut force_at, &mut model);
        while let Some(w) = tick.checked_duration_since(Instant::now()).filter(|w| *w > Duration::from_micros(20)) {
            client.set_nonblocking(false).map_err(|e| e.to_string())?;
            client.set_timeout(Some(w)).map_err(|e| e.to_string())?;
            if let Ok((seq, c, flags, m)) = client.receive_model() {
                answer(&mut rows, &sent_at, seq, &c, flags, &mut force, &mut force_at, m, &mut model);
            }
            client.set_nonblocking(true).map_err(|e| e.to_string())?;
        }
        take(&mut client, &mut rows, &sent_at, &mut force, &mut force_at, &mut model);
        // The device samples on its own clock (a device's servo loop: every `dt`, stamped with that clock),
        // whenever this loop gets to send it. Sampled at the wall clock's late wake-ups instead, the rigid hand's
        // steps were uneven on a loaded host while the rendering took them over the nominal `dt`: its velocity,
        // and the coupling's damper force, jumped every step (bench/RESULTS.md, device-sim --render).
        let t = nominal;
        let reading = path(t);
        let target = ws.to_device(&reading.position);
        // The force on the hand: the latest received, or the device's own rendering of the latest model.
        let felt = if p.render {
            let fresh = model.as_ref().filter(|(_, at)| at.elapsed() < HOLD).map(|(m, _)| *m);
            match (fresh, coupling.as_mut()) {
                (Some(m), None) => {
                    coupling = Some(Coupling::new(p.profile, m.coupling, x));
                    Vector3::zeros()
                }
                (m, Some(c)) => {
                    match m {
                        Some(m) if rendered_number != Some(m.number) => {
                            rendered_number = Some(m.number);
                            rendered.take(m.hair, (m.valid_for * p.rate_hz).round().max(1.0) as u32);
                        }
                        Some(_) => {}
                        None => {
                            rendered_number = None;
                            rendered.reset(HairReaction::none());
                        }
                    }
                    let hair = rendered.advance();
                    c.params = m.map_or(c.params, |m| m.coupling);
                    let r = DeviceReading { time: t, position: x, rotation: reading.rotation, buttons: reading.buttons };
                    c.update_implicit(&r, dt, &hair).unwrap_or_default()
                }
                (None, None) => Vector3::zeros(),
            }
        } else if force_at.is_some_and(|a| a.elapsed() < HOLD) {
            force
        } else {
            Vector3::zeros()
        };
        // The device: rigid, or pulled by the hand with that force acting on it.
        match p.hand {
            Hand::Rigid => {
                v = (target - x) / dt;
                x = target;
            }
            Hand::Spring { stiffness, damping } => {
                let target_v = (target - last_target) / dt;
                let a = ((target - x) * stiffness + (target_v - v) * damping - v * b_d + felt) / m;
                v += a * dt;
                x += v * dt;
            }
        }
        last_target = target;
        let (t0, t1) = (nominal - 0.5 * dt, nominal + 0.5 * dt);
        let paused = p.faults.pause.iter().any(|&(s, l)| nominal >= s && nominal < s + l);
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        let lost = (rng >> 11) as f64 / (1u64 << 53) as f64 <= p.faults.loss && p.faults.loss > 0.0;
        k += 1;
        if paused || lost {
            continue;
        }
        let mut r = DeviceReading { time: t, position: x, rotation: reading.rotation, buttons: reading.buttons };
        let kind = if due(&p.faults.nan_at, t0, t1) {
            r.position.x = f64::NAN;
            Sent::Nan
        } else if due(&p.faults.teleport_at, t0, t1) {
            r.position.x += 10.0;
            Sent::Teleport
        } else if due(&p.faults.duplicate_at, t0, t1) && last_packet.is_some() {
            Sent::Duplicate
        } else {
            Sent::Pose
        };
        let sent = if kind == Sent::Duplicate {
            let (s, r) = last_packet.expect("checked");
            client.send_raw(&encode_pose_version(s, &r, version)).map(|()| (s, r))
        } else {
            client.send(&r).map(|s| (s, r))
        };
        let (seq, sent) = match sent {
            Ok(x) => x,
            // The server's port is closed (it stopped or died; the ICMP of an earlier pose comes back here): this
            // pose is lost, as a device's would be, and the stream goes on.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => continue,
            Err(e) => return Err(format!("cannot send to {server}: {e}")),
        };
        sent_at.push(Instant::now());
        rows.push(SimRow { t, seq, kind, position: sent.position, force: Vector3::from_element(f64::NAN), latency: f64::NAN, flags: 0, felt });
        if kind == Sent::Pose {
            last_packet = Some((seq, r));
        }
    }
    let end = Instant::now();
    while end.elapsed() < Duration::from_millis(50) {
        take(&mut client, &mut rows, &sent_at, &mut force, &mut force_at, &mut model);
        std::thread::sleep(Duration::from_millis(1));
    }
    Ok(rows)
}

/// Summary of a run: poses sent, answered, latency quantiles (s), largest force (N), rejected answers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimSummary {
    /// Packets sent.
    pub sent: usize,
    /// Packets answered.
    pub answered: usize,
    /// Round trip, s: 50th, 99th, 99.9th percentile and largest.
    pub latency: [f64; 4],
    /// Largest force received, N.
    pub max_force: f64,
    /// Answers with the rejected flag.
    pub rejected: usize,
}

impl SimSummary {
    /// Summarises `rows`.
    pub fn of(rows: &[SimRow]) -> Self {
        let mut lat: Vec<f64> = rows.iter().filter(|r| r.answered()).map(|r| r.latency).collect();
        lat.sort_by(|a, b| a.total_cmp(b));
        let q = |f: f64| if lat.is_empty() { f64::NAN } else { lat[((f * lat.len() as f64).ceil() as usize).clamp(1, lat.len()) - 1] };
        let max_force = rows.iter().filter(|r| r.answered()).map(|r| r.force.norm()).fold(0.0, f64::max);
        Self { sent: rows.len(), answered: lat.len(), latency: [q(0.5), q(0.99), q(0.999), q(1.0)], max_force, rejected: rows.iter().filter(|r| r.flags & crate::udp::FLAG_REJECTED != 0).count() }
    }
}

impl std::fmt::Display for SimSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let l = self.latency.map(|x| x * 1e6);
        write!(
            f,
            "{} poses sent, {} answered ({:.1} %), round trip p50 {:.0} us, p99 {:.0} us, p99.9 {:.0} us, max {:.0} us; largest force {:.3} N; {} rejected",
            self.sent, self.answered, 100.0 * self.answered as f64 / self.sent.max(1) as f64, l[0], l[1], l[2], l[3], self.max_force, self.rejected
        )
    }
}
