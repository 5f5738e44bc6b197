//! A scenario's commands as the controller puts them on the bus: the step ids the wire carries
//! ([`WireId`]), the controller's side of the session (the epoch it speaks in and its sequence
//! counter), and the encoding of every timeline command into a `planner_core::wire::Command`
//! (footsteps through the controller's [`StepBook`], control commands with the next sequence
//! number). [`wire_check`] runs that encoding over a whole scenario, so a scenario that cannot
//! be sent is refused before it runs, naming the command.

use planner_core::gait::Side;
use planner_core::wire::{self, Command, ControlOp, StepBook};

use super::Scenario;

/// A footstep id as the bus carries it: the node's 16-bit step number (the low byte is byte 0
/// of `STEP_APPEND` and `STEP_MODIFY` and the `seq` of their `ACK`, the high byte is in their
/// CRC): the one definition of the id range, from a scenario file to the wire. The node of a
/// run numbers its steps from 0 (its entropy is 0), so a scenario's ids are the numbers.
pub type WireId = u16;

/// The largest id a scenario may give: a start-up numbers 65,535 steps (0 … 65,534).
pub const MAX_WIRE_ID: WireId = 0xFFFE;

/// The id of a scenario command as the bus carries it, `None` if it does not fit.
pub fn wire_id(id: u16) -> Option<WireId> {
    (id <= MAX_WIRE_ID).then_some(id)
}

/// The controller's side of the session: the epoch the node published and the sequence
/// counter (one for every control command).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Controller {
    /// The session epoch the controller speaks in.
    pub(crate) epoch: u32,
    /// The last sequence number it used.
    pub(crate) seq: u32,
}

impl Controller {
    /// The next control command `op` in the session.
    pub(crate) fn control(&mut self, op: ControlOp) -> Command {
        self.seq += 1;
        Command::Control {
            session: self.epoch as u16,
            seq: self.seq,
            op,
        }
    }

    /// The next `VELOCITY` (vx, vy, ω) in the session (the control sequence's next number).
    pub(crate) fn velocity(&mut self, vx: f64, vy: f64, wz: f64) -> Command {
        self.seq += 1;
        Command::Velocity(wire::WireVelocity::from_si(self.seq, vx, vy, wz))
    }
}

/// The frame of a scenario command: footsteps through the controller's step book, control
/// commands with the next sequence number.
pub(crate) fn encode(
    command: super::Command,
    ctl: &mut Controller,
    book: &mut StepBook,
) -> Result<Command, String> {
    let control = |ctl: &mut Controller, op| Ok(ctl.control(op));
    match command {
        super::Command::Push(id, f) | super::Command::Modify(id, f) => {
            let left = f.side == Side::Left;
            let Some(wid) = wire_id(id) else {
                return Err(format!(
                    "footstep id {id} does not fit the bus (0 … {MAX_WIRE_ID})"
                ));
            };
            // The limits as the codec has them.
            let limits = |bits| {
                let (min, max) = wire::signed_range(bits);
                (
                    f64::from(min) * wire::STEP_UNIT,
                    f64::from(max) * wire::STEP_UNIT,
                )
            };
            if let super::Command::Push(..) = command {
                book.append(wid, left, f.x, f.y, f.yaw).ok_or_else(|| {
                    let (min, max) = limits(wire::STEP_BITS);
                    format!(
                        "footstep {id} at ({}, {}) m is not representable on the bus: \
                         STEP_APPEND carries x and y within {min} … {max} m",
                        f.x, f.y
                    )
                })
            } else {
                let Some(base) = book.appended(wid) else {
                    return Err(format!(
                        "modification of footstep {id}: no append of step {id} was sent \
                         before it, and STEP_MODIFY carries the offset from the appended \
                         position"
                    ));
                };
                let (bx, by, _) = base.si();
                book.modify(wid, f.x, f.y, f.yaw).ok_or_else(|| {
                    let (min, max) = limits(wire::OFFSET_BITS);
                    format!(
                        "modification of footstep {id} to ({}, {}) m is not representable on \
                         the bus: it is ({:+.4}, {:+.4}) m from the appended ({bx:.4}, \
                         {by:.4}) m, STEP_MODIFY carries offsets within {min} … {max} m",
                        f.x,
                        f.y,
                        f.x - bx,
                        f.y - by
                    )
                })
            }
        }
        super::Command::Start => control(ctl, ControlOp::Start),
        super::Command::Stop => control(ctl, ControlOp::Stop),
        super::Command::StopNow => control(ctl, ControlOp::StopNow),
        super::Command::Velocity(vx, vy, wz) => Ok(ctl.velocity(vx, vy, wz)),
        super::Command::Goal(x, y, yaw) => {
            ctl.seq += 1;
            Ok(Command::Goal(wire::WireGoal::from_si(ctl.seq, x, y, yaw)))
        }
    }
}

/// Checks that every command of `s` can be sent on the bus, as [`simulate`](crate::sim::simulate) would send it;
/// on failure, the index of the first command that cannot and why.
pub fn wire_check(s: &Scenario) -> Result<(), (usize, String)> {
    let (mut ctl, mut book) = (Controller::default(), StepBook::new());
    for (i, &(_, command)) in s.timeline.iter().enumerate() {
        encode(command, &mut ctl, &mut book).map_err(|e| (i, e))?;
    }
    Ok(())
}

/// The DBC name of the command an `ACK` answers (its `command` byte): `ESTOP`, `CONTROL`,
/// `VELOCITY`, `GOAL`, `STEP_APPEND`, `STEP_MODIFY`, or the byte in hex for another.
pub fn command_name(code: u8) -> String {
    match code {
        0x10 => "ESTOP".into(),
        0x20 => "CONTROL".into(),
        0x2F => "VELOCITY".into(),
        0x46 => "GOAL".into(),
        0x00 => "STEP_APPEND".into(),
        0x01 => "STEP_MODIFY".into(),
        other => format!("0x{other:02x}"),
    }
}
