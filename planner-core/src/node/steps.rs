//! What the node remembers of every footstep it accepted: the append frame, the version in
//! force and its frame. Used to answer repeats (`Duplicate`: a frame equal to the step's append
//! or to its version in force), to refuse late copies of older versions (`Stale`) and to
//! rebuild a modification's position from the appended one.
//!
//! Records follow the gait's queue: appended in order, moved to `swing` when the gait lifts the
//! step off, to `done` (the last [`HISTORY`] steps walked or dropped) after that.

use core::borrow::Borrow;

use crate::gait::PREVIEW;
use crate::shaping::PreviewGains;
use heapless::Deque;

use crate::gait::Gait;
use crate::real::Real;
use crate::wire::{RawFrame, WireStep};

/// Steps walked or dropped whose frames are still recognised as repeats.
pub const HISTORY: usize = 16;

/// One accepted footstep.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Record {
    /// The accepted append (version 0).
    pub append: WireStep,
    /// The step as commanded in force: the append moved by the modification in force (the
    /// node walks it plus the step adjustment's shift).
    pub commanded: WireStep,
    /// Its frame.
    pub append_frame: RawFrame,
    /// Version in force (0: as appended).
    pub version: u8,
    /// The frame of the modification in force, if any.
    pub in_force: Option<RawFrame>,
}

impl Record {
    /// The gait's id of this step: its number less the start-up's first.
    fn id(&self, first: u16) -> u16 {
        self.append.id.wrapping_sub(first)
    }
    fn is_repeat(&self, f: &RawFrame) -> bool {
        self.append_frame == *f || self.in_force == Some(*f)
    }
}

/// The records of the queued steps (in queue order), of the step being swung, and of the last
/// steps done.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Steps<const Q: usize> {
    queued: Deque<Record, Q>,
    swing: Option<Record>,
    done: Deque<Record, HISTORY>,
}

impl<const Q: usize> Steps<Q> {
    /// No records, with every byte zero (see `Node::parked`: `swing` is `Some` of zeros,
    /// whose bytes are the zero ones, where `None` is a niche).
    pub const PARKED: Self = Self {
        queued: Deque::new(),
        swing: Some(Record {
            append: WireStep {
                id: 0,
                left: false,
                x: 0,
                y: 0,
                yaw: 0,
            },
            commanded: WireStep {
                id: 0,
                left: false,
                x: 0,
                y: 0,
                yaw: 0,
            },
            append_frame: RawFrame {
                id: 0,
                len: 0,
                data: [0; 8],
            },
            version: 0,
            in_force: None,
        }),
        done: Deque::new(),
    };

    /// Forgets everything (a `Reset`).
    pub fn clear(&mut self) {
        self.queued.clear();
        self.swing = None;
        self.done.clear();
    }

    /// `true` if `f` equals an accepted append or a version in force. (The first data byte of
    /// a footstep frame is its step id: only that step's records are compared.)
    ///
    /// Numbers are appended in sequence (a `Reset` clears the records), so while the records
    /// hold at most 256 steps no low byte is held twice: the first record with that low byte
    /// decides, and the search stops there.
    pub fn is_repeat(&self, f: &RawFrame) -> bool {
        let id = f.data[0];
        let low = |r: &Record| r.append.id as u8;
        if Q + 1 + HISTORY <= 256 {
            if let Some(r) = self.queued_guess_low(id).and_then(|i| self.queued.get(i)) {
                return r.is_repeat(f);
            }
            let first = self
                .queued
                .iter()
                .chain(self.swing.as_ref())
                .chain(self.done.iter())
                .find(|r| low(r) == id);
            return first.is_some_and(|r| r.is_repeat(f));
        }
        let same = |r: &Record| low(r) == id && r.is_repeat(f);
        self.queued.iter().any(same)
            || self.swing.as_ref().is_some_and(same)
            || self.done.iter().any(same)
    }

    /// The record of queued step `id` and its position among the queued records (for
    /// [`Steps::queued_at_mut`]).
    pub fn queued_find(&self, id: u16) -> Option<(usize, Record)> {
        if let Some(i) = self.queued_guess(id) {
            return self.queued.get(i).map(|r| (i, *r));
        }
        self.queued
            .iter()
            .enumerate()
            .find(|(_, r)| r.append.id == id)
            .map(|(i, r)| (i, *r))
    }

    /// The record of queued step `id`, looked for at `index` first (where
    /// [`Steps::queued_find`] found it), then among all.
    pub fn queued_at_mut(&mut self, index: usize, id: u16) -> Option<&mut Record> {
        let i = if self.queued.get(index).is_some_and(|r| r.append.id == id) {
            Some(index)
        } else {
            self.queued.iter().position(|r| r.append.id == id)
        };
        i.and_then(move |i| self.queued.get_mut(i))
    }

    /// Where queued step `id` is if the queued ids run on from the front's (appends are in
    /// sequence: the common case), checked; `None` if it is not there (then search). Only
    /// while no id is held twice (see [`Steps::is_repeat`]), so the record found is the one.
    fn queued_guess(&self, id: u16) -> Option<usize> {
        if Q + 1 + HISTORY > 256 {
            return None;
        }
        let front = self.queued.front()?.append.id;
        let i = usize::from(id.wrapping_sub(front));
        self.queued
            .get(i)
            .is_some_and(|r| r.append.id == id)
            .then_some(i)
    }

    /// [`Steps::queued_guess`] by the low byte of the number (what a frame carries).
    fn queued_guess_low(&self, low: u8) -> Option<usize> {
        if Q + 1 + HISTORY > 256 {
            return None;
        }
        let front = self.queued.front()?.append.id;
        let i = usize::from(low.wrapping_sub(front as u8));
        self.queued
            .get(i)
            .is_some_and(|r| r.append.id as u8 == low)
            .then_some(i)
    }

    /// Forgets the records of the queued steps after the first `keep` (the gait dropped them:
    /// [`Gait::truncate`]).
    pub fn truncate_queued(&mut self, keep: usize) {
        while self.queued.len() > keep {
            self.queued.pop_back();
        }
    }

    /// Records an accepted append (the gait queued it: there is room).
    pub fn push(&mut self, r: Record) {
        let _ = self.queued.push_back(r);
    }

    fn retire(&mut self, r: Record) {
        if self.done.is_full() {
            self.done.pop_front();
        }
        let _ = self.done.push_back(r);
    }

    /// Follows the gait after it changed: queued steps it no longer has were lifted off (the
    /// one it swings) or dropped; a swing it no longer has has landed.
    /// `first` is the start-up's first step number (gait ids are numbers less it).
    pub fn sync<T: Real, const GQ: usize, G: Borrow<PreviewGains<T, PREVIEW>>>(
        &mut self,
        gait: &Gait<T, GQ, G>,
        first: u16,
    ) {
        // Ids are compared in place; a record is copied only when it moves (no 40-byte copies
        // on the steady cycle, where nothing changes).
        if let Some(id) = self.swing.as_ref().map(|r| r.id(first)) {
            if gait.swinging() != Some(id) {
                if let Some(s) = self.swing.take() {
                    self.retire(s);
                }
            }
        }
        while let Some(id) = self.queued.front().map(|r| r.id(first)) {
            // Still the gait's next target (every steady cycle): no search of its queue.
            if gait.next_target() == Some(id) || gait.is_queued(id) {
                break;
            }
            let Some(r) = self.queued.pop_front() else {
                break;
            };
            if gait.swinging() == Some(r.id(first)) {
                if let Some(s) = self.swing.take() {
                    self.retire(s);
                }
                self.swing = Some(r);
            } else {
                self.retire(r);
            }
        }
    }

    /// The version in force of step `id` (queued, swinging or among the last done), if known.
    pub fn version(&self, id: u16) -> Option<u8> {
        if let Some(r) = self.queued_guess(id).and_then(|i| self.queued.get(i)) {
            return Some(r.version);
        }
        let of = |r: &Record| (r.append.id == id).then_some(r.version);
        self.queued
            .iter()
            .find_map(of)
            .or_else(|| self.swing.as_ref().and_then(of))
            .or_else(|| self.done.iter().rev().find_map(of))
    }

    /// The queued step number `id` as commanded, moved by `shift` \[0.5 mm\]; `None` if it is
    /// not queued or the result leaves the footstep range.
    pub fn commanded(&self, id: u16, shift: [i32; 2]) -> Option<WireStep> {
        let r = match self.queued_guess(id).and_then(|i| self.queued.get(i)) {
            Some(r) => r,
            None => self.queued.iter().find(|r| r.append.id == id)?,
        };
        shifted(&r.commanded, shift)
    }

    /// `true` if every queued step, moved by `shift`, stays inside the footstep range.
    pub fn all_shiftable(&self, shift: [i32; 2]) -> bool {
        self.queued
            .iter()
            .all(|r| shifted(&r.commanded, shift).is_some())
    }

    /// The id of the step being swung, if the node accepted it (padded steps have none).
    pub fn swinging(&self) -> Option<u16> {
        self.swing.map(|r| r.append.id)
    }
}

/// `s` moved by `shift` \[0.5 mm\]; `None` if it leaves the footstep range.
pub(super) fn shifted(s: &WireStep, shift: [i32; 2]) -> Option<WireStep> {
    if shift == [0, 0] {
        return Some(*s); // (a validated step: in range)
    }
    let m = WireStep {
        x: s.x.checked_add(shift[0])?,
        y: s.y.checked_add(shift[1])?,
        ..*s
    };
    m.in_range().then_some(m)
}
