//! The node's periodic reports (every 100 ms): `STATUS`, `DIAG`, `LINK` and `SESSION`.

use super::{ids, RawFrame};

/// The node's published state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// 0 standing, 1 walking, 2 emergency-stopped, 3 controller lost, 4 stopping (a `Stop`
    /// or `StopNow` is being carried out), 5 no session (after start-up, before the
    /// handshake). See the state table in the node's docs.
    pub state: u8,
    /// Queued steps.
    pub queue: u8,
    /// Commands rejected since start-up (saturating).
    pub rejected: u16,
    /// Control cycles that overran their budget (saturating; reported by the firmware).
    pub overruns: u16,
    /// Last single-support adjustment \[5 ms\].
    pub last_adjust: i8,
    /// Bit 0: shaping active; bit 1: last re-plan failed; bit 2: transmit backlog overflowed;
    /// bits 3–4: the side the next appended step must have (0 either, 1 left, 2 right); bit
    /// 5: the node's clock stopped ([`Status::CLOCK_FAULT`]); bit 6: the velocity the node
    /// walks was cut to what the legs can take ([`Status::CUT`]); bit 7: a goal walk stands at
    /// its goal ([`Status::AT_GOAL`]).
    pub flags: u8,
}

impl Status {
    /// The flag of a clock that did not advance with the cycles (latched until a `Reset`).
    pub const CLOCK_FAULT: u8 = 1 << 5;
    /// The flag of a velocity (or a goal's) walked slower than commanded: a component was cut
    /// to what the legs can take (while the node drives).
    pub const CUT: u8 = 1 << 6;
    /// The flag of a goal walk that stands at its goal (until the next command that moves).
    pub const AT_GOAL: u8 = 1 << 7;

    /// The side the next appended step must have: 0 either, 1 left, 2 right.
    pub fn next_side(&self) -> u8 {
        (self.flags >> 3) & 0x3
    }
}

impl Status {
    /// The frame.
    pub fn encode(&self) -> RawFrame {
        let r = self.rejected.to_le_bytes();
        let o = self.overruns.to_le_bytes();
        RawFrame {
            id: ids::STATUS,
            len: 8,
            data: [
                self.state,
                self.queue,
                r[0],
                r[1],
                o[0],
                o[1],
                self.last_adjust as u8,
                self.flags,
            ],
        }
    }
    /// Decodes a `STATUS` frame.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::STATUS || f.len != 8 {
            return None;
        }
        let d = &f.data;
        Some(Self {
            state: d[0],
            queue: d[1],
            rejected: u16::from_le_bytes([d[2], d[3]]),
            overruns: u16::from_le_bytes([d[4], d[5]]),
            last_adjust: d[6] as i8,
            flags: d[7],
        })
    }
}

/// The node's diagnostics (every 100 ms, with `STATUS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Diag {
    /// Frames received that are not the node's (other identifiers, extended or remote
    /// frames), saturating.
    pub foreign: u16,
    /// Bus errors on receive or transmit, saturating.
    pub bus_errors: u16,
    /// Frames dropped because the transmit backlog was full, saturating.
    pub tx_dropped: u16,
    /// The number of the next step to append (its low byte goes in the frame, its high
    /// byte into the CRC: see the module docs).
    pub next_step: u16,
}

impl Diag {
    /// The frame.
    pub fn encode(&self) -> RawFrame {
        let [f0, f1] = self.foreign.to_le_bytes();
        let [b0, b1] = self.bus_errors.to_le_bytes();
        let [t0, t1] = self.tx_dropped.to_le_bytes();
        let [n0, n1] = self.next_step.to_le_bytes();
        RawFrame {
            id: ids::DIAG,
            len: 8,
            data: [f0, f1, b0, b1, t0, t1, n0, n1],
        }
    }
    /// Decodes a `DIAG` frame.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::DIAG || f.len != 8 {
            return None;
        }
        let d = &f.data;
        Some(Self {
            foreign: u16::from_le_bytes([d[0], d[1]]),
            bus_errors: u16::from_le_bytes([d[2], d[3]]),
            tx_dropped: u16::from_le_bytes([d[4], d[5]]),
            next_step: u16::from_le_bytes([d[6], d[7]]),
        })
    }
}

/// The CAN link's health as the board reports it (`LINK`, every 100 ms with `STATUS`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LinkHealth {
    /// Transmit error counter.
    pub tec: u8,
    /// Receive error counter (0 … 127).
    pub rec: u8,
    /// The receive error counter has reached the error-passive level.
    pub rx_passive: bool,
    /// 0 error-active, 1 warning (a counter ≥ 96), 2 error-passive, 3 bus-off.
    pub bus_state: u8,
    /// Why the board last started: 0 unknown, 1 power-on, 2 pin, 3 brown-out, 4 software,
    /// 5 independent watchdog, 6 window watchdog, 7 fault handler, 8 clock failure,
    /// 9 low-power, 10 HSE not ready at start-up.
    pub reset: u8,
    /// Bus-off events since start-up (each recovered), saturating.
    pub bus_offs: u16,
    /// Entries into error-passive since start-up, saturating (12 bits on the wire: 4,095).
    pub passive_episodes: u16,
    /// 5 ms slots the control loop missed since start-up (an overrun longer than a period),
    /// saturating at 255.
    pub missed_slots: u8,
    /// The bus-off back-off (4 bits): 0 none (no bus-off since the last error-free stretch
    /// on the bus); `n` ≥ 1: the last bus-off kept the node off the bus for 2^(n-1) control
    /// cycles (7: the cap, 64 cycles = 320 ms).
    pub backoff: u8,
    /// Message RAM access failures since start-up (each recovered), saturating at 3 (2 bits).
    pub ram_faults: u8,
}

impl LinkHealth {
    /// Every field zero.
    pub const ZERO: Self = Self {
        tec: 0,
        rec: 0,
        rx_passive: false,
        bus_state: 0,
        reset: 0,
        bus_offs: 0,
        passive_episodes: 0,
        missed_slots: 0,
        backoff: 0,
        ram_faults: 0,
    };

    /// The largest `passive_episodes` on the wire (12 bits).
    pub const PASSIVE_EPISODES_MAX: u16 = 0x0FFF;

    /// The frame (fields beyond their widths are cut to them; `passive_episodes` and
    /// `ram_faults` saturate at their widths' maxima).
    pub fn encode(&self) -> RawFrame {
        let [b0, b1] = self.bus_offs.to_le_bytes();
        let passive = self.passive_episodes.min(Self::PASSIVE_EPISODES_MAX);
        let [p0, p1] = (passive | (u16::from(self.backoff & 0xF) << 12)).to_le_bytes();
        RawFrame {
            id: ids::LINK,
            len: 8,
            data: [
                self.tec,
                (self.rec & 0x7F) | (u8::from(self.rx_passive) << 7),
                (self.bus_state & 0x3) | ((self.reset & 0xF) << 2) | (self.ram_faults.min(3) << 6),
                b0,
                b1,
                p0,
                p1,
                self.missed_slots,
            ],
        }
    }
    /// Decodes a `LINK` frame.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::LINK || f.len != 8 {
            return None;
        }
        let d = &f.data;
        Some(Self {
            tec: d[0],
            rec: d[1] & 0x7F,
            rx_passive: d[1] & 0x80 != 0,
            bus_state: d[2] & 0x3,
            reset: (d[2] >> 2) & 0xF,
            bus_offs: u16::from_le_bytes([d[3], d[4]]),
            passive_episodes: u16::from_le_bytes([d[5], d[6]]) & Self::PASSIVE_EPISODES_MAX,
            missed_slots: d[7],
            backoff: d[6] >> 4,
            ram_faults: d[2] >> 6,
        })
    }
}

/// The session the node is in (`SESSION`, every 100 ms with `STATUS`): what a controller needs
/// to speak to it (see the module docs). After an accepted `Reset` the epoch is one more.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Session {
    /// The session epoch: drawn at start-up, one more at every accepted `Reset`. Control
    /// commands carry its low 16 bits ([`Session::tag`]).
    pub epoch: u32,
    /// The sequence number of the last accepted control command (0: none since start-up): the
    /// next one must be greater.
    pub last_seq: u32,
}

impl Session {
    /// What a `CONTROL` frame of this session carries.
    pub fn tag(&self) -> u16 {
        self.epoch as u16
    }

    /// The frame.
    pub fn encode(&self) -> RawFrame {
        let [e0, e1, e2, e3] = self.epoch.to_le_bytes();
        let [s0, s1, s2, s3] = self.last_seq.to_le_bytes();
        RawFrame {
            id: ids::SESSION,
            len: 8,
            data: [e0, e1, e2, e3, s0, s1, s2, s3],
        }
    }

    /// Decodes a `SESSION` frame.
    pub fn decode(f: &RawFrame) -> Option<Self> {
        if f.id != ids::SESSION || f.len != 8 {
            return None;
        }
        let d = &f.data;
        Some(Self {
            epoch: u32::from_le_bytes([d[0], d[1], d[2], d[3]]),
            last_seq: u32::from_le_bytes([d[4], d[5], d[6], d[7]]),
        })
    }
}
