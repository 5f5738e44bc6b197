//! The frames of the queued steps and of the feet before them, kept for the reach checks of a
//! cycle's footstep commands: each command checks its step against the two feet before it and
//! (a modification) its two successors against it, and these are the same queued steps for
//! every command of a cycle. A frame ([`Frame`]: the pose with the sine and cosine of its
//! heading) is computed the first time a check needs it and kept while the gait's footsteps
//! stay as they are ([`Gait::generation`]); the node's own append or modification puts the
//! frame its check computed in place. The frames are a cache: a frame is a function of its
//! footstep, so a check with kept frames is bit for bit the check with fresh ones
//! ([`Node::reach_broken`], which debug builds compare with every check).

use super::*;

/// The kept frames (see the module docs). Every byte zero when nothing is kept (the parked
/// node is all zero).
#[derive(Clone, Debug)]
pub(super) struct FeetFrames<T, const Q: usize> {
    /// Anything is kept, for the gait's footsteps of generation `gen`.
    valid: bool,
    gen: u32,
    /// By queue position: 0 nothing kept, else the side of the step whose frame is kept
    /// ([`LEFT`] or [`RIGHT`]).
    known: [u8; Q],
    frames: [Frame<T>; Q],
    /// The frames of the feet before the queue (by side: the swing target of that side, else
    /// the foot), when kept.
    base_known: [bool; 2],
    base: [Frame<T>; 2],
    /// The frame of the step of the last reach check on the kept frames.
    step: Frame<T>,
}

/// See [`FeetFrames::known`].
const LEFT: u8 = 1;
/// See [`FeetFrames::known`].
const RIGHT: u8 = 2;

fn code(side: Side) -> u8 {
    match side {
        Side::Left => LEFT,
        Side::Right => RIGHT,
    }
}

impl<T: Real, const Q: usize> FeetFrames<T, Q> {
    /// Nothing kept.
    pub(super) const EMPTY: Self = Self {
        valid: false,
        gen: 0,
        known: [0; Q],
        frames: [Frame::ZERO; Q],
        base_known: [false; 2],
        base: [Frame::ZERO; 2],
        step: Frame::ZERO,
    };

    /// Forgets every frame (the gait may change without a new generation: a tick).
    pub(super) fn clear(&mut self) {
        self.valid = false;
    }

    /// The kept frame at `at`.
    fn get(&self, at: At) -> Option<&Frame<T>> {
        match at {
            At::Queued(p) => self.frames.get(p),
            At::Base(k) => self.base.get(k),
        }
    }
}

/// Where a kept frame is: at a queue position, or the foot of a side before the queue.
#[derive(Clone, Copy)]
enum At {
    Queued(usize),
    Base(usize),
}

/// The frames a move of the queued step `id` and the steps after it is checked on (the step
/// adjustment's reach cut, see `adjust`): the feet before it, it and its successor, unmoved.
pub(super) struct MoveFrames<T> {
    other: Frame<T>,
    same: Frame<T>,
    step: Frame<T>,
    side: Side,
    next: Option<(Frame<T>, Side)>,
    from_rest: bool,
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// Empties the kept frames if the gait's footsteps changed.
    fn sync_frames(&mut self) {
        let gen = self.gait.generation();
        let c = &mut self.feet;
        if !c.valid || c.gen != gen {
            c.valid = true;
            c.gen = gen;
            c.known = [0; Q];
            c.base_known = [false; 2];
        }
    }

    /// Keeps the frame of the queued step at position `pos` (if there is one) and returns its
    /// side.
    #[inline(never)]
    fn ensure_at(&mut self, pos: usize) -> Option<Side> {
        match self.feet.known.get(pos) {
            Some(&LEFT) => return Some(Side::Left),
            Some(&RIGHT) => return Some(Side::Right),
            Some(_) => {}
            None => return None,
        }
        let step = self.gait.queued_at(pos)?;
        // The neighbour before it often shares the heading.
        let c = &self.feet;
        let before = match pos.checked_sub(1) {
            Some(p) if c.known.get(p).is_some_and(|&k| k != 0) => c.frames.get(p),
            _ => None,
        };
        let f = match before {
            Some(b) => Frame::like(&step, &[b]),
            None => Frame::of(&step),
        };
        self.keep(pos, f, step.side);
        Some(step.side)
    }

    /// Keeps `f`, the frame of the queued step at `pos` of `side`.
    fn keep(&mut self, pos: usize, f: Frame<T>, side: Side) {
        let c = &mut self.feet;
        if let (Some(slot), Some(k)) = (c.frames.get_mut(pos), c.known.get_mut(pos)) {
            *slot = f;
            *k = code(side);
        }
    }

    /// Keeps the frame of the foot of `side` before the queue.
    #[inline(never)]
    fn ensure_base(&mut self, side: Side) -> At {
        let k = side.index();
        if self.feet.base_known.get(k) != Some(&true) {
            let feet = self.gait.previous_feet(self.gait.next_target());
            let f = Frame::of(&feet[k]);
            let c = &mut self.feet;
            if let (Some(known), Some(slot)) = (c.base_known.get_mut(k), c.base.get_mut(k)) {
                *known = true;
                *slot = f;
            }
        }
        At::Base(k)
    }

    /// Keeps the frame of the foot of `side` before queue position `pos`: the queued step at
    /// `pos − 1` or `pos − 2` (the queue alternates sides), else the foot before the queue.
    #[inline(never)]
    fn ensure_before(&mut self, pos: usize, side: Side) -> Option<At> {
        for back in 1..=2 {
            if let Some(p) = pos.checked_sub(back) {
                if self.ensure_at(p)? == side {
                    return Some(At::Queued(p));
                }
            }
        }
        // No queued step of `side` before `pos`: only if none is (`pos` ≤ 1 alternating).
        if pos >= 2 {
            return None;
        }
        Some(self.ensure_base(side))
    }

    /// [`Node::reach_broken`] with the kept frames (see the module docs); the frame of `step`
    /// is left in [`FeetFrames::step`]. `Err(())` where the kept frames do not apply (the
    /// caller checks afresh).
    pub(super) fn reach_broken_kept(
        &mut self,
        step: &Footstep<T>,
        before: Option<u16>,
    ) -> Result<Option<Broken<T>>, ()> {
        self.sync_frames();
        let pos = match before {
            Some(id) => self.gait.position(id).ok_or(())?,
            None => self.gait.queued(),
        };
        let other = self.ensure_before(pos, step.side.other()).ok_or(())?;
        let same = self.ensure_before(pos, step.side).ok_or(())?;
        // The successors by number, as `reach_broken` takes them: with consecutive numbers
        // (the node's always are) the next positions; anything else is checked afresh.
        let mut next = [None; 2];
        if before.is_some() {
            if !self.gait.consecutive_ids() {
                return Err(());
            }
            let len = self.gait.queued();
            for (k, n) in next.iter_mut().enumerate() {
                let p = pos + k + 1;
                if p >= len {
                    break;
                }
                *n = Some((p, self.ensure_at(p).ok_or(())?));
            }
        }
        let from_rest = pos == 0 && self.gait.next_swing_from_rest();
        let c = &self.feet;
        let (Some(other), Some(same)) = (c.get(other), c.get(same)) else {
            return Err(());
        };
        let f = Frame::like(step, &[other, same]);
        let soles = Soles::of(&self.cfg.params);
        let r = &self.cfg.reach;
        let broken = (|| {
            if let Some(b) = r.broken_frames(other, same, &f, step.side, from_rest, &soles) {
                return Ok(Some(b));
            }
            let Some((p1, s1)) = next[0] else {
                return Ok(None);
            };
            let f1 = c.frames.get(p1).ok_or(())?;
            if let Some(b) = r.broken_frames(&f, other, f1, s1, false, &soles) {
                return Ok(Some(b));
            }
            let Some((p2, s2)) = next[1] else {
                return Ok(None);
            };
            let f2 = c.frames.get(p2).ok_or(())?;
            Ok(r.broken_frames(f1, &f, f2, s2, false, &soles))
        })()?;
        // (Kept in place, not returned: no copies of frames through the results.)
        self.feet.step = f;
        Ok(broken)
    }

    /// The reach check of a footstep command on the kept frames (`Crossing` or `Reach` for a
    /// broken limit, as [`Node::reach_broken`] finds it); `Ok(true)` if the frame of `step`
    /// was computed, to keep once the command is carried out ([`Node::kept_step`]).
    #[inline(never)]
    pub(super) fn check_reach_kept(
        &mut self,
        step: &Footstep<T>,
        before: Option<u16>,
    ) -> Result<bool, Reason> {
        let (broken, kept) = match self.reach_broken_kept(step, before) {
            Ok(b) => (b, true),
            Err(()) => (self.reach_broken(step, before), false),
        };
        #[cfg(debug_assertions)]
        {
            let fresh = self.reach_broken(step, before);
            let same = |a: &Broken<T>, b: &Broken<T>| {
                a.limit == b.limit
                    && a.value.bits() == b.value.bits()
                    && a.bound.bits() == b.bound.bits()
            };
            let agree = match (&broken, &fresh) {
                (None, None) => true,
                (Some(a), Some(b)) => same(a, b),
                _ => false,
            };
            debug_assert!(agree, "kept frames {broken:?}, fresh {fresh:?}");
        }
        match broken {
            None => Ok(kept),
            Some(b) => Err(b.reason()),
        }
    }

    /// The gait's footsteps changed by the node's own command, from generation `gen`: the
    /// step at queue position `pos` is now the one of the last check (its frame is kept if
    /// `kept`), of `side`; the other kept frames stay.
    #[inline(never)]
    pub(super) fn kept_step(&mut self, gen: u32, pos: usize, kept: bool, side: Side) {
        let c = &mut self.feet;
        let now = self.gait.generation();
        if !(c.valid && c.gen == gen && now == gen.wrapping_add(1)) {
            c.clear();
            return;
        }
        c.gen = now;
        if let (Some(slot), Some(k)) = (c.frames.get_mut(pos), c.known.get_mut(pos)) {
            if kept {
                *slot = c.step;
                *k = code(side);
            } else {
                *k = 0;
            }
        }
    }

    /// The kept frames for a move of the queued step `id` ([`Node::reach_broken_move`]); `None`
    /// where they do not apply (the move is then checked afresh).
    pub(super) fn move_frames(&mut self, id: u16) -> Option<MoveFrames<T>> {
        self.sync_frames();
        let pos = self.gait.position(id)?;
        let side = self.ensure_at(pos)?;
        let other = self.ensure_before(pos, side.other())?;
        let same = self.ensure_before(pos, side)?;
        if !self.gait.consecutive_ids() {
            return None;
        }
        let next = if pos + 1 < self.gait.queued() {
            Some((pos + 1, self.ensure_at(pos + 1)?))
        } else {
            None
        };
        let from_rest = pos == 0 && self.gait.next_swing_from_rest();
        let c = &self.feet;
        let next = match next {
            Some((p, s)) => Some((*c.frames.get(p)?, s)),
            None => None,
        };
        Some(MoveFrames {
            other: *c.get(other)?,
            same: *c.get(same)?,
            step: *c.frames.get(pos)?,
            side,
            next,
            from_rest,
        })
    }

    /// [`Node::reach_broken_moved`] on the kept frames `m` of the step: bit for bit the same.
    pub(super) fn reach_broken_move(&self, m: &MoveFrames<T>, delta: [T; 2]) -> Option<Broken<T>> {
        let r = &self.cfg.reach;
        let soles = Soles::of(&self.cfg.params);
        let f = m.step.shifted(delta);
        if let Some(b) = r.broken_frames(&m.other, &m.same, &f, m.side, m.from_rest, &soles) {
            return Some(b);
        }
        let (next, side) = m.next?;
        let f1 = next.shifted(delta);
        r.broken_frames(&f, &m.other, &f1, side, false, &soles)
    }
}
