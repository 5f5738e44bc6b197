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
    /// Queue positions whose frame is kept, and of those the left steps.
    known: u128,
    left: u128,
    frames: [Frame<T>; Q],
    /// The frames of the feet before the queue (by side: the swing target of that side, else
    /// the foot), when kept.
    base_known: [bool; 2],
    base: [Frame<T>; 2],
}

impl<T: Real, const Q: usize> FeetFrames<T, Q> {
    /// Nothing kept.
    pub(super) const EMPTY: Self = Self {
        valid: false,
        gen: 0,
        known: 0,
        left: 0,
        frames: [Frame::ZERO; Q],
        base_known: [false; 2],
        base: [Frame::ZERO; 2],
    };

    /// Forgets every frame (the gait may change without a new generation: a tick).
    pub(super) fn clear(&mut self) {
        self.valid = false;
    }
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

/// Bit `i` of a mask over queue positions (`Q` ≤ 128).
const fn bit(i: usize) -> u128 {
    1u128 << (i & 127)
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> Node<Q, G, T> {
    /// The kept frames, for the gait as it is now (emptied if its footsteps changed).
    fn feet_frames(&mut self) -> &mut FeetFrames<T, Q> {
        let gen = self.gait.generation();
        let c = &mut self.feet;
        if !c.valid || c.gen != gen {
            c.valid = true;
            c.gen = gen;
            c.known = 0;
            c.left = 0;
            c.base_known = [false; 2];
        }
        c
    }

    /// The frame of the queued step at position `pos` and its side, if there is one.
    fn frame_at(&mut self, pos: usize) -> Option<(Frame<T>, Side)> {
        let c = self.feet_frames();
        if c.known & bit(pos) != 0 {
            let side = if c.left & bit(pos) != 0 {
                Side::Left
            } else {
                Side::Right
            };
            return c.frames.get(pos).map(|f| (*f, side));
        }
        let step = self.gait.queued_at(pos)?;
        // The neighbour before it often shares the heading.
        let before = pos
            .checked_sub(1)
            .and_then(|p| {
                let c = &self.feet;
                (c.known & bit(p) != 0).then(|| c.frames.get(p).copied())
            })
            .flatten();
        let f = match &before {
            Some(b) => Frame::like(&step, &[b]),
            None => Frame::of(&step),
        };
        self.keep(pos, f, step.side);
        Some((f, step.side))
    }

    /// Keeps `f`, the frame of the queued step at `pos` of `side`.
    fn keep(&mut self, pos: usize, f: Frame<T>, side: Side) {
        let c = &mut self.feet;
        if let Some(slot) = c.frames.get_mut(pos) {
            *slot = f;
            c.known |= bit(pos);
            if side == Side::Left {
                c.left |= bit(pos);
            } else {
                c.left &= !bit(pos);
            }
        }
    }

    /// The frame of the foot of `side` before the queue.
    fn base_frame(&mut self, side: Side) -> Frame<T> {
        let k = side.index();
        let c = self.feet_frames();
        if let (Some(true), Some(f)) = (c.base_known.get(k), c.base.get(k)) {
            return *f;
        }
        let feet = self.gait.previous_feet(self.gait.next_target());
        let f = Frame::of(&feet[k]);
        let c = &mut self.feet;
        if let (Some(known), Some(slot)) = (c.base_known.get_mut(k), c.base.get_mut(k)) {
            *known = true;
            *slot = f;
        }
        f
    }

    /// The foot of `side` before queue position `pos`: the queued step at `pos − 1` or `pos − 2`
    /// (the queue alternates sides), else the foot before the queue.
    fn frame_before(&mut self, pos: usize, side: Side) -> Option<Frame<T>> {
        for back in 1..=2 {
            if let Some(p) = pos.checked_sub(back) {
                let (f, s) = self.frame_at(p)?;
                if s == side {
                    return Some(f);
                }
            }
        }
        // No queued step of `side` before `pos`: only if none is (`pos` ≤ 1 alternating).
        if pos >= 2 {
            return None;
        }
        Some(self.base_frame(side))
    }

    /// [`Node::reach_broken`] with the kept frames (see the module docs), and the frame of
    /// `step`: `Err(())` where the kept frames do not apply (the caller checks afresh).
    pub(super) fn reach_broken_kept(
        &mut self,
        step: &Footstep<T>,
        before: Option<u16>,
    ) -> Result<(Option<Broken<T>>, Frame<T>), ()> {
        let pos = match before {
            Some(id) => self.gait.position(id).ok_or(())?,
            None => self.gait.queued(),
        };
        let other = self.frame_before(pos, step.side.other()).ok_or(())?;
        let same = self.frame_before(pos, step.side).ok_or(())?;
        let f = Frame::like(step, &[&other, &same]);
        let from_rest = pos == 0 && self.gait.next_swing_from_rest();
        let soles = Soles::of(&self.cfg.params);
        let r = self.cfg.reach;
        let broken = r.broken_frames(&other, &same, &f, step.side, from_rest, &soles);
        if broken.is_some() || before.is_none() {
            return Ok((broken, f));
        }
        // (The successors by number, as `reach_broken` takes them: the node's queued numbers
        // are consecutive, so they are the next positions; anything else is checked afresh.)
        let id = before.ok_or(())?;
        let next = |node: &Self, k: u16| match node.gait.position(id.wrapping_add(k)) {
            Some(p) if p == pos + usize::from(k) => Ok(true),
            Some(_) => Err(()),
            None => Ok(false),
        };
        if !next(self, 1)? {
            return Ok((None, f));
        }
        let Some((f1, s1)) = self.frame_at(pos + 1) else {
            return Ok((None, f));
        };
        if let Some(b) = r.broken_frames(&f, &other, &f1, s1, false, &soles) {
            return Ok((Some(b), f));
        }
        if !next(self, 2)? {
            return Ok((None, f));
        }
        let Some((f2, s2)) = self.frame_at(pos + 2) else {
            return Ok((None, f));
        };
        Ok((r.broken_frames(&f1, &f, &f2, s2, false, &soles), f))
    }

    /// The reach check of a footstep command on the kept frames (`Crossing` or `Reach` for a
    /// broken limit, as [`Node::reach_broken`] finds it); the
    /// frame of `step`, to keep once the command is carried out ([`Node::kept_step`]).
    pub(super) fn check_reach_kept(
        &mut self,
        step: &Footstep<T>,
        before: Option<u16>,
    ) -> Result<Option<Frame<T>>, Reason> {
        let (broken, frame) = match self.reach_broken_kept(step, before) {
            Ok((b, f)) => (b, Some(f)),
            Err(()) => (self.reach_broken(step, before), None),
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
            None => Ok(frame),
            Some(b) => Err(b.reason()),
        }
    }

    /// The gait's footsteps changed by the node's own command, from generation `gen`: the
    /// step at queue position `pos` is now the one of `frame` (its check's), of `side`; the
    /// other kept frames stay.
    pub(super) fn kept_step(&mut self, gen: u32, pos: usize, frame: Option<Frame<T>>, side: Side) {
        let c = &self.feet;
        let now = self.gait.generation();
        if !(c.valid && c.gen == gen && now == gen.wrapping_add(1)) {
            self.feet.clear();
            return;
        }
        self.feet.gen = now;
        match frame {
            Some(f) => self.keep(pos, f, side),
            None => self.feet.known &= !bit(pos),
        }
    }

    /// The kept frames for a move of the queued step `id` ([`Node::reach_broken_move`]); `None`
    /// where they do not apply (the move is then checked afresh).
    pub(super) fn move_frames(&mut self, id: u16) -> Option<MoveFrames<T>> {
        let pos = self.gait.position(id)?;
        let (step, side) = self.frame_at(pos)?;
        let other = self.frame_before(pos, side.other())?;
        let same = self.frame_before(pos, side)?;
        let next = match self.gait.position(id.wrapping_add(1)) {
            Some(p) if p == pos + 1 => Some(self.frame_at(p)?),
            Some(_) => return None,
            None => None,
        };
        let from_rest = pos == 0 && self.gait.next_swing_from_rest();
        Some(MoveFrames {
            other,
            same,
            step,
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
