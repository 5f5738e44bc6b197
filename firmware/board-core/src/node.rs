//! The node's contract with the control cycle: [`ControlNode`], what the cycle needs of the
//! node (planner-core's `Node`, implemented here; host tests use stand-ins that can be slow or
//! hang).
//!
//! Its own module because both sides of the cycle use it: [`crate::control`] polls the node
//! and publishes its link health through it, [`crate::cycle`] tells it of a late cycle
//! ([`ControlNode::note_overrun`]). It depends on neither.

use core::borrow::Borrow;

use embedded_can::nb::Can;
use planner_core::gait::PREVIEW;
use planner_core::node::{Node, PollReport};
use planner_core::shaping::PreviewGains;
use planner_core::wire::LinkHealth;
use planner_core::Real;

/// What the control cycle needs of the node (planner-core's `Node`).
pub trait ControlNode {
    /// The node's scalar.
    type Scalar: Real;
    /// The link health to publish in `LINK`.
    fn set_link_health(&mut self, link: LinkHealth);
    /// One control cycle of the node at `now_ms` over `can`.
    fn poll<C: Can>(&mut self, now_ms: u32, can: &mut C) -> PollReport<Self::Scalar>;
    /// The last cycle was late.
    fn note_overrun(&mut self);
    /// Polls since start-up.
    fn cycles(&self) -> u32;
}

impl<const Q: usize, G: Borrow<PreviewGains<T, PREVIEW>>, T: Real> ControlNode for Node<Q, G, T> {
    type Scalar = T;
    #[inline(always)]
    fn set_link_health(&mut self, link: LinkHealth) {
        Node::set_link_health(self, link);
    }
    #[inline(always)]
    fn poll<C: Can>(&mut self, now_ms: u32, can: &mut C) -> PollReport<T> {
        Node::poll(self, now_ms, can)
    }
    #[inline(always)]
    fn note_overrun(&mut self) {
        Node::note_overrun(self);
    }
    #[inline(always)]
    fn cycles(&self) -> u32 {
        Node::cycles(self)
    }
}
