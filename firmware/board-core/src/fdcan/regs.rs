//! The register-access trait ([`FdcanRegs`]), the registers it names ([`Reg`], offsets of
//! RM0433 §56.5) and the bit fields this crate writes or reads.

/// An FDCAN register, its discriminant the byte offset in the instance's register block
/// (RM0433 Table 443, FDCAN register map; FDCAN1's block is at 0x4000_A000). Only the
/// non-time-triggered registers: the board does not use the TT-FDCAN of FDCAN1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[repr(u16)]
pub enum Reg {
    /// `FDCAN_CREL`: core release (read-only).
    Crel = 0x000,
    /// `FDCAN_ENDN`: endianness test value, 0x8765_4321 (read-only).
    Endn = 0x004,
    /// `FDCAN_DBTP`: data bit timing (protected; FD frames only).
    Dbtp = 0x00C,
    /// `FDCAN_TEST`: test modes (writable only with `CCCR.TEST`).
    Test = 0x010,
    /// `FDCAN_RWD`: message RAM watchdog (protected).
    Rwd = 0x014,
    /// `FDCAN_CCCR`: CC control (INIT, CCE and the protected mode bits).
    Cccr = 0x018,
    /// `FDCAN_NBTP`: nominal bit timing (protected).
    Nbtp = 0x01C,
    /// `FDCAN_TSCC`: timestamp counter configuration (protected).
    Tscc = 0x020,
    /// `FDCAN_TSCV`: timestamp counter value.
    Tscv = 0x024,
    /// `FDCAN_TOCC`: timeout counter configuration (protected).
    Tocc = 0x028,
    /// `FDCAN_TOCV`: timeout counter value.
    Tocv = 0x02C,
    /// `FDCAN_ECR`: error counters (read-only).
    Ecr = 0x040,
    /// `FDCAN_PSR`: protocol status (read-only).
    Psr = 0x044,
    /// `FDCAN_TDCR`: transmitter delay compensation (protected).
    Tdcr = 0x048,
    /// `FDCAN_IR`: interrupt flags (write 1 to clear).
    Ir = 0x050,
    /// `FDCAN_IE`: interrupt enable.
    Ie = 0x054,
    /// `FDCAN_ILS`: interrupt line select.
    Ils = 0x058,
    /// `FDCAN_ILE`: interrupt line enable.
    Ile = 0x05C,
    /// `FDCAN_GFC`: global filter (protected).
    Gfc = 0x080,
    /// `FDCAN_SIDFC`: standard-id filter list (protected).
    Sidfc = 0x084,
    /// `FDCAN_XIDFC`: extended-id filter list (protected).
    Xidfc = 0x088,
    /// `FDCAN_XIDAM`: extended-id AND mask (protected).
    Xidam = 0x090,
    /// `FDCAN_HPMS`: high-priority message status (read-only).
    Hpms = 0x094,
    /// `FDCAN_NDAT1`: new data flags of RX buffers 0-31.
    Ndat1 = 0x098,
    /// `FDCAN_NDAT2`: new data flags of RX buffers 32-63.
    Ndat2 = 0x09C,
    /// `FDCAN_RXF0C`: RX FIFO0 configuration (protected).
    Rxf0c = 0x0A0,
    /// `FDCAN_RXF0S`: RX FIFO0 status (read-only).
    Rxf0s = 0x0A4,
    /// `FDCAN_RXF0A`: RX FIFO0 acknowledge.
    Rxf0a = 0x0A8,
    /// `FDCAN_RXBC`: RX buffer configuration (protected).
    Rxbc = 0x0AC,
    /// `FDCAN_RXF1C`: RX FIFO1 configuration (protected).
    Rxf1c = 0x0B0,
    /// `FDCAN_RXF1S`: RX FIFO1 status (read-only).
    Rxf1s = 0x0B4,
    /// `FDCAN_RXF1A`: RX FIFO1 acknowledge.
    Rxf1a = 0x0B8,
    /// `FDCAN_RXESC`: RX element sizes (protected).
    Rxesc = 0x0BC,
    /// `FDCAN_TXBC`: TX buffer configuration (protected).
    Txbc = 0x0C0,
    /// `FDCAN_TXFQS`: TX FIFO/queue status (read-only).
    Txfqs = 0x0C4,
    /// `FDCAN_TXESC`: TX element size (protected).
    Txesc = 0x0C8,
    /// `FDCAN_TXBRP`: TX buffer request pending (read-only).
    Txbrp = 0x0CC,
    /// `FDCAN_TXBAR`: TX buffer add request.
    Txbar = 0x0D0,
    /// `FDCAN_TXBCR`: TX buffer cancellation request.
    Txbcr = 0x0D4,
    /// `FDCAN_TXBTO`: TX buffer transmission occurred (read-only).
    Txbto = 0x0D8,
    /// `FDCAN_TXBCF`: TX buffer cancellation finished (read-only).
    Txbcf = 0x0DC,
    /// `FDCAN_TXBTIE`: TX buffer transmission interrupt enable.
    Txbtie = 0x0E0,
    /// `FDCAN_TXBCIE`: TX buffer cancellation interrupt enable.
    Txbcie = 0x0E4,
    /// `FDCAN_TXEFC`: TX event FIFO configuration (protected).
    Txefc = 0x0F0,
    /// `FDCAN_TXEFS`: TX event FIFO status (read-only).
    Txefs = 0x0F4,
    /// `FDCAN_TXEFA`: TX event FIFO acknowledge.
    Txefa = 0x0F8,
}

impl Reg {
    /// Byte offset in the register block.
    pub const fn offset(self) -> u32 {
        self as u32
    }
}

/// The accesses to one FDCAN instance: its registers and its part of the message RAM. The
/// board implements it on FDCAN1 (volatile accesses, `firmware/board/src/fdcan1.rs`), the
/// host tests on a register-level model that enforces RM0433's rules.
///
/// Every configuration and run-time access of this crate goes through these four methods.
pub trait FdcanRegs {
    /// Reads register `reg`.
    fn read(&self, reg: Reg) -> u32;
    /// Writes `value` to register `reg`.
    fn write(&mut self, reg: Reg, value: u32);
    /// Reads word `word` of the instance's message RAM (word 0 = its first word; FDCAN1's
    /// are the 1,024 words from 0x4000_AC00, [`RAM_WORDS`]). Out of range: 0, no access.
    fn ram_read(&self, word: u32) -> u32;
    /// Writes word `word` of the instance's message RAM. Out of range: no access.
    fn ram_write(&mut self, word: u32, value: u32);
}

/// Message RAM words of FDCAN1's part (its first 4 KiB; the HAL would put FDCAN2 at word
/// 0x400 of the shared 10 KiB).
pub const RAM_WORDS: u32 = 1024;

/// `FDCAN_ENDN`'s fixed value (RM0433 §56.5.2): a register block that reads otherwise is not
/// an FDCAN's (or not clocked).
pub const ENDN_VALUE: u32 = 0x8765_4321;

/// `FDCAN_CCCR` bits (RM0433 §56.5.6).
pub mod cccr {
    /// Initialisation: the core is off the bus (set by software or by the core on bus-off).
    pub const INIT: u32 = 1 << 0;
    /// Configuration change enable (only while `INIT`; cleared with `INIT`).
    pub const CCE: u32 = 1 << 1;
    /// Restricted operation mode (protected).
    pub const ASM: u32 = 1 << 2;
    /// Clock stop acknowledge (read-only).
    pub const CSA: u32 = 1 << 3;
    /// Clock stop request.
    pub const CSR: u32 = 1 << 4;
    /// Bus monitoring mode (protected).
    pub const MON: u32 = 1 << 5;
    /// Disable automatic retransmission (protected).
    pub const DAR: u32 = 1 << 6;
    /// Test mode enable (protected).
    pub const TEST: u32 = 1 << 7;
    /// FD operation enable (protected).
    pub const FDOE: u32 = 1 << 8;
    /// Bit rate switching enable (protected).
    pub const BRSE: u32 = 1 << 9;
    /// Protocol exception handling disable (protected).
    pub const PXHD: u32 = 1 << 12;
    /// Edge filtering during bus integration (protected).
    pub const EFBI: u32 = 1 << 13;
    /// Transmit pause (protected).
    pub const TXP: u32 = 1 << 14;
    /// Non-ISO operation (protected).
    pub const NISO: u32 = 1 << 15;
    /// The bits writable only with `INIT` and `CCE` set.
    pub const PROTECTED: u32 = ASM | MON | DAR | TEST | FDOE | BRSE | PXHD | EFBI | TXP | NISO;
}

/// `FDCAN_IR` bits this crate uses (RM0433 §56.5.14; write 1 to clear).
pub mod ir {
    /// RX FIFO0: a frame was lost (the FIFO was full).
    pub const RF0L: u32 = 1 << 3;
    /// RX FIFO1: a frame was lost (the FIFO was full).
    pub const RF1L: u32 = 1 << 7;
    /// Message RAM access failure: an RX or TX handler could not access the message RAM in
    /// time (a TX failure also switches the core into restricted operation mode, `CCCR.ASM`).
    pub const MRAF: u32 = 1 << 17;
    /// Every flag (bits 29:0).
    pub const ALL: u32 = 0x3FFF_FFFF;
}

/// Fields of `FDCAN_TXFQS` (RM0433 §56.5.33).
pub mod txfqs {
    /// TX FIFO free level (bits 5:0).
    pub const fn free(status: u32) -> u32 {
        status & 0x3F
    }
    /// TX FIFO get index (bits 12:8): the buffer index of the oldest element.
    pub const fn get(status: u32) -> u32 {
        (status >> 8) & 0x1F
    }
    /// TX FIFO put index (bits 20:16): the buffer index the next element goes into.
    pub const fn put(status: u32) -> u32 {
        (status >> 16) & 0x1F
    }
    /// TX FIFO full (bit 21).
    pub const FULL: u32 = 1 << 21;
}

/// Fields of `FDCAN_RXF0S` / `FDCAN_RXF1S` (RM0433 §56.5.24, §56.5.28).
pub mod rxfs {
    /// Fill level (bits 6:0).
    pub const fn fill(status: u32) -> u32 {
        status & 0x7F
    }
    /// Get index (bits 13:8).
    pub const fn get(status: u32) -> u32 {
        (status >> 8) & 0x3F
    }
}

/// Encodings of the configuration registers' fields (RM0433 §56.5): start addresses are word
/// addresses in the message RAM, in bits 15:2.
pub mod field {
    /// `NBTP` from the time quanta (each field holds its value minus one): NSJW 31:25, NBRP
    /// 24:16, NTSEG1 15:8, NTSEG2 6:0.
    pub const fn nbtp(prescaler: u32, seg1: u32, seg2: u32, sjw: u32) -> u32 {
        ((sjw - 1) << 25) | ((prescaler - 1) << 16) | ((seg1 - 1) << 8) | (seg2 - 1)
    }
    /// `GFC`: ANFS 5:4, ANFE 3:2 (`0b00` FIFO0, `0b01` FIFO1, `0b1x` reject), RRFS 1, RRFE 0.
    pub const fn gfc(
        anfs: u32,
        anfe: u32,
        reject_remote_std: bool,
        reject_remote_ext: bool,
    ) -> u32 {
        (anfs << 4) | (anfe << 2) | ((reject_remote_std as u32) << 1) | reject_remote_ext as u32
    }
    /// `SIDFC`: LSS 23:16 (elements), FLSSA 15:2.
    pub const fn sidfc(elements: u32, start_word: u32) -> u32 {
        (elements << 16) | (start_word << 2)
    }
    /// `XIDFC`: LSE 22:16 (elements), FLESA 15:2.
    pub const fn xidfc(elements: u32, start_word: u32) -> u32 {
        (elements << 16) | (start_word << 2)
    }
    /// `RXF0C` / `RXF1C` in blocking mode without watermark: FnS 22:16 (elements), FnSA 15:2.
    pub const fn rxfc(elements: u32, start_word: u32) -> u32 {
        (elements << 16) | (start_word << 2)
    }
    /// `TXBC` with `buffers` dedicated TX buffers followed by a TX FIFO of `fifo` elements
    /// (`TFQM` = 0: FIFO mode): TFQM 30, TFQS 29:24, NDTB 21:16, TBSA 15:2.
    pub const fn txbc(buffers: u32, fifo: u32, start_word: u32) -> u32 {
        (fifo << 24) | (buffers << 16) | (start_word << 2)
    }
    /// A standard filter element (RM0433 §56.4.21): SFT 31:30, SFEC 29:27, SFID1 26:16,
    /// SFID2 10:0.
    pub const fn std_filter(sft: u32, sfec: u32, sfid1: u16, sfid2: u16) -> u32 {
        (sft << 30) | (sfec << 27) | (((sfid1 & 0x7FF) as u32) << 16) | (sfid2 & 0x7FF) as u32
    }
    /// SFT: dual-id filter (matches SFID1 or SFID2).
    pub const SFT_DUAL: u32 = 0b01;
    /// SFEC: store into RX FIFO0.
    pub const SFEC_FIFO0: u32 = 0b001;
    /// SFEC: store into RX FIFO1.
    pub const SFEC_FIFO1: u32 = 0b010;
    /// ANFS / ANFE: reject non-matching frames.
    pub const REJECT: u32 = 0b11;
}
