//! `--features mock-can`: a CAN device instead of the board's FDCAN adapter (whose driver, the
//! `fdcan` crate, has panics on values read from the hardware: see the crate docs).
//!
//! Every frame it receives is arbitrary (`black_box`: the optimiser cannot know it), and so is
//! whether a frame is there and whether a transmission is accepted.

use core::convert::Infallible;
use core::hint::black_box;

use embedded_can::{Frame, StandardId};

use crate::can::{BusCounters, ClassicFrame};

/// The board adapter's interface (`service`, `counters`, `embedded_can::nb::Can`) over
/// arbitrary frames.
#[derive(Default)]
pub struct VolatileBus {
    counters: BusCounters,
}

impl VolatileBus {
    /// Nothing to move (the board's adapter empties the hardware FIFOs here).
    pub fn service(&mut self) {
        self.counters = black_box(self.counters);
    }

    /// The counters (arbitrary).
    pub fn counters(&self) -> BusCounters {
        self.counters
    }
}

impl embedded_can::nb::Can for VolatileBus {
    type Frame = ClassicFrame;
    type Error = Infallible;

    fn transmit(&mut self, frame: &ClassicFrame) -> nb::Result<Option<ClassicFrame>, Infallible> {
        black_box(frame);
        if black_box(false) {
            Err(nb::Error::WouldBlock)
        } else {
            Ok(None)
        }
    }

    fn receive(&mut self) -> nb::Result<ClassicFrame, Infallible> {
        // [present, id low, id high, len, data 0..8]
        let b: [u8; 12] = black_box([0; 12]);
        let [present, id_lo, id_hi, len, data @ ..] = b;
        if present == 0 {
            return Err(nb::Error::WouldBlock);
        }
        let id = StandardId::new(u16::from_le_bytes([id_lo, id_hi]) & 0x7ff);
        let data = data.get(..usize::from(len)).unwrap_or(&data);
        match id.and_then(|id| ClassicFrame::new(id, data)) {
            Some(f) => Ok(f),
            None => Err(nb::Error::WouldBlock),
        }
    }
}
