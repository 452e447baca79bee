//! FRAMEs on time (docs/protocol.md, "Frames on time"; issue 16): a real `coiffure serve` on loopback, a viewer
//! that reads and one that never does.

mod common;

use common::{first_of, open, serve};
use std::time::{Duration, Instant};

#[test]
fn a_reading_viewer_gets_its_frames_on_time_while_another_does_not_read() {
    // Viewer A only reads; viewer B controls the tool, combs the back hair (60 POSEs/s) and never reads (its
    // socket fills, its writer waits). A's FRAMEs must not wait for B, nor for A's own ACKs: each FRAME's
    // lateness is its arrival less its schedule (sequence / fps) less the smallest such value (the transit),
    // counted only for FRAMEs before which A itself was not stalled (A times its own scheduling).
    // Without TCP_NODELAY a FRAME (about 25 kB once the comb moves strands) waits for the ACK of the one
    // before, which a viewer that only reads delays: 26 of 204, 36 of 218 and 45 of 226 judged FRAMEs (13-20 %) came over
    // 15 ms late here (and the idle soak saw a 193 ms gap); with it, 0. Bounds, with margins for a loaded 2-core
    // machine where the server runs at normal priority: under 5 % of the judged FRAMEs over 15 ms late (a third
    // to a quarter of the Nagle count; an idle or moderately loaded machine gives 0), A received at least half of
    // the FRAMEs sent meanwhile (skips, latest wins, are for slow viewers), and no gap beyond A's own stalls over
    // 1 s (10 x the on-time bound of 100 ms).
    let fps = 60.0;
    let s = serve(&["--render-strands", "2000", "--fps", "60", "--duration", "10"]);
    let mut a = open(&s.http, None, "").unwrap();
    first_of(&mut a, 0x82);
    let mut b = open(&s.http, None, "").unwrap();
    // B takes control and combs down the back of the head (so that FRAMEs carry the strands it moves), 60 poses/s.
    b.send(tungstenite::Message::Binary(vec![0x02, 1].into())).unwrap();
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let poser = {
        let stop = stop.clone();
        std::thread::spawn(move || {
            let t = Instant::now();
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                let phase = (t.elapsed().as_secs_f64() / 1.5).fract();
                // The soak's stroke: the comb turned 90 degrees about x (quaternion x, y, z, w).
                let h = std::f32::consts::FRAC_1_SQRT_2;
                let q = [h, 0.0, 0.0, h];
                let mut m = vec![0x01, 1];
                for x in [0.0f32, -0.115, 0.08 - 0.14 * phase as f32, q[0], q[1], q[2], q[3]] {
                    m.extend_from_slice(&x.to_le_bytes());
                }
                m.extend_from_slice(&0u32.to_le_bytes());
                if b.send(tungstenite::Message::Binary(m.into())).is_err() {
                    break;
                }
                std::thread::sleep(Duration::from_millis(16));
            }
            b
        })
    };
    // 1 s for the stroke to reach the hair (FRAMEs grow from 8 to about 25 kB), then 4 s measured. A polls (reads
    // time out after 5 ms) and times its own stalls: a FRAME that arrives after A itself did not run for over
    // 10 ms (a loaded machine) says nothing of the server and is left out of the lateness count.
    let poll = Duration::from_millis(5);
    a.get_mut().set_read_timeout(Some(poll)).unwrap();
    let t0 = Instant::now();
    // (arrival s, sequence, A stalled since the previous FRAME s)
    let mut got: Vec<(f64, u32, f64)> = Vec::new();
    let (mut size, mut back, mut stalled) = (0, Instant::now(), 0.0f64);
    while t0.elapsed() < Duration::from_secs(5) {
        let m = a.read();
        let now = Instant::now();
        stalled = stalled.max((now - back).saturating_sub(poll).as_secs_f64());
        back = now;
        match m {
            Ok(tungstenite::Message::Binary(m)) if m[0] == 0x82 => {
                if t0.elapsed() > Duration::from_secs(1) {
                    size = size.max(m.len());
                    got.push(((now - t0).as_secs_f64(), u32::from_le_bytes(m[2..6].try_into().unwrap()), stalled));
                }
                stalled = 0.0;
            }
            Ok(_) => {}
            Err(tungstenite::Error::Io(e)) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
            Err(e) => panic!("viewer A: {e}"),
        }
    }
    let late: Vec<f64> = got.iter().map(|&(t, q, _)| t - q as f64 / fps).collect();
    let floor = late.iter().copied().fold(f64::INFINITY, f64::min);
    let judged: Vec<f64> = late.iter().zip(&got).filter(|(_, g)| g.2 <= 0.010).map(|(l, _)| l - floor).collect();
    let over = judged.iter().filter(|&&l| l > 0.015).count();
    let span = got.last().unwrap().1 - got[0].1 + 1;
    // The largest gap less A's own stall in it.
    let gap = got.windows(2).map(|w| w[1].0 - w[0].0 - w[1].2).fold(0.0, f64::max);
    let mut sorted: Vec<f64> = judged.iter().map(|l| 1e3 * l).collect();
    sorted.sort_by(f64::total_cmp);
    eprintln!(
        "{} FRAMEs (up to {size} bytes) of {span} sent; {} judged (A not stalled), {over} of them over 15 ms late; lateness p50 {:.2} ms, p90 {:.2} ms, max {:.2} ms; largest gap less A's stall {:.1} ms",
        got.len(),
        judged.len(),
        sorted[sorted.len() / 2],
        sorted[sorted.len() * 9 / 10],
        sorted[sorted.len() - 1],
        1e3 * gap
    );
    assert!(judged.len() >= 60, "viewer A itself stalled before {} of {} FRAMEs: the machine is too busy to judge", got.len() - judged.len(), got.len());
    assert!((over as f64) < 0.05 * judged.len() as f64, "{over} of {} FRAMEs over 15 ms late", judged.len());
    assert!(2 * got.len() as u32 >= span, "received {} of {span}", got.len());
    assert!(gap < 1.0, "a gap of {gap:.3} s beyond A's own stalls");
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    drop(poser.join().unwrap());
    drop(a);
    // The server's own account of its writers (information: at normal priority on a busy machine they may slip).
    if let Some(l) = s.line_with("delivery:", Duration::from_secs(20)) {
        eprintln!("server: {}", l.split("delivery: ").nth(1).unwrap_or(&l));
    }
}

#[test]
fn a_viewer_that_acknowledges_its_frames_gets_the_newest_after_a_stall_not_a_backlog() {
    // A page busy for a while (software rendering, a loaded machine) used to find a socket's backlog of
    // seconds-old FRAMEs when it came back, and drove the mouse's pseudo-haptics with their stale force. A
    // viewer that acknowledges its FRAMEs (FRAME_ACK) has at most FRAME_WINDOW (2) on their way; after its stall
    // it gets those two, then the newest. Stalls of 0.5, 1 and 1.5 s; after each, A reads and acknowledges for
    // 1 s. Bounds: at most 2 FRAMEs older than the stall's end by more than a quarter of the stall (the frame
    // schedule is 60 fps: sequence / fps), the third FRAME after the stall within 0.25 s of the newest
    // sequence, and at least half the FRAMEs of the second read at the frame rate (the window does not starve a
    // viewer that keeps up). At 30, 60 and 120 fps: the window is a count of FRAMEs, not a time.
    for fps in [30.0, 60.0, 120.0] {
        stall_then_read(fps);
    }
}

/// [`a_viewer_that_acknowledges_its_frames_gets_the_newest_after_a_stall_not_a_backlog`] at `fps` frames a second.
fn stall_then_read(fps: f64) {
    let s = serve(&["--render-strands", "2000", "--fps", &fps.to_string(), "--duration", "15"]);
    let mut a = open(&s.http, None, "").unwrap();
    let ack = |a: &mut tungstenite::WebSocket<std::net::TcpStream>, seq: u32| {
        let mut m = vec![0x0B, 1];
        m.extend_from_slice(&seq.to_le_bytes());
        a.send(tungstenite::Message::Binary(m.into())).unwrap();
    };
    let seq_of = |m: &[u8]| u32::from_le_bytes(m[2..6].try_into().unwrap());
    let first = first_of(&mut a, 0x82);
    let start = Instant::now();
    let s0 = seq_of(&first);
    ack(&mut a, s0);
    a.get_mut().set_read_timeout(Some(Duration::from_millis(5))).unwrap();
    for stall in [0.5, 1.0, 1.5] {
        std::thread::sleep(Duration::from_secs_f64(stall));
        // The sequence the server is at now (its frames are scheduled at sequence / fps after the first).
        let t = Instant::now();
        let mut got: Vec<(f64, u32)> = Vec::new();
        while t.elapsed() < Duration::from_secs(1) {
            match a.read() {
                Ok(tungstenite::Message::Binary(m)) if m[0] == 0x82 => {
                    let q = seq_of(&m);
                    got.push((t.elapsed().as_secs_f64(), q));
                    ack(&mut a, q);
                }
                Ok(_) => {}
                Err(tungstenite::Error::Io(e)) if matches!(e.kind(), std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut) => {}
                Err(e) => panic!("viewer A: {e}"),
            }
        }
        // How old each FRAME was when read: where the schedule was at the stall's end less its sequence, s.
        let now_seq = s0 as f64 + (t - start).as_secs_f64() * fps;
        let stale = got.iter().filter(|&&(_, q)| now_seq - q as f64 > 0.25 * stall * fps).count();
        eprintln!("{fps} fps, stall {stall} s: {} FRAMEs in the next second, {stale} stale; the first sequences {:?} (the schedule at {now_seq:.0})", got.len(), got.iter().take(5).map(|g| g.1).collect::<Vec<_>>());
        assert!(stale <= 2, "{fps} fps: {stale} FRAMEs over {:.2} s old after a {stall} s stall: {:?}", 0.25 * stall, &got[..got.len().min(8)]);
        assert!(got.len() >= 3, "{fps} fps: {} FRAMEs in the second after the stall", got.len());
        assert!(now_seq - got[2].1 as f64 <= 0.25 * fps, "{fps} fps: the third FRAME after a {stall} s stall is {} (the schedule at {now_seq:.0})", got[2].1);
        assert!(got.len() as f64 >= 0.5 * fps, "{} FRAMEs in the second after the stall (at {fps} fps)", got.len());
    }
}
