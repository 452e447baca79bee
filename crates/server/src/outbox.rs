//! One viewer's outgoing queue (issue 16): bounded in messages, bytes and time, coalescing what only the
//! latest of matters. FRAMEs are not queued (each viewer's writer takes the latest frame when it is free, so a
//! slow viewer skips frames). A viewer whose queue overflows, or that stays behind (a message waiting, or a
//! send not finishing) for its time limit (`coiffure serve --viewer-timeout`, default [`BEHIND_LIMIT`]), is
//! disconnected with a close reason.

use crate::protocol::server;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};
use tokio::sync::{watch, Notify};

/// Most messages a viewer's queue holds (STRANDS, CONTROL, FIT, ERROR, PONG, FILE, SCENE, DEVICE).
pub const OUTBOX_CAPACITY: usize = 256;
/// Most bytes a viewer's queue holds: a SCENE and a FILE of the largest hairstyle fit (a 100,000-strand SCENE
/// is about 21 MB, its `.usda` FILE 33 MB).
pub const OUTBOX_BYTES: usize = 96 << 20;
/// Default time limit of a viewer: with a message waiting this long, or a send not finished after this long,
/// it is disconnected. Long, because a browser busy building a large scene in software rendering may not
/// read for seconds (frames are skipped meanwhile; only the queue waits).
pub const BEHIND_LIMIT: Duration = Duration::from_secs(30);

/// Most FRAMEs on their way to a viewer that acknowledges them (FRAME_ACK): sent and not yet acknowledged.
/// Two: at 60 fps the next FRAME is sent while the viewer handles one (a viewer that keeps up never waits); a
/// viewer that stalls (a busy page) holds at most two stale FRAMEs, then gets the newest, instead of handling a
/// socket's backlog of seconds-old ones (their force drove the mouse's pseudo-haptics with a stale value).
pub const FRAME_WINDOW: usize = 2;

/// Messages of which only the latest matters: a newer one replaces a queued one (moved to the back).
const LATEST_ONLY: [u8; 3] = [server::CONTROL, server::DEVICE, server::STRANDS];
/// Messages a new SCENE makes stale (they describe the previous hairstyle).
const STALE_AFTER_SCENE: [u8; 3] = [server::SCENE, server::STRANDS, server::FIT];

/// Why a viewer is disconnected: the WebSocket close code it is sent and the reason's text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CloseReason {
    /// A message over the size limit: close 1009 (message too big).
    TooBig(String),
    /// The viewer does not keep up (behind for its time limit, or its queue overflowed): close 1008 (policy
    /// violation).
    Behind(String),
}

impl CloseReason {
    /// The WebSocket close code (RFC 6455, section 7.4.1).
    pub fn code(&self) -> u16 {
        match self {
            CloseReason::TooBig(_) => 1009,
            CloseReason::Behind(_) => 1008,
        }
    }

    /// The reason's text.
    pub fn text(&self) -> &str {
        match self {
            CloseReason::TooBig(t) | CloseReason::Behind(t) => t,
        }
    }
}

impl std::fmt::Display for CloseReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.text())
    }
}

#[derive(Default)]
struct Queue {
    items: VecDeque<(Instant, Vec<u8>)>,
    bytes: usize,
}

/// A viewer's outgoing queue, shared by the posters (frame thread, other viewers' tasks) and its writer.
pub struct Outbox {
    /// The viewer's id.
    pub id: u64,
    queue: Mutex<Queue>,
    ready: Notify,
    /// Why the viewer is being disconnected (None while it is not).
    close: watch::Sender<Option<CloseReason>>,
    /// A reason to disconnect once the queue is sent (a last ERROR goes out first).
    close_after: Mutex<Option<CloseReason>>,
    /// When the send in progress started, ms after `epoch` plus 1 (0: none in progress).
    sending_since: AtomicU64,
    epoch: Instant,
    /// Time limit of [`Outbox::behind`].
    limit: Duration,
    /// The sequence number of the latest FRAME the viewer acknowledged, plus one (0: it never has).
    acked: AtomicU64,
    /// Wakes the writer on an acknowledgement.
    ack: Notify,
}

impl Outbox {
    /// An empty queue for viewer `id`, disconnected when behind for `limit`.
    pub fn new(id: u64, limit: Duration) -> Self {
        Self { limit, id, queue: Mutex::new(Queue::default()), ready: Notify::new(), close: watch::channel(None).0, close_after: Mutex::new(None), sending_since: AtomicU64::new(0), epoch: Instant::now(), acked: AtomicU64::new(0), ack: Notify::new() }
    }

    /// Queues `msg` (coalescing, see the module); a queue over [`OUTBOX_CAPACITY`] messages or
    /// [`OUTBOX_BYTES`] bytes disconnects the viewer.
    pub fn post(&self, msg: Vec<u8>) {
        if self.close.borrow().is_some() {
            return;
        }
        let over = {
            let mut q = self.queue.lock().unwrap();
            let kind = msg.first().copied().unwrap_or(0);
            let stale = |k: u8| (LATEST_ONLY.contains(&kind) && k == kind) || (kind == server::SCENE && STALE_AFTER_SCENE.contains(&k));
            let before = q.items.len();
            q.items.retain(|(_, m)| !stale(m[0]));
            if q.items.len() != before {
                q.bytes = q.items.iter().map(|(_, m)| m.len()).sum();
            }
            q.bytes += msg.len();
            q.items.push_back((Instant::now(), msg));
            (q.items.len() > OUTBOX_CAPACITY || q.bytes > OUTBOX_BYTES).then(|| (q.items.len(), q.bytes))
        };
        match over {
            Some((n, bytes)) => self.disconnect(CloseReason::Behind(format!("outgoing queue full ({n} messages, {bytes} bytes; at most {OUTBOX_CAPACITY} and {OUTBOX_BYTES}): the viewer does not read"))),
            None => self.ready.notify_one(),
        }
    }

    /// The next queued message, if any.
    pub fn pop(&self) -> Option<Vec<u8>> {
        let mut q = self.queue.lock().unwrap();
        let (_, m) = q.items.pop_front()?;
        q.bytes -= m.len();
        Some(m)
    }

    /// Waits until a message may have been queued.
    pub async fn ready(&self) {
        self.ready.notified().await
    }

    /// The viewer has finished with FRAME `seq` (FRAME_ACK); acknowledgements never go back.
    pub fn ack(&self, seq: u32) {
        self.acked.fetch_max(seq as u64 + 1, Ordering::Relaxed);
        self.ack.notify_one();
    }

    /// The latest FRAME the viewer acknowledged; None if it never has (it is then sent every frame its writer
    /// can, with no window).
    pub fn acked(&self) -> Option<u32> {
        self.acked.load(Ordering::Relaxed).checked_sub(1).map(|s| s as u32)
    }

    /// Waits until an acknowledgement may have arrived.
    pub async fn ack_arrived(&self) {
        self.ack.notified().await
    }

    /// Bytes queued now.
    #[cfg(test)]
    pub fn bytes(&self) -> usize {
        self.queue.lock().unwrap().bytes
    }

    /// Marks the viewer for disconnection with `reason` (the first reason stays), and frees its queue.
    pub fn disconnect(&self, reason: CloseReason) {
        let first = self.close.send_if_modified(|r| r.is_none() && {
            *r = Some(reason.clone());
            true
        });
        if first {
            tracing::warn!("viewer {}: disconnected: {reason}", self.id);
            *self.queue.lock().unwrap() = Queue::default();
        }
    }

    /// Marks the viewer for disconnection with `reason` once what is queued is sent ([`Outbox::close_now`]).
    pub fn disconnect_after_queue(&self, reason: CloseReason) {
        self.close_after.lock().unwrap().get_or_insert(reason);
        self.ready.notify_one();
    }

    /// A disconnection waits for the queue to be sent.
    pub fn closes_after_queue(&self) -> bool {
        self.close_after.lock().unwrap().is_some()
    }

    /// The queue is sent: the disconnection of [`Outbox::disconnect_after_queue`] happens now.
    pub fn close_now(&self) {
        if let Some(r) = self.close_after.lock().unwrap().take() {
            self.disconnect(r);
        }
    }

    /// A receiver that sees the close reason when the viewer is marked for disconnection.
    pub fn closing(&self) -> watch::Receiver<Option<CloseReason>> {
        self.close.subscribe()
    }

    /// Notes that a send started (`true`) or ended (`false`).
    pub fn sending(&self, on: bool) {
        let v = if on { self.epoch.elapsed().as_millis() as u64 + 1 } else { 0 };
        self.sending_since.store(v, Ordering::Relaxed);
    }

    /// Why the viewer is behind, if it has been for its limit: a message waiting or a send unfinished.
    pub fn behind(&self) -> Option<CloseReason> {
        let since = self.sending_since.load(Ordering::Relaxed);
        let now = self.epoch.elapsed();
        if since > 0 && now.saturating_sub(Duration::from_millis(since - 1)) > self.limit {
            return Some(CloseReason::Behind(format!("a send has not finished for {} s: the viewer does not keep up", self.limit.as_secs_f64())));
        }
        let oldest = self.queue.lock().unwrap().items.front().map(|(t, _)| t.elapsed());
        oldest.filter(|&a| a > self.limit).map(|a| CloseReason::Behind(format!("a message has waited {:.1} s: the viewer does not keep up", a.as_secs_f64())))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msg(kind: u8, len: usize) -> Vec<u8> {
        let mut m = vec![kind, 1];
        m.resize(len, 0);
        m
    }

    #[test]
    fn latest_only_messages_coalesce_and_a_scene_drops_the_stale_ones() {
        let o = Outbox::new(1, BEHIND_LIMIT);
        o.post(msg(server::PONG, 6));
        o.post(msg(server::CONTROL, 7));
        o.post(msg(server::STRANDS, 10));
        o.post(msg(server::CONTROL, 7));
        o.post(msg(server::PONG, 6));
        assert_eq!(o.bytes(), 6 + 10 + 7 + 6);
        let kinds = |o: &Outbox| std::iter::from_fn(|| o.pop()).map(|m| m[0]).collect::<Vec<_>>();
        assert_eq!(kinds(&o), [server::PONG, server::STRANDS, server::CONTROL, server::PONG]);
        assert_eq!(o.bytes(), 0);
        o.post(msg(server::SCENE, 100));
        o.post(msg(server::STRANDS, 10));
        o.post(msg(server::FIT, 84));
        o.post(msg(server::ERROR, 20));
        o.post(msg(server::SCENE, 100));
        assert_eq!(kinds(&o), [server::ERROR, server::SCENE]);
    }

    #[test]
    fn an_overflowing_queue_disconnects_and_is_freed() {
        let o = Outbox::new(2, BEHIND_LIMIT);
        let closing = o.closing();
        for _ in 0..OUTBOX_CAPACITY {
            o.post(msg(server::PONG, 6));
        }
        assert!(closing.borrow().is_none());
        o.post(msg(server::PONG, 6));
        assert!(closing.borrow().as_ref().is_some_and(|r| r.code() == 1008 && r.text().contains("outgoing queue full")));
        assert_eq!(o.bytes(), 0, "freed");
        o.post(msg(server::PONG, 6));
        assert_eq!(o.bytes(), 0, "nothing queued after");
        // Bytes: two messages over the byte bound.
        let o = Outbox::new(3, BEHIND_LIMIT);
        o.post(msg(server::FILE, OUTBOX_BYTES / 2));
        assert!(o.closing().borrow().is_none());
        o.post(msg(server::FILE, OUTBOX_BYTES / 2 + 1));
        assert!(o.closing().borrow().is_some());
    }

    #[test]
    fn a_viewer_is_behind_when_a_send_or_a_message_waits_too_long() {
        let mut o = Outbox::new(4, BEHIND_LIMIT);
        assert!(o.behind().is_none());
        o.sending(true);
        assert!(o.behind().is_none(), "just started");
        o.epoch -= BEHIND_LIMIT + Duration::from_millis(50);
        o.sending_since.store(1, Ordering::Relaxed); // started at the epoch, 3.05 s ago
        assert!(o.behind().is_some_and(|r| r.code() == 1008 && r.text().contains("send has not finished")));
        o.sending(false);
        assert!(o.behind().is_none());
        o.queue.lock().unwrap().items.push_back((Instant::now() - BEHIND_LIMIT - Duration::from_millis(1), msg(server::PONG, 6)));
        assert!(o.behind().is_some_and(|r| r.code() == 1008 && r.text().contains("has waited")));
    }
}
