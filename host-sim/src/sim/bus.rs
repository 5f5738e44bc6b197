//! An in-process CAN bus: ports that speak `embedded-can`, arbitration by identifier, the
//! bit time of the configured bitrate, a fault layer, and a candump-format log.
//!
//! * Each [`Port`] has a transmit mailbox (capacity [`MAILBOX`]; full → `WouldBlock`) and a
//!   receive FIFO (capacity [`RX_FIFO`]; a full FIFO loses the newest frame and counts it, as a
//!   controller's overrun does).
//! * [`Bus::advance`] runs the bus to a given time: whenever it is idle, the pending frame with
//!   the lowest identifier over all mailboxes wins arbitration, occupies the bus for its
//!   worst-case stuffed length ([`RawFrame::wire_bits`]) at the bitrate, and is then delivered
//!   to every other port. The busy time is accumulated for the bus load.
//! * The fault layer acts on the frames sent by one port (or all): it can drop, duplicate,
//!   corrupt (flip one data bit: a frame that a faulty gateway would pass on with a valid CRC),
//!   delay (deliver late, after frames sent later) or silence a port (bus-off: it neither sends
//!   nor receives for a while). Faults are drawn from a seeded generator, so runs repeat.
//! * Every delivered frame can be logged in the format of `candump -l` (see [below](#the-log)),
//!   for the usual CAN tools.
//!
//! # The log
//!
//! One line per delivered frame, in delivery order (so the timestamps never decrease, also with
//! delayed and duplicated frames), exactly the line format of a `candump -l` log file:
//!
//! ```text
//! (1767225600.000085) can0 020#0000FE
//! ```
//!
//! `(SSSSSSSSSS.UUUUUU)` is an absolute time in seconds and microseconds since the Unix epoch,
//! the interface is always [`LOG_IFACE`], `ID#DATA` is the standard identifier as 3 upper-case
//! hexadecimal digits and the data as 2 hexadecimal digits per byte (nothing after `#` for an
//! empty frame). The time is a fixed, stated epoch plus the simulated time, so the same run
//! gives the same log byte for byte:
//!
//! ```text
//! log time = LOG_EPOCH_S + t / 10⁹ s     (t: the bus time of the delivery [ns], truncated to 1 µs)
//! ```
//!
//! with [`LOG_EPOCH_S`] = 1767225600 = 2026-01-01T00:00:00Z; simulated time 0 is that instant.
//! The time of a frame is the end of its transmission, when every receiver has it (plus the
//! extra latency of a frame the fault layer delays). A log that started at 0 s would look to
//! can-utils' `log2asc` like a clock that is not set (a banner for every frame of the first
//! second, all timestamps zero).
//!
//! **Against `trajectory.csv`** (host-sim's [`simulate`](crate::sim::simulate) and
//! `host-sim run`): its `t` column is `j × 5 ms` for row `j`. The bus's first 5 ms are the
//! handshake's cycle (the node publishes its session, the controller opens it); row 0 is the
//! node's state before the first tick; row `j ≥ 1` is the reference of the node's poll in tick
//! `j − 1`, which runs at bus time `t + 2.5 ms` (`t` = that row's CSV time). The frames that
//! poll publishes (the five stream frames `200`, `201`, `202`, `210`, `211`, and `080` ACK,
//! `300` STATUS, `301` DIAG, `303` SESSION when due) are delivered before the next tick starts
//! (on a bus without faults), so
//!
//! ```text
//! log time − LOG_EPOCH_S = t_csv + 2.5 ms + d,    0 < d ≤ 2.5 ms
//! ```
//!
//! `d` being the frame's wait in the node's mailbox plus its own transmission
//! (`host-sim/tests/canlog.rs` checks this on every stream frame). The controller's commands of
//! tick `k` leave at bus time `5(k + 1) ms` (log time − `LOG_EPOCH_S` = `5(k + 1) ms + d`,
//! `d < 2.5 ms`), and the node reacts to them in the poll that produces CSV row `k + 1`.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

use planner_core::wire::RawFrame;

/// Transmit mailbox capacity of a port.
pub const MAILBOX: usize = 64;
/// Receive FIFO capacity of a port.
pub const RX_FIFO: usize = 64;

/// The epoch of the log: simulated time 0 is logged as this many seconds since the Unix epoch
/// (2026-01-01T00:00:00Z).
pub const LOG_EPOCH_S: u64 = 1_767_225_600;
/// The interface name in the log.
pub const LOG_IFACE: &str = "can0";

/// A frame on the virtual bus: the codec's own frame type, which is an `embedded-can` frame.
pub type VFrame = RawFrame;

/// Bus errors seen by a port.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BusError {
    /// The port is bus-off (silenced by the fault layer).
    BusOff,
}

impl embedded_can::Error for BusError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

/// Fault rates and windows (probabilities per frame).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Faults {
    /// Only frames sent by this port are affected (`None`: every port).
    pub from_port: Option<usize>,
    /// Probability that a frame is lost.
    pub drop: f64,
    /// Probability that a frame is delivered twice.
    pub duplicate: f64,
    /// Probability that one data bit is flipped.
    pub corrupt: f64,
    /// Probability that a frame is delivered late.
    pub delay: f64,
    /// The extra latency of a delayed frame \[ns\].
    pub delay_ns: u64,
    /// Silence window `[from, to)` \[ns\] of the affected port (bus-off or a dead controller).
    pub silence_ns: Option<(u64, u64)>,
}

/// Counters of the bus.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BusStats {
    /// Frames that won arbitration and were sent.
    pub sent: u64,
    /// Frames dropped by the fault layer.
    pub dropped: u64,
    /// Frames duplicated.
    pub duplicated: u64,
    /// Frames corrupted.
    pub corrupted: u64,
    /// Frames delayed.
    pub delayed: u64,
    /// Frames lost because a receive FIFO was full.
    pub rx_overflow: u64,
    /// Time the bus was busy \[ns\].
    pub busy_ns: u64,
}

struct PortState {
    mailbox: Vec<RawFrame>,
    rx: VecDeque<RawFrame>,
}

struct Inner {
    bit_ns: u64,
    now_ns: u64,
    /// The bus is busy until then.
    busy_until: u64,
    ports: Vec<PortState>,
    /// Frames on their way: (delivery time, sender, frame).
    in_flight: Vec<(u64, usize, RawFrame)>,
    faults: Faults,
    rng: u64,
    stats: BusStats,
    log: Option<Vec<String>>,
}

impl Inner {
    fn rand(&mut self) -> f64 {
        // xorshift64*: deterministic, good enough for fault injection.
        let mut x = self.rng;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.rng = x;
        (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn affected(&self, port: usize) -> bool {
        self.faults.from_port.is_none_or(|p| p == port)
    }

    fn silenced(&self, port: usize, t: u64) -> bool {
        self.affected(port) && self.faults.silence_ns.is_some_and(|(a, b)| t >= a && t < b)
    }

    fn deliver(&mut self, t: u64, from: usize, f: RawFrame) {
        if let Some(log) = self.log.as_mut() {
            log.push(log_line(t, &f));
        }
        for i in 0..self.ports.len() {
            if i == from || self.silenced(i, t) {
                continue;
            }
            if self.ports[i].rx.len() >= RX_FIFO {
                self.stats.rx_overflow += 1;
            } else {
                self.ports[i].rx.push_back(f);
            }
        }
    }

    /// Runs the bus until `t`.
    fn advance(&mut self, t: u64) {
        loop {
            // Deliver what has arrived by the time the bus is next free (or by t).
            let horizon = self.busy_until.max(self.now_ns).min(t);
            self.in_flight.sort_by_key(|e| e.0);
            while let Some(&(at, from, f)) = self.in_flight.first() {
                if at > horizon {
                    break;
                }
                self.in_flight.remove(0);
                self.deliver(at, from, f);
            }
            let start = self.busy_until.max(self.now_ns);
            if start >= t {
                self.now_ns = t;
                break;
            }
            // Arbitration: the lowest identifier among the mailboxes of active ports.
            let mut best: Option<(usize, usize)> = None;
            for (p, port) in self.ports.iter().enumerate() {
                if self.silenced(p, start) {
                    continue;
                }
                for (k, f) in port.mailbox.iter().enumerate() {
                    let better = match best {
                        None => true,
                        Some((bp, bk)) => f.id < self.ports[bp].mailbox[bk].id,
                    };
                    if better {
                        best = Some((p, k));
                    }
                }
            }
            let Some((p, k)) = best else {
                // Idle until t, or until the next delivery.
                let next = self.in_flight.first().map(|e| e.0).unwrap_or(t).min(t);
                self.now_ns = next.max(start);
                if self.now_ns >= t {
                    break;
                }
                continue;
            };
            let f = self.ports[p].mailbox.remove(k);
            let dur = u64::from(f.wire_bits()) * self.bit_ns;
            let end = start + dur;
            self.busy_until = end;
            self.now_ns = start;
            self.stats.sent += 1;
            self.stats.busy_ns += dur;
            if self.affected(p) {
                if self.rand() < self.faults.drop {
                    self.stats.dropped += 1;
                    continue;
                }
                let mut f = f;
                if f.len > 0 && self.rand() < self.faults.corrupt {
                    let bit = (self.rand() * f64::from(f.len) * 8.0) as usize;
                    let bit = bit.min(usize::from(f.len) * 8 - 1);
                    f.data[bit / 8] ^= 1 << (bit % 8);
                    self.stats.corrupted += 1;
                }
                let mut at = end;
                if self.rand() < self.faults.delay {
                    at += self.faults.delay_ns;
                    self.stats.delayed += 1;
                }
                self.in_flight.push((at, p, f));
                if self.rand() < self.faults.duplicate {
                    self.stats.duplicated += 1;
                    self.in_flight.push((at + dur, p, f));
                }
            } else {
                self.in_flight.push((end, p, f));
            }
        }
    }
}

/// The log line of a frame delivered at bus time `t_ns` (see [the log](self#the-log)).
pub fn log_line(t_ns: u64, f: &RawFrame) -> String {
    let us = LOG_EPOCH_S * 1_000_000 + t_ns / 1000;
    let data: String = f.bytes().iter().map(|b| format!("{b:02X}")).collect();
    format!(
        "({:010}.{:06}) {LOG_IFACE} {:03X}#{data}",
        us / 1_000_000,
        us % 1_000_000,
        f.id
    )
}

/// One line of the log, parsed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LogEntry {
    /// The log's time: microseconds since the Unix epoch.
    pub unix_us: u64,
    /// The frame.
    pub frame: RawFrame,
}

impl LogEntry {
    /// The simulated (bus) time of the delivery \[µs\]: the log time less [`LOG_EPOCH_S`]
    /// (`None` before the epoch).
    pub fn sim_us(&self) -> Option<u64> {
        self.unix_us.checked_sub(LOG_EPOCH_S * 1_000_000)
    }
}

/// One `candump -l` line as any interface writes it, `(time) IFACE ID#DATA` with any interface
/// name and hexadecimal of either case, through the strict form of host-sim's own log
/// ([`parse_log_line`]): the one reader of candump text (replays, the MCAP file).
pub fn parse_candump_line(line: &str) -> Option<LogEntry> {
    let mut parts = line.split_whitespace();
    let (Some(time), Some(_iface), Some(frame), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return None;
    };
    parse_log_line(&format!(
        "{time} {LOG_IFACE} {}",
        frame.to_ascii_uppercase()
    ))
}

/// The time (µs since the Unix epoch) of a `candump -l` line whose frame is not a classic data
/// frame with a standard identifier: an extended identifier (8 hexadecimal digits, at most
/// `1FFFFFFF`), a remote frame (`ID#R`, with or without its length digit) or a CAN FD frame
/// (`ID##F…`). Other nodes' traffic on a robot's bus: the node's filters never let it in.
/// `None` for anything else (a frame [`parse_candump_line`] reads, or no candump line).
pub fn other_frame_time(line: &str) -> Option<u64> {
    let mut parts = line.split_whitespace();
    let (Some(time), Some(_iface), Some(frame), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return None;
    };
    // The time as the strict reader reads it, through a frame it accepts.
    let unix_us = parse_log_line(&format!("{time} {LOG_IFACE} 000#"))?.unix_us;
    let hex = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_hexdigit());
    let (id, data) = frame.split_once('#')?;
    let extended = id.len() == 8 && hex(id) && u32::from_str_radix(id, 16).ok()? <= 0x1FFF_FFFF;
    if !(extended || id.len() == 3 && hex(id) && u16::from_str_radix(id, 16).ok()? <= 0x7FF) {
        return None;
    }
    let data_frame = data.is_empty() || hex(data) && data.len() % 2 == 0 && data.len() <= 16;
    let remote = matches!(data.as_bytes(), [b'R' | b'r'] | [b'R' | b'r', b'0'..=b'8']);
    let fd = data
        .strip_prefix('#')
        .is_some_and(|d| d.len() % 2 == 1 && d.len() <= 129 && hex(d));
    let other = if extended {
        data_frame || remote || fd
    } else {
        remote || fd
    };
    other.then_some(unix_us)
}

/// Parses one line of the log, strictly in the format [`log_line`] writes:
/// `(` ≥ 1 decimal digits `.` 6 decimal digits `) ` [`LOG_IFACE`] ` ` 3 hexadecimal digits
/// (at most `7FF`) `#` 0 to 8 bytes as hexadecimal digit pairs. `None` for anything else.
pub fn parse_log_line(line: &str) -> Option<LogEntry> {
    let rest = line.strip_prefix('(')?;
    let (time, rest) = rest.split_once(") ")?;
    let (secs, micros) = time.split_once('.')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(secs) || micros.len() != 6 || !digits(micros) {
        return None;
    }
    let unix_us = secs
        .parse::<u64>()
        .ok()?
        .checked_mul(1_000_000)?
        .checked_add(micros.parse::<u64>().ok()?)?;
    let rest = rest.strip_prefix(LOG_IFACE)?.strip_prefix(' ')?;
    let (id, data) = rest.split_once('#')?;
    let hex = |s: &str| s.bytes().all(|b| matches!(b, b'0'..=b'9' | b'A'..=b'F'));
    if id.len() != 3 || !hex(id) || data.len() % 2 != 0 || data.len() > 16 || !hex(data) {
        return None;
    }
    let id = u16::from_str_radix(id, 16).ok()?;
    let bytes: Vec<u8> = (0..data.len() / 2)
        .map(|i| u8::from_str_radix(&data[2 * i..2 * i + 2], 16))
        .collect::<Result<_, _>>()
        .ok()?;
    let frame = RawFrame::new(id, &bytes)?;
    Some(LogEntry { unix_us, frame })
}

/// The bus.
#[derive(Clone)]
pub struct Bus(Rc<RefCell<Inner>>);

/// One node's connection to the bus.
#[derive(Clone)]
pub struct Port {
    bus: Rc<RefCell<Inner>>,
    index: usize,
}

impl Bus {
    /// A bus at `bitrate` bit/s with `ports` ports, faults drawn from `seed`.
    pub fn new(bitrate: u32, ports: usize, faults: Faults, seed: u64) -> Self {
        let inner = Inner {
            bit_ns: 1_000_000_000 / u64::from(bitrate.max(1)),
            now_ns: 0,
            busy_until: 0,
            ports: (0..ports)
                .map(|_| PortState {
                    mailbox: Vec::new(),
                    rx: VecDeque::new(),
                })
                .collect(),
            in_flight: Vec::new(),
            faults,
            rng: seed | 1,
            stats: BusStats::default(),
            log: None,
        };
        Bus(Rc::new(RefCell::new(inner)))
    }

    /// Starts recording a candump log ([the log](self#the-log)).
    pub fn record(&self) {
        self.0.borrow_mut().log = Some(Vec::new());
    }

    /// The candump log so far, one line per delivered frame (no line ends).
    pub fn log(&self) -> Vec<String> {
        self.0.borrow().log.clone().unwrap_or_default()
    }

    /// Port `i`.
    pub fn port(&self, index: usize) -> Port {
        Port {
            bus: self.0.clone(),
            index,
        }
    }

    /// Runs the bus until `t_ns`.
    pub fn advance(&self, t_ns: u64) {
        self.0.borrow_mut().advance(t_ns);
    }

    /// When the bus is next free for arbitration \[ns\] (now, if it is idle).
    pub fn free_at(&self) -> u64 {
        let b = self.0.borrow();
        b.busy_until.max(b.now_ns)
    }

    /// Counters.
    pub fn stats(&self) -> BusStats {
        self.0.borrow().stats
    }

    /// Fraction of the time the bus was busy, up to now.
    pub fn load(&self) -> f64 {
        let i = self.0.borrow();
        if i.now_ns == 0 {
            0.0
        } else {
            i.stats.busy_ns as f64 / i.now_ns as f64
        }
    }
}

impl Port {
    /// Frames waiting in this port's transmit mailbox (not yet on the wire).
    pub fn pending(&self) -> usize {
        self.bus.borrow().ports[self.index].mailbox.len()
    }

    /// Frames waiting in this port's receive FIFO.
    pub fn received(&self) -> usize {
        self.bus.borrow().ports[self.index].rx.len()
    }
}

impl embedded_can::nb::Can for Port {
    type Frame = VFrame;
    type Error = BusError;

    fn transmit(&mut self, frame: &VFrame) -> nb::Result<Option<VFrame>, BusError> {
        let mut b = self.bus.borrow_mut();
        let t = b.now_ns;
        if b.silenced(self.index, t) {
            return Err(nb::Error::Other(BusError::BusOff));
        }
        let port = &mut b.ports[self.index];
        if port.mailbox.len() >= MAILBOX {
            return Err(nb::Error::WouldBlock);
        }
        port.mailbox.push(*frame);
        Ok(None)
    }

    fn receive(&mut self) -> nb::Result<VFrame, BusError> {
        let mut b = self.bus.borrow_mut();
        b.ports[self.index]
            .rx
            .pop_front()
            .ok_or(nb::Error::WouldBlock)
    }
}

/// A port that records every frame the bus accepted from it, with the cycle (`cycle`, set by
/// its user) it was handed over in: what a node sent in a cycle, before the bus delivers it
/// (the fault sweep reads the node's answers there, the replay its whole output).
pub struct Tap<'a> {
    /// The port written through.
    pub port: &'a mut Port,
    /// The cycle the frames are recorded with.
    pub cycle: u64,
    /// The frames the bus accepted, with their cycle.
    pub sent: Vec<(u64, RawFrame)>,
}

impl<'a> Tap<'a> {
    /// A tap on `port` for cycle `cycle`, nothing recorded yet.
    pub fn new(port: &'a mut Port, cycle: u64) -> Self {
        Self {
            port,
            cycle,
            sent: Vec::new(),
        }
    }

    /// The frames recorded, without their cycles.
    pub fn frames(&self) -> impl Iterator<Item = &RawFrame> {
        self.sent.iter().map(|(_, f)| f)
    }
}

impl embedded_can::nb::Can for Tap<'_> {
    type Frame = VFrame;
    type Error = BusError;
    fn transmit(&mut self, frame: &VFrame) -> nb::Result<Option<VFrame>, BusError> {
        let r = self.port.transmit(frame);
        if r.is_ok() {
            self.sent.push((self.cycle, *frame));
        }
        r
    }
    fn receive(&mut self) -> nb::Result<VFrame, BusError> {
        self.port.receive()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::nb::Can;

    fn frame(id: u16, data: &[u8]) -> VFrame {
        RawFrame::new(id, data).unwrap()
    }

    #[test]
    fn lower_identifiers_win_and_take_their_bit_time() {
        let bus = Bus::new(1_000_000, 2, Faults::default(), 1);
        bus.record();
        let (mut a, mut b) = (bus.port(0), bus.port(1));
        a.transmit(&frame(0x300, &[1; 8])).unwrap();
        a.transmit(&frame(0x100, &[2; 8])).unwrap();
        a.transmit(&frame(0x200, &[3; 2])).unwrap();
        // One 8-byte frame: 47 + 64 + 24 stuff bits = 135 µs at 1 Mbit/s.
        bus.advance(134_000);
        assert!(b.receive().is_err());
        bus.advance(135_000);
        assert_eq!(b.receive().unwrap().id, 0x100);
        bus.advance(1_000_000);
        assert_eq!(b.receive().unwrap().id, 0x200);
        assert_eq!(b.receive().unwrap().id, 0x300);
        assert!(a.receive().is_err(), "a sender does not hear itself");
        let log = bus.log();
        assert_eq!(log[0], "(1767225600.000135) can0 100#0202020202020202");
        for line in &log {
            let e = parse_log_line(line).unwrap();
            assert_eq!(log_line(e.sim_us().unwrap() * 1000, &e.frame), *line);
        }
        let busy = 135 + (47 + 16 + (34 + 16 - 1) / 4) + 135;
        assert_eq!(bus.stats().busy_ns, busy * 1000);
    }

    #[test]
    fn faults_drop_duplicate_corrupt_delay_and_silence() {
        let all = |f: Faults| {
            let bus = Bus::new(1_000_000, 2, f, 7);
            let (mut a, mut b) = (bus.port(0), bus.port(1));
            let mut got = vec![];
            for i in 0..200u32 {
                let _ = a.transmit(&frame(0x100, &i.to_le_bytes()));
                bus.advance(u64::from(i + 1) * 1_000_000);
                while let Ok(f) = b.receive() {
                    got.push(f);
                }
            }
            bus.advance(1_000_000_000);
            while let Ok(f) = b.receive() {
                got.push(f);
            }
            (got, bus.stats())
        };
        let (clean, _) = all(Faults::default());
        assert_eq!(clean.len(), 200);
        let (got, s) = all(Faults {
            drop: 0.2,
            ..Faults::default()
        });
        assert_eq!(got.len() as u64, 200 - s.dropped);
        assert!(s.dropped > 20 && s.dropped < 60, "{s:?}");
        let (got, s) = all(Faults {
            duplicate: 0.1,
            ..Faults::default()
        });
        assert_eq!(got.len() as u64, 200 + s.duplicated);
        let (got, s) = all(Faults {
            corrupt: 0.1,
            ..Faults::default()
        });
        let changed = got.iter().zip(&clean).filter(|(a, b)| a != b).count() as u64;
        assert_eq!(changed, s.corrupted);
        let (got, s) = all(Faults {
            delay: 0.1,
            delay_ns: 3_000_000,
            ..Faults::default()
        });
        assert_eq!(got.len(), 200);
        let out_of_order = got
            .windows(2)
            .filter(|w| w[0].data[0] > w[1].data[0])
            .count();
        assert!(s.delayed > 0 && out_of_order > 0);
        let (got, _) = all(Faults {
            silence_ns: Some((50_000_000, 150_000_000)),
            ..Faults::default()
        });
        assert!(got.len() <= 101 && got.len() >= 99, "{}", got.len());
    }
}
