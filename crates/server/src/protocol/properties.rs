//! Property-based tests of the client message decoder [`parse_client`] (issue 16), with `proptest`: any
//! bytes give a message or an ERROR with the right code and a message saying what is wrong, never a panic;
//! what a decoded message holds is in range; and messages encoded as docs/protocol.md says (an encoder
//! written here, independent of the viewer's) decode to what was encoded.

use super::*;
use hairstyle::fit::{Axis, FitOptions};
use proptest::prelude::*;

/// The client message types, in type-byte order from 0x01: the names their malformed-message errors carry.
const NAMES: [&str; 11] = ["POSE", "TAKE_CONTROL", "SELECT_TOOL", "SET_HAIR", "RESET", "LOAD", "SAVE", "PING", "HEAD", "SET_TREATMENT", "FRAME_ACK"];
/// The last known client type byte.
const LAST: u8 = NAMES.len() as u8;

/// Known types (and a few unknown ones) with the right version most of the time.
fn header() -> impl Strategy<Value = (u8, u8)> {
    let kind = prop_oneof![9 => 0x01u8..=LAST, 1 => any::<u8>()];
    let version = prop_oneof![9 => Just(VERSION), 1 => any::<u8>()];
    (kind, version)
}

/// A message: a header and any payload; the payload's f32 slots are sometimes NaN, infinite or huge.
fn message() -> impl Strategy<Value = Vec<u8>> {
    let word = prop_oneof![4 => any::<[u8; 4]>(), 1 => prop::sample::select(vec![f32::NAN, f32::INFINITY, -f32::INFINITY, 1e30, 3.4e38, -0.0, 0.5]).prop_map(f32::to_le_bytes)];
    (header(), prop::collection::vec(word, 0..12), 0usize..4).prop_map(|((k, v), words, extra)| {
        let mut b = vec![k, v];
        words.iter().for_each(|w| b.extend_from_slice(w));
        b.truncate(b.len().saturating_sub(extra));
        b
    })
}

/// The table above is the protocol's: its last entry is client::FRAME_ACK's name, and the next type byte is
/// unknown, so a type added to the protocol fails here every run, not only when the random bytes find it.
#[test]
fn the_known_types_are_the_protocols() {
    assert_eq!(LAST, client::FRAME_ACK);
    let e = parse_client(&[client::FRAME_ACK, VERSION]).unwrap_err();
    assert!(e.code == code::MALFORMED && e.message.contains(NAMES[LAST as usize - 1]), "{}", e.message);
    assert_eq!(parse_client(&[LAST + 1, VERSION]).unwrap_err().code, code::UNKNOWN_TYPE);
}

fn f32s(kind: u8, v: &[f32]) -> Vec<u8> {
    let mut b = vec![kind, VERSION];
    v.iter().for_each(|x| b.extend_from_slice(&x.to_le_bytes()));
    b
}

fn axis_id(a: Option<Axis>) -> u8 {
    a.map_or(0, |a| Axis::ALL.iter().position(|&b| b == a).unwrap() as u8 + 1)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn any_bytes_are_a_message_or_an_error_with_the_right_code(b in prop_oneof![message(), prop::collection::vec(any::<u8>(), 0..40)]) {
        match parse_client(&b) {
            Err(e) => {
                prop_assert!(!e.message.is_empty());
                let want = if b.len() < 2 { code::MALFORMED } else if b[1] != VERSION { code::BAD_VERSION } else if !(0x01..=LAST).contains(&b[0]) { code::UNKNOWN_TYPE } else { code::MALFORMED };
                prop_assert_eq!(e.code, want, "{}", e.message);
                // A malformed message's error names its type (the others name the version or the type byte).
                if want == code::MALFORMED && b.len() >= 2 {
                    prop_assert!(e.message.contains(NAMES[b[0] as usize - 1]), "{}", e.message);
                }
                // ERROR encodes it: code and length-prefixed text.
                let m = encode_error(&e);
                prop_assert_eq!((m[0], u16::from_le_bytes([m[2], m[3]]), u16::from_le_bytes([m[4], m[5]]) as usize), (server::ERROR, e.code, m.len() - 6));
            }
            Ok(ClientMessage::Pose { position, rotation, .. }) => {
                prop_assert!(position.iter().all(|x| x.is_finite()) && position.norm() <= MAX_POSE_DISTANCE);
                prop_assert!((rotation.transpose() * rotation - Matrix3::identity()).amax() < 1e-9 && (rotation.determinant() - 1.0).abs() < 1e-9, "{}", rotation);
            }
            Ok(ClientMessage::Command(Command::SetHair { hair_type, curliness, combing_ease })) => {
                prop_assert!((hair_type as usize) < strand::HairType::ALL.len());
                prop_assert!((0.0..=1.0).contains(&curliness) && (0.0..=1.0).contains(&combing_ease));
            }
            Ok(ClientMessage::Command(Command::SetTreatment(t))) => prop_assert_eq!(tools::treatment::Treatment::from_id(b[2]), Some(t)),
            Ok(ClientMessage::Command(Command::SetHead { position, rotation })) => {
                prop_assert!(engine::command::head_pose(&position, &rotation).is_some());
            }
            Ok(ClientMessage::Load(format, opts, _, _)) => {
                prop_assert!(format < FORMATS.len());
                prop_assert!(opts.units.is_none_or(|u| u.is_finite() && u > 0.0));
            }
            Ok(ClientMessage::Save(format)) => prop_assert!(format < FORMATS.len()),
            Ok(_) => {}
        }
    }

    #[test]
    fn poses_round_trip(p in prop::array::uniform3(-5.0f32..5.0), q in prop::array::uniform4(-1.0f32..1.0), buttons in any::<u32>()) {
        prop_assume!(q.iter().map(|x| x * x).sum::<f32>() > 1e-3);
        let mut b = f32s(client::POSE, &[p[0], p[1], p[2], q[0], q[1], q[2], q[3]]);
        b.extend_from_slice(&buttons.to_le_bytes());
        let want = UnitQuaternion::from_quaternion(Quaternion::new(q[3] as f64, q[0] as f64, q[1] as f64, q[2] as f64)).to_rotation_matrix().into_inner();
        match parse_client(&b).unwrap() {
            ClientMessage::Pose { position, rotation, buttons: got } => {
                prop_assert_eq!(position, Vector3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                prop_assert!((rotation - want).amax() < 1e-12);
                prop_assert_eq!(got, buttons);
            }
            m => prop_assert!(false, "{:?}", m),
        }
    }

    #[test]
    fn commands_round_trip(tool in 0u8..6, hair in 0u8..strand::HairType::ALL.len() as u8, c in 0.0f32..=1.0, e in 0.0f32..=1.0, head in prop::array::uniform3(-0.5f32..0.5), turn in prop::array::uniform3(-1.5f32..1.5), token in any::<u32>(), format in 0u8..4) {
        prop_assert_eq!(parse_client(&[client::SELECT_TOOL, VERSION, tool]).unwrap(), ClientMessage::Command(Command::SelectTool(Tool::from_id(tool).unwrap())));
        let mut b = vec![client::SET_HAIR, VERSION, hair];
        b.extend_from_slice(&c.to_le_bytes());
        b.extend_from_slice(&e.to_le_bytes());
        prop_assert_eq!(parse_client(&b).unwrap(), ClientMessage::Command(Command::SetHair { hair_type: hair, curliness: c as f64, combing_ease: e as f64 }));
        let b = f32s(client::HEAD, &[head[0], head[1], head[2], turn[0], turn[1], turn[2]]);
        let v = |a: [f32; 3]| Vector3::new(a[0] as f64, a[1] as f64, a[2] as f64);
        prop_assert_eq!(parse_client(&b).unwrap(), ClientMessage::Command(Command::SetHead { position: v(head), rotation: v(turn) }));
        let mut b = vec![client::PING, VERSION];
        b.extend_from_slice(&token.to_le_bytes());
        prop_assert_eq!(parse_client(&b).unwrap(), ClientMessage::Ping(token));
        prop_assert_eq!(parse_client(&[client::SAVE, VERSION, format]).unwrap(), ClientMessage::Save(format as usize));
        prop_assert_eq!(parse_client(&[client::RESET, VERSION]).unwrap(), ClientMessage::Command(Command::Reset));
        prop_assert_eq!(parse_client(&[client::TAKE_CONTROL, VERSION]).unwrap(), ClientMessage::TakeControl);
    }

    #[test]
    fn loads_round_trip(format in 0u8..4, up in prop::option::of(prop::sample::select(Axis::ALL.to_vec())), front in prop::option::of(prop::sample::select(Axis::ALL.to_vec())), fit in any::<bool>(), units in prop::option::of(1e-4f32..10.0), with_options in any::<bool>(), file in prop::collection::vec(any::<u8>(), 0..64)) {
        let (mut b, opts) = if with_options {
            let mut b = vec![client::LOAD, VERSION, 0x80 | format, axis_id(up), axis_id(front), !fit as u8, 0];
            b.extend_from_slice(&units.unwrap_or(0.0).to_le_bytes());
            (b, FitOptions { units: units.map(|u| u as f64), up, front, fit })
        } else {
            (vec![client::LOAD, VERSION, format], FitOptions::default())
        };
        b.extend_from_slice(&file);
        prop_assert_eq!(parse_client(&b).unwrap(), ClientMessage::Load(format as usize, opts, None, file));
    }
}
