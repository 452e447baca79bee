//! Property-based tests of the UDP device protocol (issue 16), with `proptest`: the packet decoders never
//! panic, refuse a wrong size or magic saying which, and read back what the encoders wrote bit for bit; and
//! a real device fed any stream of pose packets (valid, damaged, absurd) only ever hands the loop finite,
//! in-reach poses, and answers every rejected one with zero force and the rejected flag.

use haptics::device::{DeviceCommand, DeviceProfile, DeviceReading, HapticDevice};
use haptics::udp::{decode_force, decode_pose, encode_force, encode_pose, PacketError, UdpClient, UdpDevice, UdpParams, FLAG_REJECTED, FORCE_BYTES, POSE_BYTES};
use haptics::workspace::Workspace;
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;
use std::time::{Duration, Instant};

/// Any f64 bit pattern (NaN, infinities, subnormals included).
fn any_f64() -> impl Strategy<Value = f64> + Clone {
    any::<u64>().prop_map(f64::from_bits)
}

fn reading(x: impl Strategy<Value = f64> + Clone) -> impl Strategy<Value = DeviceReading> {
    (x.clone(), prop::array::uniform3(x.clone()), prop::array::uniform9(x), any::<u32>())
        .prop_map(|(time, p, m, buttons)| DeviceReading { time, position: Vector3::from(p), rotation: Matrix3::from_row_slice(&m), buttons })
}

fn bits(r: &DeviceReading) -> Vec<u64> {
    std::iter::once(r.time).chain(r.position.iter().copied()).chain(r.rotation.iter().copied()).map(f64::to_bits).collect()
}

/// A decoder's refusal names the size or the magic it found.
fn check_refusal(e: &PacketError, bytes: &[u8], size: usize) -> Result<(), TestCaseError> {
    let text = e.to_string();
    match e {
        PacketError::Size(n, want) => prop_assert!(*n == bytes.len() && *want == size && text.contains(&format!("{n} bytes")), "{}", text),
        PacketError::Magic(m) => prop_assert!(bytes.len() == size && m[..] == bytes[..4] && text.contains("magic"), "{}", text),
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn pose_packets_round_trip_bit_for_bit(seq in any::<u32>(), r in reading(any_f64())) {
        let (s, back) = decode_pose(&encode_pose(seq, &r)).unwrap();
        prop_assert_eq!(s, seq);
        prop_assert_eq!(bits(&back), bits(&r));
        prop_assert_eq!(back.buttons, r.buttons);
    }

    #[test]
    fn force_packets_round_trip_bit_for_bit(seq in any::<u32>(), f in prop::array::uniform3(any_f64()), t in prop::array::uniform3(any_f64()), flags in any::<u32>()) {
        let c = DeviceCommand { force: Vector3::from(f), torque: Vector3::from(t) };
        let (s, back, fl) = decode_force(&encode_force(seq, &c, flags)).unwrap();
        prop_assert_eq!((s, fl), (seq, flags));
        let b = |v: &Vector3<f64>| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        prop_assert_eq!((b(&back.force), b(&back.torque)), (b(&c.force), b(&c.torque)));
    }

    #[test]
    fn arbitrary_datagrams_never_panic_the_decoders(bytes in prop::collection::vec(any::<u8>(), 0..200), magic in prop::sample::select(vec![&b"CFP1"[..], b"CFF1", b"XXXX"])) {
        let mut bytes = bytes;
        if bytes.len() >= 4 {
            bytes[..4].copy_from_slice(magic);
        }
        match decode_pose(&bytes) {
            Ok(_) => prop_assert!(bytes.len() == POSE_BYTES && &bytes[..4] == b"CFP1"),
            Err(e) => check_refusal(&e, &bytes, POSE_BYTES)?,
        }
        match decode_force(&bytes) {
            Ok(_) => prop_assert!(bytes.len() == FORCE_BYTES && &bytes[..4] == b"CFF1"),
            Err(e) => check_refusal(&e, &bytes, FORCE_BYTES)?,
        }
    }
}

/// A pose packet: plausible (near the last, in reach), absurd (any bit pattern), or damaged bytes.
#[derive(Debug, Clone)]
enum Sent {
    Plausible(u32, f64, [f64; 3]),
    Absurd(u32, DeviceReading),
    Damaged(Vec<u8>),
}

fn sent() -> impl Strategy<Value = Sent> {
    prop_oneof![
        3 => (0u32..40, 0.0f64..1.0, prop::array::uniform3(-0.3f64..0.3)).prop_map(|(s, t, p)| Sent::Plausible(s, t, p)),
        2 => (any::<u32>(), reading(prop_oneof![any_f64(), -2.0f64..2.0])).prop_map(|(s, r)| Sent::Absurd(s, r)),
        1 => prop::collection::vec(any::<u8>(), 0..130).prop_map(Sent::Damaged),
    ]
}

proptest! {
    // Real sockets: fewer cases.
    #![proptest_config(ProptestConfig { cases: 24, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn a_device_fed_any_stream_gives_the_loop_only_sane_poses(stream in prop::collection::vec(sent(), 1..24)) {
        let params = UdpParams { workspace: Workspace { scale: 1.0, offset: Vector3::zeros() }, wall_clock: false, max_packets_per_step: 64, ..UdpParams::for_profile(&DeviceProfile::PHANTOM_OMNI) };
        let max_reach = params.max_reach;
        let mut dev = UdpDevice::bind_with("127.0.0.1:0", params).unwrap();
        let mut client = UdpClient::connect(dev.local_addr().unwrap()).unwrap();
        client.set_timeout(Some(Duration::from_secs(2))).unwrap();
        let mut poses = 0u64;
        for s in &stream {
            match s {
                Sent::Plausible(seq, t, p) => {
                    client.send_seq(*seq, &DeviceReading { time: *t, position: Vector3::from(*p), rotation: Matrix3::identity(), buttons: 0 }).unwrap();
                    poses += 1;
                }
                Sent::Absurd(seq, r) => {
                    client.send_seq(*seq, r).unwrap();
                    poses += 1;
                }
                Sent::Damaged(b) => {
                    // A damaged packet that still decodes is a pose like any other.
                    if decode_pose(b).is_ok() {
                        poses += 1;
                    }
                    client.send_raw(b).unwrap();
                }
            }
        }
        // Read until every packet was judged (loopback delivers in microseconds), then answer with 1 N.
        let st = dev.status();
        let judged = || { let c = st.counts(); c.accepted + c.rejected_total() + c.foreign + c.malformed };
        let deadline = Instant::now() + Duration::from_secs(5);
        let mut r = dev.read(0.0);
        while judged() < stream.len() as u64 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_micros(200));
            r = dev.read(0.0);
        }
        prop_assert_eq!(judged(), stream.len() as u64);
        prop_assert_eq!(st.counts().malformed, stream.len() as u64 - poses);
        if let Some(r) = r {
            prop_assert!(r.time.is_finite() && r.position.iter().chain(r.rotation.iter()).all(|x| x.is_finite()), "{:?}", r);
            prop_assert!(r.position.norm() <= max_reach, "{:?}", r);
        }
        let c = st.counts();
        dev.write(&DeviceCommand { force: Vector3::new(1.0, 0.0, 0.0), torque: Vector3::zeros() });
        let (mut rejected, mut accepted) = (0, 0);
        for _ in 0..c.accepted + c.rejected_total() {
            let (_, f, flags) = client.receive().unwrap();
            if flags & FLAG_REJECTED != 0 {
                prop_assert_eq!(f.force, Vector3::zeros());
                rejected += 1;
            } else {
                prop_assert_eq!(f.force.x, 1.0);
                accepted += 1;
            }
        }
        prop_assert_eq!((accepted, rejected), (c.accepted, c.rejected_total()));
        prop_assert_eq!(c.malformed + c.accepted + c.rejected_total() + c.foreign, stream.len() as u64);
    }
}
