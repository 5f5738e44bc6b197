//! The book's state table (`docs/src/reliability.md`, between the `state-table` markers) checked
//! against the node, cell by cell: every state is set up as described here, every command is
//! sent valid (fresh sequence number, the next id, the right foot, in reach, a queued step when
//! there is one), and the answer and the state after it must be what the cell says. A refused
//! command must also change nothing (the rig compares the node with a clone that ran the same
//! cycle without it). The test fails if the table misses a state or a command.

mod common;

use common::{state_name, y, Rig};
use planner_core::gait::Side;
use planner_core::wire::{Command, ControlOp, Reason, WireGoal, WireVelocity};

const STATES: [&str; 10] = [
    "no session",
    "standing",
    "walking",
    "walking (velocity)",
    "walking (goal)",
    "stopping",
    "lost (moving)",
    "lost (standing)",
    "e-stopped (moving)",
    "e-stopped (standing)",
];
const COMMANDS: [&str; 13] = [
    "ESTOP",
    "HEARTBEAT",
    "START",
    "START_ADJUSTING",
    "STOP",
    "STOP_NOW",
    "RESET",
    "STEP_APPEND",
    "STEP_MODIFY",
    "MEASURED",
    "VELOCITY",
    "GOAL",
    "silence > 500 ms",
];

/// The table: (state, command, cell).
fn table() -> Vec<(String, String, String)> {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/src/reliability.md"
    ))
    .expect("docs/src/reliability.md");
    let start = text.find("<!-- state-table -->").expect("start marker");
    let end = text.find("<!-- /state-table -->").expect("end marker");
    let rows: Vec<Vec<String>> = text[start..end]
        .lines()
        .filter(|l| l.starts_with('|'))
        .map(|l| {
            l.trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect();
    let header = &rows[0];
    assert_eq!(header[0], "state");
    assert_eq!(&header[1..], &COMMANDS, "the table's columns");
    let mut cells = vec![];
    for row in &rows[2..] {
        assert_eq!(row.len(), header.len(), "{row:?}");
        for (c, cell) in header[1..].iter().zip(&row[1..]) {
            cells.push((row[0].clone(), c.clone(), cell.clone()));
        }
    }
    let states: Vec<&str> = rows[2..].iter().map(|r| r[0].as_str()).collect();
    assert_eq!(states, STATES, "the table's rows");
    cells
}

/// What a cell says: the answer (`None`: accepted) and the state after it.
fn expect(state: &str, cell: &str) -> (Option<u8>, String) {
    if let Some(next) = cell.strip_prefix("ok → ") {
        return (None, next.to_string());
    }
    if cell == "ok" {
        return (None, state.to_string());
    }
    let code: u8 = cell
        .parse()
        .unwrap_or_else(|_| panic!("cell {cell:?}: `ok`, `ok → state` or a reason code"));
    (Some(code), state.to_string())
}

/// A walking robot: five steps queued, started, in the start window's double support.
fn walking() -> Rig {
    let mut r = Rig::hrp2();
    for i in 0..5u16 {
        let left = i % 2 == 1;
        assert_eq!(r.append(i, left, 0.1 * f64::from(i + 1), y(left)), None);
    }
    assert_eq!(r.control(ControlOp::Start), None);
    r.run(2, true);
    r
}

fn setup(state: &str) -> Rig {
    let mut r = match state {
        "no session" => {
            let mut r = Rig::unopened(planner_core::node::NodeConfig::hrp2());
            r.cycle(); // the session is published
            r
        }
        "standing" => {
            let mut r = Rig::hrp2();
            assert_eq!(r.append(0, false, 0.1, -0.1), None);
            r
        }
        "walking" => walking(),
        "walking (velocity)" => {
            let mut r = Rig::hrp2();
            let c = velocity(&mut r);
            assert_eq!(r.ask(c), None);
            r
        }
        "walking (goal)" => {
            let mut r = Rig::hrp2();
            let c = goal(&mut r);
            assert_eq!(r.ask(c), None);
            r
        }
        "stopping" => {
            let mut r = walking();
            assert_eq!(r.control(ControlOp::Stop), None);
            r
        }
        "lost (moving)" | "lost (standing)" => {
            let mut r = walking();
            r.run(101, false);
            if state == "lost (standing)" {
                r.until(3000, |n| n.gait().is_standing());
            }
            r
        }
        "e-stopped (moving)" | "e-stopped (standing)" => {
            let mut r = walking();
            assert_eq!(r.ask(Command::EmergencyStop { seq: 1 }), None);
            if state == "e-stopped (standing)" {
                r.until(3000, |n| n.gait().is_standing());
            }
            r
        }
        _ => panic!("no set-up for state {state:?}"),
    };
    assert_eq!(state_name(&r.n), state, "set-up");
    r.run(1, true);
    r
}

/// A valid `VELOCITY`: 0.1 m/s forward.
fn velocity(r: &mut Rig) -> Command {
    r.seq += 1;
    Command::Velocity(WireVelocity::from_si(r.seq, 0.1, 0.0, 0.0))
}

/// A valid `GOAL`: 2 m ahead.
fn goal(r: &mut Rig) -> Command {
    r.seq += 1;
    Command::Goal(WireGoal::from_si(r.seq, 2.0, 0.0, 0.0))
}

/// The last appended step number, and the next.
fn ids(r: &Rig) -> (Option<u16>, u16) {
    let next = r.n.next_step();
    let last = next.wrapping_sub(1);
    (r.book.appended(last).map(|_| last), next)
}

/// Sends `command` (valid) and returns its answer and the state after the cycle.
fn apply(r: &mut Rig, command: &str) -> (Option<u8>, String) {
    let code = |x: Option<Reason>| x.map(Reason::code);
    let answer = match command {
        "ESTOP" => code(r.ask(Command::EmergencyStop { seq: 2 })),
        "HEARTBEAT" => {
            let hb = r.heartbeat();
            code(r.ask(hb))
        }
        "START" => code(r.control(ControlOp::Start)),
        "START_ADJUSTING" => code(r.control(ControlOp::StartAdjusting)),
        "MEASURED" => code(r.measure([0.001, -0.002])),
        "VELOCITY" => {
            let c = velocity(r);
            code(r.ask(c))
        }
        "GOAL" => {
            let c = goal(r);
            code(r.ask(c))
        }
        "STOP" => code(r.control(ControlOp::Stop)),
        "STOP_NOW" => code(r.control(ControlOp::StopNow)),
        "RESET" => code(r.control(ControlOp::Reset)),
        "STEP_APPEND" => {
            let (_, id) = ids(r);
            let side = r.n.gait().next_side().unwrap_or(Side::Right);
            // A step 0.1 m ahead of the other foot, at the nominal width.
            let other = r.n.gait().previous_other(side, None);
            let beside = other.beside(0.2);
            let (s, c) = other.yaw.sin_cos();
            let c = r
                .book
                .append(
                    id,
                    side == Side::Left,
                    beside.x + 0.1 * c,
                    beside.y + 0.1 * s,
                    other.yaw,
                )
                .expect("representable");
            code(r.ask(c))
        }
        "STEP_MODIFY" => {
            // The last queued step (or, with none queued, the last appended), 1 cm further.
            let (last, next) = ids(r);
            let id = (0..=255u16)
                .map(|k| next.wrapping_sub(k))
                .find(|&i| r.n.gait().is_queued(i))
                .or(last)
                .unwrap_or_else(|| {
                    // Nothing appended (no session): a step the controller's book knows.
                    r.book.append(next, false, 0.1, -0.1, 0.0);
                    next
                });
            // (A step the node chose itself: the controller's book learns it from the node.)
            if r.book.appended(id).is_none() {
                if let Some(q) = r.n.gait().queued_step(id) {
                    r.book.append(id, q.side == Side::Left, q.x, q.y, q.yaw);
                }
            }
            let f = r.book.appended(id).expect("appended").si();
            let c = r
                .book
                .modify(id, f.0 + 0.01, f.1, f.2)
                .expect("representable");
            code(r.ask(c))
        }
        "silence > 500 ms" => {
            r.run(101, false);
            None
        }
        _ => panic!("no command {command:?}"),
    };
    (answer, state_name(&r.n).to_string())
}

#[test]
fn the_readme_state_table_is_what_the_node_does() {
    let cells = table();
    assert_eq!(cells.len(), STATES.len() * COMMANDS.len());
    let mut wrong = vec![];
    for (state, command, cell) in &cells {
        let want = expect(state, cell);
        let mut r = setup(state);
        let got = apply(&mut r, command);
        if got != want {
            wrong.push(format!(
                "{state} × {command}: the book says {cell:?}, the node {got:?}"
            ));
        }
    }
    assert!(wrong.is_empty(), "\n{}", wrong.join("\n"));
}
