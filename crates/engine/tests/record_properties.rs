//! Property-based tests of the session record reader (issues 16, 32), with `proptest`: any record written reads
//! back exactly; arbitrary bytes and damaged records never panic, and are refused with the byte offset or read
//! up to their last intact chunk (saying where and why it stopped); a record cut at any byte reads up to its last
//! whole chunk.

use engine::command::Command;
use engine::record::{Ending, Record, RecordError, RecordSettings, StepRecord};
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

/// A haptic step reading a lattice version in 0..=`versions` (a record's steps read only versions its global
/// steps produced), with 1 to 5 device steps (0 to 4 further readings).
fn step(versions: u64) -> impl Strategy<Value = StepRecord> {
    let more = prop::collection::vec(reading(), 0..5);
    (reading(), more, 0..=versions, prop::collection::vec(command(), 0..4), v3(), prop_oneof![Just(0u32), 1u32..=200]).prop_map(|(reading, more_readings, lattice_version, commands, force, carried)| StepRecord { reading, more_readings, lattice_version, commands, force, carried })
}

fn settings() -> impl Strategy<Value = Option<RecordSettings>> {
    prop::option::of((1usize..200_000, 1usize..400, any::<bool>(), 0.1f64..100.0).prop_map(|(render_strands, guides, device, hairs_per_render_strand)| RecordSettings {
        render_strands,
        guides,
        input: if device { "device" } else { "pointer" }.into(),
        hairs_per_render_strand,
        ..RecordSettings::default()
    }))
}

/// Records of up to 2,500 haptic steps (up to three chunks), with lattice resets among their global steps.
fn record() -> impl Strategy<Value = Record> {
    (prop::collection::vec((global_input(), any::<bool>()), 0..6), 0usize..2500).prop_flat_map(|(globals, n)| {
        let versions = globals.len() as u64;
        let resets: Vec<u64> = globals.iter().enumerate().filter(|(_, g)| g.1).map(|(i, _)| i as u64 + 1).collect();
        let inputs: Vec<ToolInput> = globals.iter().map(|g| g.0).collect();
        // Many steps share one drawn step (drawing 2,500 each is slow); their versions never go down.
        (1.0f64..4000.0, settings(), prop::collection::vec(step(versions), 1..5), Just(resets), Just(inputs), Just(n)).prop_map(|(rate_hz, settings, drawn, global_resets, global_inputs, n)| {
            let mut steps: Vec<StepRecord> = (0..n).map(|i| drawn[i * drawn.len() / n.max(1)].clone()).collect();
            steps.sort_by_key(|s| s.lattice_version);
            Record { rate_hz, settings, global_resets, global_inputs, steps }
        })
    })
}

/// A refusal names a byte offset inside the file (or at its end) and what is wrong; so does a read that stopped
/// before the end chunk, and what it read replays (every step reads a lattice version its global steps made).
fn check_refusal(bytes: &[u8]) -> Result<(), TestCaseError> {
    if let Err(e) = Record::from_bytes(bytes) {
        let RecordError::Bad { offset, what } = &e;
        prop_assert!(*offset <= bytes.len() && !what.is_empty(), "{}", e);
        prop_assert!(e.to_string().starts_with(&format!("bad session record at byte {offset}: ")), "{}", e);
    }
    if let Ok(r) = Record::read(bytes) {
        if let Ending::Cut(c) = &r.ending {
            prop_assert!(c.offset <= bytes.len() && !c.why.is_empty() && c.file_bytes == bytes.len(), "{:?}", c);
        }
        let globals = r.record.global_inputs.len() as u64;
        prop_assert!(r.record.steps.iter().all(|s| s.lattice_version <= globals));
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
            bytes[..8].copy_from_slice(b"CFREC4\0\0");
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
    fn every_cut_record_reads_up_to_its_last_whole_chunk(r in record(), cut in any::<prop::sample::Index>()) {
        // Cut anywhere: not a whole record (from_bytes refuses it, naming the offset), but read up to the end of
        // the last whole chunk before the cut (found here by walking the chunk lengths), its steps a prefix of
        // the record's; or refused when the cut is in the magic or the header chunk.
        let b = r.to_bytes();
        let n = cut.index(b.len());
        prop_assert!(Record::from_bytes(&b[..n]).is_err(), "the first {} of {} bytes read as a record", n, b.len());
        check_refusal(&b[..n])?;
        let mut ends = vec![];
        let mut at = 8;
        while at < b.len() {
            at += 8 + u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
            ends.push(at);
        }
        match Record::read(&b[..n]) {
            Err(e) => prop_assert!(n < ends[0], "refused though the header is whole: {}", e),
            Ok(got) => {
                let last = ends.iter().copied().filter(|&e| e <= n).last().unwrap();
                let Ending::Cut(c) = &got.ending else { return Err(TestCaseError::fail(format!("{:?}", got.ending))) };
                prop_assert_eq!(c.offset, last);
                prop_assert!(r.steps.starts_with(&got.record.steps) && r.global_inputs.starts_with(&got.record.global_inputs));
                prop_assert_eq!(&got.record.settings, &r.settings);
            }
        }
    }
}

#[test]
fn a_huge_length_in_a_short_file_is_refused_at_once() {
    // A chunk announcing 4 GiB (a damaged length) is not read, nor allocated: the read stops at its offset.
    let mut b = Record::new(1000.0).to_bytes();
    let n = b.len() - 8 - 20; // without the end chunk (20 bytes of payload)
    b.truncate(n);
    b.extend_from_slice(&u32::MAX.to_le_bytes());
    b.extend_from_slice(&[0; 4]);
    let e = Record::from_bytes(&b).unwrap_err();
    assert!(e.to_string().contains(&format!("byte {n}")), "{e}");
}
