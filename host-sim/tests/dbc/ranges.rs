//! Layout and ranges (see the docs of `main.rs`).

use super::*;

#[test]
fn every_data_bit_belongs_to_exactly_one_signal() {
    let d = dbc();
    for m in &d.messages {
        let mut owner: Vec<Option<&str>> = vec![None; 8 * m.size as usize];
        for s in &m.signals {
            for b in s.start_bit..s.start_bit + s.size {
                let slot = owner
                    .get_mut(b as usize)
                    .unwrap_or_else(|| panic!("{}.{}: bit {b} past the end", m.name, s.name));
                if let Some(other) = slot.replace(&s.name) {
                    panic!("{}: bit {b} is in {other} and {}", m.name, s.name);
                }
            }
        }
        for (b, o) in owner.iter().enumerate() {
            assert!(o.is_some(), "{}: bit {b} belongs to no signal", m.name);
        }
    }
}

/// The unit of `STATUS.last_adjust`: one control cycle (5 ms).
pub(crate) fn cycle_s() -> f64 {
    GaitParams::<f64>::hrp2().dt
}

pub(crate) type Values = Vec<(&'static str, f64)>;

/// One frame of every message with every field at the codec's lowest (`high` false) or highest
/// value, and the value of every signal but the CRCs as the codec means it (in SI units).
pub(crate) fn codec_extremes(high: bool) -> Vec<(RawFrame, Values)> {
    let pick = |(lo, hi): (i32, i32)| if high { hi } else { lo };
    let byte = if high { u8::MAX } else { 0 };
    let word = if high { u16::MAX } else { 0 };
    let b = |v: u8| f64::from(v);
    let mut out = vec![];

    out.push((
        Command::EmergencyStop { seq: byte }.encode(),
        vec![("seq", b(byte))],
    ));
    let ops = OPS.map(op_code);
    let op = if high {
        ops.iter().max()
    } else {
        ops.iter().min()
    };
    let op = OPS[ops.iter().position(|c| Some(c) == op).unwrap()];
    let long = if high { u32::MAX } else { 0 };
    let f = Command::Control {
        session: word,
        seq: long,
        op,
    }
    .encode();
    out.push((
        f,
        vec![
            ("session", f64::from(word)),
            ("seq", f64::from(long)),
            ("op", b(op_code(op))),
        ],
    ));

    // (The frames carry the low byte of the step number.)
    let s = WireStep {
        id: word,
        left: high,
        x: pick(signed_range(STEP_BITS)),
        y: pick(signed_range(STEP_BITS)),
        yaw: pick(signed_range(YAW_BITS)) as i16,
    };
    assert!(s.in_range());
    let (x, y, yaw) = s.si();
    out.push((
        Command::Append(s).encode(),
        vec![
            ("step_id", b(s.id as u8)),
            ("left", b(u8::from(s.left))),
            ("reserved", 0.0), // the encoder writes 0, the decoder refuses 1
            ("x", x),
            ("y", y),
            ("yaw", yaw),
        ],
    ));
    let m = WireModify {
        id: word,
        version: if high { VERSIONS - 1 } else { 0 },
        left: high,
        dx: pick(signed_range(OFFSET_BITS)),
        dy: pick(signed_range(OFFSET_BITS)),
        yaw: pick(signed_range(YAW_BITS)) as i16,
    };
    out.push((
        Command::Modify(m).encode(),
        vec![
            ("step_id", b(m.id as u8)),
            ("version", b(m.version)),
            ("left", b(u8::from(m.left))),
            ("dx", f64::from(m.dx) * STEP_UNIT),
            ("dy", f64::from(m.dy) * STEP_UNIT),
            ("yaw", f64::from(m.yaw) * YAW_UNIT),
        ],
    ));

    let me = Measured {
        stamp: if high { STAMPS - 1 } else { 0 },
        deviation: [pick(signed_range(DEVIATION_BITS)); 2],
    };
    out.push((
        Command::Measured(me).encode(),
        vec![
            ("stamp", f64::from(me.stamp)),
            ("dcm_dx", f64::from(me.deviation[0]) * DEVIATION_UNIT),
            ("dcm_dy", f64::from(me.deviation[1]) * DEVIATION_UNIT),
            ("measured_reserved", 0.0), // the encoder writes 0, the decoder refuses 1
        ],
    ));
    // `VELOCITY` and `GOAL`: the lowest value the encoder gives is one above the field's
    // reserved most negative one (not a number).
    let end = |bits: u32| {
        let (lo, hi) = signed_range(bits);
        if high {
            hi
        } else {
            lo + 1
        }
    };
    // A session whose second byte is XORed into the sequence number's bits 16-23 (which
    // give the field's end with it).
    let epoch: u32 = if high { 0xA5_00 } else { 0x5A_00 };
    let seq = if high {
        u32::MAX ^ (0xA5 << 16)
    } else {
        0x5A << 16
    };
    let mid = f64::from(((seq >> 16) ^ (epoch >> 8)) & 0xFF);
    assert_eq!(mid, if high { 255.0 } else { 0.0 });
    let v = WireVelocity {
        seq,
        vx: end(DRIVE_BITS),
        vy: end(DRIVE_BITS),
        wz: end(DRIVE_TURN_BITS),
    };
    out.push((
        Command::Velocity(v).encode_in(epoch),
        vec![
            ("seq_low", f64::from(seq & 0xFFFF)),
            ("seq_mid", mid),
            ("vx", f64::from(v.vx) * SPEED_UNIT),
            ("vy", f64::from(v.vy) * SPEED_UNIT),
            ("wz", f64::from(v.wz) * TURN_UNIT),
        ],
    ));
    let g = WireGoal {
        seq,
        x: end(DRIVE_BITS),
        y: end(DRIVE_BITS),
        yaw: end(DRIVE_TURN_BITS),
    };
    out.push((
        Command::Goal(g).encode_in(epoch),
        vec![
            ("seq_low", f64::from(seq & 0xFFFF)),
            ("seq_mid", mid),
            ("x", f64::from(g.x) * GOAL_UNIT),
            ("y", f64::from(g.y) * GOAL_UNIT),
            ("yaw", f64::from(g.yaw) * GOAL_YAW_UNIT),
        ],
    ));
    let flag = u8::from(high);
    let ad = Adjust {
        from: byte,
        shift: [if high { i16::MAX } else { i16::MIN }; 2],
        count: byte,
        flags: if high {
            Adjust::REACH_LIMITED | Adjust::ZMP_LIMITED | Adjust::FRESH
        } else {
            0
        },
    };
    out.push((
        ad.encode(),
        vec![
            ("from_step", b(ad.from)),
            ("shift_x", ad.shift_si()[0]),
            ("shift_y", ad.shift_si()[1]),
            ("count", b(ad.count)),
            ("reach_limited", b(flag)),
            ("zmp_limited", b(flag)),
            ("fresh", b(flag)),
            ("adjust_reserved", 0.0), // sent as 0
        ],
    ));

    let codes = commands().map(|(c, _)| c.code());
    let reason = if high {
        Reason::ALL.iter().copied().max_by_key(|r| r.code())
    } else {
        None // accepted
    };
    let a = Ack {
        command: if high {
            codes.iter().max()
        } else {
            codes.iter().min()
        }
        .copied()
        .unwrap(),
        seq: byte,
        reason,
        queue: byte,
        echo: byte,
        version: if high { None } else { Some(0) },
    };
    out.push((
        a.encode(),
        vec![
            ("command", b(a.command)),
            ("seq", b(a.seq)),
            ("reason", b(a.reason.map_or(0, Reason::code))),
            ("queue", b(a.queue)),
            ("echo", b(a.echo)),
            ("version", b(a.version.unwrap_or(0xFF))), // 0xFF: none
        ],
    ));

    let st = Status {
        state: if high {
            STATES.iter().max_by_key(|&&s| s as u8)
        } else {
            STATES.iter().min_by_key(|&&s| s as u8)
        }
        .map(|&s| s as u8)
        .unwrap(),
        queue: byte,
        rejected: word,
        overruns: word,
        last_adjust: if high { i8::MAX } else { i8::MIN },
        // Every flag set, the side at its highest (2: right), the reserved bits set.
        flags: if high { 0b1110_0111 | 2 << 3 } else { 0 },
    };
    // `Status::flags`: bit 0 shaping, bit 1 last re-plan failed, bit 2 transmit overflow,
    // bits 3-4 the next side, bit 5 the clock fault.
    out.push((
        st.encode(),
        vec![
            ("state", b(st.state)),
            ("queue", b(st.queue)),
            ("rejected", f64::from(st.rejected)),
            ("overruns", f64::from(st.overruns)),
            ("last_adjust", f64::from(st.last_adjust) * cycle_s()),
            ("shaping", b(st.flags & 1)),
            ("replan_failed", b(st.flags >> 1 & 1)),
            ("tx_overflow", b(st.flags >> 2 & 1)),
            ("next_side", b(st.next_side())),
            ("clock_fault", b(st.flags >> 5 & 1)),
            ("velocity_cut", b(st.flags >> 6 & 1)),
            ("at_goal", b(st.flags >> 7 & 1)),
        ],
    ));
    let lk = LinkHealth {
        tec: byte,
        rec: if high { 127 } else { 0 },
        rx_passive: high,
        bus_state: if high { 3 } else { 0 },
        reset: if high { 15 } else { 0 },
        bus_offs: word,
        passive_episodes: if high {
            LinkHealth::PASSIVE_EPISODES_MAX
        } else {
            0
        },
        missed_slots: byte,
        backoff: if high { 15 } else { 0 },
        ram_faults: if high { 3 } else { 0 },
    };
    let lf = lk.encode();
    assert_eq!(LinkHealth::decode(&lf), Some(lk));
    out.push((
        lf,
        vec![
            ("tec", b(lk.tec)),
            ("rec", b(lk.rec)),
            ("rx_passive", b(u8::from(lk.rx_passive))),
            ("bus_state", b(lk.bus_state)),
            ("reset", b(lk.reset)),
            ("ram_faults", b(lk.ram_faults)),
            ("bus_offs", f64::from(lk.bus_offs)),
            ("passive_episodes", f64::from(lk.passive_episodes)),
            ("backoff", b(lk.backoff)),
            ("missed_slots", b(lk.missed_slots)),
        ],
    ));
    let dg = Diag {
        foreign: word,
        bus_errors: word,
        tx_dropped: word,
        next_step: word,
    };
    out.push((
        dg.encode(),
        vec![
            ("foreign", f64::from(dg.foreign)),
            ("bus_errors", f64::from(dg.bus_errors)),
            ("tx_dropped", f64::from(dg.tx_dropped)),
            ("next_step", f64::from(dg.next_step)),
        ],
    ));
    let long = if high { u32::MAX } else { 0 };
    let se = Session {
        epoch: long,
        last_seq: long,
    };
    out.push((
        se.encode(),
        vec![
            ("epoch", f64::from(se.epoch)),
            ("last_seq", f64::from(se.last_seq)),
        ],
    ));

    // The stream saturates: values far out give the codec's extremes.
    let v = if high { 1e12 } else { -1e12 };
    let stream = Stream {
        cog: [v; 2],
        cog_vel: [v; 2],
        zmp: [v; 2],
        phase: if high { PHASES.len() - 1 } else { 0 } as u8,
        tick: if high { STAMPS - 1 } else { 0 },
        feet: [[v; 4]; 2],
    };
    let frames = stream.encode();
    let mut st = Stream::default();
    for f in &frames {
        assert!(st.decode_into(f));
    }
    let foot = |k: usize| -> Values {
        let f = st.feet[k];
        vec![("x", f[0]), ("y", f[1]), ("z", f[2]), ("yaw", f[3])]
    };
    let values: [Values; 5] = [
        vec![("cog_x", st.cog[0]), ("cog_y", st.cog[1])],
        vec![("zmp_x", st.zmp[0]), ("zmp_y", st.zmp[1])],
        vec![
            ("cog_vx", st.cog_vel[0]),
            ("cog_vy", st.cog_vel[1]),
            ("phase", b(st.phase)),
            ("tick", f64::from(st.tick)),
        ],
        foot(0),
        foot(1),
    ];
    out.extend(frames.into_iter().zip(values));
    out
}

/// Every signal's `[min|max]` in the DBC is the codec's range: the frame with every field at
/// its lowest (highest) value decodes, with the DBC, to the codec's value and to the DBC's
/// minimum (maximum). The codec's ranges come from its own definitions (`signed_range` of
/// `STEP_BITS`, `OFFSET_BITS`, `YAW_BITS` in `STEP_UNIT`, `YAW_UNIT`; `VERSIONS`; the
/// enumerations; the stream's saturation).
#[test]
fn every_signal_range_is_the_codecs_range() {
    let d = dbc();
    for high in [false, true] {
        let bound = if high { "max" } else { "min" };
        let mut seen = BTreeSet::new();
        for (f, values) in codec_extremes(high) {
            let m = message(&d, f.id);
            assert!(seen.insert(f.id), "{} twice", m.name);
            let s = decode(&d, &f);
            let values: HashMap<&str, f64> = values.into_iter().collect();
            for sig in &m.signals {
                if sig.name == "crc" {
                    // The last byte, any value.
                    assert_eq!(sig.start_bit, 8 * (m.size - 1), "{}.crc", m.name);
                    assert_eq!((sig.size, sig.value_type), (8, ValueType::Unsigned));
                    assert_eq!((number(sig.min), number(sig.max)), (0.0, 255.0));
                    continue;
                }
                let what = format!("{}.{} {bound}", m.name, sig.name);
                let codec = *values
                    .get(sig.name.as_str())
                    .unwrap_or_else(|| panic!("{}.{}: not a codec field", m.name, sig.name));
                let dbc_bound = number(if high { sig.max } else { sig.min });
                assert!(
                    same(s[&sig.name], codec),
                    "{what}: DBC decodes {}, codec {codec}",
                    s[&sig.name]
                );
                assert!(
                    same(dbc_bound, codec),
                    "{what}: DBC says {dbc_bound}, codec {codec}"
                );
            }
            let names: BTreeSet<&str> = m.signals.iter().map(|s| s.name.as_str()).collect();
            for k in values.keys() {
                assert!(names.contains(k), "{}.{k}: not in the DBC", m.name);
            }
        }
        let all: BTreeSet<u16> = d.messages.iter().map(|m| m.id.raw() as u16).collect();
        assert_eq!(seen, all);
    }
}

#[test]
fn the_reserved_bit_of_step_append_is_refused_when_set() {
    let d = dbc();
    let r = signal(&d, ids::STEP_APPEND, "reserved");
    assert_eq!((r.size, number(r.min), number(r.max)), (1, 0.0, 0.0));
    let mut f = Command::Append(WireStep::from_si(1, false, 0.1, -0.1, 0.0).unwrap()).encode();
    let bits = u64::from_le_bytes(f.data) | 1 << r.start_bit;
    f.data = bits.to_le_bytes();
    f.data[7] = wire::crc8_keyed(f.id, wire::step_key(1), &f.data[..7]);
    assert_eq!(decode(&d, &f)["reserved"], 1.0);
    assert_eq!(Command::decode(&f, 1), Err((Reason::OutOfRange, 1)));
    let comment = d
        .signal_comment(MessageId::Standard(ids::STEP_APPEND), "reserved")
        .expect("a comment");
    assert!(comment.contains("must be 0"), "{comment}");
}

#[test]
fn each_flag_of_status_is_its_own_bit() {
    let d = dbc();
    let names = [
        "shaping",
        "replan_failed",
        "tx_overflow",
        "",
        "",
        "clock_fault",
        "velocity_cut",
        "at_goal",
    ];
    for (k, name) in names.iter().enumerate() {
        if name.is_empty() {
            continue; // (bits 3-4: the next side, a field of two bits)
        }
        let st = Status {
            flags: 1 << k,
            ..Status::default()
        };
        let s = decode(&d, &st.encode());
        for (j, other) in names.iter().enumerate().filter(|(_, n)| !n.is_empty()) {
            assert_eq!(
                s[*other],
                f64::from(u8::from(j == k)),
                "flag bit {k}: {other}"
            );
        }
        let c = d
            .signal_comment(MessageId::Standard(ids::STATUS), name)
            .expect("a comment");
        assert!(c.contains(&format!("bit {k}")), "{name}: {c}");
    }
}
