//! The model's bus side: frames arriving through RM0433's acceptance filtering (§56.4.5) into
//! the RX FIFOs, and the TX buffers' requests sent or cancelled.

use super::*;

/// A frame on the modelled bus.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusFrame {
    /// 11-bit (standard) or 29-bit (extended) identifier.
    pub id: u32,
    pub extended: bool,
    pub remote: bool,
    pub dlc: u8,
    pub data: [u8; 8],
}

impl BusFrame {
    /// A standard data frame.
    pub fn std(id: u16, data: &[u8]) -> Self {
        let mut d = [0; 8];
        d[..data.len()].copy_from_slice(data);
        Self {
            id: u32::from(id),
            extended: false,
            remote: false,
            dlc: data.len() as u8,
            data: d,
        }
    }
    /// A standard remote frame.
    pub fn std_remote(id: u16, dlc: u8) -> Self {
        Self {
            remote: true,
            dlc,
            ..Self::std(id, &[])
        }
    }
    /// An extended data frame.
    pub fn ext(id: u32, data: &[u8]) -> Self {
        Self {
            id,
            extended: true,
            ..Self::std(0, data)
        }
    }
    /// A planner-core frame.
    pub fn raw(r: &planner_core::wire::RawFrame) -> Self {
        Self::std(r.id, r.bytes())
    }
}

/// Where the acceptance filtering put a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The core is in its initialisation state: not on the bus.
    NotOnBus,
    /// Stored in RX FIFO `n` (`filter`: the matching element, `None` = accepted non-matching).
    Fifo { n: u8, filter: Option<u32> },
    /// A remote frame rejected by `RRFS`/`RRFE`.
    RemoteRejected,
    /// Rejected by filter element `i` (SFEC/EFEC = 011).
    FilterRejected(u32),
    /// Non-matching, rejected by `ANFS`/`ANFE`.
    NonMatchingRejected,
    /// Matched a "set priority" element (SFEC 100): flagged, not stored.
    PriorityOnly(u32),
    /// Matched an element storing into an RX buffer / as a debug message (SFEC 111).
    RxBuffer(u32),
    /// Accepted into a FIFO of size 0 (disabled): not stored.
    FifoDisabled(u8),
    /// Accepted, but the FIFO was full in blocking mode: lost (`IR.RFnL`).
    Lost(u8),
}

impl Verdict {
    /// `true` if the frame went into a FIFO (the software will see it).
    pub fn stored(self) -> bool {
        matches!(self, Verdict::Fifo { .. })
    }
}

impl State {
    /// A frame arrives on the bus: acceptance filtering (RM0433 §56.4.5), then storage.
    pub fn arrive(&mut self, f: BusFrame) -> Verdict {
        // In INIT, or bus-off (its recovery included), the core takes no part in the bus; in
        // bus monitoring it receives as in normal operation.
        let v = if !self.on_bus() {
            Verdict::NotOnBus
        } else {
            match self.filter(&f) {
                Ok((n, filter)) => self.store(n, &f, filter),
                Err(v) => v,
            }
        };
        self.arrivals.push((f, v));
        v
    }

    /// The acceptance filtering: the FIFO and the matching element, or the verdict.
    pub fn filter(&self, f: &BusFrame) -> Result<(usize, Option<u32>), Verdict> {
        let gfc = self.regs[idx(GFC)];
        let (list, count, anf, reject_remote) = if f.extended {
            let x = self.regs[idx(XIDFC)];
            (
                (x >> 2) & 0x3FFF,
                (x >> 16) & 0x7F,
                (gfc >> 2) & 3,
                gfc & 1 != 0,
            )
        } else {
            let s = self.regs[idx(SIDFC)];
            (
                (s >> 2) & 0x3FFF,
                (s >> 16) & 0xFF,
                (gfc >> 4) & 3,
                gfc & 2 != 0,
            )
        };
        if f.remote && reject_remote {
            return Err(Verdict::RemoteRejected);
        }
        for i in 0..count {
            let (ty, ec, id1, id2, masked) = if f.extended {
                let f0 = self.ram[(list + 2 * i) as usize];
                let f1 = self.ram[(list + 2 * i + 1) as usize];
                let ty = f1 >> 30;
                // XIDAM is ANDed to the identifier, except for EFT = 11.
                let m = if ty == 0b11 {
                    f.id
                } else {
                    f.id & self.regs[idx(XIDAM)]
                };
                (ty, f0 >> 29, f0 & 0x1FFF_FFFF, f1 & 0x1FFF_FFFF, m)
            } else {
                let e = self.ram[(list + i) as usize];
                (e >> 30, (e >> 27) & 7, (e >> 16) & 0x7FF, e & 0x7FF, f.id)
            };
            if ec == 0b000 {
                continue; // element disabled
            }
            if ec == 0b111 {
                // RX buffer or debug message: SFT/EFT ignored, the identifier is ID1.
                if f.id == id1 {
                    return Err(Verdict::RxBuffer(i));
                }
                continue;
            }
            let matched = match ty {
                0b00 | 0b11 if f.extended => id1 <= masked && masked <= id2,
                0b00 => id1 <= masked && masked <= id2,
                0b01 => masked == id1 || masked == id2,
                0b10 => masked & id2 == id1 & id2,
                _ => false, // SFT = 11: disabled
            };
            if !matched {
                continue;
            }
            return match ec {
                0b001 | 0b101 => Ok((0, Some(i))),
                0b010 | 0b110 => Ok((1, Some(i))),
                0b011 => Err(Verdict::FilterRejected(i)),
                _ => Err(Verdict::PriorityOnly(i)),
            };
        }
        match anf {
            0b00 => Ok((0, None)),
            0b01 => Ok((1, None)),
            _ => Err(Verdict::NonMatchingRejected),
        }
    }

    pub(super) fn store(&mut self, n: usize, f: &BusFrame, filter: Option<u32>) -> Verdict {
        let (sa, size, overwrite, ew) = self.fifo_config(n);
        let (new, full, lost) = if n == 0 {
            (IR_RF0N, IR_RF0F, IR_RF0L)
        } else {
            (IR_RF1N, IR_RF1F, IR_RF1L)
        };
        if size == 0 {
            return Verdict::FifoDisabled(n as u8);
        }
        if self.fifo[n].fill >= size {
            if !overwrite {
                self.ir |= lost;
                return Verdict::Lost(n as u8);
            }
            // Overwrite mode: the oldest element makes room.
            let q = &mut self.fifo[n];
            q.get = (q.get + 1) % size;
            q.fill -= 1;
        }
        let q = self.fifo[n];
        let put = (q.get + q.fill) % size;
        let r0 = u32::from(f.extended) << 30
            | u32::from(f.remote) << 29
            | if f.extended {
                f.id & 0x1FFF_FFFF
            } else {
                (f.id & 0x7FF) << 18
            };
        let r1 = u32::from(filter.is_none()) << 31
            | (filter.unwrap_or(0) & 0x7F) << 24
            | u32::from(f.dlc & 0xF) << 16;
        let mut data = [0u8; 8];
        if !f.remote {
            let n = usize::from(f.dlc.min(8));
            data[..n].copy_from_slice(&f.data[..n]);
        }
        let words = [
            r0,
            r1,
            u32::from_le_bytes([data[0], data[1], data[2], data[3]]),
            u32::from_le_bytes([data[4], data[5], data[6], data[7]]),
        ];
        let base = sa + put * ew;
        for k in 0..ew {
            let w = base + k;
            if let Some(slot) = self.ram.get_mut(w as usize) {
                *slot = words.get(k as usize).copied().unwrap_or(0);
            }
        }
        self.fifo[n].fill += 1;
        self.ir |= new;
        if self.fifo[n].fill == size {
            self.ir |= full;
        }
        Verdict::Fifo { n: n as u8, filter }
    }

    // --- TX ---

    pub(super) fn tx_configured(&self) -> u32 {
        let txbc = self.regs[idx(TXBC)];
        let n = (((txbc >> 16) & 0x3F) + ((txbc >> 24) & 0x3F)).min(32);
        if n >= 32 {
            u32::MAX
        } else {
            (1 << n) - 1
        }
    }

    /// `TXBC`: (NDTB, TFQS, TFQM): dedicated buffers, TX FIFO/queue elements after them,
    /// queue mode.
    pub(super) fn txbc_fields(&self) -> (u32, u32, bool) {
        let txbc = self.regs[idx(TXBC)];
        (
            (txbc >> 16) & 0x3F,
            (txbc >> 24) & 0x3F,
            txbc & (1 << 30) != 0,
        )
    }

    /// The TX FIFO's buffers (bits NDTB … NDTB + TFQS - 1).
    fn fifo_mask(&self) -> u32 {
        let (ndtb, tfqs, _) = self.txbc_fields();
        self.tx_configured() & !((1u64 << ndtb.min(32)) - 1) as u32 & {
            let end = (ndtb + tfqs).min(32);
            ((1u64 << end) - 1) as u32
        }
    }

    /// Drops cancelled elements at the get index (RM0433: a cancelled request at the get
    /// index moves it on to the next pending element).
    fn txq_skip_cancelled(&mut self) {
        let (ndtb, tfqs, _) = self.txbc_fields();
        while self.txq_fill > 0 && self.txbrp & (1 << (ndtb + self.txq_get)) == 0 {
            self.txq_get = (self.txq_get + 1) % tfqs;
            self.txq_fill -= 1;
        }
    }

    /// `TXFQS` (RM0433 §56.5.33): free level 5:0, get index 12:8, put index 20:16, full 21;
    /// indices are buffer numbers (the FIFO's follow the dedicated buffers).
    pub(super) fn txfqs(&mut self) -> u32 {
        let (ndtb, tfqs, _) = self.txbc_fields();
        if tfqs == 0 {
            return 0;
        }
        self.txq_skip_cancelled();
        let free = tfqs - self.txq_fill;
        let get = ndtb + self.txq_get;
        let put = ndtb + (self.txq_get + self.txq_fill) % tfqs;
        free | get << 8 | put << 16 | u32::from(free == 0) << 21
    }

    pub(super) fn tx_add(&mut self, v: u32) {
        if self.monitoring() {
            // Bus monitoring: TXBRP is held in reset (RM0433 FDCAN "Bus monitoring mode"):
            // the request is dropped.
            if v != 0 {
                self.violations.push(Violation::RequestIgnored {
                    bits: v,
                    cccr: self.regs[idx(CCCR)],
                });
            }
            return;
        }
        let cfg = self.tx_configured();
        if v & !cfg != 0 {
            self.violations
                .push(Violation::UnconfiguredBuffer { bits: v & !cfg });
        }
        let fifo = v & cfg & self.fifo_mask();
        if fifo != 0 {
            let (_, _, queue) = self.txbc_fields();
            if queue {
                self.violations.push(Violation::QueueModeUnmodelled);
            }
            let st = self.txfqs();
            let put = (st >> 16) & 0x1F;
            if st & (1 << 21) != 0 {
                self.violations.push(Violation::FifoFull);
            } else if fifo != 1 << put {
                self.violations
                    .push(Violation::FifoNotAtPutIndex { bits: fifo, put });
            } else {
                self.txbrp |= fifo;
                self.txq_fill += 1;
            }
        }
        self.txbrp |= v & cfg & !self.fifo_mask();
    }

    pub(super) fn tx_cancel(&mut self, v: u32) {
        // Bits of unconfigured buffers and of buffers without a request are ignored.
        self.cancel_requested |= v & self.tx_configured() & self.txbrp;
        if !self.defer_cancel {
            self.complete_cancels();
        }
    }

    /// Requested cancellations complete (`TXBRP` cleared, `TXBCF` set).
    pub fn complete_cancels(&mut self) {
        let c = self.cancel_requested & self.txbrp;
        self.txbrp &= !c;
        self.txbcf |= c;
        if c != 0 {
            self.ir |= IR_TCF;
        }
        self.cancel_requested = 0;
    }

    /// Pending TX buffers.
    pub fn pending(&self) -> u32 {
        self.txbrp
    }

    /// The bus carries up to `n` pending frames, highest priority first; none while the core
    /// is in `INIT`, bus-off, restricted operation (`CCCR.ASM`) or bus monitoring
    /// (`CCCR.MON`). Returns how many. RM0433 §56.4.13/14: the candidates are the
    /// pending dedicated buffers and the TX FIFO's element at its get index (the FIFO's
    /// elements leave in put order); among them the lowest identifier wins, then the lowest
    /// buffer number.
    pub fn bus_sends(&mut self, n: usize) -> usize {
        let txbc = self.regs[idx(TXBC)];
        let tbsa = (txbc >> 2) & 0x3FFF;
        let ew = element_words(self.regs[idx(TXESC)]);
        let (ndtb, tfqs, _) = self.txbc_fields();
        let mut sent = 0;
        // Restricted operation (ASM) and bus monitoring (MON): no data frames sent.
        let restricted = self.regs[idx(CCCR)] & (CCCR_ASM | CCCR_MON) != 0;
        while sent < n
            && !restricted
            && !self.in_init()
            && self.psr & PSR_BO == 0
            && self.txbrp != 0
        {
            self.txq_skip_cancelled();
            let fifo_head = (self.txq_fill > 0).then_some(ndtb + self.txq_get);
            let element = |slot: u32| tbsa + slot * ew;
            let Some(slot) = (0..32)
                .filter(|s| self.txbrp & (1 << s) != 0)
                .filter(|s| *s < ndtb || Some(*s) == fifo_head)
                .min_by_key(|s| {
                    let t0 = self.ram[element(*s) as usize];
                    let key = if t0 & (1 << 30) != 0 {
                        t0 & 0x1FFF_FFFF
                    } else {
                        ((t0 >> 18) & 0x7FF) << 18
                    };
                    (key, *s)
                })
            else {
                break;
            };
            let base = element(slot) as usize;
            let (t0, t1) = (self.ram[base], self.ram[base + 1]);
            let mut data = [0u8; 8];
            data[..4].copy_from_slice(&self.ram[base + 2].to_le_bytes());
            data[4..].copy_from_slice(&self.ram[base + 3].to_le_bytes());
            let extended = t0 & (1 << 30) != 0;
            self.wire.push(BusFrame {
                id: if extended {
                    t0 & 0x1FFF_FFFF
                } else {
                    (t0 >> 18) & 0x7FF
                },
                extended,
                remote: t0 & (1 << 29) != 0,
                dlc: ((t1 >> 16) & 0xF) as u8,
                data,
            });
            if Some(slot) == fifo_head {
                self.txq_get = (self.txq_get + 1) % tfqs;
                self.txq_fill -= 1;
            }
            let b = 1 << slot;
            // A frame on the wire is sent even if its cancellation was requested.
            self.txbrp &= !b;
            self.cancel_requested &= !b;
            self.txbto |= b;
            self.ir |= IR_TC;
            sent += 1;
        }
        sent
    }
}
