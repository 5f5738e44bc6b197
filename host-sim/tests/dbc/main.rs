//! The DBC file (`host-sim/can/walking.dbc`) and the Rust codec (`planner_core::wire`) agree,
//! so that neither can drift from the other:
//!
//! * every message of the DBC exists in the codec with the same identifier and length, and every
//!   data bit of a message belongs to exactly one signal (reserved bits included);
//! * every signal decoded with the DBC's own definition (start bit, size, sign, factor, offset)
//!   from a frame built by the Rust encoder gives back the value that was encoded (to half a
//!   unit), and every signal's `[min|max]` is the codec's range: frames with every field at the
//!   codec's lowest (highest) value decode to exactly the DBC's minimum (maximum);
//! * every value table (`VAL_`) is the codec's enumeration, code for code and name for name
//!   (the snake case of the Rust variant): `Reason::ALL`, `ControlOp`, the command codes of
//!   `ACK`, `NodeState`, the phases and next sides the node publishes, and `LINK`'s bus
//!   states and reset reasons (the board firmware's `board_core::BusState` and
//!   `board_core::ResetReason`);
//! * every message's `GenMsgCycleTime` is the period at which a running node sends it (0 for
//!   the commands and `ACK`, sent on events; `LINK` from a node whose firmware reports its link
//!   health every cycle, as the board does), and the bits of `STATUS`'s flags byte are the
//!   node's.

use std::collections::{BTreeMap, BTreeSet, HashMap, VecDeque};

use can_dbc::{AttributeDefinition, AttributeValue, AttributeValueType, ByteOrder, Dbc, Message};
use can_dbc::{MessageId, NumericValue, Signal, ValueDescription, ValueType};
use planner_core::gait::{GaitParams, Phase, Side};
use planner_core::node::{Node, NodeConfig, NodeState, TX_BACKLOG};
use planner_core::wire::{
    self, ids, signed_range, Ack, Adjust, Command, ControlOp, Diag, LinkHealth, Measured, RawFrame,
    Reason, Session, Status, Stream, WireGoal, WireModify, WireStep, WireVelocity, DEVIATION_BITS,
    DEVIATION_UNIT, DRIVE_BITS, DRIVE_TURN_BITS, GOAL_UNIT, GOAL_YAW_UNIT, OFFSET_BITS, SPEED_UNIT,
    STAMPS, STEP_BITS, STEP_UNIT, TURN_UNIT, VERSIONS, YAW_BITS, YAW_UNIT,
};

mod ranges;
mod running;
mod tables;

use ranges::*;
use tables::*;

fn dbc() -> Dbc {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/can/walking.dbc"))
        .expect("the DBC file is in the repository");
    Dbc::try_from(text.as_str()).expect("the DBC file parses")
}

/// Decodes every signal of `frame` with the DBC's definition.
fn decode(dbc: &Dbc, frame: &RawFrame) -> HashMap<String, f64> {
    let msg = dbc
        .messages
        .iter()
        .find(|m| m.id == MessageId::Standard(frame.id))
        .unwrap_or_else(|| panic!("id {:#x} not in the DBC", frame.id));
    assert_eq!(msg.size, u64::from(frame.len), "{}: length", msg.name);
    let bits = u64::from_le_bytes(frame.data);
    msg.signals
        .iter()
        .map(|s| {
            assert_eq!(s.byte_order, ByteOrder::LittleEndian, "{}", s.name);
            let raw = (bits >> s.start_bit)
                & if s.size == 64 {
                    u64::MAX
                } else {
                    (1 << s.size) - 1
                };
            let v = match s.value_type {
                ValueType::Signed => ((raw << (64 - s.size)) as i64 >> (64 - s.size)) as f64,
                ValueType::Unsigned => raw as f64,
            };
            (s.name.clone(), v * s.factor + s.offset)
        })
        .collect()
}

fn close(got: f64, want: f64, unit: f64, what: &str) {
    assert!(
        (got - want).abs() <= unit / 2.0 + 1e-12,
        "{what}: DBC gives {got}, encoded {want}"
    );
}

#[test]
fn every_message_of_the_codec_is_in_the_dbc_and_nothing_else() {
    let d = dbc();
    let mut dbc_ids: Vec<u32> = d.messages.iter().map(|m| m.id.raw()).collect();
    dbc_ids.sort();
    let mut ours: Vec<u32> = [
        ids::ESTOP,
        ids::CONTROL,
        ids::VELOCITY,
        ids::GOAL,
        ids::ACK,
        ids::STEP_APPEND,
        ids::STEP_MODIFY,
        ids::MEASURED,
        ids::ADJUST,
        ids::COG,
        ids::ZMP,
        ids::COG_VEL,
        ids::FOOT_LEFT,
        ids::FOOT_RIGHT,
        ids::STATUS,
        ids::DIAG,
        ids::LINK,
        ids::SESSION,
    ]
    .iter()
    .map(|&i| u32::from(i))
    .collect();
    ours.sort();
    assert_eq!(dbc_ids, ours);
}

#[test]
fn commands_decode_the_same_with_the_dbc() {
    let d = dbc();
    for &(id, left, x, y, yaw) in &[
        (7u16, true, 0.4, 0.1, 0.0),
        (200, false, -12.3456, 28.0, -3.0),
        (0, true, 0.0005, -0.0005, 3.1),
        (0x12A4, false, 1.0, -0.1, 0.2),
    ] {
        let w = WireStep::from_si(id, left, x, y, yaw).unwrap();
        let c = Command::Append(w);
        let s = decode(&d, &c.encode());
        // The low byte of the number; the CRC keyed with the Gray code of the high byte.
        let key = (id >> 8) as u8 ^ (id >> 9) as u8;
        assert_eq!(s["step_id"], f64::from(id & 0xFF));
        assert_eq!(s["left"], f64::from(u8::from(left)));
        assert_eq!(s["reserved"], 0.0);
        close(s["x"], x, planner_core::wire::STEP_UNIT, "x");
        close(s["y"], y, planner_core::wire::STEP_UNIT, "y");
        close(s["yaw"], yaw, planner_core::wire::YAW_UNIT, "yaw");
        let f = c.encode();
        assert_eq!(
            s["crc"],
            f64::from(wire::crc8_keyed(f.id, key, &f.data[..7]))
        );
        // A modification of it: version, offsets from the appended position, heading.
        let (mx, my, myaw) = (x - 1.2345, y + 4.0, -yaw);
        let m = WireModify::from_si(&w, 99, mx, my, myaw).unwrap();
        let c = Command::Modify(m);
        let s = decode(&d, &c.encode());
        assert_eq!((s["step_id"], s["version"]), (f64::from(id & 0xFF), 99.0));
        assert_eq!(s["left"], f64::from(u8::from(left)));
        let (bx, by, _) = w.si();
        close(s["dx"], mx - bx, planner_core::wire::STEP_UNIT, "dx");
        close(s["dy"], my - by, planner_core::wire::STEP_UNIT, "dy");
        close(s["yaw"], myaw, planner_core::wire::YAW_UNIT, "yaw");
        let f = c.encode();
        assert_eq!(
            s["crc"],
            f64::from(wire::crc8_keyed(f.id, key, &f.data[..7]))
        );
    }
    let s = decode(&d, &Command::EmergencyStop { seq: 9 }.encode());
    assert_eq!(s["seq"], 9.0);
    let s = decode(
        &d,
        &Command::Control {
            session: 0xBEEF,
            seq: 0x0102_0304,
            op: ControlOp::StopNow,
        }
        .encode(),
    );
    assert_eq!(
        (s["session"], s["seq"], s["op"]),
        (f64::from(0xBEEFu16), f64::from(0x0102_0304u32), 3.0)
    );
    let body = [0xEF, 0xBE, 4, 3, 2, 1, 3];
    assert_eq!(s["crc"], f64::from(wire::crc8(ids::CONTROL, &body)));
}

#[test]
fn answers_status_and_stream_decode_the_same_with_the_dbc() {
    let d = dbc();
    let a = Ack {
        command: 0x01,
        seq: 17,
        reason: Some(Reason::LiftedOff),
        queue: 5,
        echo: 0xC3,
        version: Some(42),
    };
    let s = decode(&d, &a.encode());
    assert_eq!(
        (
            s["command"],
            s["seq"],
            s["reason"],
            s["queue"],
            s["echo"],
            s["version"]
        ),
        (
            1.0,
            17.0,
            f64::from(Reason::LiftedOff.code()),
            5.0,
            195.0,
            42.0
        )
    );
    let body = [1, 17, Reason::LiftedOff.code(), 5, 0xC3, 42];
    assert_eq!(s["crc"], f64::from(wire::crc8(ids::ACK, &body)));
    let st = Status {
        state: 1,
        queue: 3,
        rejected: 1234,
        overruns: 7,
        last_adjust: -40,
        flags: 5 | 1 << 3 | Status::CLOCK_FAULT,
    };
    let s = decode(&d, &st.encode());
    assert_eq!(
        (s["state"], s["queue"], s["rejected"], s["overruns"]),
        (1.0, 3.0, 1234.0, 7.0)
    );
    // Bit 0 (shaping), bit 2 (transmit overflow), the next side left, the clock fault.
    assert_eq!(
        (
            s["shaping"],
            s["replan_failed"],
            s["tx_overflow"],
            s["next_side"],
            s["clock_fault"],
            s["velocity_cut"],
            s["at_goal"]
        ),
        (1.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0)
    );
    close(s["last_adjust"], -0.2, 0.005, "last_adjust");
    let dg = Diag {
        foreign: 40_000,
        bus_errors: 12,
        tx_dropped: 3,
        next_step: 0x1234,
    };
    let s = decode(&d, &dg.encode());
    assert_eq!(
        (
            s["foreign"],
            s["bus_errors"],
            s["tx_dropped"],
            s["next_step"]
        ),
        (40_000.0, 12.0, 3.0, f64::from(0x1234u16))
    );
    let se = Session {
        epoch: 0xDEAD_BEEF,
        last_seq: 77,
    };
    let s = decode(&d, &se.encode());
    assert_eq!(
        (s["epoch"], s["last_seq"]),
        (f64::from(0xDEAD_BEEFu32), 77.0)
    );
    let stream = Stream {
        cog: [12.345678, -0.123456],
        cog_vel: [0.3125, -0.25],
        zmp: [-1.5, 0.07],
        phase: 3,
        tick: 200,
        feet: [[12.4, 0.1, 0.0321, 0.5], [-12.2, -0.1, 0.0, -0.25]],
    };
    let frames = stream.encode();
    let s = decode(&d, &frames[0]);
    close(s["cog_x"], 12.345678, 1e-6, "cog_x");
    close(s["cog_y"], -0.123456, 1e-6, "cog_y");
    let s = decode(&d, &frames[1]);
    close(s["zmp_x"], -1.5, 1e-6, "zmp_x");
    close(s["zmp_y"], 0.07, 1e-6, "zmp_y");
    let s = decode(&d, &frames[2]);
    close(s["cog_vx"], 0.3125, 1e-4, "cog_vx");
    close(s["cog_vy"], -0.25, 1e-4, "cog_vy");
    assert_eq!((s["phase"], s["tick"]), (3.0, 200.0));
    for (k, f) in frames[3..].iter().enumerate() {
        let s = decode(&d, f);
        let want = stream.feet[k];
        close(s["x"], want[0], 1e-4, "foot x");
        close(s["y"], want[1], 1e-4, "foot y");
        close(s["z"], want[2], 5e-4, "foot z");
        close(s["yaw"], want[3], 1e-4, "foot yaw");
    }
}

// ---------------------------------------------------------------------------------------------
// The DBC's definitions, looked up.

fn message(d: &Dbc, id: u16) -> &Message {
    d.messages
        .iter()
        .find(|m| m.id == MessageId::Standard(id))
        .unwrap_or_else(|| panic!("id {id:#x} not in the DBC"))
}

fn signal<'a>(d: &'a Dbc, id: u16, name: &str) -> &'a Signal {
    d.signal_by_name(MessageId::Standard(id), name)
        .unwrap_or_else(|| panic!("{}.{name} not in the DBC", message(d, id).name))
}

/// The value table (`VAL_`) of a signal.
fn table(d: &Dbc, id: u16, name: &str) -> BTreeMap<i64, String> {
    d.value_descriptions_for_signal(MessageId::Standard(id), name)
        .unwrap_or_else(|| panic!("{}.{name} has no value table", message(d, id).name))
        .iter()
        .map(|v| (v.id, v.description.clone()))
        .collect()
}

fn number(v: NumericValue) -> f64 {
    match v {
        NumericValue::Uint(u) => u as f64,
        NumericValue::Int(i) => i as f64,
        NumericValue::Double(x) => x,
    }
}

/// Equal but for the last digits of a decimal written to 15 significant digits.
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1.0)
}

/// The DBC name of a Rust variant from its `Debug` form: `EmergencyStopped` →
/// `emergency_stopped`, `Single(Left)` → `single_left`.
fn snake(debug: &str) -> String {
    let mut out = String::new();
    for c in debug.chars() {
        if c.is_ascii_uppercase() {
            if !out.is_empty() && !out.ends_with('_') {
                out.push('_');
            }
            out.push(c.to_ascii_lowercase());
        } else if c.is_ascii_alphanumeric() {
            out.push(c);
        } else if !out.is_empty() && !out.ends_with('_') {
            out.push('_');
        }
    }
    out.trim_end_matches('_').to_string()
}

fn name_of(v: &impl std::fmt::Debug) -> String {
    snake(&format!("{v:?}"))
}
