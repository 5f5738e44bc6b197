//! # board-core
//!
//! The STM32H743 board image's logic that needs no hardware, tested on the host:
//!
//! * [`link`]: the CAN link adapter, `embedded_can::nb::Can` for the node over the small
//!   [`link::Fdcan`] trait (the run-time register accesses of the FDCAN): software queues,
//!   bus-off recovery and the error state, replacement of stale stream frames, counters,
//!   `ESTOP` (RX FIFO1) before everything else;
//! * [`fdcan`]: the FDCAN at register level over a register-access trait
//!   ([`fdcan::FdcanRegs`]): the board's configuration and its bring-up with read-back
//!   (the bus is joined only if every register and filter element reads back as written),
//!   and [`link::Fdcan`] over the registers ([`fdcan::RegFdcan`]);
//! * [`bor`]: when to program the brown-out level's option byte, and what its result means;
//! * [`frame`]: the classic frame and the message-RAM element format;
//! * [`pace`]: the 5 ms slots from a free-running 32-bit counter, missed slots counted;
//! * [`reset`]: the reset reason from `RCC_RSR` and the fault handler's mark;
//! * [`uninit`]: the no-init RAM words on ECC RAM, written before any read after a power-on;
//! * [`clock`]: the system clock the silicon revision allows (480 MHz only on revision V);
//! * [`rtt`]: the never-blocking part of the board's RTT logger (whole frames or nothing);
//! * [`safe_state`]: the order of the fault handlers' safe state (the CAN TX pin recessive
//!   as a GPIO, the reset mark, the fault pin, then the FDCAN, then a reset at once) over a
//!   small trait of the hardware;
//! * [`fault_entry`]: the fault handlers' entry, which leaves an overflowed stack behind
//!   before any Rust code runs, the MPU guard below the stack ([`StackGuard`]) and the MPU
//!   background region over the external-memory space ([`ExternalMemoryGuard`]);
//! * [`node`]: the node's contract with the control cycle ([`ControlNode`], implemented for
//!   planner-core's `Node`), which [`cycle`] and [`control`] both use;
//! * [`cycle`]: the bookkeeping of one control cycle (overruns told to the node, the
//!   statistics window summarised once per second);
//! * [`control`]: the board's whole control cycle over small traits of its hardware (the
//!   wait for the slot, the link health, the timed poll, the late decision, the statistics,
//!   the watchdog feed, what to log), run by the board image, the QEMU image and the no-panic
//!   check alike.
//!
//! The board implements [`fdcan::FdcanRegs`] on FDCAN1 (`firmware/board/src/fdcan1.rs`) and
//! runs [`fdcan::bring_up`] and [`fdcan::RegFdcan`] over it; the tests run the same code over
//! a register-level model that enforces RM0433's rules (`tests/fdcan_model.rs`), and the
//! adapter over a simpler model of the peripheral (`tests/link.rs`), with planner-core's node
//! on top. The QEMU image runs [`control`] around its replayed polls, over the real [`Link`]
//! on an in-memory FDCAN.
#![cfg_attr(not(test), no_std)]
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod bor;
pub mod clock;
pub mod control;
pub mod cycle;
pub mod fault_entry;
pub mod fdcan;
pub mod frame;
pub mod link;
pub mod node;
pub mod pace;
pub mod reset;
pub mod rtt;
pub mod safe_state;
pub mod uninit;

pub use control::{ControlLoop, Io, LogSink, Port, SlotRun};
pub use fault_entry::{ExternalMemoryGuard, StackGuard};
pub use frame::ClassicFrame;
pub use link::{BusState, Fdcan, Health, Link, RxLost};
pub use node::ControlNode;
pub use pace::{Pacer, Slot};
pub use reset::ResetReason;
