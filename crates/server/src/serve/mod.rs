//! `coiffure serve`: the live session behind an HTTP server (the built viewer) and a WebSocket (`/ws`, binary
//! protocol in docs/protocol.md). One frame pump thread reads the session's latest snapshots at the frame
//! rate, encodes one FRAME message and hands it to every viewer; each viewer's task sends it on. Several
//! viewers may watch; the first to connect controls the tool until it leaves or another sends TAKE_CONTROL.
//!
//! Files: `config` (arguments and their validation), `access` (who may connect), `app` (the shared state),
//! `pump` (the frame thread), `viewer` (one WebSocket), `handlers` (the viewers' messages), `report` (the
//! end-of-run figures).

mod access;
mod app;
mod config;
mod handlers;
mod pump;
mod report;
mod viewer;

pub use config::{parse_device, ServeArgs};

use crate::delivery::{DeliveryStats, Frame, PublishLog};
use crate::protocol;
use anyhow::{anyhow, Context};
use app::{App, Control, LatestGuides};
use axum::routing::get;
use axum::Router;
use config::Config;
use engine::record::{RecordFile, RecordSettings, RecordTarget};
use engine::session::{Scene, Session, SessionIo};
use haptics::device::HapticDevice;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::watch;
use tower_http::services::ServeDir;

/// Runs the server until Ctrl-C (or `--duration`). Stages: 1. check the arguments and bind the device
/// ([`Config::from_args`]); 2. build the built-in scene and start the session (recording with `--record`);
/// 3. start the frame thread ([`pump::spawn`]); 4. serve HTTP and the WebSocket until the end; 5. stop the
/// frame thread and the session and print the report ([`report::print`]).
pub fn run(args: &ServeArgs) -> anyhow::Result<()> {
    let Config { web, access, viewer_timeout, opts, params, haptic_priority, udp } = Config::from_args(args)?;
    let t0 = Instant::now();
    let scene = Arc::new(Scene::builtin(&opts).context("building the built-in scene")?);
    tracing::info!("scene: {} render strands, {} guides, {} lattice nodes, built in {:.2} s", scene.render.strands(), scene.guides.len(), scene.lattice.node_count(), t0.elapsed().as_secs_f64());
    let first_device = match &udp {
        Some((d, _)) => Some(Box::new(d.try_clone()?) as Box<dyn HapticDevice>),
        None => None,
    };
    let record = match &args.record {
        Some(path) => Some(RecordTarget {
            sink: Box::new(RecordFile::create(path).with_context(|| format!("cannot create the record {}", path.display()))?),
            settings: Some(RecordSettings::of(&opts, &params)),
        }),
        None => None,
    };
    let (session, io) = Session::start_recording(scene.clone(), params, first_device, record).context("starting the session")?;
    let record_status = session.record_status();
    let SessionIo { device, commands, lattice, haptic } = io;
    let scene_msg = Arc::new(protocol::encode_scene(&scene, params.global.nozzle_standoff));
    let (frame_tx, frame_rx) = watch::channel(Arc::new(Frame::none()));
    let stop = Arc::new(AtomicBool::new(false));
    let app = Arc::new(App {
        scene_msg: Mutex::new(scene_msg),
        scene: Mutex::new(scene),
        frames: frame_rx,
        delivery: DeliveryStats::default(),
        published: PublishLog::default(),
        device: Mutex::new(device),
        commands: Mutex::new(commands),
        control: Mutex::new(Control { controller: None, viewers: Vec::new() }),
        next_id: AtomicU64::new(1),
        started: Instant::now(),
        latest_lattice: Mutex::new(Vec::new()),
        latest_head: Mutex::new(nalgebra::Isometry3::identity()),
        latest_guides: Mutex::new(LatestGuides::default()),
        opts,
        params,
        session: Mutex::new(Some(session)),
        access,
        last_save: Mutex::new(None),
        loading: Mutex::new(()),
        viewer_timeout,
        swap: Mutex::new(None),
        udp,
        record: record_status,
    });
    let app_end = app.clone();

    // Frames on time on a busy machine: the frame thread runs real-time just below the haptic loop, when the
    // haptic loop does.
    let frame_priority = haptic_priority.map(|p| (p - 1).max(1));
    let pump = pump::spawn(app.clone(), stop.clone(), args.fps, frame_priority, lattice, haptic, frame_tx)?;

    // The runtime's threads (the viewers' writers and readers) run real-time one below the frame thread, so
    // that a FRAME is not queued behind normal work on a busy machine; heavy jobs (LOAD, SAVE) go back to normal
    // priority on their blocking thread (`delivery::normal_priority`).
    let worker_priority = frame_priority.map(|p| (p - 1).max(1));
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .on_thread_start(move || {
            if let Some(p) = worker_priority {
                if let Err(why) = haptics::realtime::request_realtime(p) {
                    tracing::debug!("a runtime thread runs at normal priority: {why}");
                }
            }
        })
        .build()?;
    let addr = SocketAddr::new(args.addr, args.port);
    let duration = args.duration;
    let app_token = app.access.token.clone();
    let served = rt.block_on(async move {
        let router = Router::new().route("/ws", get(viewer::ws_handler)).route("/debug/carried", axum::routing::post(handlers::carried_handler)).fallback_service(ServeDir::new(&web)).with_state(app.clone());
        let listener = tokio::net::TcpListener::bind(addr).await.with_context(|| format!("cannot bind {addr}"))?;
        let local = listener.local_addr()?;
        match &app_token {
            Some(t) => println!("coiffure serve: listening on http://{local}/?token={t} (viewer from {}; the token is required)", web.display()),
            None => println!("coiffure serve: listening on http://{local}/ (viewer from {})", web.display()),
        }
        use std::io::Write;
        let _ = std::io::stdout().flush();
        let shutdown = async move {
            match duration {
                Some(d) => tokio::time::sleep(Duration::from_secs_f64(d.max(0.0))).await,
                None => {
                    let _ = tokio::signal::ctrl_c().await;
                }
            }
        };
        // TCP_NODELAY: a FRAME leaves at once. With Nagle's algorithm a FRAME (smaller than a segment) waits for
        // the ACK of the previous one, which a viewer that only reads sends late (delayed ACKs, 40-200 ms):
        // before, a reading viewer got a fifth of its FRAMEs about 30 ms late and gaps up to 193 ms.
        axum::serve(nodelay(listener), router).with_graceful_shutdown(shutdown).await.context("server failed")?;
        anyhow::Ok(())
    });
    stop.store(true, Ordering::Relaxed);
    let st = pump.join().map_err(|_| anyhow!("the frame thread panicked"))?;
    let session = app_end.session.lock().unwrap().take().ok_or_else(|| anyhow!("no session to stop"))?;
    let report = session.stop();
    report::print(args, &app_end, &st, &report);
    served
}

/// `listener` with TCP_NODELAY set on every accepted connection (see where it is used).
fn nodelay(listener: tokio::net::TcpListener) -> impl axum::serve::Listener<Io = tokio::net::TcpStream, Addr = SocketAddr> {
    use axum::serve::ListenerExt;
    listener.tap_io(|tcp| {
        if let Err(e) = tcp.set_nodelay(true) {
            tracing::warn!("cannot set TCP_NODELAY on a connection (its FRAMEs may wait for ACKs): {e}");
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test]
    async fn accepted_connections_send_without_nagle_delays() {
        // Every connection the server accepts has TCP_NODELAY (a FRAME must not wait for the ACK of the one
        // before: a viewer that only reads acknowledges late). Without it, `nodelay()` hands out a socket
        // with the option off (Linux's default) and this fails.
        use axum::serve::Listener;
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let addr = listener.local_addr().unwrap();
        let mut listener = nodelay(listener);
        let client = tokio::net::TcpStream::connect(addr).await.unwrap();
        assert!(!client.nodelay().unwrap(), "the default is off (else this test proves nothing)");
        let (served, _) = listener.accept().await;
        assert!(served.nodelay().unwrap());
    }
}
