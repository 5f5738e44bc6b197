//! The velocity walk of the fault sweep ([`super::Walk::Velocity`]): a stick that streams
//! `VELOCITY` every [`crate::sim::STREAM_TICKS`] (50 ms), as `run` does for a scenario's
//! velocity entries, each frame with a new sequence number (the stream is its own
//! retransmission: a lost frame is replaced by the next one), and what the node did with the
//! frames, as its state tells ([`VelocityRun`]).

use std::collections::HashMap;

use planner_core::node::{Node, NodeState};
use planner_core::wire::{Ack, Command, Reason};

use super::VelocityRun;
use crate::scenario::wire::Controller;

/// The stick: the velocity it holds, its frames sent, and the node's uptake of them.
#[derive(Default)]
pub(super) struct Stick {
    /// The velocity held, once the scenario gave one.
    held: Option<(f64, f64, f64)>,
    /// The tick of the last frame sent.
    sent_at: u64,
    /// Every frame sent: sequence number → (velocity as the wire carries it, tick sent).
    sent: HashMap<u32, ((f64, f64, f64), u64)>,
    /// The node's last accepted sequence number seen after its previous cycle.
    last_seq: u32,
    /// The greatest sequence number of a `VELOCITY` the node took.
    newest: u32,
    /// The tick the controller fell silent (`silence`), as the run's tick count.
    silent_from: Option<u64>,
    /// The node was lost (controller lost) at some cycle.
    lost: bool,
    run: VelocityRun,
}

impl Stick {
    /// A stick whose controller falls silent at tick `silent_from` (`silence`), if ever.
    pub(super) fn new(silent_from: Option<u64>) -> Self {
        Self {
            silent_from,
            ..Self::default()
        }
    }

    /// The scenario's stick moves to `v` at tick `k`: sent at once.
    pub(super) fn hold(&mut self, v: (f64, f64, f64), k: u64, ctl: &mut Controller) -> Command {
        self.held = Some(v);
        self.frame(k, ctl)
    }

    /// The stream's frame due at tick `k`, if any.
    pub(super) fn due(&mut self, k: u64, ctl: &mut Controller) -> Option<Command> {
        (self.held.is_some() && k >= self.sent_at + crate::sim::STREAM_TICKS)
            .then(|| self.frame(k, ctl))
    }

    fn frame(&mut self, k: u64, ctl: &mut Controller) -> Command {
        let (vx, vy, wz) = self.held.unwrap_or_default();
        let c = ctl.velocity(vx, vy, wz);
        if let Command::Velocity(w) = c {
            self.sent.insert(w.seq, (w.si_in::<f64>(), k));
        }
        self.sent_at = k;
        self.run.sent += 1;
        c
    }

    /// After the node's cycle at tick `k`: its answers to `VELOCITY` (`acks`, as it sent them)
    /// and its state.
    pub(super) fn observe<const Q: usize>(
        &mut self,
        k: u64,
        node: &Node<Q>,
        acks: impl Iterator<Item = Ack>,
    ) {
        for a in acks.filter(|a| a.command == super::VELOCITY_CODE) {
            match a.reason {
                None => self.run.taken += 1,
                Some(Reason::Stale | Reason::Duplicate) => self.run.refused_old += 1,
                Some(Reason::BadCrc) => self.run.refused_crc += 1,
                Some(_) => self.run.refused_other += 1,
            }
        }
        let seq = node.session().last_seq;
        if seq != self.last_seq {
            if let Some(&(v, at)) = self.sent.get(&seq) {
                // A `VELOCITY` taken last in this cycle: newer than every one taken before,
                // and the velocity in force is the one it carries (unless cut).
                if seq <= self.newest {
                    self.run.old_taken += 1;
                }
                self.newest = seq;
                self.run.max_age_taken = self.run.max_age_taken.max(k - at);
                if self.lost {
                    self.run.taken_after_lost += 1;
                }
                match node.drive_velocity() {
                    Some((d, cut)) if !cut.any() => {
                        let off = (d.vx - v.0).abs() + (d.vy - v.1).abs() + (d.wz - v.2).abs();
                        self.run.wrong_velocity += usize::from(off > 1e-9);
                    }
                    Some(_) => {}
                    None => self.run.wrong_velocity += 1,
                }
            }
            self.last_seq = seq;
        }
        self.lost |= node.state() == NodeState::ControllerLost;
        if let Some(s) = self.silent_from.filter(|s| k >= *s) {
            if node.state() == NodeState::ControllerLost && self.run.lost_after.is_none() {
                self.run.lost_after = Some(k - s);
            }
            if node.gait().is_standing() && self.run.standing_after.is_none() {
                self.run.standing_after = Some(k - s);
            }
        }
    }

    /// What the run counted.
    pub(super) fn finish(self) -> VelocityRun {
        self.run
    }
}
