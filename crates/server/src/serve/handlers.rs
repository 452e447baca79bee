//! What the server does with a viewer's messages (POSE, COMMAND, TAKE_CONTROL, PING, SAVE, LOAD), and the
//! `POST /debug/carried` endpoint.

use super::access::check_access;
use super::app::{App, SAVE_INTERVAL};
use crate::protocol::{self, ClientMessage, WireError};
use axum::extract::State;
use axum::response::IntoResponse;
use engine::session::{Scene, Session, SessionIo};
use haptics::device::DeviceReading;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// `POST /debug/carried` (`crate::carried`), after the access checks of `/ws`: the named render vertices carried
/// by the live scene's one law on the lattice and head pose the request gives (JSON in and out); 400 naming
/// what is wrong with a bad request.
pub(super) async fn carried_handler(headers: axum::http::HeaderMap, query: axum::extract::Query<std::collections::HashMap<String, String>>, State(app): State<Arc<App>>, body: axum::body::Bytes) -> axum::response::Response {
    use axum::http::StatusCode;
    if let Err(why) = check_access(&headers, query.get("token").map(String::as_str), &app.access) {
        return (StatusCode::FORBIDDEN, why).into_response();
    }
    let req = match crate::carried::parse(&body) {
        Ok(r) => r,
        Err(why) => return (StatusCode::BAD_REQUEST, why).into_response(),
    };
    let scene = app.scene.lock().unwrap().clone();
    match tokio::task::spawn_blocking(move || crate::carried::carried(&scene, &req)).await {
        Ok(Ok(answer)) => ([(axum::http::header::CONTENT_TYPE, "application/json")], serde_json::to_vec(&answer).unwrap_or_default()).into_response(),
        Ok(Err(why)) => (StatusCode::BAD_REQUEST, why).into_response(),
        Err(e) => (StatusCode::INTERNAL_SERVER_ERROR, e.to_string()).into_response(),
    }
}

/// Handles one binary message; returns the reply, if any.
pub(super) fn handle(app: &App, id: u64, bytes: &[u8]) -> Option<Vec<u8>> {
    let msg = match protocol::parse_client(bytes) {
        Ok(m) => m,
        Err(e) => {
            tracing::debug!("viewer {id}: {}", e.message);
            return Some(protocol::encode_error(&e));
        }
    };
    // Whether this viewer holds the tool, read only by the messages that need it (a PING or a FRAME_ACK, sent
    // every frame, takes the control lock at most once).
    let controls = || app.control.lock().unwrap().controller == Some(id);
    let not_controller = || Some(protocol::encode_error(&WireError { code: protocol::code::NOT_CONTROLLER, message: "another viewer controls the tool; send TAKE_CONTROL first".into() }));
    match msg {
        ClientMessage::Ping(t) => Some(protocol::encode_pong(t)),
        ClientMessage::FrameAck(seq) => {
            if let Some(v) = app.control.lock().unwrap().viewers.iter().find(|v| v.id == id) {
                v.ack(seq);
            }
            None
        }
        ClientMessage::TakeControl => {
            app.control.lock().unwrap().controller = Some(id);
            app.broadcast_control();
            None
        }
        ClientMessage::Pose { position, rotation, buttons } => {
            if !controls() {
                return not_controller();
            }
            if app.udp.is_some() {
                // A haptic device drives the tool (`--device`); the mouse does not fight it.
                return None;
            }
            let time = app.started.elapsed().as_secs_f64();
            app.device.lock().unwrap().push(DeviceReading { time, position, rotation, buttons });
            None
        }
        ClientMessage::Command(c) => {
            if !controls() {
                return not_controller();
            }
            let _ = app.commands.lock().unwrap().send(c);
            None
        }
        ClientMessage::Save(format) => {
            // A SAVE writes the whole hairstyle (up to a second of work at 100k strands): only the viewer in
            // control, at most one per `SAVE_INTERVAL`.
            if !controls() {
                return not_controller();
            }
            {
                let mut last = app.last_save.lock().unwrap();
                if last.is_some_and(|t| t.elapsed() < SAVE_INTERVAL) {
                    return Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message: format!("SAVE at most once every {} s; try again", SAVE_INTERVAL.as_secs_f64()) }));
                }
                *last = Some(Instant::now());
            }
            match save(app, format) {
                Ok(b) => Some(protocol::encode_file(format, &b)),
                Err(e) => Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message: e })),
            }
        }
        ClientMessage::Load(format, opts, follow, bytes) => {
            if !controls() {
                return not_controller();
            }
            let f = hairstyle::formats::Format::from_path(Path::new(&format!("x.{}", protocol::FORMATS[format]))).expect("known extension");
            let file_error = |message| Some(protocol::encode_error(&WireError { code: protocol::code::FILE, message }));
            // One LOAD at a time (control can move between two viewers' LOADs): a second is refused.
            let Ok(_loading) = app.loading.try_lock() else {
                return file_error("another hairstyle is being loaded; send the LOAD again when its SCENE has arrived".into());
            };
            let start = Instant::now();
            match hairstyle::fit::read_and_fit(f, &bytes, &opts, &app.opts.load) {
                Ok((c, report)) => {
                    if let Err(message) = app.opts.load.check_time(start, "the fit") {
                        return file_error(message);
                    }
                    tracing::info!("loaded hairstyle fitted: scale {:.5} m per unit, up {} front {} ({}), {:.1} % of the strands rooted on the scalp (roots median {:.2} mm, p95 {:.2} mm from it)", report.transform.scale, report.up.name(), report.front.name(), report.orientation_source.name(), 100.0 * report.rooted, 1e3 * report.rooted_distance.median, 1e3 * report.rooted_distance.p95);
                    match load(app, &c, follow, start) {
                        Ok(()) => {
                            let msg = protocol::encode_fit(&report);
                            for v in app.viewers() {
                                v.post(msg.clone());
                            }
                            None
                        }
                        Err(message) => file_error(message),
                    }
                }
                Err(hairstyle::fit::LoadError::Format(e)) => file_error(format!("cannot read the {} file: {e}", protocol::FORMATS[format])),
                Err(e) => file_error(e.to_string()),
            }
        }
    }
}

/// Replaces the live hairstyle by `curves` (m, head frame, as `hairstyle::fit` leaves them): a scene of the built-in head
/// with guides fitted to the file's strands and `follow` follow strands around each (default the server's
/// `SceneOptions::follow_strands`; [`Scene::load`]), a new session on it, the new SCENE sent to every viewer, then
/// the frame thread switched to the new session's snapshots. The old session stops. Refused while
/// recording (a record is of one scene).
fn load(app: &App, curves: &hairstyle::HairCurves, follow: Option<usize>, t0: Instant) -> Result<(), String> {
    if app.record.is_some() {
        return Err("cannot load a hairstyle while recording (--record): a record replays one scene".into());
    }
    let opts = engine::scene::SceneOptions { follow_strands: follow.or(app.opts.follow_strands), ..app.opts.clone() };
    let (scene, report) = Scene::load(curves, &opts).map_err(|e| format!("cannot use the loaded hairstyle: {e}"))?;
    let scene = Arc::new(scene);
    tracing::info!("loaded hairstyle: {}", report.summary());
    // Over the budget the new scene is dropped before anything live changes.
    app.opts.load.check_time(t0, "building the scene")?;
    let (session, io) = Session::start_with_device(scene.clone(), app.params, app.session_device()?).map_err(|e| e.to_string())?;
    let SessionIo { device, commands, lattice, haptic } = io;
    let old = app.session.lock().unwrap().replace(session);
    *app.device.lock().unwrap() = device;
    *app.commands.lock().unwrap() = commands;
    let msg = Arc::new(protocol::encode_scene(&scene, app.params.global.nozzle_standoff));
    *app.scene.lock().unwrap() = scene.clone();
    *app.scene_msg.lock().unwrap() = msg.clone();
    app.latest_guides.lock().unwrap().kept = Arc::new(Vec::new());
    for v in app.viewers() {
        v.post((*msg).clone());
    }
    *app.swap.lock().unwrap() = Some((lattice, haptic));
    if let Some(old) = old {
        old.stop();
    }
    tracing::info!("loaded a hairstyle: {} render strands, {} lattice nodes, in {:.2} s", scene.render.strands(), scene.lattice.node_count(), t0.elapsed().as_secs_f64());
    Ok(())
}

/// The current hairstyle (render strands through the latest lattice, following the active guides, cut
/// strands shortened: `Scene::render_curves`, the law the viewer's shader draws) as file bytes.
fn save(app: &App, format: usize) -> Result<Vec<u8>, String> {
    let scene = app.scene.lock().unwrap().clone();
    let nodes: Vec<nalgebra::Point3<f64>> = app.latest_lattice.lock().unwrap().iter().map(|p| nalgebra::Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)).collect();
    let head = *app.latest_head.lock().unwrap();
    let latest = app.latest_guides.lock().unwrap().clone();
    let guides = engine::scene::GuideDisplacements { active: &latest.active, displacement: &latest.displacement, samples: latest.samples };
    let curves = scene.render_curves(&nodes, &head, &engine::scene::Scene::kept_lengths_of_points(&latest.kept), &guides);
    let f = hairstyle::formats::Format::from_path(Path::new(&format!("x.{}", protocol::FORMATS[format]))).expect("known extension");
    // thickness (USD `widths`) from the scene's hair type
    let mut curves = curves;
    curves.thickness = Some(vec![scene.hair_type.major_diameter as f32; curves.num_points()]);
    f.write(&curves).map_err(|e| format!("cannot write {}: {e}", protocol::FORMATS[format]))
}
