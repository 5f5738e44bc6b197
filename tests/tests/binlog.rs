//! The QEMU image's binary CAN log: host-sim's encoder (`host_sim::sim::replay::binary_log`)
//! against the target's decoder (`gait_loop::binlog`), compiled for the host.
//!
//! * round trip: random candump logs (any identifiers, lengths, data and non-decreasing times)
//!   decode to exactly the frames `host_sim::sim::replay::parse` replays, with their times, and the
//!   header's period, first and last time, count and feet;
//! * every strict prefix of a valid file is refused as truncated (never a panic, never a
//!   shorter log taken for a whole one); single-field corruptions are refused by name.

use gait_loop::binlog::{Error, Frames, Header, SliceBytes};
use gait_loop::player::Source;
use host_sim::sim::bus::{log_line, LOG_EPOCH_S};
use host_sim::sim::replay::{self, binary_log, node_sends};
use planner_core::gait::{Footstep, Side};
use planner_core::node::NodeConfig;
use planner_core::wire::RawFrame;
use proptest::prelude::*;

/// Decodes one log: its header and its frames (time, frame).
fn decode(bytes: &[u8]) -> Result<(Header, Vec<(u64, RawFrame)>), Error> {
    let mut src = SliceBytes::new(bytes);
    let header = Header::read(&mut src)?.ok_or(Error::Truncated)?;
    let mut frames = Frames::new(&header, &mut src);
    let mut out = Vec::new();
    while let Some(f) = frames.next_frame() {
        out.push((f.us, f.frame));
    }
    if let Some(e) = frames.error() {
        return Err(e);
    }
    Ok((header, out))
}

fn config() -> NodeConfig {
    NodeConfig {
        left: Footstep::new(Side::Left, 0.25, 0.125, 0.5),
        right: Footstep::new(Side::Right, -0.25, -0.0625, -0.75),
        ..NodeConfig::hrp2()
    }
}

/// A candump log of `frames` (bus time increments in ns, identifier, data).
fn log_of(frames: &[(u64, u16, Vec<u8>)]) -> Vec<String> {
    let mut t = 0u64;
    frames
        .iter()
        .map(|(dt, id, data)| {
            t += dt;
            log_line(t, &RawFrame::new(*id, data).unwrap())
        })
        .collect()
}

fn frame_strategy() -> impl Strategy<Value = (u64, u16, Vec<u8>)> {
    (
        prop_oneof![Just(0u64), 0u64..10_000_000, 0u64..100_000_000_000],
        prop_oneof![
            0u16..=0x7FF,
            Just(0x010u16),
            Just(0x020),
            Just(0x080),
            Just(0x100),
            Just(0x200)
        ],
        proptest::collection::vec(any::<u8>(), 0..=8),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn a_log_round_trips(frames in proptest::collection::vec(frame_strategy(), 0..40)) {
        let cfg = config();
        let log = log_of(&frames);
        let bytes = binary_log("prop", &log, &cfg).unwrap();
        let (header, got) = decode(&bytes).unwrap();
        prop_assert_eq!(header.name(), "prop");
        prop_assert_eq!(header.period_us, 5000);
        prop_assert_eq!(header.feet, [cfg.left, cfg.right]);
        let first_us = LOG_EPOCH_S * 1_000_000 + frames.first().map_or(0, |f| f.0 / 1000);
        prop_assert_eq!(header.first_us, if frames.is_empty() { 0 } else { first_us });
        // The frames `replay::parse` replays, with their log times.
        let mut t = 0u64;
        let want: Vec<(u64, RawFrame)> = frames
            .iter()
            .filter_map(|(dt, id, data)| {
                t += dt;
                let f = RawFrame::new(*id, data).unwrap();
                (!node_sends(*id)).then_some((LOG_EPOCH_S * 1_000_000 + t / 1000, f))
            })
            .collect();
        prop_assert_eq!(&got, &want);
        prop_assert_eq!(header.count as usize, want.len());
        let text = log.join("\n");
        let parsed = replay::parse(&text, cfg.params.dt).unwrap().frames;
        prop_assert_eq!(parsed.len(), got.len());
        for (p, (_, f)) in parsed.iter().zip(&got) {
            prop_assert_eq!(p.frame, *f);
        }
        if let Some(&(last, _)) = want.last() {
            prop_assert_eq!(header.last_us, last);
        }
    }
}

#[test]
fn truncated_and_corrupted_logs_are_refused() {
    let frames: Vec<(u64, u16, Vec<u8>)> = vec![
        (1_000, 0x020, vec![1, 0, 0x17]),
        (2_000_000, 0x080, vec![0; 8]),
        (300_000_000, 0x010, vec![1, 2, 3, 4, 5, 6, 7, 8]),
        (5_000, 0x7FF, vec![]),
    ];
    let cfg = config();
    let bytes = binary_log("cut", &log_of(&frames), &cfg).unwrap();
    assert_eq!(decode(&bytes).unwrap().1.len(), 3); // the ACK (0x080) is the node's
    for n in 1..bytes.len() {
        assert_eq!(
            decode(&bytes[..n]).err(),
            Some(Error::Truncated),
            "prefix {n}"
        );
    }
    // An empty input is the end of the file, not a log.
    assert_eq!(Header::read(&mut SliceBytes::new(&[])), Ok(None));

    let corrupt = |at: usize, b: u8| {
        let mut v = bytes.clone();
        v[at] = b;
        decode(&v).err()
    };
    let name_at = 6;
    let period_at = name_at + 3;
    let first_at = period_at + 4;
    let count_at = first_at + 16;
    let feet_at = count_at + 4;
    let frames_at = feet_at + 48;
    assert_eq!(corrupt(0, b'X'), Some(Error::Magic));
    assert_eq!(corrupt(4, 2), Some(Error::Version(2)));
    assert_eq!(corrupt(5, 33), Some(Error::Name));
    assert_eq!(corrupt(name_at, b' '), Some(Error::Name));
    let mut v = bytes.clone();
    v[period_at..period_at + 4].copy_from_slice(&1u32.to_le_bytes());
    assert_eq!(decode(&v).err(), Some(Error::Period));
    let mut v = bytes.clone();
    v[first_at + 8..first_at + 16].copy_from_slice(&0u64.to_le_bytes());
    assert_eq!(decode(&v).err(), Some(Error::Last));
    let mut v = bytes.clone();
    v[feet_at..feet_at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
    assert_eq!(decode(&v).err(), Some(Error::Feet));
    // One frame fewer announced: the last one read is not at `last_us`.
    let mut v = bytes.clone();
    v[count_at..count_at + 4].copy_from_slice(&2u32.to_le_bytes());
    assert_eq!(decode(&v).err(), Some(Error::Time));
    // The first frame: its increment (0: the log starts with it), identifier, length.
    assert_eq!(bytes[frames_at], 0);
    let mut v = bytes.clone();
    v[frames_at + 2] = 0x08;
    assert_eq!(decode(&v).err(), Some(Error::Id(0x820)));
    assert_eq!(corrupt(frames_at + 3, 9), Some(Error::Length(9)));
    // An increment beyond the last time, and one of 11 bytes.
    let mut v = bytes[..frames_at].to_vec();
    v.extend_from_slice(&[0xFF; 10]);
    v.push(0x01);
    assert_eq!(decode(&v).err(), Some(Error::Delta));
    let mut v = bytes[..frames_at].to_vec();
    v.extend_from_slice(&[0xFF, 0xFF, 0xFF, 0x7F, 0x20, 0x00, 0x00]);
    assert_eq!(decode(&v).err(), Some(Error::Time));
}

#[test]
fn the_encoder_refuses_what_the_format_cannot_hold() {
    let cfg = config();
    let log = log_of(&[(0, 0x020, vec![1, 0, 0x17])]);
    assert!(binary_log("a name with spaces", &log, &cfg).is_err());
    assert!(binary_log(&"x".repeat(33), &log, &cfg).is_err());
    assert!(binary_log("ok", &["not a log line".to_string()], &cfg).is_err());
    let backwards = vec![
        log_line(2_000, &RawFrame::new(0x020, &[]).unwrap()),
        log_line(1_000, &RawFrame::new(0x020, &[]).unwrap()),
    ];
    assert!(binary_log("ok", &backwards, &cfg).is_err());
    // Several logs in one file are read one after the other.
    let mut two = binary_log("one", &log, &cfg).unwrap();
    two.extend(binary_log("two", &log, &cfg).unwrap());
    let mut src = SliceBytes::new(&two);
    for name in ["one", "two"] {
        let h = Header::read(&mut src).unwrap().unwrap();
        assert_eq!(h.name(), name);
        Frames::new(&h, &mut src).skip_rest().unwrap();
    }
    assert_eq!(Header::read(&mut src), Ok(None));
}
