//! One control cycle ([`Node::poll`]): receive a bounded batch, act on it in priority order
//! (`ESTOP`, `StopNow`, the rest; one step's modifications newest version first; the step
//! adjustment, then the modifications that plan, so that eq. 17 is planned once on the final
//! steps), supervise (the controller's silence by clock and by cycles, the clock itself), tick
//! the gait, publish.

use super::*;

/// The priority class of a command frame: 0 an emergency stop, 1 a stop now (by its op byte;
/// validated when it is handled), 2 the rest.
pub(super) fn rank(f: &RawFrame) -> u8 {
    match f.id {
        ids::ESTOP => 0,
        ids::CONTROL if f.len == 8 && f.data[6] == 3 => 1,
        _ => 2,
    }
}

/// The class by which a cycle's held frames make room for another ([`Node::poll`]'s receive):
/// [`rank`], with the estimator's `MEASURED` below the controller's commands (a state is
/// superseded by the next cycle's).
pub(super) fn keep_rank(f: &RawFrame) -> u8 {
    match f.id {
        ids::MEASURED => 3,
        _ => rank(f),
    }
}

/// `LinkHealth::bus_state` of a link off the bus.
const BUS_OFF: u8 = 3;

/// What the acting of a cycle keeps (see [`Node::poll`]).
pub(super) struct Acting {
    /// Commands refused.
    pub(super) refused: u8,
    /// The last `StopNow` of the batch carried out.
    pub(super) stop_at: Option<usize>,
}

/// The order in which a cycle acts on its held frames `batch` (indices into it): by [`rank`];
/// within a rank in the order of arrival, except that the modifications of one step
/// (`STEP_MODIFY` with the same step number's low byte) are acted on together, where the first
/// of them arrived, newest version first (of equal versions, the first to arrive). One pass
/// gives each frame a key (rank, place of its group, version, arrival) and an insertion sort
/// orders the keys: the frames arrive nearly in that order, so the sort is about linear.
///
/// Out of line: its table is off the stack before the cycle acts.
#[inline(never)]
pub(super) fn act_order(batch: &[RawFrame]) -> heapless::Vec<u8, MAX_RX> {
    let mut order = heapless::Vec::new();
    // (A cycle without modifications, the common one, in its order of arrival by class.)
    if !batch.iter().any(|f| f.id == ids::STEP_MODIFY) {
        for pass in 0..3u8 {
            for (i, f) in batch.iter().enumerate().take(MAX_RX) {
                if rank(f) == pass {
                    let _ = order.push(i as u8);
                }
            }
        }
        return order;
    }
    // The place of each step's first modification (by the low byte of its number).
    let mut first = [u8::MAX; 256];
    let mut keys: heapless::Vec<u32, MAX_RX> = heapless::Vec::new();
    for (i, f) in batch.iter().enumerate().take(MAX_RX) {
        let i = i as u8;
        let (group, newness) = if f.id == ids::STEP_MODIFY {
            let slot = &mut first[usize::from(f.data[0])];
            if *slot == u8::MAX {
                *slot = i;
            }
            (*slot, 0x7F - (f.data[1] & 0x7F))
        } else {
            (i, 0)
        };
        let key = u32::from(rank(f)) << 24
            | u32::from(group) << 16
            | u32::from(newness) << 8
            | u32::from(i);
        // Insertion: shift the greater keys up by one.
        let _ = keys.push(key);
        let mut j = keys.len();
        while j > 1 {
            let (Some(&a), Some(&b)) = (keys.get(j - 2), keys.get(j - 1)) else {
                break;
            };
            if a <= b {
                break;
            }
            if let Some(x) = keys.get_mut(j - 2) {
                *x = b;
            }
            if let Some(x) = keys.get_mut(j - 1) {
                *x = a;
            }
            j -= 1;
        }
    }
    for k in &keys {
        let _ = order.push(*k as u8);
    }
    order
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// The clock check and the supervision rule (module docs, step 3): a moving robot whose
    /// controller has not been heard for longer than the timeout (by the clock or by the
    /// cycles), whose clock has stopped, or whose link was off the bus for more than
    /// [`OFF_BUS_CYCLES`] cycles, stops, and stays "controller lost". Checked in
    /// every cycle, so it holds for the whole walk.
    pub(super) fn supervise(&mut self, now_ms: u32) {
        if self.cycle == 1 {
            self.window = (self.cycle, now_ms);
        } else if self.cycle.wrapping_sub(self.window.0) >= CLOCK_WINDOW {
            // At least half of the window's nominal time.
            let elapsed = now_ms.wrapping_sub(self.window.1);
            if elapsed < self.window_ms / 2 {
                self.clock_fault = true;
            }
            self.window = (self.cycle, now_ms);
        }
        if self.clock_fault && self.open {
            self.lost = true;
        }
        // The link: cycles in a row off the bus.
        let off = self.link.is_some_and(|l| l.bus_state == BUS_OFF);
        self.off_bus = if off {
            self.off_bus.saturating_add(1)
        } else {
            0
        };
        if self.off_bus > OFF_BUS_CYCLES && self.open && !self.gait.is_standing() {
            self.lost = true;
        }
        if self.gait.is_standing() {
            return;
        }
        let silent = match self.last_heard {
            Some(heard) => {
                now_ms.wrapping_sub(heard) > self.cfg.heartbeat_timeout_ms
                    || self.cycle.wrapping_sub(self.heard_cycle) > self.timeout_cycles
            }
            None => true,
        };
        if silent && !self.lost {
            self.lost = true;
        }
        if self.lost && (self.gait.queued() > 0 || !self.gait.is_stopping()) {
            self.gait.clear_and_stop();
            self.steps.sync(&self.gait, self.first);
        }
    }

    /// Holds the command frame `f` among the cycle's `batch` (at most `max` frames): returns
    /// the frame left out, if any (`f`, or the newest held frame of the lowest class below
    /// `f`'s, whose place `f` takes; the others keep their order of arrival).
    pub(super) fn hold(
        &self,
        batch: &mut heapless::Vec<RawFrame, MAX_RX>,
        max: usize,
        f: RawFrame,
    ) -> Option<RawFrame> {
        if batch.len() < max {
            return batch.push(f).err();
        }
        let mine = keep_rank(&f);
        let mut worst: Option<(usize, u8)> = None;
        for (i, g) in batch.iter().enumerate() {
            let k = keep_rank(g);
            if k > mine && worst.is_none_or(|(_, w)| k >= w) {
                worst = Some((i, k));
            }
        }
        let Some((i, _)) = worst else {
            return Some(f);
        };
        // The others in their order, then `f` (built anew: no index or rotation that could
        // panic; only when the held frames are full).
        let out = batch.get(i).copied();
        let mut kept: heapless::Vec<RawFrame, MAX_RX> = heapless::Vec::new();
        for (j, g) in batch.iter().enumerate() {
            if j != i {
                let _ = kept.push(*g);
            }
        }
        let _ = kept.push(f);
        *batch = kept;
        out
    }

    /// `true` if `decoded` is a footstep command whose own work no longer fits the cycle's
    /// budget (an append's, or the checks of a modification that does not plan): it is refused
    /// `Busy` before its reach checks, so that a refusal for the budget costs little more than
    /// it spends. (A repeat, a stale version or an append out of sequence is left to its own
    /// answer, which carries out nothing either; a modification that plans, to its checks.)
    fn over_budget(&self, decoded: &Result<Command, (Reason, u8)>) -> bool {
        match decoded {
            Ok(Command::Append(s)) => s.id == self.next_step() && self.afford(WORK_APPEND).is_err(),
            Ok(Command::Modify(m)) => {
                self.afford(WORK_STEP).is_err()
                    && !self.plans_modify(self.gait_id(m.id))
                    && self
                        .steps
                        .queued_find(m.id)
                        .is_some_and(|(_, r)| m.is_newer_than(r.version))
            }
            _ => false,
        }
    }

    /// Refuses the command frame `f`, `decoded`, `Busy`, unread beyond its decoding.
    fn busy(&mut self, f: &RawFrame, decoded: &Result<Command, (Reason, u8)>, act: &mut Acting) {
        self.refuse(Reason::Busy);
        let ack = self.refusal(f, decoded, Reason::Busy);
        act.refused = act.refused.saturating_add(1);
        self.enqueue(ack.encode());
    }

    pub(super) fn enqueue(&mut self, f: RawFrame) {
        if self.tx.push_back(f).is_err() {
            self.counters.tx_dropped = self.counters.tx_dropped.saturating_add(1);
        }
    }

    /// One control cycle (see the module docs).
    pub fn poll<C>(&mut self, now_ms: u32, can: &mut C) -> PollReport<T>
    where
        C: embedded_can::nb::Can,
    {
        self.cycle = self.cycle.wrapping_add(1);
        // 1. Receive: everything waiting, up to `max_frames` frames of all kinds; the node's
        // commands are held (at most `max_rx`), the others counted. When the held frames are
        // full, a frame of a higher class (`keep_rank`: an `ESTOP`, a `StopNow`, a controller's
        // command before an estimator's state) takes the place of the newest one of the
        // lowest class held; the frame left out is answered `Busy` after the cycle.
        let mut batch: heapless::Vec<RawFrame, MAX_RX> = heapless::Vec::new();
        let mut left_out: heapless::Vec<RawFrame, TX_BACKLOG> = heapless::Vec::new();
        let mut received = 0u8;
        let mut drained = 0usize;
        let max_rx = self.cfg.max_rx.min(MAX_RX);
        while drained < self.cfg.max_frames {
            match can.receive() {
                Ok(f) => {
                    drained += 1;
                    received = received.saturating_add(1);
                    // Extended and remote frames are not ours either.
                    match RawFrame::from_frame(&f).filter(|r| ids::is_command(r.id)) {
                        Some(raw) => {
                            let out = self.hold(&mut batch, max_rx, raw);
                            if let Some(out) = out {
                                self.refuse(Reason::Busy);
                                if left_out.push(out).is_err() {
                                    // (its answer could not be queued either)
                                    self.counters.tx_dropped =
                                        self.counters.tx_dropped.saturating_add(1);
                                }
                            }
                        }
                        None => {
                            self.counters.foreign = self.counters.foreign.saturating_add(1);
                        }
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => {
                    self.counters.bus_errors = self.counters.bus_errors.saturating_add(1);
                    break;
                }
            }
        }
        // 2. Act in priority order: emergency stops, stops now, then the rest as they came,
        // with the modifications of one step together, newest version first (the first one
        // accepted is in force, the older ones are then `Stale` by the version rule; a newer
        // one refused leaves an older one its turn). The order is read from the frames' bytes
        // (class, step number's low byte, version), each frame is read when it is acted on.
        let order = act_order(&batch);
        // The step adjustment's share of the budget is kept from the commands (a walk that
        // adjusts: the commands cannot crowd out a capture step).
        let budget = self.cfg.work_budget;
        let reserve = if self.adjusts() {
            WORK_ADJUST.min(budget)
        } else {
            0
        };
        self.plans_left = self.cfg.max_plans;
        self.work_left = budget.saturating_sub(reserve);
        // The frames kept for the reach checks are this phase's (the tick moved the feet).
        self.feet.clear();
        let mut act = Acting {
            refused: 0,
            stop_at: None,
        };
        // A modification that plans (eq. 17: the next swing target while walking) waits for
        // the end of the command phase, with its work kept: it is then checked once on the
        // final steps.
        // (By a mask and the next step number each was read with: read again then, as it was.)
        let mut later: u64 = 0;
        let mut later_next = [0u16; MAX_RX];
        // The first of them keeps its work from the commands after it (the next swing target
        // is the one whose change cannot wait).
        let mut kept_for_later = 0;
        for &i in &order {
            let Some(f) = batch.get(usize::from(i)) else {
                continue;
            };
            let decoded = Command::decode(f, self.expect());
            if matches!(decoded, Ok(Command::EmergencyStop { .. })) {
                self.estop_now = true;
            }
            if self.plans_later(f, &decoded) {
                if let Some(n) = later_next.get_mut(usize::from(i)) {
                    *n = self.next_step();
                    if later == 0 && self.afford(WORK_STEP + WORK_PLAN).is_ok() {
                        kept_for_later = WORK_STEP + WORK_PLAN;
                        self.spend(kept_for_later);
                    }
                    later |= 1 << (i & 63);
                    continue;
                }
            }
            let stale = act.stop_at.is_some_and(|s| usize::from(i) < s);
            if !stale && self.over_budget(&decoded) {
                self.busy(f, &decoded, &mut act);
                continue;
            }
            let stop_now = rank(f) == 1;
            let accepted = self.act(usize::from(i), f, decoded, &mut act, now_ms);
            if stop_now && accepted {
                act.stop_at = Some(usize::from(i));
            }
        }
        // The step adjustment, with its share and what the commands left, then the
        // modifications that plan, if the adjustment did not plan.
        self.work_left = self.work_left.saturating_add(reserve);
        self.adjust_step();
        self.work_left = self.work_left.saturating_add(kept_for_later);
        for &i in order.iter().filter(|_| later != 0) {
            let (Some(f), Some(&next_step)) =
                (batch.get(usize::from(i)), later_next.get(usize::from(i)))
            else {
                continue;
            };
            if later & (1 << (i & 63)) == 0 {
                continue;
            }
            let expect = Expect {
                next_step,
                epoch: self.epoch,
                last_seq: self.last_seq,
            };
            let decoded = Command::decode(f, expect);
            self.act(usize::from(i), f, decoded, &mut act, now_ms);
        }
        // The steps the node chooses itself, topped up with what the commands left.
        let drives = self.drive.driver != drive::Driver::Steps;
        if drives {
            self.drive_ahead();
        }
        let refused = act.refused;
        self.estop_now = false;
        self.feet.clear();
        // (`Node::handle` outside a cycle: the budget of one.)
        self.plans_left = self.cfg.max_plans;
        self.work_left = self.cfg.work_budget;
        // 3. Supervision, 4. the gait's tick (only in a session: nothing moves before it).
        if drives {
            self.drive_supervise(now_ms);
        }
        self.supervise(now_ms);
        let streaming = self.open;
        let reference = if streaming {
            let r = self.gait.tick();
            self.steps.sync(&self.gait, self.first);
            r
        } else {
            *self.gait.last()
        };
        // The shift ends with its walk, and so does a velocity or a goal.
        self.end_of_walk();
        if drives {
            self.drive_end();
        }
        // A stale reference in the backlog is dropped: the new one supersedes it. (One pass
        // of pop and push rather than `Deque::retain`, whose heapless implementation keeps
        // panicking branches the optimiser cannot remove: see firmware/nopanic.)
        for _ in 0..self.tx.len() {
            if let Some(f) = self.tx.pop_front() {
                if matches!(
                    f.id,
                    ids::ACK | ids::ADJUST | ids::STATUS | ids::DIAG | ids::LINK | ids::SESSION
                ) {
                    let _ = self.tx.push_back(f);
                }
            }
        }
        // `ADJUST` (before the stream: frames go out in identifier order) when the shift
        // changed, and every 20 cycles half-way between the reports (the bus load spread:
        // no cycle carries more than one report frame beyond the stream's and the reports')
        // while the walk adjusts, or once the session has adjusted (the shift in force, or
        // its end with the walk).
        let adjusting = self.adj.enabled || self.adj.shift != [0, 0] || self.adj.count > 0;
        if (streaming && self.adj.due) || (adjusting && self.cycle % 20 == 11) {
            self.adj.due = false;
            let a = self.adjustment().encode();
            self.enqueue(a);
        }
        if streaming {
            for f in self.stream(&reference).encode() {
                self.enqueue(f);
            }
        }
        if self.cycle % 20 == 1 {
            let s = self.status().encode();
            self.enqueue(s);
            let d = self.diag().encode();
            self.enqueue(d);
            let e = self.session().encode();
            self.enqueue(e);
            if let Some(l) = self.link {
                self.enqueue(l.encode());
            }
        }
        // The frames left out of the cycle, refused `Busy` (they changed nothing): after the
        // stream and the reports, so that a flood cannot push those out of the backlog.
        let expect = self.expect();
        for f in &left_out {
            let decoded = Command::decode(f, expect);
            let a = self.refusal(f, &decoded, Reason::Busy).encode();
            self.enqueue(a);
        }
        let refused = refused.saturating_add(left_out.len().min(255) as u8);
        let mut sent = 0u8;
        while let Some(raw) = self.tx.pop_front() {
            let Some(frame) = raw.to_frame::<C::Frame>() else {
                continue;
            };
            match can.transmit(&frame) {
                Ok(displaced) => {
                    sent = sent.saturating_add(1);
                    if let Some(d) = displaced.as_ref().and_then(RawFrame::from_frame) {
                        let _ = self.tx.push_front(d);
                        break;
                    }
                }
                Err(nb::Error::WouldBlock) => {
                    let _ = self.tx.push_front(raw);
                    break;
                }
                Err(nb::Error::Other(_)) => {
                    self.counters.bus_errors = self.counters.bus_errors.saturating_add(1);
                    let _ = self.tx.push_front(raw);
                    break;
                }
            }
        }
        PollReport {
            reference,
            received,
            refused,
            sent,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The acting order by its definition: by class, in the order of arrival, each step's
    /// modifications together where the first arrived, newest version first (of equal
    /// versions the first to arrive), found by scanning the batch.
    fn scanned(batch: &[RawFrame]) -> Vec<u8> {
        let mut order = vec![];
        let mut placed = vec![false; batch.len()];
        for pass in 0..3u8 {
            for (i, f) in batch.iter().enumerate() {
                if rank(f) != pass || placed[i] {
                    continue;
                }
                let same_step = |g: &RawFrame| g.id == ids::STEP_MODIFY && g.data[0] == f.data[0];
                if f.id != ids::STEP_MODIFY {
                    placed[i] = true;
                    order.push(i as u8);
                    continue;
                }
                loop {
                    let mut newest: Option<(usize, u8)> = None;
                    for (j, g) in batch.iter().enumerate().skip(i) {
                        let version = g.data[1] & 0x7F;
                        if !placed[j] && same_step(g) && newest.is_none_or(|(_, v)| version > v) {
                            newest = Some((j, version));
                        }
                    }
                    let Some((j, _)) = newest else {
                        break;
                    };
                    placed[j] = true;
                    order.push(j as u8);
                }
            }
        }
        order
    }

    /// Random batches of every class (emergency stops, stops now, other control commands,
    /// appends, measured states, modifications of a few steps in a few versions): the sorted
    /// order is the scanned one.
    #[test]
    fn the_acting_order_is_the_scanned_one() {
        let mut seed = 0x2545_F491_4F6C_DD1Du64;
        let mut next = |n: u64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed % n
        };
        for _ in 0..2000 {
            let len = next(MAX_RX as u64 + 1) as usize;
            let batch: Vec<RawFrame> = (0..len)
                .map(|_| {
                    let mut data = [0u8; 8];
                    let id = match next(6) {
                        0 => ids::ESTOP,
                        1 => {
                            data[6] = if next(2) == 0 { 3 } else { 1 };
                            ids::CONTROL
                        }
                        2 => ids::STEP_APPEND,
                        3 => ids::MEASURED,
                        _ => {
                            data[0] = next(4) as u8;
                            data[1] = next(256) as u8;
                            ids::STEP_MODIFY
                        }
                    };
                    RawFrame::new(id, &data).unwrap()
                })
                .collect();
            let sorted: Vec<u8> = act_order(&batch).iter().copied().collect();
            assert_eq!(sorted, scanned(&batch), "{batch:?}");
        }
    }
}
