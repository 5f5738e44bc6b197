//! The FDCAN at register level, written once for the board and the host tests: the
//! register-access trait ([`FdcanRegs`], [`Reg`]), the board's configuration and its bring-up
//! with read-back ([`bring_up`], [`config`], [`STD_FILTERS`], [`layout`]), the fault path's
//! [`silence`], and the link adapter's run-time accesses over the registers ([`RegFdcan`]).
//!
//! The board implements [`FdcanRegs`] on FDCAN1 (`firmware/board/src/fdcan1.rs`: volatile
//! accesses, the only `unsafe` of the CAN path); `tests/fdcan_model.rs` on a register-level
//! model that enforces RM0433's rules (configuration writes only in configuration mode,
//! write-1-to-clear flags, TX requests and cancellations, FIFO indices, message RAM bounds
//! and layout) and runs the acceptance filters on frames of a modelled bus.
//!
//! No `fdcan` crate: its `into_normal()` re-applies its stored configuration while leaving
//! the initialisation state, and that configuration never holds the global filter, so `GFC`
//! would be reset to "accept non-matching frames into FIFO0" (see firmware/README.md).

pub mod config;
pub mod regs;
pub mod runtime;

pub use config::{
    bring_up, config, configure, join, layout, silence, verify, BitTiming, BringUpError, CCCR_MODE,
    GFC, INIT_WAIT_READS, RX1_ELEMENTS, STD_FILTERS, STD_FILTER_COUNT,
};
pub use regs::{FdcanRegs, Reg, RAM_WORDS};
pub use runtime::RegFdcan;
