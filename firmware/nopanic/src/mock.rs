//! `--features mock-can`: a CAN device instead of the board's link adapter (the check's scope
//! before the board had its own FDCAN accesses; kept as a narrower variant).
//!
//! Every frame it receives is arbitrary (`black_box`: the optimiser cannot know it), and so is
//! whether a frame is there and whether a transmission is accepted.

use core::convert::Infallible;
use core::hint::black_box;

use board_core::{ClassicFrame, Health};
use embedded_can::{Frame, StandardId};

/// The board adapter's interface (board-core's `control::Port`) over
/// arbitrary frames.
#[derive(Default)]
pub struct VolatileBus {
    health: Health,
}

impl board_core::control::Port for VolatileBus {
    /// Nothing to move (the board's adapter empties the hardware FIFOs here).
    fn service(&mut self) {
        self.health = black_box(self.health);
    }

    /// The health (arbitrary).
    fn health(&self) -> Health {
        self.health
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
