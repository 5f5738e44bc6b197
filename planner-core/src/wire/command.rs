//! The commands from the bus, validated once ([`Command::decode`]), and their answer, the
//! `ACK` ([`Ack`]).

use super::drive::{WireGoal, WireVelocity};
use super::measured::Measured;
use super::step::{WireModify, WireStep, VERSIONS};
use super::{crc8, crc_ok, crc_ok_over, ids, RawFrame, Reason};

/// The step number a footstep frame's low byte `low` names when the node expects `next` for
/// its next append: the number with that low byte nearest to `next`, from 128 below it to 127
/// above (`next` itself for the expected append; exact for every queued and remembered step,
/// at most 128 below it; a step skipped ahead reads as ahead).
pub fn step_number(low: u8, next: u16) -> u16 {
    let d = low.wrapping_sub(next as u8) as i8;
    next.wrapping_add(d as u16)
}

/// What the validation of a frame depends on in the node's state: the number of its next
/// append (footstep frames are read by [`step_number`] and their CRC keyed with the number's
/// [`super::step_key`]) and the session epoch (the key of `MEASURED`). A bare `u16` is the next
/// step number with epoch 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Expect {
    /// The number of the node's next append (`DIAG`).
    pub next_step: u16,
    /// The session epoch (`SESSION`).
    pub epoch: u32,
    /// The last accepted control sequence number (`SESSION`): `VELOCITY` and `GOAL` carry the
    /// low 24 bits of theirs, read against it ([`super::seq_number`]).
    pub last_seq: u32,
}

impl From<u16> for Expect {
    fn from(next_step: u16) -> Self {
        Self {
            next_step,
            epoch: 0,
            last_seq: 0,
        }
    }
}

/// Control operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ControlOp {
    /// Keep-alive: the controller is there.
    Heartbeat,
    /// Start walking with the queued steps.
    Start,
    /// Walk the queued steps, then stop.
    Stop,
    /// Drop the queue and stop as soon as possible.
    StopNow,
    /// Leave the emergency-stopped state (only when standing).
    Reset,
    /// Start walking with the queued steps, and let the node move the next landing from the
    /// measured state for this walk (the node's step adjustment; [`ControlOp::Start`] walks
    /// the steps where they are commanded).
    StartAdjusting,
}

impl ControlOp {
    fn code(self) -> u8 {
        match self {
            ControlOp::Heartbeat => 0,
            ControlOp::Start => 1,
            ControlOp::Stop => 2,
            ControlOp::StopNow => 3,
            ControlOp::Reset => 4,
            ControlOp::StartAdjusting => 5,
        }
    }
    fn from_code(c: u8) -> Option<Self> {
        Some(match c {
            0 => ControlOp::Heartbeat,
            1 => ControlOp::Start,
            2 => ControlOp::Stop,
            3 => ControlOp::StopNow,
            4 => ControlOp::Reset,
            5 => ControlOp::StartAdjusting,
            _ => return None,
        })
    }
}

/// A validated command from the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Emergency stop with its sequence number.
    EmergencyStop {
        /// Sequence number.
        seq: u8,
    },
    /// A control operation with its session and sequence number.
    Control {
        /// The low 16 bits of the session epoch the command belongs to (`SESSION`).
        session: u16,
        /// Sequence number (greater than that of every control command before it).
        seq: u32,
        /// Operation.
        op: ControlOp,
    },
    /// Append a footstep.
    Append(WireStep),
    /// Modify a queued footstep.
    Modify(WireModify),
    /// The robot's measured state (not a command of the controller: it never proves the
    /// controller alive).
    Measured(Measured),
    /// Walk at a velocity (a control command of the session, numbered with `CONTROL`).
    Velocity(WireVelocity),
    /// Walk to a relative goal (a control command of the session, numbered with `CONTROL`).
    Goal(WireGoal),
}

impl Command {
    /// Validates a frame, for a node in the state `expect` says ([`Expect`]; a `u16` is the
    /// next step number). On error, the reason and the low byte of the sequence, step number
    /// or stamp to answer with (0 when the frame is too short to carry one).
    #[inline(never)] // (one copy for its callers)
    pub fn decode(f: &RawFrame, expect: impl Into<Expect>) -> Result<Self, (Reason, u8)> {
        let Expect {
            next_step: next,
            epoch,
            last_seq,
        } = expect.into();
        let b = f.bytes();
        let first = b.first().copied().unwrap_or(0);
        let need = |n: usize, key: u8| {
            if b.len() == n {
                Ok(())
            } else {
                Err((Reason::BadLength, key))
            }
        };
        match f.id {
            ids::ESTOP => {
                need(1, first)?;
                Ok(Command::EmergencyStop { seq: first })
            }
            ids::CONTROL => {
                let low = b.get(2).copied().unwrap_or(0);
                need(8, low)?;
                if !crc_ok(f.id, b) {
                    return Err((Reason::BadCrc, low));
                }
                let session = u16::from_le_bytes([b[0], b[1]]);
                let seq = u32::from_le_bytes([b[2], b[3], b[4], b[5]]);
                let op = ControlOp::from_code(b[6]).ok_or((Reason::OutOfRange, low))?;
                Ok(Command::Control { session, seq, op })
            }
            ids::MEASURED => {
                need(8, first)?;
                Measured::decode(b, epoch)
                    .map(Command::Measured)
                    .map_err(|r| (r, first))
            }
            ids::VELOCITY => {
                need(8, first)?;
                WireVelocity::decode(b, epoch, last_seq)
                    .map(Command::Velocity)
                    .map_err(|r| (r, first))
            }
            ids::GOAL => {
                need(8, first)?;
                WireGoal::decode(b, epoch, last_seq)
                    .map(Command::Goal)
                    .map_err(|r| (r, first))
            }
            ids::STEP_APPEND | ids::STEP_MODIFY => {
                need(8, first)?;
                let number = step_number(first, next);
                if !crc_ok_over(f.id, Some(super::step_key(number)), b) {
                    return Err((Reason::BadCrc, first));
                }
                let mut d = [0u8; 8];
                d.copy_from_slice(b);
                Ok(if f.id == ids::STEP_APPEND {
                    Command::Append(WireStep::unpack(&d, number).map_err(|r| (r, first))?)
                } else {
                    Command::Modify(WireModify::unpack(&d, number))
                })
            }
            _ => Err((Reason::UnknownId, 0)),
        }
    }

    /// The frame that carries this command (a measured state for session epoch 0: see
    /// [`Command::encode_in`]).
    pub fn encode(&self) -> RawFrame {
        self.encode_in(0)
    }

    /// The frame that carries this command in the session `epoch` (only the CRCs of the
    /// measured state, `VELOCITY` and `GOAL` depend on it).
    pub fn encode_in(&self, epoch: u32) -> RawFrame {
        match self {
            Command::Measured(m) => return m.encode(epoch),
            Command::Velocity(v) => return v.encode(epoch),
            Command::Goal(g) => return g.encode(epoch),
            _ => {}
        }
        let (id, data, n) = match self {
            Command::EmergencyStop { seq } => (ids::ESTOP, [*seq, 0, 0, 0, 0, 0, 0, 0], 1),
            Command::Control { session, seq, op } => {
                let [s0, s1] = session.to_le_bytes();
                let [q0, q1, q2, q3] = seq.to_le_bytes();
                let body = [s0, s1, q0, q1, q2, q3, op.code()];
                let c = crc8(ids::CONTROL, &body);
                (ids::CONTROL, [s0, s1, q0, q1, q2, q3, op.code(), c], 8)
            }
            Command::Append(s) => (ids::STEP_APPEND, s.pack(), 8),
            Command::Modify(s) => (ids::STEP_MODIFY, s.pack(), 8),
            Command::Measured(m) => (ids::MEASURED, m.encode(0).data, 8),
            Command::Velocity(v) => (ids::VELOCITY, v.encode(0).data, 8),
            Command::Goal(g) => (ids::GOAL, g.encode(0).data, 8),
        };
        RawFrame {
            id,
            len: n,
            data: {
                let mut d = [0u8; 8];
                d[..usize::from(n)].copy_from_slice(&data[..usize::from(n)]);
                d
            },
        }
    }

    /// The step number of a footstep command.
    pub fn step_id(&self) -> Option<u16> {
        match self {
            Command::Append(s) => Some(s.id),
            Command::Modify(m) => Some(m.id),
            _ => None,
        }
    }

    /// What an `ACK` to this command carries as `seq`: the low byte of the step number or of
    /// the sequence number.
    pub fn key(&self) -> u8 {
        match self {
            Command::Append(s) => s.id as u8,
            Command::Modify(m) => m.id as u8,
            Command::Control { seq, .. } => *seq as u8,
            Command::EmergencyStop { seq } => *seq,
            Command::Measured(m) => m.stamp as u8,
            Command::Velocity(v) => v.seq as u8,
            Command::Goal(g) => g.seq as u8,
        }
    }

    /// The code of the command in `ACK` frames (the low byte of its identifier).
    pub fn code(&self) -> u8 {
        let id = match self {
            Command::EmergencyStop { .. } => ids::ESTOP,
            Command::Control { .. } => ids::CONTROL,
            Command::Append(_) => ids::STEP_APPEND,
            Command::Modify(_) => ids::STEP_MODIFY,
            Command::Measured(_) => ids::MEASURED,
            Command::Velocity(_) => ids::VELOCITY,
            Command::Goal(_) => ids::GOAL,
        };
        (id & 0xFF) as u8
    }

    /// What the `ACK` to this command echoes: the last byte of its frame (the CRC, except for
    /// the emergency stop, whose only byte is its sequence number; a measured state's for
    /// session epoch 0: see [`Command::echo_in`]).
    pub fn echo(&self) -> u8 {
        echo_of(&self.encode())
    }

    /// [`Command::echo`] in the session `epoch`.
    pub fn echo_in(&self, epoch: u32) -> u8 {
        echo_of(&self.encode_in(epoch))
    }
}

/// The byte an `ACK` echoes of the frame it answers: its last data byte (0 if it has none).
pub fn echo_of(f: &RawFrame) -> u8 {
    f.bytes().last().copied().unwrap_or(0)
}

/// An `ACK` frame: the answer to a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ack {
    /// Low byte of the command's identifier (0x10 e-stop, 0x20 control, 0xD8 measured state,
    /// 0x00 append, 0x01 modify).
    pub command: u8,
    /// The low byte of the command's sequence number or step number.
    pub seq: u8,
    /// `None` when accepted.
    pub reason: Option<Reason>,
    /// Queued steps after the command.
    pub queue: u8,
    /// The last byte of the answered frame ([`echo_of`]; the command's CRC for `CONTROL` and
    /// footsteps).
    pub echo: u8,
    /// For a footstep command: the version of that step in force after the command (0 as
    /// appended), whatever the answer; `None` (0xFF on the wire) for other commands and for
    /// steps the node does not know. A controller whose newer modification was refused learns
    /// from it which of its versions the node walks. For an accepted `VELOCITY` or `GOAL`:
    /// what the node cut of the command to what the legs can take ([`Ack::cut`]: bit 0
    /// forward, 1 across, 2 turn, 3 stepped in place; 0 nothing cut).
    pub version: Option<u8>,
}

impl Ack {
    /// The frame (with its CRC).
    pub fn encode(&self) -> RawFrame {
        let r = self.reason.map(Reason::code).unwrap_or(0);
        let v = self.version.unwrap_or(0xFF);
        let body = [self.command, self.seq, r, self.queue, self.echo, v];
        let c = crc8(ids::ACK, &body);
        RawFrame {
            id: ids::ACK,
            len: 7,
            data: [body[0], body[1], body[2], body[3], body[4], v, c, 0],
        }
    }
    /// For the answer to an accepted `VELOCITY` or `GOAL`: what the node cut, as bits (see
    /// [`Ack::version`]: bit 0 forward, 1 across, 2 turn, 3 stepped in place; 0 nothing cut;
    /// `planner_core::velocity::Saturation::from_mask` reads them); `None` for other answers.
    pub fn cut(&self) -> Option<u8> {
        let drive = [(ids::VELOCITY & 0xFF) as u8, (ids::GOAL & 0xFF) as u8];
        if !drive.contains(&self.command) || self.reason.is_some() {
            return None;
        }
        self.version
    }

    /// Decodes an `ACK` frame; `None` if it is not one or its CRC is wrong.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::ACK || f.len != 7 || !crc_ok(f.id, f.bytes()) {
            return None;
        }
        let reason = match f.data[2] {
            0 => None,
            c => Some(Reason::from_code(c)?),
        };
        Some(Self {
            command: f.data[0],
            seq: f.data[1],
            reason,
            queue: f.data[3],
            echo: f.data[4],
            version: match f.data[5] {
                0xFF => None,
                v if v < VERSIONS => Some(v),
                _ => return None,
            },
        })
    }
}
