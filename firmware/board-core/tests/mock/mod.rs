//! A model of the FDCAN peripheral behind `board_core::Fdcan`: RX FIFO0 of a given depth that
//! drops (and flags) frames when full, optionally an RX FIFO1 that takes `ESTOP` (as the
//! board's filters route it), 16 dedicated TX buffers and a TX FIFO of 16 that the "bus"
//! sends by identifier priority (the FIFO's oldest element competing, as buffer 16), cancellation (immediate or deferred), PSR/ECR and CCCR.INIT. (The register-level
//! model of the real path is `regmodel`, used by `fdcan_model.rs`.)

use std::collections::VecDeque;

use board_core::link::{TX_FIFO, TX_SLOTS};
use board_core::{ClassicFrame, Fdcan};
use embedded_can::{Frame, StandardId};
use planner_core::wire::ids;

pub struct MockFdcan {
    pub rx_depth: usize,
    pub rx: VecDeque<[u32; 4]>,
    /// `ESTOP` goes into RX FIFO1 (`rx1`, of the same depth), as on the board; else every
    /// frame into FIFO0.
    pub estop_fifo1: bool,
    pub rx1: VecDeque<[u32; 4]>,
    pub rx_lost_flag: bool,
    /// Elements that arrive at the first `rx_pop` (a burst during the node's poll).
    pub burst: Vec<[u32; 4]>,
    pub slots: [Option<[u32; 4]>; TX_SLOTS],
    /// The TX FIFO, oldest first.
    pub fifo: VecDeque<[u32; 4]>,
    /// Cancellations requested and not completed (deferred mode).
    pub cancel_requested: u32,
    pub defer_cancel: bool,
    pub psr: u32,
    pub ecr: u32,
    pub init: bool,
    pub leave_init_calls: u32,
    /// Frames the bus carried, in order.
    pub wire: Vec<ClassicFrame>,
    pub cancelled: Vec<ClassicFrame>,
}

impl MockFdcan {
    pub fn new(rx_depth: usize) -> Self {
        Self {
            rx_depth,
            rx: VecDeque::new(),
            estop_fifo1: false,
            rx1: VecDeque::new(),
            rx_lost_flag: false,
            burst: Vec::new(),
            slots: [None; TX_SLOTS],
            fifo: VecDeque::new(),
            cancel_requested: 0,
            defer_cancel: false,
            psr: 0,
            ecr: 0,
            init: false,
            leave_init_calls: 0,
            wire: Vec::new(),
            cancelled: Vec::new(),
        }
    }

    /// A frame arrives from the bus (dropped and flagged if the FIFO is full).
    pub fn arrive(&mut self, e: [u32; 4]) {
        let estop = (e[0] >> 18) & 0x7FF == u32::from(ids::ESTOP);
        let fifo = if self.estop_fifo1 && estop {
            &mut self.rx1
        } else {
            &mut self.rx
        };
        if fifo.len() >= self.rx_depth {
            self.rx_lost_flag = true;
        } else {
            fifo.push_back(e);
        }
    }

    /// The bus sends up to `n` pending frames, lowest identifier first (then lowest buffer).
    pub fn bus_sends(&mut self, n: usize) {
        for _ in 0..n {
            let next = (0..TX_SLOTS)
                .filter_map(|i| self.slots[i].map(|e| (e[0] >> 18, i)))
                .chain(self.fifo.front().map(|e| (e[0] >> 18, TX_SLOTS)))
                .min();
            let Some((_, i)) = next else { return };
            let e = if i == TX_SLOTS {
                self.fifo.pop_front().unwrap()
            } else {
                self.slots[i].take().unwrap()
            };
            self.cancel_requested &= !(1 << i);
            self.wire.push(ClassicFrame::from_element(&e).unwrap());
        }
    }

    /// Deferred cancellations complete.
    pub fn complete_cancels(&mut self) {
        for i in 0..TX_SLOTS {
            if self.cancel_requested & (1 << i) != 0 {
                if let Some(e) = self.slots[i].take() {
                    self.cancelled.push(ClassicFrame::from_element(&e).unwrap());
                }
            }
        }
        self.cancel_requested = 0;
    }

    pub fn pending_count(&self) -> usize {
        self.slots.iter().filter(|s| s.is_some()).count() + self.fifo.len()
    }
}

impl Fdcan for MockFdcan {
    fn rx_pop(&mut self) -> Option<[u32; 4]> {
        for e in std::mem::take(&mut self.burst) {
            self.arrive(e);
        }
        self.rx.pop_front()
    }
    fn rx_pop_fifo1(&mut self) -> Option<[u32; 4]> {
        if self.estop_fifo1 {
            self.rx1.pop_front()
        } else {
            None
        }
    }
    fn rx_take_lost(&mut self) -> bool {
        std::mem::take(&mut self.rx_lost_flag)
    }
    fn tx_pending(&self) -> u32 {
        (0..TX_SLOTS)
            .filter(|&i| self.slots[i].is_some())
            .fold(0, |m, i| m | 1 << i)
    }
    fn tx_start(&mut self, slot: usize, element: &[u32; 4]) {
        assert!(
            self.slots[slot].is_none(),
            "buffer {slot} written while pending"
        );
        self.slots[slot] = Some(*element);
    }
    fn tx_fifo_put(&mut self, element: &[u32; 4]) -> bool {
        if self.fifo.len() >= TX_FIFO {
            return false;
        }
        self.fifo.push_back(*element);
        true
    }
    fn tx_cancel(&mut self, mask: u32) {
        self.cancel_requested |= mask & self.tx_pending();
        if !self.defer_cancel {
            self.complete_cancels();
        }
    }
    fn protocol_status(&self) -> u32 {
        self.psr
    }
    fn error_counters(&self) -> u32 {
        self.ecr
    }
    fn in_init(&self) -> bool {
        self.init
    }
    fn leave_init(&mut self) {
        self.init = false;
        self.leave_init_calls += 1;
    }
    fn take_ram_failure(&mut self) -> bool {
        false
    }
}

pub fn frame(id: u16, data: &[u8]) -> ClassicFrame {
    ClassicFrame::new(StandardId::new(id).unwrap(), data).unwrap()
}
