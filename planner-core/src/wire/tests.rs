//! Unit tests of the message set.

use super::stream::round_to_i32;
use super::*;

#[test]
fn round_to_i32_is_libm_round_saturated() {
    let mut cases = vec![
        0.0,
        -0.0,
        0.5,
        -0.5,
        1.5,
        -1.5,
        2.5,
        -2.5,
        0.49999999999999994,
        -0.49999999999999994,
        1e-300,
        -1e-300,
        2147483646.5,
        2147483647.4,
        2147483647.5,
        -2147483648.4,
        -2147483648.5,
        -2147483649.0,
        1e12,
        -1e12,
        f64::MAX,
        f64::MIN,
        f64::INFINITY,
        f64::NEG_INFINITY,
        4503599627370495.5,
        -4503599627370495.5,
    ];
    let mut x = 0x1234_5678_9abc_def0_u64;
    for _ in 0..100_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let u = (x >> 11) as f64 / (1u64 << 53) as f64;
        // Spread over ±2^33, with many exact halves.
        cases.push((u - 0.5) * 2f64.powi(34));
        cases.push(((x % 20_001) as f64 - 10_000.0) * 0.5);
    }
    for &c in &cases {
        let want = libm::round(c).clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32;
        assert_eq!(round_to_i32(c), want, "{c:e}");
    }
    assert_eq!(round_to_i32(f64::NAN), 0);
}

/// The `f32` path (the Cortex-M4F node's encoding) against `libm::roundf`, saturated, on the
/// same kinds of values: halves, the ends of the `i32` range, huge values, and every `f32`
/// bit pattern of a spread sample (NaNs included).
#[test]
fn round_to_i32_of_f32_is_libm_roundf_saturated() {
    let mut cases = vec![
        0.0_f32,
        -0.0,
        0.5,
        -0.5,
        1.5,
        -1.5,
        2.5,
        -2.5,
        0.499_999_97,
        -0.499_999_97,
        1e-40,
        -1e-40,
        2_147_483_500.0,
        2_147_483_648.0,
        -2_147_483_648.0,
        -2_147_483_904.0,
        8_388_607.5,
        -8_388_607.5,
        16_777_215.0,
        1e12,
        -1e12,
        f32::MAX,
        f32::MIN,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ];
    let mut x = 0x9abc_def0_u32;
    for _ in 0..200_000 {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        cases.push(f32::from_bits(x));
        cases.push(((x % 20_001) as f32 - 10_000.0) * 0.5);
    }
    for &c in &cases {
        let want = if c.is_nan() {
            0
        } else {
            // Through f64: exact for every f32, and f64's clamp to the i32 range is exact.
            f64::from(libm::roundf(c)).clamp(f64::from(i32::MIN), f64::from(i32::MAX)) as i32
        };
        assert_eq!(round_to_i32(c), want, "{c:e}");
    }
}

#[test]
fn steps_round_trip_at_wire_precision() {
    for &(x, y, yaw) in &[
        (0.0, 0.0, 0.0),
        (1.2345, -0.1, 0.3),
        (-32.0, 32.7, -3.1),
        (0.0002, 0.0003, 3.1),
    ] {
        let s = WireStep::from_si(7, true, x, y, yaw).unwrap();
        let f = Command::Append(s).encode();
        let Command::Append(back) = Command::decode(&f).unwrap() else {
            panic!("not an append")
        };
        assert_eq!(back, s);
        let (bx, by, byaw) = back.si();
        let half = STEP_UNIT / 2.0 + 1e-12;
        assert!((bx - x).abs() <= half && (by - y).abs() <= half);
        let dyaw = libm::remainder(byaw - yaw, core::f64::consts::TAU);
        assert!(dyaw.abs() <= YAW_UNIT / 2.0 + 1e-12, "{yaw} -> {byaw}");
    }
    assert!(WireStep::from_si(0, false, 33.0, 0.0, 0.0).is_none());
    assert!(WireStep::from_si(0, false, f64::NAN, 0.0, 0.0).is_none());
}

/// Every heading is representable: ±π, π − half a unit, several turns (issue 10, item 7).
#[test]
fn every_finite_heading_is_representable() {
    use core::f64::consts::{PI, TAU};
    for yaw in [PI, -PI, PI - 5e-4, -PI + 5e-4, 3.0 * PI, 100.0, -7.0, 0.0] {
        let s = WireStep::from_si(0, true, 0.0, 0.0, yaw).expect("representable");
        let Ok(Command::Append(back)) = Command::decode(&Command::Append(s).encode()) else {
            panic!("decodes");
        };
        let d = libm::remainder(back.si().2 - yaw, TAU);
        assert!(d.abs() <= YAW_UNIT / 2.0 + 1e-9, "{yaw}: {}", back.si().2);
    }
    assert!(WireStep::from_si(0, true, 0.0, 0.0, f64::INFINITY).is_none());
}

/// Encoder and decoder agree on every range: the extreme values the decoder accepts are
/// produced by the encoder, and one unit beyond is refused by it (issue 10, item 7).
#[test]
fn encoder_and_decoder_agree_on_the_ranges() {
    let (min, max) = signed_range(STEP_BITS);
    for v in [min, max] {
        let m = f64::from(v) * STEP_UNIT;
        let s = WireStep::from_si(1, false, m, m, 0.0).expect("extreme encodable");
        assert_eq!((s.x, s.y), (v, v));
        let Ok(Command::Append(back)) = Command::decode(&Command::Append(s).encode()) else {
            panic!("decodes");
        };
        assert_eq!(back, s);
    }
    let beyond = f64::from(max + 1) * STEP_UNIT;
    assert!(WireStep::from_si(1, false, beyond, 0.0, 0.0).is_none());
    let below = f64::from(min - 1) * STEP_UNIT;
    assert!(WireStep::from_si(1, false, 0.0, below, 0.0).is_none());
    // Every 17-bit pattern decodes to a value in range, and re-encodes to itself.
    for raw in [0u64, 1, 0xFFFF, 0x1_0000, 0x1_FFFF] {
        let bits = raw << 10 | raw << 27;
        let mut d = bits.to_le_bytes();
        d[7] = crc8(ids::STEP_APPEND, &d[..7]);
        let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
        let Ok(Command::Append(s)) = Command::decode(&f) else {
            panic!("decodes");
        };
        assert!(s.in_range());
        assert_eq!(Command::Append(s).encode(), f);
    }
}

#[test]
fn modifications_carry_a_version_and_an_offset() {
    let base = WireStep::from_si(5, true, 10.0, 0.1, 0.0).unwrap();
    let m = WireModify::from_si(&base, 3, 10.25, 0.05, -0.2).unwrap();
    assert_eq!(
        (m.id, m.version, m.left, m.dx, m.dy),
        (5, 3, true, 500, -100)
    );
    let f = Command::Modify(m).encode();
    assert_eq!(Command::decode(&f), Ok(Command::Modify(m)));
    let s = m.applied_to(&base).unwrap();
    let (x, y, yaw) = s.si();
    assert!((x - 10.25).abs() < 1e-12 && (y - 0.05).abs() < 1e-12);
    assert!((yaw + 0.2).abs() <= YAW_UNIT / 2.0);
    // The offset's range: ±4.096 m.
    assert!(WireModify::from_si(&base, 1, 14.0955, 0.1, 0.0).is_some());
    assert!(WireModify::from_si(&base, 1, 14.1, 0.1, 0.0).is_none());
    // Newer: 1 … 63 ahead modulo 128.
    let v = |version| WireModify { version, ..m };
    assert!(v(4).is_newer_than(3) && v(66).is_newer_than(3) && v(0).is_newer_than(127));
    assert!(!v(3).is_newer_than(3) && !v(2).is_newer_than(3) && !v(67).is_newer_than(3));
    // The controller's book counts versions per step.
    let mut book = StepBook::new();
    assert!(book.modify(9, 0.0, 0.0, 0.0).is_none(), "never appended");
    assert!(book.append(9, false, 0.2, -0.1, 0.0).is_some());
    for want in 1..=130u32 {
        let Some(Command::Modify(m)) = book.modify(9, 0.25, -0.1, 0.0) else {
            panic!("modify");
        };
        assert_eq!(u32::from(m.version), want % 128);
    }
}

#[test]
fn bad_frames_are_rejected_with_a_reason() {
    let f = RawFrame::new(ids::CONTROL, &[3, 9, crc8(ids::CONTROL, &[3, 9])]).unwrap();
    assert_eq!(Command::decode(&f), Err((Reason::OutOfRange, 3)));
    let f = RawFrame::new(ids::CONTROL, &[3, 1]).unwrap();
    assert_eq!(Command::decode(&f), Err((Reason::BadLength, 3)));
    let f = RawFrame::new(0x123, &[]).unwrap();
    assert_eq!(Command::decode(&f), Err((Reason::UnknownId, 0)));
    let mut d = Command::Append(WireStep::from_si(1, false, 0.1, -0.1, 0.0).unwrap())
        .encode()
        .data;
    d[1] |= 0x02; // the reserved bit, CRC not updated
    let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
    assert_eq!(Command::decode(&f), Err((Reason::BadCrc, 1)));
    d[7] = crc8(ids::STEP_APPEND, &d[..7]); // a sender that sets it on purpose
    let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
    assert_eq!(Command::decode(&f), Err((Reason::OutOfRange, 1)));
    let f = RawFrame::new(ids::CONTROL, &[3, 1, 0]).unwrap();
    assert_eq!(Command::decode(&f), Err((Reason::BadCrc, 3)));
}

/// The catalogue check value of CRC-8/AUTOSAR ("123456789" → 0xDF) is an oracle
/// independent of this implementation; the identifier is prepended as two bytes.
#[test]
fn crc8_matches_the_autosar_check_value() {
    // The identifier's two bytes are the first two of the message: "12" + "3456789".
    assert_eq!(crc8(u16::from_le_bytes(*b"12"), b"3456789"), 0xDF);
    // The identifier enters the CRC: a frame moved to another identifier fails.
    assert_ne!(crc8(0x100, &[0; 7]), crc8(0x101, &[0; 7]));
}

/// Every error of up to three bits in a protected command (identifier bits included) is
/// refused, never accepted as another command.
#[test]
fn every_one_two_and_three_bit_error_is_caught() {
    let step = WireStep::from_si(9, true, 1.2345, -0.2, 0.25).unwrap();
    let change = WireModify::from_si(&step, 77, 1.3, -0.25, 0.2).unwrap();
    for cmd in [
        Command::Append(step),
        Command::Modify(change),
        Command::Control {
            seq: 77,
            op: ControlOp::Stop,
        },
    ] {
        let f = cmd.encode();
        let n = 8 * usize::from(f.len) + 11; // data bits, then the identifier's
        let flip = |f: &mut RawFrame, k: usize| {
            if k < 8 * usize::from(f.len) {
                f.data[k / 8] ^= 1 << (k % 8);
            } else {
                f.id ^= 1 << (k - 8 * usize::from(f.len));
            }
        };
        let mut tried = 0;
        for a in 0..n {
            for b in a..n {
                for c in b..n {
                    let mut g = f;
                    flip(&mut g, a);
                    if b > a {
                        flip(&mut g, b);
                    }
                    if c > b {
                        flip(&mut g, c);
                    }
                    if g == f {
                        continue;
                    }
                    tried += 1;
                    // Another identifier may be a command too: still refused.
                    assert!(Command::decode(&g).is_err(), "{cmd:?}: bits {a} {b} {c}");
                }
            }
        }
        // Single flips, pairs (each twice: (a, a, c) and (a, c, c)), triples.
        assert_eq!(tried, n + n * (n - 1) + n * (n - 1) * (n - 2) / 6);
    }
}

#[test]
fn acks_status_and_stream_round_trip() {
    for r in [None, Some(Reason::Infeasible), Some(Reason::PlanFailed)] {
        let a = Ack {
            command: 0x01,
            seq: 42,
            reason: r,
            queue: 3,
            echo: 0xA5,
            version: r.map(|_| 17),
        };
        assert_eq!(Ack::decode(&a.encode()), Some(a));
        let mut bad = a.encode();
        bad.data[3] ^= 0x10;
        assert_eq!(Ack::decode(&bad), None);
    }
    let d = Diag {
        foreign: 700,
        bus_errors: 3,
        tx_dropped: 1,
        next_side: 2,
        last_control: 9,
    };
    assert_eq!(Diag::decode(&d.encode()), Some(d));
    let l = LinkHealth {
        tec: 200,
        rec: 127,
        rx_passive: true,
        bus_state: 3,
        reset: 9,
        bus_offs: 513,
        passive_episodes: 40_000,
        missed_slots: 255,
    };
    assert_eq!(LinkHealth::decode(&l.encode()), Some(l));
    assert_eq!(l.encode().data[2], 3 | 9 << 2);
    assert_eq!(l.encode().data[1], 0xFF);
    let s = Status {
        state: 1,
        queue: 4,
        rejected: 300,
        overruns: 2,
        last_adjust: -40,
        flags: 5,
    };
    assert_eq!(Status::decode(&s.encode()), Some(s));
    let st = Stream {
        cog: [12.345678, -0.1],
        cog_vel: [0.3, -0.25],
        zmp: [12.3, -0.09],
        phase: 2,
        tick: 77,
        feet: [[12.4, 0.1, 0.0321, 0.5], [12.2, -0.1, 0.0, -0.25]],
    };
    let mut back = Stream::default();
    for f in st.encode() {
        assert!(back.decode_into(&f));
    }
    for k in 0..2 {
        assert!((back.cog[k] - st.cog[k]).abs() <= 0.5e-6 + 1e-12);
        assert!((back.zmp[k] - st.zmp[k]).abs() <= 0.5e-6 + 1e-12);
        assert!((back.cog_vel[k] - st.cog_vel[k]).abs() <= 0.5e-4 + 1e-12);
        for i in 0..4 {
            let unit = [1e-4, 1e-4, 5e-4, 1e-4][i];
            assert!((back.feet[k][i] - st.feet[k][i]).abs() <= unit / 2.0 + 1e-12);
        }
    }
    assert_eq!((back.phase, back.tick), (2, 77));
    // The foot fields' range ends: ±(2¹⁹ − 1) units, as the DBC declares; the one code below
    // it (−2¹⁹, never sent) reads as the end, so every decoded value encodes back to itself.
    let far = Stream {
        feet: [[-60.0, 60.0, 0.0, 0.0], [0.0; 4]],
        ..Stream::default()
    };
    let f = far.encode()[3];
    let mut back = Stream::default();
    assert!(back.decode_into(&f));
    assert_eq!(back.feet[0][..2], [-524_287.0 * 1e-4, 524_287.0 * 1e-4]);
    let mut below = f;
    below.data[..3].copy_from_slice(&[0x00, 0x00, 0x08 | (f.data[2] & 0xF0)]);
    let mut edge = Stream::default();
    assert!(edge.decode_into(&below));
    assert_eq!(edge.feet[0], back.feet[0]);
}
