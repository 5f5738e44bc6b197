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
        let Command::Append(back) = Command::decode(&f, 7).unwrap() else {
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

/// Every heading is representable: ±π, π − half a unit, several turns.
#[test]
fn every_finite_heading_is_representable() {
    use core::f64::consts::{PI, TAU};
    for yaw in [PI, -PI, PI - 5e-4, -PI + 5e-4, 3.0 * PI, 100.0, -7.0, 0.0] {
        let s = WireStep::from_si(0, true, 0.0, 0.0, yaw).expect("representable");
        let Ok(Command::Append(back)) = Command::decode(&Command::Append(s).encode(), 0) else {
            panic!("decodes");
        };
        let d = libm::remainder(back.si().2 - yaw, TAU);
        assert!(d.abs() <= YAW_UNIT / 2.0 + 1e-9, "{yaw}: {}", back.si().2);
    }
    assert!(WireStep::from_si(0, true, 0.0, 0.0, f64::INFINITY).is_none());
}

/// Encoder and decoder agree on every range: the extreme values the decoder accepts are
/// produced by the encoder, and one unit beyond is refused by it.
#[test]
fn encoder_and_decoder_agree_on_the_ranges() {
    let (min, max) = signed_range(STEP_BITS);
    for v in [min, max] {
        let m = f64::from(v) * STEP_UNIT;
        let s = WireStep::from_si(1, false, m, m, 0.0).expect("extreme encodable");
        assert_eq!((s.x, s.y), (v, v));
        let Ok(Command::Append(back)) = Command::decode(&Command::Append(s).encode(), 1) else {
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
        d[7] = crc8_keyed(ids::STEP_APPEND, 0, &d[..7]);
        let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
        let Ok(Command::Append(s)) = Command::decode(&f, 0) else {
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
    assert_eq!(Command::decode(&f, 6), Ok(Command::Modify(m)));
    let s = m.applied_to(&base).unwrap();
    let (x, y, yaw) = s.si();
    assert!((x - 10.25).abs() < 1e-12 && (y - 0.05).abs() < 1e-12);
    assert!((yaw + 0.2).abs() <= YAW_UNIT / 2.0);
    // The offset's range: ±4.096 m.
    assert!(WireModify::from_si(&base, 1, 14.0955, 0.1, 0.0).is_some());
    assert!(WireModify::from_si(&base, 1, 14.1, 0.1, 0.0).is_none());
    // Newer: greater, with no modulo (a version 65 steps old is older, whatever the wrap of
    // a 7-bit counter would say); versions are 1 … 127.
    let v = |version| WireModify { version, ..m };
    assert!(v(4).is_newer_than(3) && v(127).is_newer_than(3) && v(66).is_newer_than(65));
    assert!(!v(3).is_newer_than(3) && !v(2).is_newer_than(3) && !v(1).is_newer_than(66));
    assert!(!v(0).is_newer_than(127));
    assert!(WireModify::from_si(&base, 0, 10.0, 0.1, 0.0).is_none());
    assert!(WireModify::from_si(&base, 128, 10.0, 0.1, 0.0).is_none());
    // The controller's book counts versions per step.
    let mut book = StepBook::new();
    assert!(book.modify(9, 0.0, 0.0, 0.0).is_none(), "never appended");
    assert!(book.append(9, false, 0.2, -0.1, 0.0).is_some());
    for want in 1..=127u8 {
        let Some(Command::Modify(m)) = book.modify(9, 0.25, -0.1, 0.0) else {
            panic!("modify");
        };
        assert_eq!(m.version, want);
    }
    // Versions never wrap: the 128th modification cannot be made.
    assert!(book.modify(9, 0.25, -0.1, 0.0).is_none());
    // A step 256 numbers later takes the slot: the older one is no longer known.
    assert!(book.append(9 + 256, true, 0.2, 0.1, 0.0).is_some());
    assert!(book.appended(9).is_none() && book.modify(9, 0.2, -0.1, 0.0).is_none());
}

fn control(session: u16, seq: u32, op: u8) -> RawFrame {
    let [s0, s1] = session.to_le_bytes();
    let [q0, q1, q2, q3] = seq.to_le_bytes();
    let body = [s0, s1, q0, q1, q2, q3, op];
    let mut d = [0u8; 8];
    d[..7].copy_from_slice(&body);
    d[7] = crc8(ids::CONTROL, &body);
    RawFrame::new(ids::CONTROL, &d).unwrap()
}

#[test]
fn bad_frames_are_rejected_with_a_reason() {
    let f = control(0x1234, 0x0000_0103, 9);
    assert_eq!(Command::decode(&f, 0), Err((Reason::OutOfRange, 3)));
    let f = control(0x1234, 0x0000_0103, 4);
    assert_eq!(
        Command::decode(&f, 0),
        Ok(Command::Control {
            session: 0x1234,
            seq: 0x103,
            op: ControlOp::Reset
        })
    );
    let f = RawFrame::new(ids::CONTROL, &f.data[..7]).unwrap();
    assert_eq!(Command::decode(&f, 0), Err((Reason::BadLength, 3)));
    // The control frame of the earlier layout (3 bytes) is refused for its length.
    let f = RawFrame::new(ids::CONTROL, &[3, 1, crc8(ids::CONTROL, &[3, 1])]).unwrap();
    assert_eq!(Command::decode(&f, 0), Err((Reason::BadLength, f.data[2])));
    let f = RawFrame::new(0x123, &[]).unwrap();
    assert_eq!(Command::decode(&f, 0), Err((Reason::UnknownId, 0)));
    let mut d = Command::Append(WireStep::from_si(1, false, 0.1, -0.1, 0.0).unwrap())
        .encode()
        .data;
    d[1] |= 0x02; // the reserved bit, CRC not updated
    let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
    assert_eq!(Command::decode(&f, 1), Err((Reason::BadCrc, 1)));
    d[7] = crc8_keyed(ids::STEP_APPEND, 0, &d[..7]); // a sender that sets it on purpose
    let f = RawFrame::new(ids::STEP_APPEND, &d).unwrap();
    assert_eq!(Command::decode(&f, 1), Err((Reason::OutOfRange, 1)));
    let mut f = control(1, 2, 1);
    f.data[7] ^= 1;
    assert_eq!(Command::decode(&f, 0), Err((Reason::BadCrc, 2)));
}

/// Every footstep frame, of any content, has its CRC matched by exactly one step key (one
/// high byte): the CRC alone cannot tell a frame numbered outside the node's window (answered
/// `BadCrc`, see the module docs) from a corrupted one.
#[test]
fn exactly_one_step_key_matches_any_footstep_frame() {
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    for _ in 0..2000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let d = x.to_le_bytes();
        for id in [ids::STEP_APPEND, ids::STEP_MODIFY] {
            let matching = (0..=255u8)
                .filter(|&h| crc8_keyed(id, step_key(u16::from(h) << 8), &d[..7]) == d[7])
                .count();
            assert_eq!(matching, 1, "{id:#x} {d:02x?}");
        }
    }
}

/// A footstep frame's number is the one with its low byte nearest to the next append (128
/// below … 127 above), and the number's key is in the CRC: a copy of a step 256 · k numbers
/// older (k = 1 … 255), whose frame bytes are otherwise equal, never decodes; every queued
/// step's does.
#[test]
fn step_numbers_alias_never_by_their_high_byte() {
    assert_eq!(step_number(0x34, 0x1234), 0x1234);
    assert_eq!(step_number(0x33, 0x1234), 0x1233);
    assert_eq!(step_number(0x35, 0x1234), 0x1235);
    assert_eq!(step_number(0xB4, 0x1234), 0x11B4);
    assert_eq!(step_number(0xB3, 0x1234), 0x12B3);
    assert_eq!(step_number(0xFF, 0x0000), 0xFFFF);
    assert_eq!(step_number(0x01, 0x0000), 0x0001);
    let next = 0x5A07u16;
    for back in 0..=128u16 {
        let id = next.wrapping_sub(back);
        let s = WireStep::from_si(id, back % 2 == 0, 1.0, 0.1, 0.2).unwrap();
        let m = WireModify::from_si(&s, 5, 1.1, 0.1, 0.2).unwrap();
        assert_eq!(
            Command::decode(&Command::Append(s).encode(), next),
            Ok(Command::Append(s))
        );
        assert_eq!(
            Command::decode(&Command::Modify(m).encode(), next),
            Ok(Command::Modify(m))
        );
        for k in 1..=255u16 {
            let old = WireStep {
                id: id.wrapping_sub(256 * k),
                ..s
            };
            let om = WireModify { id: old.id, ..m };
            assert_eq!(Command::Append(old).encode().data[0], (id & 0xFF) as u8);
            assert!(matches!(
                Command::decode(&Command::Append(old).encode(), next),
                Err((Reason::BadCrc, _))
            ));
            assert!(matches!(
                Command::decode(&Command::Modify(om).encode(), next),
                Err((Reason::BadCrc, _))
            ));
        }
    }
}

#[test]
fn sessions_round_trip() {
    let s = Session {
        epoch: 0xDEAD_BEEF,
        last_seq: 0x0102_0304,
    };
    assert_eq!(Session::decode(&s.encode()), Some(s));
    assert_eq!(s.tag(), 0xBEEF);
    assert_eq!(
        Session::decode(&RawFrame::new(ids::SESSION, &[0; 7]).unwrap()),
        None
    );
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

/// Every error of up to two bits in a protected command (identifier bits included) is
/// refused, never accepted as another command; so is every error of three bits, except those
/// that move a footstep frame's number into the neighbouring block of 256 (the key, read from
/// the low byte, then changes by one bit: four bits in all), or a velocity or goal frame's
/// sequence number into the neighbouring block of 2²⁴ (likewise), which are counted: at most
/// 1 in 100 of them passes the CRC. The frames are taken at a block's edge, where that happens
/// most.
#[test]
fn every_one_two_and_three_bit_error_is_caught() {
    let next = 0x0102u16;
    let step = WireStep::from_si(next, true, 1.2345, -0.2, 0.25).unwrap();
    let queued = WireStep::from_si(next - 3, true, 1.2345, -0.2, 0.25).unwrap();
    let change = WireModify::from_si(&queued, 77, 1.3, -0.25, 0.2).unwrap();
    let (mut crossing, mut passed) = (0u32, 0u32);
    for cmd in [
        Command::Append(step),
        Command::Modify(change),
        Command::Control {
            session: 0x4321,
            seq: 77,
            op: ControlOp::Stop,
        },
        Command::Measured(Measured::from_si(0x12_3456, [1.5, -0.25]).unwrap()),
        Command::Control {
            session: 0x4321,
            seq: 78,
            op: ControlOp::StartAdjusting,
        },
        Command::Velocity(WireVelocity::from_si(0xFF_FFF0, 0.25, -0.05, 0.3)),
        Command::Goal(WireGoal::from_si(0x100_0001, 1.5, -0.4, 2.0)),
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
                    let bits = 1 + usize::from(b > a) + usize::from(c > b);
                    // The block the corrupted frame's number falls in, if a footstep frame.
                    let moved = matches!(g.id, ids::STEP_APPEND | ids::STEP_MODIFY)
                        && cmd.step_id().is_some_and(|id| {
                            step_key(step_number(g.data[0], next)) != step_key(id)
                        });
                    // Or the block of 2²⁴ sequence numbers of a velocity or goal frame (its
                    // low 24 bits read against the last accepted number, 0x100_0000 here: a block edge).
                    let last = 0x100_0000;
                    let seq_of =
                        |v: &RawFrame| u32::from_le_bytes([v.data[0], v.data[1], v.data[2], 0]);
                    let moved = moved
                        || (matches!(g.id, ids::VELOCITY | ids::GOAL)
                            && matches!(f.id, ids::VELOCITY | ids::GOAL)
                            && seq_number(seq_of(&g), last) >> 24
                                != seq_number(seq_of(&f), last) >> 24);
                    let expect = Expect {
                        next_step: next,
                        epoch: 0,
                        last_seq: last,
                    };
                    let decoded = Command::decode(&g, expect);
                    if bits == 3 && moved {
                        crossing += 1;
                        passed += u32::from(decoded.is_ok());
                    } else {
                        // Another identifier may be a command too: still refused.
                        assert!(decoded.is_err(), "{cmd:?}: bits {a} {b} {c}");
                    }
                }
            }
        }
        // Single flips, pairs (each twice: (a, a, c) and (a, c, c)), triples.
        assert_eq!(tried, n + n * (n - 1) + n * (n - 1) * (n - 2) / 6);
    }
    assert!(crossing > 0);
    assert!(passed * 100 <= crossing, "{passed} of {crossing}");
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
        next_step: 0xA55A,
    };
    assert_eq!(Diag::decode(&d.encode()), Some(d));
    let l = LinkHealth {
        tec: 200,
        rec: 127,
        rx_passive: true,
        bus_state: 3,
        reset: 9,
        bus_offs: 513,
        passive_episodes: 4_000,
        missed_slots: 255,
        backoff: 7,
        ram_faults: 2,
    };
    assert_eq!(LinkHealth::decode(&l.encode()), Some(l));
    assert_eq!(l.encode().data[2], 3 | 9 << 2 | 2 << 6);
    assert_eq!(l.encode().data[1], 0xFF);
    // passive_episodes 12 bits, the back-off in the high nibble of byte 6.
    assert_eq!(l.encode().data[5..7], [0xA0, 0x7F]);
    // Beyond their widths: passive_episodes and ram_faults saturate, the back-off is cut.
    let big = LinkHealth {
        passive_episodes: 40_000,
        ram_faults: 200,
        backoff: 0x17,
        ..l
    };
    let back = LinkHealth::decode(&big.encode()).unwrap();
    assert_eq!(
        (back.passive_episodes, back.ram_faults, back.backoff),
        (4095, 3, 7)
    );
    // Every frame decodes to values that encode to it again (no reserved bit left).
    let mut f = l.encode();
    f.data = [0xFF; 8];
    assert_eq!(LinkHealth::decode(&f).unwrap().encode(), f);
    let s = Status {
        state: 1,
        queue: 4,
        rejected: 300,
        overruns: 2,
        last_adjust: -40,
        flags: 5 | 2 << 3 | Status::CLOCK_FAULT,
    };
    assert_eq!(Status::decode(&s.encode()), Some(s));
    assert_eq!(s.next_side(), 2);
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

/// A measured state survives its encoding, its CRC is keyed with the session's low byte
/// (another session's frame is `BadCrc`), the reserved bits are refused, and out-of-range
/// values are not encoded.
#[test]
fn measured_states_round_trip_and_belong_to_their_session() {
    for (cycle, dev) in [
        (0u32, [0.0, 0.0]),
        (0x00FF_FFFF, [1.6383, -1.6384]),
        (0x0123_4567, [-0.0001, 0.0004]),
    ] {
        let m = Measured::from_si(cycle, dev).unwrap();
        assert_eq!(m.stamp, cycle & 0xFF_FFFF);
        for epoch in [0u32, 0x1234_5678, u32::MAX] {
            let f = m.encode(epoch);
            let expect = Expect {
                next_step: 0,
                epoch,
                last_seq: 0,
            };
            assert_eq!(Command::decode(&f, expect), Ok(Command::Measured(m)));
            let other = Expect {
                next_step: 0,
                epoch: epoch.wrapping_add(1),
                last_seq: 0,
            };
            assert_eq!(
                Command::decode(&f, other),
                Err((Reason::BadCrc, m.stamp as u8))
            );
        }
        let back = m.deviation_in::<f64>();
        assert!((dev[0] - back[0]).abs() <= 5e-5 && (dev[1] - back[1]).abs() <= 5e-5);
    }
    assert_eq!(Measured::from_si(0, [1.6384, 0.0]), None);
    assert_eq!(Measured::from_si(0, [f64::NAN, 0.0]), None);
    // Either reserved bit set (with a right CRC) is refused.
    for bit in [0x40u8, 0x80] {
        let mut d = Measured::from_si(5, [0.1, 0.1]).unwrap().encode(0).data;
        d[6] |= bit;
        d[7] = crc8_keyed(ids::MEASURED, 0, &d[..7]);
        let f = RawFrame::new(ids::MEASURED, &d).unwrap();
        assert_eq!(Command::decode(&f, 0), Err((Reason::OutOfRange, 5)));
    }
    let d = Measured::from_si(5, [0.1, 0.1]).unwrap().encode(0).data;
    let short = RawFrame::new(ids::MEASURED, &d[..7]).unwrap();
    assert_eq!(Command::decode(&short, 0), Err((Reason::BadLength, 5)));
}

/// `ADJUST` survives its encoding and its CRC catches a flipped bit.
#[test]
fn adjustments_round_trip() {
    let a = Adjust {
        from: 0xA5,
        shift: [-1234, 32767],
        count: 3,
        flags: Adjust::REACH_LIMITED | Adjust::FRESH,
    };
    let f = a.encode();
    assert_eq!(Adjust::decode(&f), Some(a));
    assert!((a.shift_si()[0] + 0.617).abs() < 1e-12);
    let mut g = f;
    g.data[3] ^= 0x10;
    assert_eq!(Adjust::decode(&g), None);
}

/// `VELOCITY` and `GOAL` round-trip in their units; the values that are not numbers are
/// refused `OutOfRange`, finite values beyond a field are sent at its end; another session's
/// frame and a frame 2²⁴ numbers old (its low bits read as new) fail the CRC.
#[test]
fn velocity_and_goal_frames_round_trip_and_old_ones_fail() {
    let last = 0x0123_4567;
    let expect = |epoch: u32| Expect {
        next_step: 0,
        epoch,
        last_seq: last,
    };
    let v = WireVelocity::from_si(last + 1, 0.25, -0.05, 0.3);
    assert_eq!((v.vx, v.vy, v.wz), (250, -50, 150));
    let f = Command::Velocity(v).encode_in(7);
    assert_eq!(f.id, ids::VELOCITY);
    assert_eq!(Command::decode(&f, expect(7)), Ok(Command::Velocity(v)));
    assert_eq!(
        Command::decode(&f, expect(8)).map_err(|e| e.0),
        Err(Reason::BadCrc)
    );
    let g = WireGoal::from_si(last + 2, 1.5, -0.4, -3.0);
    let f = Command::Goal(g).encode_in(7);
    assert_eq!(Command::decode(&f, expect(7)), Ok(Command::Goal(g)));
    let (x, y, yaw) = g.si_in::<f64>();
    assert!((x - 1.5).abs() < 5e-3 && (y + 0.4).abs() < 5e-3 && (yaw + 3.0).abs() < 4e-3);
    // Beyond the field: its end; not a number: the reserved value, refused.
    let big = WireVelocity::from_si(last + 1, 5.0, -5.0, 5.0);
    assert_eq!((big.vx, big.vy, big.wz), (1023, -1023, 511));
    for bad in [
        WireVelocity::from_si(last + 1, f64::NAN, 0.0, 0.0),
        WireVelocity::from_si(last + 1, 0.0, f64::INFINITY, 0.0),
        WireVelocity::from_si(last + 1, 0.0, 0.0, f64::NEG_INFINITY),
    ] {
        let f = Command::Velocity(bad).encode_in(7);
        assert_eq!(
            Command::decode(&f, expect(7)).map_err(|e| e.0),
            Err(Reason::OutOfRange)
        );
    }
    // Within 2²³ of the last: read as sent (older is older); 2²⁴ back: the CRC fails.
    for seq in [last - 5, last, last + 0x7F_FFFF, last - 0x80_0000] {
        let v = WireVelocity::from_si(seq, 0.1, 0.0, 0.0);
        let f = Command::Velocity(v).encode_in(7);
        assert_eq!(
            Command::decode(&f, expect(7)),
            Ok(Command::Velocity(v)),
            "{seq:#x}"
        );
    }
    for back in 1..=255u32 {
        let old = WireVelocity::from_si((last + 1).wrapping_sub(back << 24), 0.1, 0.0, 0.0);
        let f = Command::Velocity(old).encode_in(7);
        assert_eq!(
            Command::decode(&f, expect(7)).map_err(|e| e.0),
            Err(Reason::BadCrc),
            "{back}"
        );
    }
}
