//! The codec's enumerations. Each list comes with an exhaustive `match`: a new variant does not (see the docs of `main.rs`).

use super::*;

pub(crate) const OPS: [ControlOp; 6] = [
    ControlOp::Heartbeat,
    ControlOp::Start,
    ControlOp::Stop,
    ControlOp::StopNow,
    ControlOp::Reset,
    ControlOp::StartAdjusting,
];

pub(crate) fn op_position(op: ControlOp) -> usize {
    match op {
        ControlOp::Heartbeat => 0,
        ControlOp::Start => 1,
        ControlOp::Stop => 2,
        ControlOp::StopNow => 3,
        ControlOp::Reset => 4,
        ControlOp::StartAdjusting => 5,
    }
}

/// The code of a control operation on the wire: the `op` byte of its `CONTROL` frame.
pub(crate) fn op_code(op: ControlOp) -> u8 {
    Command::Control {
        session: 0,
        seq: 0,
        op,
    }
    .encode()
    .data[6]
}

pub(crate) const STATES: [NodeState; 6] = [
    NodeState::Standing,
    NodeState::Walking,
    NodeState::EmergencyStopped,
    NodeState::ControllerLost,
    NodeState::Stopping,
    NodeState::NoSession,
];

pub(crate) fn state_position(s: NodeState) -> usize {
    match s {
        NodeState::Standing => 0,
        NodeState::Walking => 1,
        NodeState::EmergencyStopped => 2,
        NodeState::ControllerLost => 3,
        NodeState::Stopping => 4,
        NodeState::NoSession => 5,
    }
}

/// The phases of the reference, in the order of their codes in `COG_VEL` (the node's run
/// checks the codes).
pub(crate) const PHASES: [Phase; 4] = [
    Phase::Standing,
    Phase::Double,
    Phase::Single(Side::Left),
    Phase::Single(Side::Right),
];

pub(crate) fn phase_position(p: Phase) -> usize {
    match p {
        Phase::Standing => 0,
        Phase::Double => 1,
        Phase::Single(Side::Left) => 2,
        Phase::Single(Side::Right) => 3,
    }
}

/// The sides the next step may have, in the order of their codes in `STATUS` (checked by the
/// node's run too).
pub(crate) const NEXT_SIDES: [Option<Side>; 3] = [None, Some(Side::Left), Some(Side::Right)];

pub(crate) fn next_side_position(s: Option<Side>) -> usize {
    match s {
        None => 0,
        Some(Side::Left) => 1,
        Some(Side::Right) => 2,
    }
}

pub(crate) fn next_side_name(s: Option<Side>) -> String {
    s.map_or_else(|| "either".to_string(), |side| name_of(&side))
}

/// One command of each kind, with its name in `ACK.command`.
pub(crate) fn commands() -> [(Command, &'static str); 7] {
    let step = WireStep::from_si(3, true, 0.2, 0.1, 0.0).unwrap();
    let change = WireModify::from_si(&step, 1, 0.25, 0.1, 0.0).unwrap();
    [
        Command::EmergencyStop { seq: 1 },
        Command::Control {
            session: 0,
            seq: 1,
            op: ControlOp::Heartbeat,
        },
        Command::Append(step),
        Command::Modify(change),
        Command::Measured(Measured::from_si(7, [0.01, -0.02]).unwrap()),
        Command::Velocity(WireVelocity::from_si(2, 0.1, 0.0, 0.0)),
        Command::Goal(WireGoal::from_si(3, 1.0, 0.0, 0.0)),
    ]
    .map(|c| {
        let name = match c {
            Command::EmergencyStop { .. } => "estop",
            Command::Control { .. } => "control",
            Command::Append(_) => "append",
            Command::Modify(_) => "modify",
            Command::Measured(_) => "measured",
            Command::Velocity(_) => "velocity",
            Command::Goal(_) => "goal",
        };
        (c, name)
    })
}

#[test]
fn the_lists_of_variants_are_complete_and_in_order() {
    assert!(OPS.iter().enumerate().all(|(i, &v)| op_position(v) == i));
    assert!(STATES
        .iter()
        .enumerate()
        .all(|(i, &v)| state_position(v) == i));
    assert!(PHASES
        .iter()
        .enumerate()
        .all(|(i, &v)| phase_position(v) == i));
    assert!(NEXT_SIDES
        .iter()
        .enumerate()
        .all(|(i, &v)| next_side_position(v) == i));
    assert_eq!(snake("EmergencyStopped"), "emergency_stopped");
    assert_eq!(name_of(&Phase::Single(Side::Left)), "single_left");
}

// ---------------------------------------------------------------------------------------------
// Value tables.

/// The value tables the tests below compare with the codec: a table added to the DBC without
/// a comparison fails here.
pub(crate) const TABLES: [(u16, &str); 9] = [
    (ids::CONTROL, "op"),
    (ids::ACK, "command"),
    (ids::ACK, "reason"),
    (ids::ACK, "version"),
    (ids::COG_VEL, "phase"),
    (ids::STATUS, "state"),
    (ids::STATUS, "next_side"),
    (ids::LINK, "bus_state"),
    (ids::LINK, "reset"),
];

#[test]
fn every_value_table_is_compared_with_the_codec() {
    let d = dbc();
    let in_dbc: BTreeSet<(u32, String)> = d
        .value_descriptions
        .iter()
        .map(|v| match v {
            ValueDescription::Signal {
                message_id, name, ..
            } => (message_id.raw(), name.clone()),
            ValueDescription::EnvironmentVariable { name, .. } => panic!("VAL_ {name}"),
        })
        .collect();
    let checked: BTreeSet<(u32, String)> = TABLES
        .iter()
        .map(|&(id, name)| (u32::from(id), name.to_string()))
        .collect();
    assert_eq!(in_dbc, checked);
    assert!(d.value_tables.is_empty(), "VAL_TABLE_ is not used");
    for (id, name) in TABLES {
        signal(&d, id, name); // the table's signal exists
    }
}

#[test]
fn ack_reason_table_is_reason_all_and_accepted() {
    let d = dbc();
    let mut want = BTreeMap::from([(0, "accepted".to_string())]);
    for r in Reason::ALL {
        let old = want.insert(i64::from(r.code()), name_of(&r));
        assert!(old.is_none(), "{r:?}: code {} taken twice", r.code());
        assert_eq!(Reason::from_code(r.code()), Some(r));
        // The node's ACK carries the code where the DBC reads it.
        let a = Ack {
            command: 0x20,
            seq: 1,
            reason: Some(r),
            queue: 0,
            echo: 0,
            version: None,
        };
        assert_eq!(decode(&d, &a.encode())["reason"], f64::from(r.code()));
    }
    assert_eq!(Reason::from_code(0), None, "0 is accepted");
    assert_eq!(table(&d, ids::ACK, "reason"), want);
}

#[test]
fn control_op_table_is_every_code_the_codec_takes() {
    let d = dbc();
    let want: BTreeMap<i64, String> = OPS
        .iter()
        .map(|&op| {
            let f = Command::Control {
                session: 0,
                seq: 0,
                op,
            }
            .encode();
            assert_eq!(decode(&d, &f)["op"], f64::from(f.data[6]));
            (i64::from(op_code(op)), name_of(&op))
        })
        .collect();
    assert_eq!(want.len(), OPS.len(), "two operations share a code");
    assert_eq!(table(&d, ids::CONTROL, "op"), want);
    // Every other code is refused by the decoder: the table is all the codec accepts.
    for c in 0..=u8::MAX {
        let body = [1, 0, 7, 0, 0, 0, c];
        let mut d8 = [0u8; 8];
        d8[..7].copy_from_slice(&body);
        d8[7] = wire::crc8(ids::CONTROL, &body);
        let f = RawFrame::new(ids::CONTROL, &d8).unwrap();
        match Command::decode(&f, 0) {
            Ok(Command::Control { op, .. }) => assert_eq!(want[&i64::from(c)], name_of(&op)),
            Ok(other) => panic!("{other:?}"),
            Err((reason, _)) => {
                assert_eq!(reason, Reason::OutOfRange);
                assert!(!want.contains_key(&i64::from(c)), "{c}");
            }
        }
    }
}

#[test]
fn ack_command_table_is_the_low_byte_of_the_command_ids() {
    let d = dbc();
    let by_id: BTreeMap<i64, String> = [
        (ids::ESTOP, "estop"),
        (ids::CONTROL, "control"),
        (ids::STEP_APPEND, "append"),
        (ids::STEP_MODIFY, "modify"),
        (ids::MEASURED, "measured"),
        (ids::VELOCITY, "velocity"),
        (ids::GOAL, "goal"),
    ]
    .iter()
    .map(|&(id, name)| (i64::from(id & 0xFF), name.to_string()))
    .collect();
    assert_eq!(table(&d, ids::ACK, "command"), by_id);
    // The codec's own codes: `Command::code` of each kind, every identifier of `ids::COMMANDS`.
    let mut seen = BTreeSet::new();
    for (c, name) in commands() {
        let id = c.encode().id;
        assert_eq!(c.code(), (id & 0xFF) as u8, "{c:?}");
        assert_eq!(by_id[&i64::from(c.code())], name, "{c:?}");
        seen.insert(id);
    }
    assert_eq!(seen, ids::COMMANDS.into_iter().collect());
}

#[test]
fn ack_version_table_names_the_codecs_none() {
    let d = dbc();
    let a = Ack {
        command: 0x00,
        seq: 1,
        reason: None,
        queue: 0,
        echo: 0,
        version: None,
    };
    let none = decode(&d, &a.encode())["version"];
    assert_eq!(
        table(&d, ids::ACK, "version"),
        BTreeMap::from([(none as i64, "none".to_string())])
    );
    assert!(none >= f64::from(VERSIONS), "not a version");
}

#[test]
fn status_state_table_is_node_state() {
    let d = dbc();
    let want: BTreeMap<i64, String> = STATES
        .iter()
        .map(|&s| (i64::from(s as u8), name_of(&s)))
        .collect();
    assert_eq!(want.len(), STATES.len());
    assert_eq!(table(&d, ids::STATUS, "state"), want);
    assert_eq!(want[&3], "controller_lost");
    assert_eq!(want[&2], "emergency_stopped");
}

#[test]
fn phase_and_next_side_tables_have_every_variant() {
    // The codes are the node's: see `a_running_node_speaks_the_dbc`.
    let d = dbc();
    let phases: BTreeMap<i64, String> = PHASES
        .iter()
        .enumerate()
        .map(|(i, p)| (i as i64, name_of(p)))
        .collect();
    assert_eq!(table(&d, ids::COG_VEL, "phase"), phases);
    let sides: BTreeMap<i64, String> = NEXT_SIDES
        .iter()
        .enumerate()
        .map(|(i, &s)| (i as i64, next_side_name(s)))
        .collect();
    assert_eq!(table(&d, ids::STATUS, "next_side"), sides);
}

#[test]
fn link_tables_are_the_boards_bus_states_and_reset_reasons() {
    let d = dbc();
    let states: BTreeMap<i64, String> = board_core::BusState::ALL
        .iter()
        .map(|&s| (s as i64, name_of(&s)))
        .collect();
    assert_eq!(states.len(), 4);
    assert_eq!(table(&d, ids::LINK, "bus_state"), states);
    let resets: BTreeMap<i64, String> = board_core::ResetReason::ALL
        .iter()
        .map(|&r| (r as i64, name_of(&r)))
        .collect();
    assert_eq!(resets.len(), board_core::ResetReason::ALL.len());
    assert_eq!(table(&d, ids::LINK, "reset"), resets);
    assert_eq!(resets[&5], "independent_watchdog");
    // Every code fits the 4-bit field.
    assert!(resets.keys().all(|&c| c < 16));
}
