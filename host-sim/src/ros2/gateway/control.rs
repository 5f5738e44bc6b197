//! Pause, resume and abort: the peer's stops, as the node's `StopNow`.

use super::*;

impl Gateway {
    /// The node holds or walks some of the plan: a walk, steps it queued or whose append is on
    /// its way, or a start on its way.
    fn node_holds_plan(&self) -> bool {
        self.walking.is_some()
            || self
                .steps
                .iter()
                .any(|s| matches!(s.state, State::Sent | State::Queued))
            || self
                .inflight
                .iter()
                .any(|f| matches!(f.item, Item::Start(..)))
    }

    /// A pause (`true`) or resume (`false`) from the peer; `clear`: drop the held steps.
    ///
    /// A pause holds every step not yet walked, whether the walk has started or not: the node
    /// stops after the step being swung (`StopNow`; standing, it drops its queue) and nothing
    /// else is sent. Lists that come while paused are matched with the held steps and held
    /// too. The resume sends the held steps again, in order, and starts the walk.
    pub fn on_pause(&mut self, id: u32, pause: bool, clear: bool) {
        if pause {
            let planned = self.walking.is_some()
                || !self.deferred.is_empty()
                || self.steps.iter().any(|s| s.unlifted());
            if self.paused || !planned {
                let why = if self.paused {
                    "already paused"
                } else {
                    "no walk to pause"
                };
                return self.refusal(id, 0, -1, "pause", Err("not_walking"), why.into());
            }
            let in_node = self.node_holds_plan();
            self.paused = true;
            let held = if clear { State::Dropped } else { State::Held };
            for s in self.steps.iter_mut().filter(|s| s.unlifted()) {
                s.state = held;
            }
            self.outbox
                .retain(|i| !matches!(i, Item::Append(_) | Item::Modify(..) | Item::Start(..)));
            if in_node {
                self.outbox
                    .push_back(Item::Control(ControlOp::StopNow, Origin::Pause(id)));
            } else {
                self.outputs
                    .push(Output::Walking(WALKING_ABORT_REQUESTED, id));
            }
        } else {
            if !self.paused {
                return self.refusal(id, 0, -1, "resume", Err("not_paused"), "no pause".into());
            }
            // Carried out once the robot stands (appends are refused while it stops).
            self.resume = true;
            self.run_deferred();
        }
    }

    /// The steps a pause held, sent again (new step numbers) in order, and walked.
    pub(super) fn resume_now(&mut self) {
        self.resume = false;
        self.paused = false;
        let held: Vec<usize> = (0..self.steps.len())
            .filter(|&k| self.steps[k].state == State::Held)
            .collect();
        if held.is_empty() {
            return;
        }
        self.batch += 1;
        for &k in &held {
            let mut s = self.steps[k].clone();
            self.steps[k].state = State::Dropped;
            self.steps[k].closed = true;
            (s.state, s.number, s.batch) = (State::Pending, None, self.batch);
            self.steps.push(s);
            self.outbox.push_back(Item::Append(self.steps.len() - 1));
        }
        self.outbox
            .push_back(Item::Start(self.batch, self.adjusting));
    }

    /// An abort from the peer: the node drops every step not yet walked (`StopNow`).
    pub fn on_abort(&mut self, id: u32) {
        let had = self
            .steps
            .iter()
            .any(|s| s.unlifted() || s.state == State::Held)
            || !self.deferred.is_empty();
        let in_node = self.node_holds_plan();
        for s in self
            .steps
            .iter_mut()
            .filter(|s| s.unlifted() || s.state == State::Held)
        {
            s.state = State::Dropped;
        }
        self.deferred.clear();
        self.paused = false;
        self.resume = false;
        self.outbox
            .retain(|i| !matches!(i, Item::Append(_) | Item::Modify(..) | Item::Start(..)));
        if in_node {
            self.outbox
                .push_back(Item::Control(ControlOp::StopNow, Origin::Abort(id)));
        } else if had {
            // Nothing reached the node: the abort is carried out here.
            self.outputs
                .push(Output::Walking(WALKING_ABORT_REQUESTED, id));
            self.close_walk();
        } else {
            self.refusal(id, 0, -1, "abort", Err("not_walking"), "no walk".into());
        }
    }
}
