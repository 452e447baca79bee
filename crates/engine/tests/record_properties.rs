//! Property-based tests of the session record reader (issue 16), with `proptest`: any record written reads
//! back exactly; arbitrary bytes and damaged records never panic and are refused with the byte offset.

use engine::command::Command;
use engine::record::{Record, RecordError, StepRecord};
use engine::tool::{Tool, ToolInput};
use haptics::device::DeviceReading;
use nalgebra::{Isometry3, Matrix3, Vector3};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    ProptestConfig { cases: 128, failure_persistence: None, ..ProptestConfig::default() }
}

/// Any f64 the record keeps bit for bit (it is written exactly; NaN would not compare equal).
fn x() -> impl Strategy<Value = f64> {
    prop_oneof![4 => -10.0f64..10.0, 1 => Just(-0.0), 1 => Just(f64::INFINITY), 1 => Just(1e-300), 1 => Just(f64::MAX)]
}

fn v3() -> impl Strategy<Value = Vector3<f64>> {
    [x(), x(), x()].prop_map(|[a, b, c]| Vector3::new(a, b, c))
}

fn m3() -> impl Strategy<Value = Matrix3<f64>> {
    prop::array::uniform9(x()).prop_map(|m| Matrix3::from_column_slice(&m))
}

fn tool() -> impl Strategy<Value = Tool> {
    prop::sample::select(Tool::ALL.to_vec())
}

fn command() -> impl Strategy<Value = Command> {
    prop_oneof![
        tool().prop_map(Command::SelectTool),
        (any::<u8>(), x(), x()).prop_map(|(hair_type, curliness, combing_ease)| Command::SetHair { hair_type, curliness, combing_ease }),
        Just(Command::Reset),
        (v3(), v3()).prop_map(|(position, rotation)| Command::SetHead { position, rotation }),
        any::<u32>().prop_map(Command::LimitStrands),
        prop::sample::select(tools::treatment::Treatment::ALL.to_vec()).prop_map(Command::SetTreatment),
    ]
}

fn global_input() -> impl Strategy<Value = ToolInput> {
    // A moved head is kept as a unit quaternion: from a finite rotation vector.
    let head = prop_oneof![Just(Isometry3::identity()), ([-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0], [-3.0f64..3.0, -3.0f64..3.0, -3.0f64..3.0]).prop_map(|(t, r)| Isometry3::new(Vector3::from(t), Vector3::from(r)))];
    (tool(), any::<bool>(), v3(), m3(), any::<bool>(), any::<u64>(), head).prop_map(|(tool, present, position, rotation, pressed, cuts, head)| ToolInput { tool, present, position, rotation, pressed, cuts, head })
}

fn reading() -> impl Strategy<Value = Option<DeviceReading>> {
    prop::option::of((x(), v3(), m3(), any::<u32>()).prop_map(|(time, position, rotation, buttons)| DeviceReading { time, position, rotation, buttons }))
}

fn step() -> impl Strategy<Value = StepRecord> {
    // Several device steps per physics step (0 further readings: one).
    let more = prop::collection::vec(reading(), 0..5);
    (reading(), more, any::<u64>(), prop::collection::vec(command(), 0..4), v3()).prop_map(|(reading, more_readings, lattice_version, commands, force)| StepRecord { reading, more_readings, lattice_version, commands, force })
}

fn record() -> impl Strategy<Value = Record> {
    (1.0f64..4000.0, prop::collection::vec(any::<u64>(), 0..4), prop::collection::vec(global_input(), 0..4), prop::collection::vec(step(), 0..6))
        .prop_map(|(rate_hz, global_resets, global_inputs, steps)| Record { rate_hz, global_resets, global_inputs, steps })
}

/// A refusal names a byte offset inside the file (or at its end) and what is wrong.
fn check_refusal(bytes: &[u8]) -> Result<(), TestCaseError> {
    if let Err(e) = Record::from_bytes(bytes) {
        let RecordError::Bad { offset, what } = &e;
        prop_assert!(*offset <= bytes.len() && !what.is_empty(), "{}", e);
        prop_assert!(e.to_string().starts_with(&format!("bad session record at byte {offset}: ")), "{}", e);
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn records_round_trip_exactly(r in record()) {
        prop_assert_eq!(Record::from_bytes(&r.to_bytes()).unwrap(), r);
    }

    #[test]
    fn arbitrary_bytes_never_panic(mut bytes in prop::collection::vec(any::<u8>(), 0..300), magic in any::<bool>()) {
        if magic && bytes.len() >= 8 {
            bytes[..8].copy_from_slice(b"CFREC2\0\0");
        }
        check_refusal(&bytes)?;
    }

    #[test]
    fn damaged_records_never_panic_and_name_the_offset(r in record(), at in any::<prop::sample::Index>(), byte in any::<u8>()) {
        let mut b = r.to_bytes();
        let i = at.index(b.len());
        b[i] = byte;
        check_refusal(&b)?;
    }

    #[test]
    fn every_cut_record_is_refused(r in record(), cut in any::<prop::sample::Index>()) {
        let b = r.to_bytes();
        let n = cut.index(b.len());
        prop_assert!(Record::from_bytes(&b[..n]).is_err(), "the first {} of {} bytes read as a record", n, b.len());
        check_refusal(&b[..n])?;
    }
}

#[test]
fn a_huge_count_in_a_short_file_is_refused_at_once() {
    let mut b = Record::new(1000.0).to_bytes();
    let n = b.len();
    b[n - 8..].copy_from_slice(&u64::MAX.to_le_bytes()); // steps: u64::MAX, none follow
    let e = Record::from_bytes(&b).unwrap_err();
    assert!(e.to_string().contains(&format!("byte {n}")), "{e}");
}
