//! One viewer's WebSocket: the upgrade after the access checks, then a writer task (queued messages, then the
//! latest FRAME) and a reader loop (the viewer's messages, answered by `handlers`), and why it is closed.

use super::access::check_access;
use super::app::{record_stopped, App};
use crate::outbox::{CloseReason, Outbox, FRAME_WINDOW};
use std::collections::VecDeque;
use crate::protocol::{self, WireError};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::response::IntoResponse;
use futures_util::{SinkExt, StreamExt};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The WebSocket upgrade, after the access checks ([`check_access`]); messages and frames up to 64 MiB.
pub(super) async fn ws_handler(ws: WebSocketUpgrade, headers: axum::http::HeaderMap, query: axum::extract::Query<std::collections::HashMap<String, String>>, State(app): State<Arc<App>>) -> axum::response::Response {
    if let Err(why) = check_access(&headers, query.get("token").map(String::as_str), &app.access) {
        tracing::warn!("refused a WebSocket: {why}");
        return (axum::http::StatusCode::FORBIDDEN, why).into_response();
    }
    // The largest message is a LOAD of the largest file (its 2-byte header and 9 bytes of format and options).
    let max = app.opts.load.max_file_bytes + 16;
    ws.max_message_size(max).max_frame_size(max).on_upgrade(move |socket| viewer(socket, app)).into_response()
}

/// One viewer: sends the scene, then frames; handles its messages. Its outgoing messages go through its
/// [`Outbox`] (bounded; FRAMEs are not queued: the writer takes the latest when free); a viewer that falls
/// behind or overflows its queue is disconnected with a close reason (policy violation, 1008), and a message
/// over the size limit is answered by ERROR 1 and a close (message too big, 1009).
async fn viewer(socket: WebSocket, app: Arc<App>) {
    let id = app.next_id.fetch_add(1, Ordering::Relaxed);
    let (mut sink, mut stream) = socket.split();
    let outbox = Arc::new(Outbox::new(id, app.viewer_timeout));
    {
        let mut c = app.control.lock().unwrap();
        c.viewers.push(outbox.clone());
        if c.controller.is_none() {
            c.controller = Some(id);
        }
    }
    // The scene and the strands' kept points (all uncut until the first cut), queued first.
    outbox.post((**app.scene_msg.lock().unwrap()).clone());
    let kept = app.latest_guides.lock().unwrap().kept.clone();
    if !kept.is_empty() {
        outbox.post(protocol::encode_strands(&kept));
    }
    if let Some((_, status)) = &app.udp {
        outbox.post(protocol::encode_device(&status.counts()));
    }
    if let Some(why) = app.record.as_ref().and_then(|r| r.stopped()) {
        outbox.post(record_stopped(why));
    }
    app.broadcast_control();
    let mut frames = app.frames.clone();
    let (app_w, out_w) = (app.clone(), outbox.clone());
    let mut closing_w = outbox.closing();
    let mut writer = tokio::spawn(async move {
        // Queued messages first (a STRANDS precedes the FRAME carrying its version), then the latest frame.
        let mut cut = false;
        // Since when the writer has been free to send (its pickup delays are measured from it).
        let mut free_since = Instant::now();
        let mut last_seq = None;
        // FRAMEs sent and not yet acknowledged, oldest first: a viewer that acknowledges gets at most FRAME_WINDOW
        // of them. They are kept (the last few) before its first acknowledgement too, so that the frames already
        // on their way when it starts count against its window.
        let mut in_flight: VecDeque<u32> = VecDeque::new();
        loop {
            let mut frame_seq = None;
            let acked = out_w.acked();
            if let Some(a) = acked {
                while in_flight.front().is_some_and(|&s| s <= a) {
                    in_flight.pop_front();
                }
            }
            let window_full = acked.is_some() && in_flight.len() >= FRAME_WINDOW;
            let bytes = match out_w.pop() {
                Some(m) => m,
                None if out_w.closes_after_queue() => {
                    out_w.close_now();
                    break;
                }
                None => tokio::select! {
                    // The viewer is behind: the writer waits for its acknowledgement, then sends the newest
                    // frame (the wait is the viewer's, not a pickup delay of the server's).
                    _ = out_w.ack_arrived(), if window_full => {
                        free_since = Instant::now();
                        continue;
                    }
                    changed = frames.changed(), if !window_full => {
                        if changed.is_err() { break; }
                        let f = frames.borrow_and_update().clone();
                        if f.bytes.is_empty() { continue; }
                        let seq = protocol::frame_seq(&f.bytes).expect("a FRAME holds its sequence number");
                        app_w.delivery.pickup(&app_w.published, seq, f.published, last_seq, free_since);
                        last_seq = Some(seq);
                        frame_seq = Some(seq);
                        let mut bytes = f.bytes.clone();
                        let you = app_w.control.lock().map(|c| c.controller == Some(id)).unwrap_or(false);
                        bytes[protocol::FRAME_FLAGS_OFFSET] = you as u8;
                        bytes
                    }
                    _ = out_w.ready() => continue,
                    _ = closing_w.wait_for(Option::is_some) => break,
                },
            };
            out_w.sending(true);
            let sent = tokio::select! {
                r = sink.send(Message::Binary(bytes.into())) => r.is_ok(),
                _ = closing_w.wait_for(Option::is_some) => { cut = true; false }
            };
            out_w.sending(false);
            free_since = Instant::now();
            if !sent {
                break;
            }
            if let Some(seq) = frame_seq {
                in_flight.push_back(seq);
                if in_flight.len() > 4 * FRAME_WINDOW {
                    in_flight.pop_front();
                }
            }
        }
        // Say why, unless a send was cut half way (the stream is then broken) or the socket failed.
        let reason = closing_w.borrow().clone();
        if let (Some(reason), false) = (reason, cut) {
            let close = Message::Close(Some(axum::extract::ws::CloseFrame { code: reason.code(), reason: reason.text().chars().take(120).collect::<String>().into() }));
            let _ = tokio::time::timeout(Duration::from_secs(1), sink.send(close)).await;
        }
    });
    let mut closing = outbox.closing();
    let mut tick = tokio::time::interval(Duration::from_millis(250));
    loop {
        // Stop when the socket fails (the writer ends), the viewer is behind or its queue overflowed.
        let msg = tokio::select! {
            m = stream.next() => match m {
                Some(Ok(m)) => m,
                // Over the size limit (tungstenite's capacity error; the stream cannot go on): ERROR 1 naming the
                // limit, then a close. Other errors: the socket failed.
                Some(Err(e)) if over_size_limit(&e) => {
                    let limit = app.opts.load.max_file_bytes + 16;
                    let text = format!("message of more than {limit} bytes, the limit (a LOAD of a file up to {} MiB): {e}", app.opts.load.max_file_bytes >> 20);
                    outbox.post(protocol::encode_error(&WireError { code: protocol::code::MALFORMED, message: text.clone() }));
                    outbox.disconnect_after_queue(CloseReason::TooBig(text));
                    break;
                }
                Some(Err(_)) | None => break,
            },
            _ = &mut writer => break,
            _ = closing.wait_for(Option::is_some) => break,
            _ = tick.tick() => {
                if let Some(why) = outbox.behind() {
                    outbox.disconnect(why);
                }
                continue;
            }
        };
        let reply = match msg {
            // LOAD and SAVE parse, fit and build scenes for up to seconds: on a blocking thread, so that the
            // runtime's workers keep serving the other viewers.
            Message::Binary(b) if matches!(b.first(), Some(&protocol::client::LOAD) | Some(&protocol::client::SAVE)) => {
                let app = app.clone();
                tokio::task::spawn_blocking(move || {
                    crate::delivery::normal_priority();
                    super::handlers::handle(&app, id, &b)
                })
                .await.unwrap_or_else(|_| Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message: "the file operation failed".into() })))
            }
            Message::Binary(b) => super::handlers::handle(&app, id, &b),
            Message::Text(_) => Some(protocol::encode_error(&WireError { code: protocol::code::TEXT, message: "text frames are not part of the protocol; send binary messages (docs/protocol.md)".into() })),
            Message::Close(_) => break,
            _ => None,
        };
        if let Some(r) = reply {
            outbox.post(r);
        }
    }
    // A disconnected viewer's writer says why (at most a second for the close); otherwise it is stopped.
    leave(&app, id);
    let kicked = outbox.closing().borrow().is_some() || outbox.closes_after_queue();
    if !kicked || tokio::time::timeout(Duration::from_secs(2), &mut writer).await.is_err() {
        writer.abort();
    }
}

/// Removes viewer `id`; control passes to the first viewer left, and everyone is told.
fn leave(app: &App, id: u64) {
    {
        let mut c = app.control.lock().unwrap();
        c.viewers.retain(|v| v.id != id);
        if c.controller == Some(id) {
            c.controller = c.viewers.first().map(|v| v.id);
        }
    }
    app.broadcast_control();
}

/// A read failed because the message was over the size limit (tungstenite's capacity error, after which the
/// stream cannot go on), not because the socket failed.
fn over_size_limit(e: &axum::Error) -> bool {
    std::error::Error::source(e).and_then(|s| s.downcast_ref::<tungstenite::Error>()).is_some_and(|t| matches!(t, tungstenite::Error::Capacity(_)))
}
