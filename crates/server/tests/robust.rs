//! Robustness of `coiffure serve` under abuse (issue 16): a real server, real WebSocket clients on loopback.
//! The runaway guard's count reaches the viewers in FRAME; a LOAD beyond the bounds, a viewer that does not
//! read, a message over the limit and a burst of RESETs are each handled without harm.

mod common;

use common::{first_of, open, serve};
use std::sync::Mutex;

/// One test at a time: each runs a server, and the burst test measures the haptic loop's timing.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn serial() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

/// A POSE message: position (m), identity rotation, no buttons.
fn pose(p: [f32; 3]) -> Vec<u8> {
    let mut b = vec![0x01, 1];
    [p[0], p[1], p[2], 0.0, 0.0, 0.0, 1.0].iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
    b.extend_from_slice(&0u32.to_le_bytes());
    b
}

/// FRAME's runaway count (docs/protocol.md "FRAME, proxy health"): the u32 before the hair's surface (u8
/// treatment, f32 tool friction), which ends the FRAME.
fn runaways(frame: &[u8]) -> u32 {
    u32::from_le_bytes(frame[frame.len() - 9..frame.len() - 5].try_into().unwrap())
}

#[test]
fn the_runaway_count_reaches_the_viewers() {
    let _one = serial();
    // The pointer put at the head's centre: its target is kept out of the body as the tool is (a pointer's depth
    // is a guess), so the comb is pressed onto the scalp through the hair, whose push stretches the coupling by
    // about a millimetre. With the guard at 0.5 mm (`--max-proxy-lag 0.0005`) that is a runaway again and again,
    // and FRAME says so; a watching viewer sees the same count. (Before the pointer's target was kept out of the
    // body, the proxy stayed on the scalp 9 cm from it and a 5 cm guard sufficed.)
    let s = serve(&["--render-strands", "2000", "--max-proxy-lag", "0.0005"]);
    let mut ws = open(&s.http, None, "").unwrap();
    let mut watcher = open(&s.http, None, "").unwrap();
    // The first viewer to register controls the tool, and registering follows the handshake, so the watcher can
    // come first (it did, once in 15 runs): `ws` takes control (TAKE_CONTROL) before it poses.
    ws.send(tungstenite::Message::Binary(vec![0x02, 1].into())).unwrap();
    assert_eq!(runaways(&first_of(&mut ws, 0x82)), 0, "none before the tool is pushed in");
    // The pose is held as a viewer holds it (sent again with every frame read; a burst of poses once was not
    // always enough on a loaded machine).
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    let mut n = 0;
    while n == 0 && std::time::Instant::now() < deadline {
        ws.send(tungstenite::Message::Binary(pose([0.0, 0.0, 0.0]).into())).unwrap();
        n = runaways(&first_of(&mut ws, 0x82));
    }
    assert!(n > 0, "no runaway counted with the comb pressed onto the scalp and a 0.5 mm guard");
    let mut seen = 0;
    while seen < n && std::time::Instant::now() < deadline + std::time::Duration::from_secs(20) {
        seen = runaways(&first_of(&mut watcher, 0x82));
    }
    assert!(seen >= n, "the watching viewer saw {seen} runaways, the controller {n}");
    // The default guard (0.2 m) lets the same push be.
    let s = serve(&["--render-strands", "2000"]);
    let mut ws = open(&s.http, None, "").unwrap();
    for _ in 0..20 {
        ws.send(tungstenite::Message::Binary(pose([0.0, 0.0, 0.0]).into())).unwrap();
    }
    for _ in 0..60 {
        assert_eq!(runaways(&first_of(&mut ws, 0x82)), 0);
    }
}

/// An ERROR's code and text.
fn error_of(ws: &mut tungstenite::WebSocket<std::net::TcpStream>) -> (u16, String) {
    let e = first_of(ws, 0x83);
    (u16::from_le_bytes([e[2], e[3]]), String::from_utf8_lossy(&e[6..]).into_owned())
}

/// A LOAD of a one-strand `.data` file through `points` (m), taken as metres in the head frame without fitting
/// (docs/protocol.md: format 1 with options; up and facing detected, flags 1 = no fit, 1 m per unit).
fn data_load_as_metres(points: &[[f32; 3]]) -> Vec<u8> {
    let mut load = vec![0x06, 1, 0x80 | 1, 0, 0, 1, 0];
    load.extend_from_slice(&1f32.to_le_bytes());
    load.extend_from_slice(&1u32.to_le_bytes());
    load.extend_from_slice(&(points.len() as u32).to_le_bytes());
    points.iter().flatten().for_each(|x| load.extend_from_slice(&x.to_le_bytes()));
    load
}

#[test]
fn a_load_beyond_the_bounds_is_refused_naming_the_bound() {
    let _one = serial();
    let s = serve(&["--render-strands", "2000"]);
    let mut ws = open(&s.http, None, "").unwrap();
    first_of(&mut ws, 0x84);
    // The audit's small file: one .data strand from (-1.35, -1.35, -1.35) to (1.35, 1.35, 1.35) m, loaded as
    // metres without fitting. It asked for a 185,193-node lattice; now the box around the head refuses it.
    ws.send(tungstenite::Message::Binary(data_load_as_metres(&[[-1.35, -1.35, -1.35], [1.35, 1.35, 1.35]]).into())).unwrap();
    let (code, text) = error_of(&mut ws);
    assert_eq!(code, 5, "{text}");
    assert!(text.contains("strand 0 point 0") && text.contains("outside the box around the head"), "{text}");
    // A file one byte over the size bound (64 MiB) is refused before it is read, naming the bound.
    let mut big = vec![0x06, 1, 1];
    big.resize(3 + (64 << 20) + 1, 0);
    ws.send(tungstenite::Message::Binary(big.into())).unwrap();
    let (code, text) = error_of(&mut ws);
    assert_eq!(code, 5, "{text}");
    assert!(text.contains("at most 67108864 bytes (64 MiB)"), "{text}");
    // The connection is still up and the hairstyle unchanged: frames keep coming.
    first_of(&mut ws, 0x82);
}

/// A LOAD over its time budget (`--load-budget`, `hairstyle::LoadLimits::max_seconds`) is refused with an
/// ERROR naming the stage and the budget, and the live hairstyle stays (no new SCENE; frames keep coming). A
/// budget of 0 s is over at the first check whatever the machine's speed.
#[test]
fn a_load_over_its_time_budget_is_refused_and_the_hairstyle_stays() {
    let _one = serial();
    let s = serve(&["--render-strands", "2000", "--load-budget", "0"]);
    let mut ws = open(&s.http, None, "").unwrap();
    first_of(&mut ws, 0x84);
    // A valid .data file: one strand hanging 10 cm from the top of the head (metres, head frame, not fitted).
    ws.send(tungstenite::Message::Binary(data_load_as_metres(&[[0.0, 0.0, 0.095], [0.0, -0.05, 0.09], [0.0, -0.1, 0.05]]).into())).unwrap();
    let (code, text) = error_of(&mut ws);
    assert_eq!(code, 5, "{text}");
    assert!(text.contains("over its time budget of 0 s"), "{text}");
    // No SCENE follows: the next 30 messages are frames (or STRANDS), never a new scene.
    for _ in 0..30 {
        let m = match ws.read().unwrap() {
            tungstenite::Message::Binary(b) => b,
            _ => continue,
        };
        assert_ne!(m[0], 0x84, "a new SCENE was sent after a refused LOAD");
    }
    // (A LOAD within the default budget is the browser suite's `viewer.test.mjs` load.)
}

#[test]
fn a_viewer_that_does_not_read_is_disconnected_and_the_server_stays_small() {
    let _one = serial();
    // A viewer that connects and then neither reads nor sends: its socket fills with frames, its writer blocks,
    // and after `--viewer-timeout` (3 s here; default 30) it is dropped (before, it stayed forever). A watching viewer sees
    // the count of viewers go from 2 back to 1; the server's resident memory meanwhile grows by less than
    // 64 MiB (the frames are not queued; the queue holds at most 256 messages and 96 MiB).
    let s = serve(&["--render-strands", "2000", "--viewer-timeout", "3"]);
    let mut watcher = open(&s.http, None, "").unwrap();
    first_of(&mut watcher, 0x82);
    let rss0 = s.rss();
    let idle = open(&s.http, None, "").unwrap();
    let t0 = std::time::Instant::now();
    let viewers = |w: &mut tungstenite::WebSocket<std::net::TcpStream>| {
        let c = first_of(w, 0x84);
        u32::from_le_bytes(c[3..7].try_into().unwrap())
    };
    assert_eq!(viewers(&mut watcher), 2);
    let mut peak = rss0;
    let mut n = 2;
    while n != 1 && t0.elapsed() < std::time::Duration::from_secs(30) {
        // CONTROL comes when the count changes; frames in between keep the watcher reading.
        let m = first_of_any(&mut watcher);
        if m[0] == 0x84 {
            n = u32::from_le_bytes(m[3..7].try_into().unwrap());
        }
        peak = peak.max(s.rss());
    }
    assert_eq!(n, 1, "the idle viewer was not disconnected in {:?}", t0.elapsed());
    eprintln!("idle viewer dropped after {:?}; server RSS {} -> peak {} MB", t0.elapsed(), rss0 >> 20, peak >> 20);
    assert!(peak < rss0 + (64 << 20), "RSS {} -> {} MB", rss0 >> 20, peak >> 20);
    drop(idle);
}

/// The next binary message.
fn first_of_any(ws: &mut tungstenite::WebSocket<std::net::TcpStream>) -> Vec<u8> {
    loop {
        if let tungstenite::Message::Binary(b) = ws.read().unwrap() {
            return b.to_vec();
        }
    }
}

#[test]
fn a_message_over_the_limit_gets_an_error_and_a_close_with_the_reason() {
    let _one = serial();
    // A frame header announcing 64 MiB + 100 bytes (over the LOAD limit of 64 MiB + 16): the server cannot read
    // on, but answers ERROR 1 naming the limit and closes with 1009 (message too big) and the reason, instead
    // of resetting the connection.
    use std::io::Write;
    let s = serve(&["--render-strands", "2000"]);
    let mut ws = open(&s.http, None, "").unwrap();
    first_of(&mut ws, 0x84);
    let len: u64 = (64 << 20) + 100;
    let mut head = vec![0x82u8, 0x80 | 127];
    head.extend_from_slice(&len.to_be_bytes());
    head.extend_from_slice(&[1, 2, 3, 4]); // mask key
    head.extend_from_slice(&[0u8; 64]);
    ws.get_mut().write_all(&head).unwrap();
    let (code, text) = error_of(&mut ws);
    assert_eq!(code, 1, "{text}");
    assert!(text.contains("67108880 bytes, the limit"), "{text}");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
    loop {
        assert!(std::time::Instant::now() < deadline, "no close");
        match ws.read() {
            Ok(tungstenite::Message::Close(Some(f))) => {
                assert_eq!(u16::from(f.code), 1009);
                assert!(f.reason.contains("limit"), "{}", f.reason);
                break;
            }
            Ok(tungstenite::Message::Close(None)) => panic!("a close without a reason"),
            Ok(_) => {}
            Err(e) => panic!("the connection failed without a close: {e}"),
        }
    }
}

#[test]
fn a_burst_of_1000_resets_does_not_stall_the_haptic_loop() {
    let _one = serial();
    // 1,000 RESETs in one burst (2 KB). Before, all ran in one haptic step and froze the 1 kHz loop for 0.45 s.
    // Now at most `engine::live::MAX_COMMANDS_PER_STEP` (2) run per step: the session's record shows all 1,000
    // applied, never more than 2 in a step (counts, whatever the machine's load), and the loop's longest step,
    // printed when the server stops, stays under 0.25 s (loose: a shared machine at normal priority preempts
    // steps by tens of ms). The speed figure (p99.9 around the burst) is the `burst` example's (bench/RESULTS.md).
    let dir = common::scratch("burst");
    let record = dir.join("burst.rec");
    let s = serve(&["--render-strands", "2000", "--duration", "6", "--record", record.to_str().unwrap()]);
    let mut ws = open(&s.http, None, "").unwrap();
    first_of(&mut ws, 0x82);
    for _ in 0..1000 {
        ws.send(tungstenite::Message::Binary(vec![0x05, 1].into())).unwrap();
    }
    // (wall s, haptic s) of the frames of the next 2 s: information (the haptic clock's lag is the machine's load).
    let t0 = std::time::Instant::now();
    let mut seen = Vec::new();
    while t0.elapsed() < std::time::Duration::from_secs(2) {
        let f = first_of(&mut ws, 0x82);
        seen.push((t0.elapsed().as_secs_f64(), f32::from_le_bytes(f[6..10].try_into().unwrap()) as f64));
    }
    let worst = seen.iter().flat_map(|a| seen.iter().filter(move |b| b.0 > a.0).map(move |b| (b.0 - a.0) - (b.1 - a.1))).fold(0.0f64, f64::max);
    eprintln!("{} frames; worst lag of the haptic clock behind the wall clock {:.3} s", seen.len(), worst);
    drop(ws);
    let line = s.line_with("haptic loop:", std::time::Duration::from_secs(30)).expect("the server's summary");
    eprintln!("{line}");
    s.line_with("record:", std::time::Duration::from_secs(30)).expect("the record written");
    let rec = engine::record::Record::from_bytes(&std::fs::read(&record).unwrap()).unwrap();
    let resets: Vec<usize> = rec.steps.iter().map(|st| st.commands.iter().filter(|c| **c == engine::session::Command::Reset).count()).collect();
    assert_eq!(resets.iter().sum::<usize>(), 1000, "every RESET applied");
    let busiest = resets.iter().copied().max().unwrap();
    let spread = resets.iter().filter(|&&n| n > 0).count();
    eprintln!("the 1000 resets ran in {spread} haptic steps, at most {busiest} in one");
    assert!(busiest <= engine::live::MAX_COMMANDS_PER_STEP, "{busiest} resets in one step");
    let max_us: f64 = line.split("max ").nth(1).and_then(|r| r.split_whitespace().next()).and_then(|v| v.parse().ok()).expect(&line);
    assert!(max_us < 2.5e5, "longest haptic step {max_us} us");
}
