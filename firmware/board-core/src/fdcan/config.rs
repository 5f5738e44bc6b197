//! The board's FDCAN configuration and its bring-up: message RAM layout, acceptance filters,
//! the register values ([`config`], for the nominal bit timing the board sets: [`BitTiming`]),
//! and the sequence that writes them in configuration mode, reads every one back and joins
//! the bus only if all agree ([`bring_up`]); [`silence`] takes the core off the bus again.

use planner_core::wire::ids;

use super::regs::{cccr, field, ir, FdcanRegs, Reg, ENDN_VALUE, RAM_WORDS};
use crate::link::{RX_ELEMENTS, TX_FIFO, TX_SLOTS};

/// Nominal bit timing in time quanta.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BitTiming {
    /// Kernel clock cycles per time quantum (1-512).
    pub prescaler: u32,
    /// Time quanta before the sample point, propagation and phase 1 (1-256).
    pub seg1: u32,
    /// Time quanta after the sample point (1-128).
    pub seg2: u32,
    /// Synchronisation jump width (1-128, at most `seg2`).
    pub sjw: u32,
}

impl BitTiming {
    /// The bit rate from a kernel clock of `kernel_hz` \[bit/s\] (truncated).
    pub const fn bit_rate(&self, kernel_hz: u32) -> u32 {
        kernel_hz / self.prescaler / (1 + self.seg1 + self.seg2)
    }

    /// The `NBTP` value.
    pub const fn nbtp(&self) -> u32 {
        field::nbtp(self.prescaler, self.seg1, self.seg2, self.sjw)
    }

    /// The sample point in per mille of the bit (after sync and `seg1`).
    pub const fn sample_point_permille(&self) -> u32 {
        1000 * (1 + self.seg1) / (1 + self.seg1 + self.seg2)
    }

    /// `true` if every field is within `NBTP`'s range and `sjw` ≤ `seg2`.
    pub const fn is_valid(&self) -> bool {
        self.prescaler >= 1
            && self.prescaler <= 512
            && self.seg1 >= 1
            && self.seg1 <= 256
            && self.seg2 >= 1
            && self.seg2 <= 128
            && self.sjw >= 1
            && self.sjw <= self.seg2
    }
}

pub use crate::link::RX1_ELEMENTS;

/// The message RAM layout, in words of FDCAN1's part (from 0x4000_AC00), all elements with
/// 8-byte data fields (4 words):
///
/// | words | what |
/// |---|---|
/// | 0 … 3     | [`STD_FILTERS`]: one standard filter element per command identifier |
/// | —         | no extended filter elements (XIDFC.LSE = 0, its start address at word 4) |
/// | 4 … 259   | RX FIFO0: [`RX_ELEMENTS`] elements, blocking (the commands but `ESTOP`) |
/// | 260 … 323 | RX FIFO1: [`RX1_ELEMENTS`] elements, blocking (`ESTOP`) |
/// | 324 … 387 | [`TX_SLOTS`] dedicated TX buffers (buffers 0 … 15: the stream frames) |
/// | 388 … 451 | the TX FIFO, [`TX_FIFO`] elements (buffers 16 … 31: the `ACK`s, in order) |
///
/// No RX buffers, no TX event FIFO. The rest of the message RAM is not
/// initialised (a reset does not): the core reads only the filter elements before they are
/// written (it writes the RX elements itself, the adapter each TX buffer before requesting it).
pub mod layout {
    use super::{RX1_ELEMENTS, RX_ELEMENTS, STD_FILTER_COUNT, TX_FIFO, TX_SLOTS};

    /// Words of an element with an 8-byte data field (2 header words, 2 data words).
    pub const ELEMENT_WORDS: u32 = 4;
    /// The standard filter list.
    pub const STD_FILTERS: u32 = 0;
    /// Where an extended filter list would start (it has no elements).
    pub const EXT_FILTERS: u32 = STD_FILTERS + STD_FILTER_COUNT as u32;
    /// RX FIFO0.
    pub const RX_FIFO0: u32 = EXT_FILTERS;
    /// RX FIFO1.
    pub const RX_FIFO1: u32 = RX_FIFO0 + ELEMENT_WORDS * RX_ELEMENTS as u32;
    /// The TX buffers: the dedicated ones, then the TX FIFO's (one section, `TXBC.TBSA`).
    pub const TX_BUFFERS: u32 = RX_FIFO1 + ELEMENT_WORDS * RX1_ELEMENTS as u32;
    /// The first word after the layout.
    pub const END: u32 = TX_BUFFERS + ELEMENT_WORDS * (TX_SLOTS + TX_FIFO) as u32;
}
const _: () = assert!(layout::END <= RAM_WORDS);
const _: () = assert!(RX_ELEMENTS <= 64 && RX1_ELEMENTS <= 64 && TX_SLOTS + TX_FIFO <= 32);

/// Standard filter elements: one per identifier of `ids::COMMANDS`.
pub const STD_FILTER_COUNT: usize = ids::COMMANDS.len();
const _: () = assert!(STD_FILTER_COUNT <= 128);

/// The standard filter list: element `i` is a dual-id filter with both identifiers
/// `ids::COMMANDS[i]`, storing into RX FIFO1 for `ESTOP` and into RX FIFO0 for the others.
/// With [`GFC`] rejecting non-matching and remote frames, nothing else reaches the software.
pub const STD_FILTERS: [u32; STD_FILTER_COUNT] = command_filters();

const fn command_filters() -> [u32; STD_FILTER_COUNT] {
    let mut f = [0; STD_FILTER_COUNT];
    let mut i = 0;
    while i < STD_FILTER_COUNT {
        let id = ids::COMMANDS[i];
        assert!(
            id <= 0x7FF,
            "a command identifier is not an 11-bit identifier"
        );
        let sfec = if id == ids::ESTOP {
            field::SFEC_FIFO1
        } else {
            field::SFEC_FIFO0
        };
        f[i] = field::std_filter(field::SFT_DUAL, sfec, id, id);
        i += 1;
    }
    f
}

/// `GFC`: non-matching standard and extended frames rejected, remote frames rejected.
pub const GFC: u32 = field::gfc(field::REJECT, field::REJECT, true, true);

/// The protected `CCCR` bits in configuration: classic CAN only (`FDOE` = `BRSE` = 0),
/// automatic retransmission (`DAR` = 0), protocol exception handling off (`PXHD`), no test,
/// monitoring, restricted, non-ISO mode, edge filtering or transmit pause.
pub const CCCR_MODE: u32 = cccr::PXHD;

/// Every configuration register the bring-up writes, with its value for the nominal bit
/// timing `timing` (a board setting), in the order written and read back (`GFC` first: what
/// keeps foreign frames out). `CCCR`'s protected bits ([`CCCR_MODE`]) are written and
/// checked besides.
pub const fn config(timing: &BitTiming) -> [(Reg, u32); 14] {
    [
        (Reg::Gfc, GFC),
        (Reg::Nbtp, timing.nbtp()),
        (
            Reg::Sidfc,
            field::sidfc(STD_FILTER_COUNT as u32, layout::STD_FILTERS),
        ),
        (Reg::Xidfc, field::xidfc(0, layout::EXT_FILTERS)),
        // Its reset value (all 29 bits compared); unused without extended filters.
        (Reg::Xidam, 0x1FFF_FFFF),
        (
            Reg::Rxf0c,
            field::rxfc(RX_ELEMENTS as u32, layout::RX_FIFO0),
        ),
        (
            Reg::Rxf1c,
            field::rxfc(RX1_ELEMENTS as u32, layout::RX_FIFO1),
        ),
        (Reg::Rxbc, 0),
        // 8-byte data fields (code 0) in RX FIFO0, RX FIFO1 and the RX buffers.
        (Reg::Rxesc, 0),
        // Dedicated buffers for the streams, a TX FIFO (TFQM = 0) for the ACKs.
        (
            Reg::Txbc,
            field::txbc(TX_SLOTS as u32, TX_FIFO as u32, layout::TX_BUFFERS),
        ),
        (Reg::Txesc, 0),
        (Reg::Txefc, 0),
        // No interrupts: the loop polls.
        (Reg::Ie, 0),
        (Reg::Ile, 0),
    ]
}

/// Reads of `CCCR` a wait for `INIT` takes at most (an APB read is some tens of core cycles:
/// a few ms at 480 MHz, well inside the watchdog period).
pub const INIT_WAIT_READS: u32 = 100_000;

/// Why the bring-up did not join the bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BringUpError {
    /// `ENDN` did not read 0x8765_4321: not an FDCAN register block (or its clock is off).
    NotFdcan,
    /// `CCCR.INIT` did not read back set within [`INIT_WAIT_READS`] reads.
    InitTimeout,
    /// `CCCR.CCE` did not read back set in the initialisation state.
    CceRefused,
    /// This configuration register read back another value than written (`Reg::Cccr`: its
    /// protected mode bits).
    Register(Reg),
    /// This standard filter element read back another value than written.
    StdFilter(u8),
    /// `CCCR.INIT` did not read back clear within [`INIT_WAIT_READS`] reads after joining.
    JoinTimeout,
}

impl BringUpError {
    /// A short description of the error and its detail (the register's offset or the
    /// element's index, else 0), for a log line.
    pub const fn describe(&self) -> (&'static str, u32) {
        match self {
            Self::NotFdcan => ("ENDN is not an FDCAN's", 0),
            Self::InitTimeout => ("INIT not entered", 0),
            Self::CceRefused => ("CCE not set", 0),
            Self::Register(r) => ("register at offset", r.offset()),
            Self::StdFilter(i) => ("standard filter element", *i as u32),
            Self::JoinTimeout => ("INIT not left", 0),
        }
    }
}

/// Waits (bounded, [`INIT_WAIT_READS`]) until `CCCR.INIT` reads `set`. Not inlined: one copy
/// for every wait.
#[inline(never)]
pub(crate) fn wait_init<R: FdcanRegs>(regs: &R, set: bool) -> bool {
    let want = if set { cccr::INIT } else { 0 };
    let mut reads = INIT_WAIT_READS;
    while reads > 0 {
        if regs.read(Reg::Cccr) & cccr::INIT == want {
            return true;
        }
        reads -= 1;
    }
    false
}

/// The whole bring-up with the nominal bit timing `timing`: [`configure`], [`verify`],
/// [`join`], then [`verify`] once more on the bus; on any error the core is left in (or put
/// back into) its initialisation state, off the bus ([`silence`]).
pub fn bring_up<R: FdcanRegs>(regs: &mut R, timing: &BitTiming) -> Result<(), BringUpError> {
    let done = configure(regs, timing)
        .and_then(|()| verify(regs, timing))
        .and_then(|()| join(regs))
        .and_then(|()| verify(regs, timing));
    if done.is_err() {
        silence(regs);
    }
    done
}

/// Configuration mode, then every configuration register and the standard filter list; the
/// interrupt flags cleared. The core stays in configuration mode (`INIT` = `CCE` = 1).
pub fn configure<R: FdcanRegs>(regs: &mut R, timing: &BitTiming) -> Result<(), BringUpError> {
    if regs.read(Reg::Endn) != ENDN_VALUE {
        return Err(BringUpError::NotFdcan);
    }
    // Request the initialisation state (only INIT changes; a clock stop request is withdrawn)
    // and wait for it: the write crosses into the CAN clock domain.
    let c = regs.read(Reg::Cccr) & !(cccr::CSA | cccr::CSR);
    regs.write(Reg::Cccr, c | cccr::INIT);
    if !wait_init(regs, true) {
        return Err(BringUpError::InitTimeout);
    }
    // CCE only once INIT is set; then the protected mode bits, in a write of their own.
    let c = regs.read(Reg::Cccr) & !cccr::CSA;
    regs.write(Reg::Cccr, c | cccr::INIT | cccr::CCE);
    if regs.read(Reg::Cccr) & cccr::CCE == 0 {
        return Err(BringUpError::CceRefused);
    }
    regs.write(Reg::Cccr, cccr::INIT | cccr::CCE | CCCR_MODE);
    for (w, f) in (layout::STD_FILTERS..).zip(STD_FILTERS) {
        regs.ram_write(w, f);
    }
    for (reg, value) in config(timing) {
        regs.write(reg, value);
    }
    regs.write(Reg::Ir, ir::ALL);
    Ok(())
}

/// Reads back every configuration register of [`config`]`(timing)`, `CCCR`'s protected bits
/// and every standard filter element; the first that differs is the error.
pub fn verify<R: FdcanRegs>(regs: &R, timing: &BitTiming) -> Result<(), BringUpError> {
    for (reg, value) in config(timing) {
        if regs.read(reg) != value {
            return Err(BringUpError::Register(reg));
        }
    }
    if regs.read(Reg::Cccr) & cccr::PROTECTED != CCCR_MODE {
        return Err(BringUpError::Register(Reg::Cccr));
    }
    for (i, (w, f)) in (layout::STD_FILTERS..).zip(STD_FILTERS).enumerate() {
        if regs.ram_read(w) != f {
            return Err(BringUpError::StdFilter(i as u8));
        }
    }
    Ok(())
}

/// Leaves the initialisation state (clearing `INIT` clears `CCE`) and waits (bounded) until
/// the core reads back out of it; it then joins the bus after 11 recessive bits.
pub fn join<R: FdcanRegs>(regs: &mut R) -> Result<(), BringUpError> {
    let c = regs.read(Reg::Cccr) & !(cccr::INIT | cccr::CCE | cccr::CSA);
    regs.write(Reg::Cccr, c);
    if wait_init(regs, false) {
        Ok(())
    } else {
        Err(BringUpError::JoinTimeout)
    }
}

/// Takes the core off the bus at once: `INIT` requested (the output recessive, no error
/// frames) and every TX buffer's request cancelled. Needs no configuration mode; works in any
/// state (the fault handler's path). `true` if the register block answered: `ENDN` read
/// back its fixed value (it needs no kernel clock; an access that faulted, ignored at fault
/// priority, reads otherwise).
pub fn silence<R: FdcanRegs>(regs: &mut R) -> bool {
    let c = regs.read(Reg::Cccr) & !cccr::CSA;
    regs.write(Reg::Cccr, c | cccr::INIT);
    regs.write(Reg::Txbcr, u32::MAX);
    regs.read(Reg::Endn) == ENDN_VALUE
}
