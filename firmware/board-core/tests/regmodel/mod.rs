//! A register-level model of FDCAN1 (RM0433 §56) behind `board_core::fdcan::FdcanRegs` that
//! ENFORCES the reference manual's rules and records every breach as a [`Violation`] (the
//! tests fail on any):
//!
//! * the protected configuration registers (DBTP, RWD, NBTP, TSCC, TOCC, TDCR, GFC, SIDFC,
//!   XIDFC, XIDAM, RXF0C, RXBC, RXF1C, RXESC, TXBC, TXESC, TXEFC) and `CCCR`'s protected
//!   mode bits are written only while `CCCR.INIT` and `CCCR.CCE` are both set (a write
//!   otherwise is ignored and recorded); `TEST` only with `CCCR.TEST`;
//! * `CCCR.INIT` takes effect after a few reads of `CCCR` (the clock-domain crossing), `CCE`
//!   can only be set once `INIT` reads set, clearing `INIT` clears `CCE`; read-only registers
//!   are not written;
//! * `IR` is write-1-to-clear; `TXBAR` sets `TXBRP` bits (only of configured buffers),
//!   `TXBCR` cancels (at once or deferred), the bus clears `TXBRP` and sets `TXBTO`; a TX
//!   buffer element is not written while its request is pending;
//! * configuration mode: setting `CCE` (with `INIT`) resets `HPMS`, `RXF0S`, `RXF1S`,
//!   `TXFQS`, `TXBRP`, `TXBTO`, `TXBCF` and `TXEFS` (the RX FIFOs read empty, every TX
//!   request is gone); while `CCE` is set, `TXBAR` and `TXBCR` writes are ignored (a `TXBAR`
//!   write, a frame silently not sent, is recorded);
//! * bus monitoring (`CCCR.MON`, a protected bit: only with `INIT` and `CCE`): the core
//!   receives but never transmits (`TXBRP` held in reset: a `TXBAR` write is ignored and
//!   recorded);
//! * fault confinement (`errors.rs`): `PSR.EW`/`EP` derived from injected error counters
//!   (TEC/REC, `ECR.RP`); bus-off sets `INIT`; the recovery after `INIT` is cleared takes 129
//!   sequences of 11 recessive bits of modelled bus time (≈1.42 ms at 1 Mbit/s), during which
//!   the core is still bus-off, neither receives nor sends;
//! * RX FIFOs: fill level, get and put index in `RXFnS`, `RXFnA` releases up to the index
//!   acknowledged (which must be in the fill), blocking or overwrite mode, `IR.RFnL`;
//! * the message RAM is FDCAN1's 1,024 words (an access beyond is recorded); leaving `INIT`
//!   checks the layout (every section inside the RAM, none overlapping another, sizes within
//!   the register fields' limits);
//! * a frame arriving on the modelled bus goes through the acceptance filtering of RM0433
//!   §56.4.5: remote frames by `RRFS`/`RRFE`, the standard filter list (`SIDFC`, elements
//!   SFT/SFEC/SFID1/SFID2: range, dual id, classic mask, disabled, SFEC 000-111) or the
//!   extended one (`XIDFC`, `XIDAM`, EFT/EFEC/EFID1/EFID2), first match wins, else `GFC`'s
//!   ANFS/ANFE; then into RX FIFO0 or FIFO1 as an RX element (R0: XTD, RTR, identifier; R1:
//!   ANMF, FIDX, DLC; data little-endian).
//!
//! The model works by the reference manual's offsets and bit positions, written out here,
//! not by board-core's constants (only `Reg::offset` connects the two), so an encoding
//! mistake in board-core shows up as a wrong behaviour of the model.

#![allow(dead_code)] // each test binary uses a part

use std::cell::{RefCell, RefMut};

use board_core::fdcan::{FdcanRegs, Reg};

mod bus;
mod errors;
pub use bus::{BusFrame, Verdict};
#[allow(unused_imports)] // each test binary uses a part
pub use errors::RECOVERY_BITS;

/// FDCAN1's message RAM words.
pub const RAM_WORDS: u32 = 1024;

// Register offsets (RM0433 Table 443).
pub const CREL: u32 = 0x000;
pub const ENDN: u32 = 0x004;
pub const DBTP: u32 = 0x00C;
pub const TEST: u32 = 0x010;
pub const RWD: u32 = 0x014;
pub const CCCR: u32 = 0x018;
pub const NBTP: u32 = 0x01C;
pub const TSCC: u32 = 0x020;
pub const TSCV: u32 = 0x024;
pub const TOCC: u32 = 0x028;
pub const TOCV: u32 = 0x02C;
pub const ECR: u32 = 0x040;
pub const PSR: u32 = 0x044;
pub const TDCR: u32 = 0x048;
pub const IR: u32 = 0x050;
pub const IE: u32 = 0x054;
pub const ILS: u32 = 0x058;
pub const ILE: u32 = 0x05C;
pub const GFC: u32 = 0x080;
pub const SIDFC: u32 = 0x084;
pub const XIDFC: u32 = 0x088;
pub const XIDAM: u32 = 0x090;
pub const HPMS: u32 = 0x094;
pub const NDAT1: u32 = 0x098;
pub const NDAT2: u32 = 0x09C;
pub const RXF0C: u32 = 0x0A0;
pub const RXF0S: u32 = 0x0A4;
pub const RXF0A: u32 = 0x0A8;
pub const RXBC: u32 = 0x0AC;
pub const RXF1C: u32 = 0x0B0;
pub const RXF1S: u32 = 0x0B4;
pub const RXF1A: u32 = 0x0B8;
pub const RXESC: u32 = 0x0BC;
pub const TXBC: u32 = 0x0C0;
pub const TXFQS: u32 = 0x0C4;
pub const TXESC: u32 = 0x0C8;
pub const TXBRP: u32 = 0x0CC;
pub const TXBAR: u32 = 0x0D0;
pub const TXBCR: u32 = 0x0D4;
pub const TXBTO: u32 = 0x0D8;
pub const TXBCF: u32 = 0x0DC;
pub const TXBTIE: u32 = 0x0E0;
pub const TXBCIE: u32 = 0x0E4;
pub const TXEFC: u32 = 0x0F0;
pub const TXEFS: u32 = 0x0F4;
pub const TXEFA: u32 = 0x0F8;

// CCCR bits (RM0433 §56.5.6).
pub const INIT: u32 = 1 << 0;
pub const CCE: u32 = 1 << 1;
pub const CSA: u32 = 1 << 3;
pub const CSR: u32 = 1 << 4;
pub const CCCR_TEST: u32 = 1 << 7;
pub const CCCR_ASM: u32 = 1 << 2;
/// Bus monitoring mode.
pub const CCCR_MON: u32 = 1 << 5;
/// ASM, MON, DAR, TEST, FDOE, BRSE, PXHD, EFBI, TXP, NISO.
pub const CCCR_PROTECTED: u32 = 0b1111_0011_1110_0100;
/// The implemented CCCR bits.
const CCCR_MASK: u32 = 0xF3FF;

// IR bits (RM0433 §56.5.14).
pub const IR_RF0N: u32 = 1 << 0;
pub const IR_RF0F: u32 = 1 << 2;
pub const IR_RF0L: u32 = 1 << 3;
pub const IR_RF1N: u32 = 1 << 4;
pub const IR_RF1F: u32 = 1 << 6;
pub const IR_RF1L: u32 = 1 << 7;
pub const IR_TC: u32 = 1 << 9;
pub const IR_TCF: u32 = 1 << 10;
pub const IR_MRAF: u32 = 1 << 17;
pub const IR_MASK: u32 = 0x3FFF_FFFF;

// PSR bits (RM0433 FDCAN_PSR): LEC 2:0, EP 5, EW 6, BO 7.
pub const PSR_LEC: u32 = 0b111;
pub const PSR_EP: u32 = 1 << 5;
pub const PSR_EW: u32 = 1 << 6;
pub const PSR_BO: u32 = 1 << 7;
/// PSR after reset: LEC = DLEC = 7 ("no change").
const PSR_RESET: u32 = 0x0000_0707;

/// The registers writable only with `CCCR.INIT` and `CCCR.CCE` set, with their implemented
/// bits (the rest reads 0) and reset values.
const PROTECTED: [(u32, u32, u32); 17] = [
    (DBTP, 0x009F_1FFF, 0x0000_0A33),
    (RWD, 0x0000_00FF, 0),
    (NBTP, 0xFFFF_FF7F, 0x0600_0A03),
    (TSCC, 0x000F_0003, 0),
    (TOCC, 0xFFFF_0007, 0xFFFF_0000),
    (TDCR, 0x0000_7F7F, 0),
    (GFC, 0x0000_003F, 0),
    (SIDFC, 0x00FF_FFFC, 0),
    (XIDFC, 0x007F_FFFC, 0),
    (XIDAM, 0x1FFF_FFFF, 0x1FFF_FFFF),
    (RXF0C, 0xFF7F_FFFC, 0),
    (RXBC, 0x0000_FFFC, 0),
    (RXF1C, 0xFF7F_FFFC, 0),
    (RXESC, 0x0000_0777, 0),
    (TXBC, 0x7F3F_FFFC, 0),
    (TXESC, 0x0000_0007, 0),
    (TXEFC, 0x3F3F_FFFC, 0),
];

/// Plain read/write registers (no rule but their implemented bits).
const PLAIN: [(u32, u32); 6] = [
    (IE, 0x3FFF_FFFF),
    (ILS, 0x3FFF_FFFF),
    (ILE, 0x0000_0003),
    (TXBTIE, 0xFFFF_FFFF),
    (TXBCIE, 0xFFFF_FFFF),
    (TXEFA, 0x0000_001F),
];

/// Read-only registers.
const READ_ONLY: [u32; 12] = [
    CREL, ENDN, ECR, PSR, HPMS, RXF0S, RXF1S, TXFQS, TXBRP, TXBTO, TXBCF, TXEFS,
];

/// A breach of RM0433's rules by the software driving the model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Violation {
    /// A protected configuration register written without `CCCR.INIT` and `CCE` set.
    Protected { offset: u32, value: u32 },
    /// `CCCR`'s protected mode bits changed without `INIT` and `CCE` set.
    ProtectedCccrBits { old: u32, new: u32 },
    /// `CCCR.CCE` set while `INIT` did not read set.
    CceWithoutInit,
    /// `TEST` changed without `CCCR.TEST`.
    TestWithoutTestMode,
    /// A write to a read-only register.
    ReadOnly { offset: u32 },
    /// A message RAM word beyond FDCAN1's 1,024.
    RamBounds { word: u32 },
    /// `RXFnA` acknowledged an index outside the FIFO's fill (or of a disabled FIFO).
    AckOutsideFill { fifo: u8, index: u32 },
    /// `TXBAR` requested a buffer that `TXBC` does not configure.
    UnconfiguredBuffer { bits: u32 },
    /// A TX buffer element written while its transmission request is pending.
    BufferWrittenWhilePending { slot: u32 },
    /// Leaving `INIT` with a section of the message RAM layout that breaks a rule.
    Layout {
        section: &'static str,
        problem: &'static str,
    },
    /// Leaving `INIT` with two sections of the message RAM layout overlapping.
    LayoutOverlap(&'static str, &'static str),
    /// `TXBAR` requested TX FIFO buffers other than the one at the put index (`TXFQS.TFQPI`).
    FifoNotAtPutIndex { bits: u32, put: u32 },
    /// `TXBAR` requested a TX FIFO buffer while the FIFO was full (`TXFQS.TFQF`).
    FifoFull,
    /// The model covers the TX FIFO, not the TX queue (`TXBC.TFQM` = 1).
    QueueModeUnmodelled,
    /// A `TXBAR` write the core ignores: in configuration mode (`CCE`) or in bus monitoring
    /// (`MON`, `TXBRP` held in reset). The frame is never sent.
    RequestIgnored { bits: u32, cccr: u32 },
}

#[derive(Clone, Copy, Debug, Default)]
struct Fifo {
    get: u32,
    fill: u32,
}

/// Words of an RX/TX element with data field size code `code` (RXESC/TXESC: 8, 12, 16, 20,
/// 24, 32, 48, 64 bytes; 2 header words).
fn element_words(code: u32) -> u32 {
    const BYTES: [u32; 8] = [8, 12, 16, 20, 24, 32, 48, 64];
    2 + BYTES[(code & 7) as usize] / 4
}

fn idx(offset: u32) -> usize {
    (offset / 4) as usize
}

/// The model's state (behind a `RefCell`: the hardware changes between reads, so a read of
/// the trait, `&self`, may change it: the `INIT` crossing, the bounds record).
pub struct State {
    regs: [u32; 0x100 / 4],
    ram: Vec<u32>,
    /// A pending `INIT` change and the `CCCR` reads until it shows.
    pending_init: Option<(bool, u32)>,
    /// Reads of `CCCR` an `INIT` change takes to show.
    pub init_latency: u32,
    /// Fault injection: `INIT` never reads set (no kernel clock, say).
    pub init_never_set: bool,
    /// Fault injection: `INIT` never reads clear after a leave request.
    pub init_never_clear: bool,
    /// Fault injection: (register offset, bits) that keep their value whatever is written.
    pub stuck_bits: Vec<(u32, u32)>,
    /// Fault injection: (register offset, bits) that read 1 whatever is written.
    pub forced_bits: Vec<(u32, u32)>,
    /// Fault injection: a message RAM word that ignores writes.
    pub stuck_word: Option<u32>,
    test: u32,
    fifo: [Fifo; 2],
    txbrp: u32,
    txbto: u32,
    txbcf: u32,
    cancel_requested: u32,
    /// TX FIFO: the get index's offset in the FIFO's buffers, and the elements requested
    /// (from the get index on; cancelled ones leave at the get index).
    txq_get: u32,
    txq_fill: u32,
    /// Cancellations complete only at [`State::complete_cancels`] (or a transmission).
    pub defer_cancel: bool,
    psr: u32,
    ecr: u32,
    /// Bus-off recovery: recessive bit times counted since `INIT` was cleared in bus-off
    /// (`None`: no recovery running).
    recovery: Option<u32>,
    ir: u32,
    /// Every breach, in order.
    pub violations: Vec<Violation>,
    /// Frames the bus carried from the TX buffers, in order.
    pub wire: Vec<BusFrame>,
    /// Every arrival and its verdict.
    pub arrivals: Vec<(BusFrame, Verdict)>,
    /// Times the core left `INIT` (joined the bus).
    pub joins: u32,
}

impl State {
    fn after_reset() -> Self {
        let mut regs = [0u32; 0x100 / 4];
        for (off, _, reset) in PROTECTED {
            regs[idx(off)] = reset;
        }
        regs[idx(CCCR)] = INIT;
        regs[idx(TOCV)] = 0xFFFF;
        // The message RAM is not initialised by a reset: garbage.
        let mut x = 0x1234_5678u32;
        let ram = (0..RAM_WORDS)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 17;
                x ^= x << 5;
                x
            })
            .collect();
        Self {
            regs,
            ram,
            pending_init: None,
            init_latency: 3,
            init_never_set: false,
            init_never_clear: false,
            stuck_bits: Vec::new(),
            forced_bits: Vec::new(),
            stuck_word: None,
            test: 0,
            fifo: [Fifo::default(); 2],
            txbrp: 0,
            txbto: 0,
            txbcf: 0,
            cancel_requested: 0,
            txq_get: 0,
            txq_fill: 0,
            defer_cancel: false,
            psr: PSR_RESET,
            ecr: 0,
            recovery: None,
            ir: 0,
            violations: Vec::new(),
            wire: Vec::new(),
            arrivals: Vec::new(),
            joins: 0,
        }
    }

    /// A register as stored (no side effect; a pending `INIT` change not applied).
    pub fn peek(&self, offset: u32) -> u32 {
        match offset {
            IR => self.ir,
            TXBRP => self.txbrp,
            _ => self.regs[idx(offset)],
        }
    }

    /// A message RAM word (no bounds rule).
    pub fn peek_ram(&self, word: u32) -> u32 {
        self.ram[word as usize]
    }

    /// `CCCR.INIT` as the core is now.
    pub fn in_init(&self) -> bool {
        self.regs[idx(CCCR)] & INIT != 0
    }

    /// Elements in RX FIFO `n`.
    pub fn fill(&self, n: usize) -> u32 {
        self.fifo[n].fill
    }

    fn config_enabled(&self) -> bool {
        self.regs[idx(CCCR)] & (INIT | CCE) == INIT | CCE
    }

    /// Applies a pending `INIT` change now (as if enough time had passed).
    pub fn settle(&mut self) {
        if let Some((set, _)) = self.pending_init.take() {
            self.apply_init(set);
        }
    }

    fn apply_init(&mut self, set: bool) {
        if set {
            self.regs[idx(CCCR)] |= INIT;
            // Back in INIT before the recovery ended: it starts again at the next clear.
            self.recovery = None;
        } else {
            // Clearing INIT clears CCE; the core integrates into the bus (after a bus-off:
            // once the recovery has counted its recessive bits, `errors.rs`).
            self.regs[idx(CCCR)] &= !(INIT | CCE);
            self.joins += 1;
            self.check_layout();
            if self.psr & PSR_BO != 0 {
                self.recovery = Some(0);
            }
        }
    }

    /// `CCCR.MON` as the core is now.
    pub fn monitoring(&self) -> bool {
        self.regs[idx(CCCR)] & CCCR_MON != 0
    }

    /// The core takes part in the bus now: out of `INIT`, not bus-off (a recovery still
    /// running counts as bus-off).
    pub fn on_bus(&self) -> bool {
        !self.in_init() && self.psr & PSR_BO == 0
    }

    /// A message RAM access failure (`IR.MRAF`): of the RX handler (an element not stored),
    /// or of the TX handler (`tx`), which also puts the core into restricted operation
    /// (`CCCR.ASM`): it then sends nothing until software clears `ASM`.
    pub fn ram_access_failure(&mut self, tx: bool) {
        self.ir |= IR_MRAF;
        if tx {
            self.regs[idx(CCCR)] |= CCCR_ASM;
        }
    }

    fn store_masked(&mut self, offset: u32, mask: u32, value: u32) {
        let stuck = self
            .stuck_bits
            .iter()
            .filter(|(o, _)| *o == offset)
            .fold(0, |m, (_, b)| m | b);
        let forced = self
            .forced_bits
            .iter()
            .filter(|(o, _)| *o == offset)
            .fold(0, |m, (_, b)| m | b);
        let r = &mut self.regs[idx(offset)];
        *r = (*r & stuck) | (value & mask & !stuck) | forced;
    }

    fn read(&mut self, offset: u32) -> u32 {
        match offset {
            CCCR => {
                if let Some((set, n)) = self.pending_init {
                    if n == 0 {
                        self.pending_init = None;
                        self.apply_init(set);
                    } else {
                        self.pending_init = Some((set, n - 1));
                    }
                }
                self.regs[idx(CCCR)]
            }
            CREL => 0x3214_1218,
            ENDN => 0x8765_4321,
            ECR => self.ecr,
            PSR => self.psr,
            IR => self.ir,
            RXF0S => self.fifo_status(0),
            RXF1S => self.fifo_status(1),
            TXBRP => self.txbrp,
            TXBTO => self.txbto,
            TXBCF => self.txbcf,
            // RX pin recessive.
            TEST => self.test | 1 << 7,
            TXFQS => self.txfqs(),
            TXEFS | HPMS | NDAT1 | NDAT2 | TSCV => 0,
            _ => self.regs[idx(offset)],
        }
    }

    fn write(&mut self, offset: u32, v: u32) {
        if let Some((_, mask, _)) = PROTECTED.iter().find(|(o, _, _)| *o == offset) {
            if self.config_enabled() {
                self.store_masked(offset, *mask, v);
            } else {
                self.violations
                    .push(Violation::Protected { offset, value: v });
            }
            return;
        }
        if let Some((_, mask)) = PLAIN.iter().find(|(o, _)| *o == offset) {
            self.store_masked(offset, *mask, v);
            return;
        }
        if READ_ONLY.contains(&offset) {
            self.violations.push(Violation::ReadOnly { offset });
            return;
        }
        match offset {
            CCCR => self.write_cccr(v),
            // Write 1 to clear.
            IR => self.ir &= !(v & IR_MASK),
            TXBAR | TXBCR if self.regs[idx(CCCR)] & CCE != 0 => {
                // Ignored while CCE is set (RM0433 FDCAN_TXBAR / FDCAN_TXBCR descriptions);
                // a cancellation there has nothing to cancel (TXBRP was reset with CCE), an add
                // request is a frame lost.
                if offset == TXBAR && v != 0 {
                    self.violations.push(Violation::RequestIgnored {
                        bits: v,
                        cccr: self.regs[idx(CCCR)],
                    });
                }
            }
            TXBAR => self.tx_add(v),
            TXBCR => self.tx_cancel(v),
            RXF0A => self.ack(0, v),
            RXF1A => self.ack(1, v),
            TEST => {
                if self.regs[idx(CCCR)] & CCCR_TEST != 0 {
                    self.test = v & 0x70;
                } else if (v ^ self.test) & 0x70 != 0 {
                    self.violations.push(Violation::TestWithoutTestMode);
                }
            }
            // New-data flags (no RX buffers here), counters reset by a write.
            NDAT1 | NDAT2 | TSCV | TOCV => {}
            _ => panic!("the model has no register at {offset:#x}"),
        }
    }

    fn write_cccr(&mut self, v: u32) {
        let cur = self.regs[idx(CCCR)];
        // Fault injection: bits that keep their value (a CCE that never takes resets nothing).
        let stuck = self
            .stuck_bits
            .iter()
            .filter(|(o, _)| *o == CCCR)
            .fold(0, |m, (_, b)| m | b);
        let mut new = cur;
        // ASM (restricted operation) can be cleared by software at any time (RM0433
        // §56.5.6); setting it, like the other protected bits, needs INIT and CCE.
        if cur & CCCR_ASM != 0 && v & CCCR_ASM == 0 {
            new &= !CCCR_ASM;
        }
        // MON likewise: set only with INIT and CCE, reset by software at any time (Bosch's
        // M_CAN user's manual, CCCR.MON; the FDCAN of RM0433 is that core).
        if cur & CCCR_MON != 0 && v & CCCR_MON == 0 {
            new &= !CCCR_MON;
        }
        let changed = (v ^ new) & CCCR_PROTECTED;
        if changed != 0 {
            if self.config_enabled() {
                new = (new & !CCCR_PROTECTED) | (v & CCCR_PROTECTED);
            } else {
                self.violations
                    .push(Violation::ProtectedCccrBits { old: cur, new: v });
            }
        }
        // CCE: set only once INIT reads set (and stays requested); clearable any time.
        if v & CCE != 0 && cur & CCE == 0 && stuck & CCE == 0 {
            if cur & INIT != 0 && v & INIT != 0 {
                new |= CCE;
                // Setting CCE resets HPMS, RXF0S, RXF1S, TXFQS, TXBRP, TXBTO, TXBCF and TXEFS
                // (RM0433, FDCAN "Software initialization"; the same list in Bosch's M_CAN
                // user's manual, "Software Initialization"). HPMS and TXEFS read 0 in this
                // model throughout (no high-priority filters, no TX event FIFO); the RX FIFOs'
                // fill and indices and every TX request go: elements still in the message RAM
                // are no longer in any FIFO.
                self.fifo = [Fifo::default(); 2];
                self.txbrp = 0;
                self.txbto = 0;
                self.txbcf = 0;
                self.cancel_requested = 0;
                self.txq_get = 0;
                self.txq_fill = 0;
            } else {
                self.violations.push(Violation::CceWithoutInit);
            }
        } else if v & CCE == 0 {
            new &= !CCE;
        }
        // Clock stop request, acknowledged at once (CSA is read-only).
        new &= !(CSR | CSA);
        if v & CSR != 0 {
            new |= CSR | CSA;
        }
        let want = v & INIT != 0;
        if want != (cur & INIT != 0) {
            if !want {
                new &= !CCE;
            }
            let never = if want {
                self.init_never_set
            } else {
                self.init_never_clear
            };
            self.pending_init = if never {
                None
            } else {
                Some((want, self.init_latency))
            };
        } else {
            self.pending_init = None;
        }
        self.regs[idx(CCCR)] = ((cur & stuck) | (new & !stuck)) & CCCR_MASK;
    }

    fn check_layout(&mut self) {
        let r = |o: u32| self.regs[idx(o)];
        let start = |v: u32| (v >> 2) & 0x3FFF;
        let lss = (r(SIDFC) >> 16) & 0xFF;
        let lse = (r(XIDFC) >> 16) & 0x7F;
        let f0s = (r(RXF0C) >> 16) & 0x7F;
        let f1s = (r(RXF1C) >> 16) & 0x7F;
        let efs = (r(TXEFC) >> 16) & 0x3F;
        let ndtb = (r(TXBC) >> 16) & 0x3F;
        let tfqs = (r(TXBC) >> 24) & 0x3F;
        let mut bad = Vec::new();
        for (section, n, max) in [
            ("standard filters", lss, 128),
            ("extended filters", lse, 64),
            ("RX FIFO0", f0s, 64),
            ("RX FIFO1", f1s, 64),
            ("TX event FIFO", efs, 32),
            ("TX buffers", ndtb + tfqs, 32),
        ] {
            if n > max {
                bad.push(Violation::Layout {
                    section,
                    problem: "more elements than the field allows",
                });
            }
        }
        let sections = [
            ("standard filters", start(r(SIDFC)), lss),
            ("extended filters", start(r(XIDFC)), 2 * lse),
            ("RX FIFO0", start(r(RXF0C)), f0s * element_words(r(RXESC))),
            (
                "RX FIFO1",
                start(r(RXF1C)),
                f1s * element_words(r(RXESC) >> 4),
            ),
            ("TX event FIFO", start(r(TXEFC)), 2 * efs),
            (
                "TX buffers",
                start(r(TXBC)),
                (ndtb + tfqs) * element_words(r(TXESC)),
            ),
        ];
        let used: Vec<_> = sections.iter().filter(|s| s.2 > 0).collect();
        for (i, a) in used.iter().enumerate() {
            if a.1 + a.2 > RAM_WORDS {
                bad.push(Violation::Layout {
                    section: a.0,
                    problem: "beyond FDCAN1's 1,024 words",
                });
            }
            for b in &used[i + 1..] {
                if a.1 < b.1 + b.2 && b.1 < a.1 + a.2 {
                    bad.push(Violation::LayoutOverlap(a.0, b.0));
                }
            }
        }
        self.violations.extend(bad);
    }

    fn ram_read(&mut self, word: u32) -> u32 {
        match self.ram.get(word as usize) {
            Some(v) => *v,
            None => {
                self.violations.push(Violation::RamBounds { word });
                0
            }
        }
    }

    fn ram_write(&mut self, word: u32, v: u32) {
        if word >= RAM_WORDS {
            self.violations.push(Violation::RamBounds { word });
            return;
        }
        let txbc = self.regs[idx(TXBC)];
        let tbsa = (txbc >> 2) & 0x3FFF;
        let n = ((txbc >> 16) & 0x3F) + ((txbc >> 24) & 0x3F);
        let ew = element_words(self.regs[idx(TXESC)]);
        if word >= tbsa && word < tbsa + n * ew {
            let slot = (word - tbsa) / ew;
            if self.txbrp & (1 << slot) != 0 {
                self.violations
                    .push(Violation::BufferWrittenWhilePending { slot });
            }
        }
        if self.stuck_word != Some(word) {
            self.ram[word as usize] = v;
        }
    }

    // --- RX ---

    fn fifo_config(&self, n: usize) -> (u32, u32, bool, u32) {
        let c = self.regs[idx(if n == 0 { RXF0C } else { RXF1C })];
        let ew = element_words(self.regs[idx(RXESC)] >> (4 * n));
        ((c >> 2) & 0x3FFF, (c >> 16) & 0x7F, c >> 31 != 0, ew)
    }

    fn fifo_status(&self, n: usize) -> u32 {
        let (_, size, _, _) = self.fifo_config(n);
        let f = self.fifo[n];
        if size == 0 {
            return 0;
        }
        let put = (f.get + f.fill) % size;
        let lost = self.ir & if n == 0 { IR_RF0L } else { IR_RF1L } != 0;
        f.fill | f.get << 8 | put << 16 | u32::from(f.fill == size) << 24 | u32::from(lost) << 25
    }

    fn ack(&mut self, n: usize, v: u32) {
        let (_, size, _, _) = self.fifo_config(n);
        let a = v & 0x3F;
        let f = self.fifo[n];
        let offset = if size == 0 {
            0
        } else {
            (a + size - f.get % size) % size
        };
        if size == 0 || a >= size || f.fill == 0 || offset >= f.fill {
            self.violations.push(Violation::AckOutsideFill {
                fifo: n as u8,
                index: a,
            });
            return;
        }
        self.fifo[n] = Fifo {
            get: (a + 1) % size,
            fill: f.fill - offset - 1,
        };
    }
}

/// The model behind `FdcanRegs`.
pub struct FdcanModel {
    s: RefCell<State>,
}

impl Default for FdcanModel {
    fn default() -> Self {
        Self::after_reset()
    }
}

impl FdcanModel {
    /// FDCAN1 after a reset: `CCCR.INIT` set, reset values, the message RAM full of garbage.
    pub fn after_reset() -> Self {
        Self {
            s: RefCell::new(State::after_reset()),
        }
    }

    /// The state (bus events, fault injection, inspection).
    pub fn st(&self) -> RefMut<'_, State> {
        self.s.borrow_mut()
    }

    /// The breaches so far.
    pub fn violations(&self) -> Vec<Violation> {
        self.st().violations.clone()
    }
}

impl FdcanRegs for FdcanModel {
    fn read(&self, reg: Reg) -> u32 {
        self.st().read(reg.offset())
    }
    fn write(&mut self, reg: Reg, value: u32) {
        self.st().write(reg.offset(), value)
    }
    fn ram_read(&self, word: u32) -> u32 {
        self.st().ram_read(word)
    }
    fn ram_write(&mut self, word: u32, value: u32) {
        self.st().ram_write(word, value)
    }
}
