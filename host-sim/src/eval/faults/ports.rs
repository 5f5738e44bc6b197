//! What a fault run puts on the bus besides the controller: the babbling port of the `flood`
//! fault ([`Flood`]) and the seeded random numbers every fault draws from ([`Rng`]). (The
//! node's port is wrapped in [`crate::sim::bus::Tap`] to record what the node hands to the bus.)

use embedded_can::nb::Can;
use planner_core::wire::RawFrame;

use crate::sim::bus::{Bus, Port};

pub(super) struct Rng(u64);

impl Rng {
    pub(super) fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    pub(super) fn next(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.0 = x;
        x
    }
    pub(super) fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub(super) fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.unit()
    }
}

/// The babbling port: one frame at a time, the next one ready as soon as the previous one
/// has been on the bus (a listener port sees it), so that with `rate` 1 it takes every
/// arbitration its random identifier wins. With a lower rate, a new frame is ready after each
/// 50 µs step with a probability that offers about `rate` of the bus time.
pub(super) struct Flood {
    pub(super) on: bool,
    pub(super) rate: f64,
    pub(super) port: Port,
    pub(super) listener: Port,
    pub(super) waiting: Option<RawFrame>,
    pub(super) rng: Rng,
}

impl Flood {
    /// Runs the bus from `from` to `t` \[ns\], the babbler included.
    pub(super) fn run(&mut self, bus: &Bus, from: u64, t: u64) {
        if !self.on {
            bus.advance(t);
            return;
        }
        const STEP: u64 = 50_000;
        // A frame of random length (0 … 8 bytes) takes about 95 µs on average.
        let p = (self.rate * STEP as f64 / 95_000.0).min(1.0);
        let mut now = from;
        while now < t {
            if self.waiting.is_none() && (self.rate >= 1.0 || self.rng.unit() < p) {
                let r = self.rng.next();
                let len = ((r >> 11) % 9) as usize;
                let data = self.rng.next().to_le_bytes();
                if let Some(f) = RawFrame::new((r & 0x7FF) as u16, &data[..len]) {
                    if self.port.transmit(&f).is_ok() {
                        self.waiting = Some(f);
                    }
                }
            }
            now = (now + STEP).min(t);
            bus.advance(now);
            while let Ok(f) = self.listener.receive() {
                if Some(f) == self.waiting {
                    self.waiting = None;
                }
            }
        }
    }
}
