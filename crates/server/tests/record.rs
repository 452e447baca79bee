//! Records streamed to disk (issue 32), end to end: a real `coiffure serve --device ... --record FILE` driven by a
//! real `coiffure device-sim` streaming bench/device-comb.toml; the server killed with SIGKILL, or its file size
//! limited (a full disk); the record replayed and compared bit for bit with the forces the device received.

mod common;

use common::{bin, scratch};
use engine::record::{Ending, ReadRecord, Record};
use std::path::{Path, PathBuf};
use std::process::Child;
use std::sync::Arc;
use std::time::{Duration, Instant};

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}

/// The server of these tests: a device on UDP, 5000 render strands standing for 20 hairs each, recording to `rec`.
const SERVE: [&str; 6] = ["--render-strands", "5000", "--hairs-per-render-strand", "20", "--device", "udp:127.0.0.1:0"];

/// `coiffure device-sim` streaming bench/device-comb.toml at 1 kHz to `udp` for `seconds`, its rows to `csv`.
fn device_sim(udp: &str, seconds: f64, csv: &Path) -> Child {
    bin()
        .args(["device-sim", "--server", &format!("udp:{udp}"), "--rate", "1000", "--repeat", "--duration", &seconds.to_string()])
        .arg("--path")
        .arg(repo("bench/device-comb.toml"))
        .arg("--out")
        .arg(csv)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

/// Rows of device-sim's CSV answered without a flag: (time sent s, force received N).
fn felt(csv: &Path) -> Vec<(f64, [f64; 3])> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next().unwrap(), haptics::sim::CSV_HEADER);
    lines
        .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect::<Vec<_>>())
        .filter(|r| r[4].is_finite() && r[8] == 0.0)
        .map(|r| (r[0], [r[4], r[5], r[6]]))
        .collect()
}

/// What a record's replay says against what the device felt.
#[derive(Debug)]
struct Check {
    /// Poses answered within the record's span, and those whose force equals the replayed one bit for bit.
    answered: usize,
    equal: usize,
    /// Replayed steps whose force differs from the recorded one.
    replay_differs: usize,
    /// Largest force felt in the span, N.
    peak: f64,
    /// Time of the last pose the record read and of the last answered pose, s (device-sim's clock).
    last_read: f64,
    last_answered: f64,
}

/// Replays `rec` on the scene and settings it names, checks every force against the recorded one (the haptic
/// step's last device step's), and each answered pose within the record's span against the force of the device
/// step that read it (the device loop runs several device steps per haptic step, each answering the poses it
/// read).
fn check(rec: &Record, felt: &[(f64, [f64; 3])]) -> Check {
    let settings = rec.settings.clone().expect("serve writes its settings");
    let scene = Arc::new(engine::session::Scene::builtin(&settings.scene_options()).unwrap());
    let params = settings.session_params(rec.rate_hz).unwrap();
    assert_eq!(params.input, engine::session::InputKind::Device);
    let forces = engine::replay::replay_device_steps(scene, params, rec).unwrap();
    assert_eq!(forces.len(), rec.steps.len());
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let replay_differs = (0..rec.steps.len()).filter(|&i| forces[i].len() != rec.steps[i].readings().len() || bits(forces[i].last().unwrap().as_slice()) != bits(rec.steps[i].force.as_slice())).count();
    let last_read = rec.steps.iter().rev().find_map(|s| s.readings().iter().rev().find_map(|r| r.map(|r| r.time))).unwrap_or(f64::NAN);
    let times: Vec<f64> = felt.iter().map(|r| r.0).collect();
    let (mut answered, mut equal, mut peak) = (0, 0, 0.0f64);
    for (step, (_, f)) in rec.steps_reading(&times).into_iter().zip(felt) {
        let Some((i, j)) = step else { continue };
        answered += 1;
        peak = peak.max(nalgebra::Vector3::from(*f).norm());
        equal += (bits(forces[i][j].as_slice()) == bits(f)) as usize;
    }
    Check { answered, equal, replay_differs, peak, last_read, last_answered: times.last().copied().unwrap_or(f64::NAN) }
}

/// The tests with a server and a device run one at a time (two at once on two cores would skip haptic periods).
static ONE_SERVER: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn read(path: &Path) -> ReadRecord {
    Record::read(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn a_server_killed_mid_session_leaves_a_record_that_replays_to_the_forces_the_device_felt() {
    // The server records while device-sim combs the back hair; 3 s after the stream started it is killed with
    // SIGKILL (no clean exit, no end chunk). The file is there, read up to its last whole chunk with at least the
    // first 2 s of the stream; replayed headless on the scene and settings the record names, every step's force is the recorded
    // one and every pose the device sent in that span was answered with the replayed force of the step that
    // read it, bit for bit. At most a second of the session before the kill is missing from the record.
    let _one = ONE_SERVER.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("record-kill");
    let (rec_path, csv) = (dir.join("s.rec"), dir.join("felt.csv"));
    let mut args = SERVE.to_vec();
    args.extend(["--record", rec_path.to_str().unwrap()]);
    let mut server = common::serve(&args);
    assert!(rec_path.is_file(), "the record exists as soon as the server runs");
    let mut sim = device_sim(server.udp.as_deref().unwrap(), 4.0, &csv);
    let t0 = Instant::now();
    std::thread::sleep(Duration::from_secs(3));
    server.kill();
    let killed = t0.elapsed().as_secs_f64();
    assert!(sim.wait().unwrap().success(), "device-sim goes on when the server is gone");
    let r = read(&rec_path);
    let Ending::Cut(cut) = &r.ending else { panic!("a killed server's record has no end chunk: {:?}", r.ending) };
    let c = check(&r.record, &felt(&csv));
    eprintln!("killed after {killed:.2} s; record: {} steps ({:.2} s), cut at byte {} of {}: {}; {c:?}", r.record.steps.len(), r.record.seconds(), cut.offset, cut.file_bytes, cut.why);
    // At least the first 2 s of the device's stream are in the record (in steps, fewer when a busy machine made the
    // loop skip periods: those are not run, so not recorded).
    assert!(c.last_read >= 2.0, "{} s of steps, the last read at {} s", r.record.seconds(), c.last_read);
    assert_eq!(c.replay_differs, 0, "replayed forces differ from the recorded ones");
    assert!(c.answered >= 1500, "{c:?}");
    assert_eq!(c.equal, c.answered, "forces felt equal to the replayed ones, bit for bit");
    assert!(c.peak > 0.01, "the comb met the hair: {c:?}");
    assert!(c.last_answered - c.last_read <= 1.0, "at most a second lost: {c:?}");
    // `coiffure replay` of the cut file replays what is there and says where it was cut.
    let out = bin().arg("replay").arg(&rec_path).arg("--out").arg(dir.join("replay")).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(text.contains(&format!("cut: read up to byte {} of {}", cut.offset, cut.file_bytes)) && text.contains(&format!("{} haptic steps", r.record.steps.len())), "{text}");
    // Its device_force.csv has every device step's force (the device loop's rate), as the device was sent it
    // (printed to 7 significant digits), each stamped with its pose's time.
    let csv = std::fs::read_to_string(dir.join("replay").join("device_force.csv")).unwrap();
    let scene = Arc::new(engine::session::Scene::builtin(&r.record.settings.clone().unwrap().scene_options()).unwrap());
    let params = r.record.settings.clone().unwrap().session_params(r.record.rate_hz).unwrap();
    let forces: Vec<_> = engine::replay::replay_device_steps(scene, params, &r.record).unwrap().into_iter().flatten().collect();
    let readings: Vec<_> = r.record.steps.iter().flat_map(|s| s.readings()).collect();
    let rows: Vec<Vec<f64>> = csv.lines().skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(csv.lines().next(), Some("period,t,fx,fy,fz,tx,ty,tz"));
    assert_eq!(rows.len(), forces.len(), "one row per device step");
    assert!(forces.len() > 2 * r.record.steps.len(), "device steps {} for {} physics steps", forces.len(), r.record.steps.len());
    for (i, (row, f)) in rows.iter().zip(&forces).enumerate() {
        assert!((0..3).all(|k| (row[2 + k] - f[k]).abs() <= 1e-6 * f.norm() + 1e-12), "device step {i}: {row:?} vs {f:?}");
        let t = readings[i].map_or(f64::NAN, |r| r.time);
        assert!((row[1] - t).abs() <= 1e-6 || (row[1].is_nan() && t.is_nan()), "device step {i}: time {} vs {t}", row[1]);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Sets the file size limit of the command's process to `bytes` (RLIMIT_FSIZE) and ignores SIGXFSZ, so that a
/// write beyond it fails with EFBIG ("File too large") as a write to a full disk fails with ENOSPC.
fn limit_file_size(cmd: &mut std::process::Command, bytes: u64) {
    use std::os::unix::process::CommandExt;
    // SAFETY: between fork and exec only async-signal-safe calls (signal, setrlimit) on the child's own state.
    unsafe {
        cmd.pre_exec(move || {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let lim = libc::rlimit { rlim_cur: bytes, rlim_max: bytes };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
}

/// The size limit on the server's files in the full-disk test, bytes.
const FILE_LIMIT: u64 = 450_000;

#[test]
fn a_full_disk_stops_recording_the_session_goes_on_and_the_record_replays_to_the_failure() {
    // The server may write at most 450 kB: recording fails part way, after two or three of its half-second chunks
    // (a haptic step of device-sim's 4 kHz stream, four device readings of 67 bytes each, is about 300 bytes: the
    // first chunk alone is some 150 kB). The session goes
    // on at its rate (the device's poses are still answered; the haptic clock in the FRAMEs runs after the failure
    // at least half as fast as in the second before it, on this machine whatever its load; that the haptic thread
    // never waits for the disk is tested with a stalled writer in engine::record::stream), a viewer
    // gets ERROR 7 naming the failure, the server's output says so, and the file, cut back to its last whole
    // chunk, replays to the forces the device felt up to there, bit for bit.
    let _one = ONE_SERVER.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("record-full");
    let (rec_path, csv) = (dir.join("s.rec"), dir.join("felt.csv"));
    let mut args = SERVE.to_vec();
    args.extend(["--record", rec_path.to_str().unwrap(), "--duration", "6"]);
    let server = common::serve_with(&args, |c| limit_file_size(c, FILE_LIMIT));
    let mut ws = common::open(&server.http, None, "").unwrap();
    let mut sim = device_sim(server.udp.as_deref().unwrap(), 4.0, &csv);
    // FRAMEs (wall time s, haptic time s) until ERROR 7, and 2 s after it.
    let t0 = Instant::now();
    let mut frames: Vec<(f64, f64)> = vec![];
    let (mut err, mut err_at) = (Vec::new(), f64::NAN);
    while err.is_empty() || t0.elapsed().as_secs_f64() < err_at + 2.0 {
        assert!(t0.elapsed() < Duration::from_secs(30), "no ERROR 7 within 30 s");
        let msg = match ws.read() {
            Ok(m) => m,
            // The server closed the viewer (its session ended): what was read is checked.
            Err(e) if !err.is_empty() => {
                eprintln!("viewer closed: {e}");
                break;
            }
            Err(e) => panic!("viewer: {e}"),
        };
        if let tungstenite::Message::Binary(b) = msg {
            let now = t0.elapsed().as_secs_f64();
            match b[0] {
                0x82 => frames.push((now, f32::from_le_bytes(b[6..10].try_into().unwrap()) as f64)),
                0x83 if err.is_empty() => (err, err_at) = (b.to_vec(), now),
                _ => {}
            }
        }
    }
    let rate = |from: f64, to: f64| {
        let w: Vec<_> = frames.iter().filter(|f| f.0 >= from && f.0 <= to).collect();
        (w.last().unwrap().1 - w[0].1) / (w.last().unwrap().0 - w[0].0)
    };
    let (before, after) = (rate(err_at - 1.0, err_at), rate(err_at, err_at + 2.0));
    eprintln!("haptic clock: {before:.3} s/s in the second before ERROR 7, {after:.3} s/s in the 2 s after");
    assert!(after >= 0.5 * before && after > 0.2, "the haptic loop slowed after the failure: {before} then {after} s/s");
    let code = u16::from_le_bytes([err[2], err[3]]);
    let message = String::from_utf8_lossy(&err[6..]).to_string();
    assert_eq!(code, 7, "{message}");
    assert!(message.contains("recording stopped") && message.contains("File too large"), "{message}");
    assert!(sim.wait().unwrap().success());
    let summary = server.line_with("haptic loop:", Duration::from_secs(30)).expect("the server's summary");
    let record_line = server.line_with("record:", Duration::from_secs(10)).expect("the record's line");
    eprintln!("{message}\n{summary}\n{record_line}");
    assert!(record_line.contains("stopped early") && record_line.contains("File too large"), "{record_line}");
    // Every pose after the failure was answered still (the session went on).
    let felt = felt(&csv);
    let r = read(&rec_path);
    let Ending::Cut(cut) = &r.ending else { panic!("{:?}", r.ending) };
    assert_eq!(cut.offset, cut.file_bytes, "cut back to its last whole chunk");
    assert!(cut.file_bytes as u64 <= FILE_LIMIT);
    let c = check(&r.record, &felt);
    eprintln!("record: {} steps ({:.2} s), {} bytes; {c:?}; {} poses answered in all", r.record.steps.len(), r.record.seconds(), cut.file_bytes, felt.len());
    assert!(r.record.steps.len() >= 200, "{} steps recorded", r.record.steps.len());
    assert_eq!(c.replay_differs, 0);
    assert!(c.answered >= 100 && c.equal == c.answered, "{c:?}");
    assert!(c.last_answered - c.last_read >= 1.5, "the session went on after the failure: {c:?}");
    assert!(felt.len() >= 3000, "{} of about 4000 poses answered", felt.len());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_record_of_an_older_version_is_refused_naming_it() {
    let dir = scratch("record-old");
    // CFREC2: written at a clean exit; CFREC3: streamed, but one device step per haptic step (before the device
    // loop ran at its own rate): neither replays with this version's device steps.
    for v in [2, 3] {
        let old = dir.join(format!("old{v}.rec"));
        let mut b = format!("CFREC{v}\0\0").into_bytes();
        b.extend_from_slice(&1000.0f64.to_le_bytes());
        b.extend_from_slice(&[0; 24]);
        std::fs::write(&old, b).unwrap();
        let out = bin().arg("replay").arg(&old).arg("--out").arg(dir.join("o")).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(err.contains(&format!("version-{v} session record (CFREC{v})")) && err.contains("version 4"), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
