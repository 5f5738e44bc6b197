//! The node's configuration ([`NodeConfig`]).

use super::*;

/// Node configuration, in the node's scalar `T` ([`NodeConfig::cast`] converts the `f64`
/// configuration that a robot file gives).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeConfig<T = f64> {
    /// Gait parameters.
    pub params: GaitParams<T>,
    /// Where the left foot stands at start-up.
    pub left: Footstep<T>,
    /// Where the right foot stands at start-up.
    pub right: Footstep<T>,
    /// Silence of the controller after which a moving robot stops \[ms\] (see the module
    /// docs: the supervision bound).
    pub heartbeat_timeout_ms: u32,
    /// Silence of a `VELOCITY` stream after which a robot walking at a velocity stops as for
    /// a lost controller \[ms\] (a stick or a policy sends every 50 ms or faster: five
    /// periods by default). Only `VELOCITY` frames keep the stream alive.
    pub velocity_timeout_ms: u32,
    /// Command frames acted on per cycle at most, of every sender (at most [`MAX_RX`]): when
    /// more arrive, the node keeps them by class (see the module docs) and refuses the rest
    /// `Busy`.
    pub max_rx: usize,
    /// Frames of all kinds (the node's and others) taken from the device per cycle at most:
    /// more than the bus carries in a cycle, so that nothing waits for the next one.
    pub max_frames: usize,
    /// Planning commands (`Start`, `STEP_MODIFY` of the next swing target while walking)
    /// handled per cycle at most (see the module docs).
    pub max_plans: usize,
    /// The command work a cycle may do, in estimated Cortex-M7 instructions ([`WORK_BUDGET`]
    /// by default; see there for what each command costs). At most [`WORK_BUDGET`] (the bound
    /// the timing figures measure) and at least [`WORK_ADJUST`] and a plan with its checks
    /// ([`WORK_STEP`] + [`WORK_PLAN`]); `max_plans` at least 1: else the start-up refuses the
    /// configuration.
    pub work_budget: u32,
    /// Reach limits.
    pub reach: Reach<T>,
    /// The step adjustment from the measured state (see `adjust`).
    pub adjust: AdjustConfig<T>,
    /// A value that differs at every start-up (the firmware takes it from its hardware random
    /// number generator): the start-up's session epoch, and (its high half) the number of its
    /// first step. Frames of an earlier start-up are then refused except by chance (2⁻¹⁶ for
    /// a control command); within a start-up, by construction.
    pub entropy: u32,
}

impl NodeConfig {
    /// HRP-2 defaults: [`GaitParams::hrp2`], [`Reach::default`] and
    /// [`NodeConfig::for_robot`]'s node settings.
    pub fn hrp2() -> Self {
        Self::for_robot(GaitParams::hrp2(), Reach::default())
    }

    /// The node for a robot's gait parameters and reach limits (a robot file gives both: see
    /// `planner_core::robot`, feature `robot`), with the node settings that do not depend on
    /// the robot: the feet `step_width` apart at the origin, heading along x; 500 ms
    /// X's one, with room for emergency stops of other senders) out of at most 160
    /// frames of all kinds taken from the device (a 1 Mbit/s bus carries at most 106 in
    /// 5 ms); one planning command per cycle.
    pub fn for_robot(params: GaitParams<f64>, reach: Reach) -> Self {
        let half = params.step_width / 2.0;
        Self {
            params,
            left: Footstep::new(Side::Left, 0.0, half, 0.0),
            right: Footstep::new(Side::Right, 0.0, -half, 0.0),
            heartbeat_timeout_ms: 500,
            velocity_timeout_ms: 250,
            max_rx: 20,
            max_frames: 160,
            max_plans: 1,
            work_budget: WORK_BUDGET,
            reach,
            adjust: AdjustConfig::DEFAULT,
            entropy: 0,
        }
    }

    /// This configuration in the scalar `T` (every real rounded to the nearest `T`; exact for
    /// `f64`): how the `f32` node is configured from a robot file.
    pub fn cast<T: Real>(&self) -> NodeConfig<T> {
        let foot = |f: &Footstep<f64>| Footstep::new(f.side, T::of(f.x), T::of(f.y), T::of(f.yaw));
        let p = &self.params;
        NodeConfig {
            params: GaitParams {
                omega: T::of(p.omega),
                dt: T::of(p.dt),
                single_ticks: p.single_ticks,
                double_ticks: p.double_ticks,
                start_ticks: p.start_ticks,
                settle_ticks: p.settle_ticks,
                stand_ticks: p.stand_ticks,
                rest_ticks: p.rest_ticks,
                adjust_min_ticks: p.adjust_min_ticks,
                adjust_max_ticks: p.adjust_max_ticks,
                step_width: T::of(p.step_width),
                sole_half_length: T::of(p.sole_half_length),
                sole_half_width: T::of(p.sole_half_width),
                step_height: T::of(p.step_height),
                tail: p.tail,
                shaping: p.shaping,
                cog_height: p.cog_height,
                gravity: p.gravity,
                preview_qe: p.preview_qe,
                preview_r: p.preview_r,
            },
            left: foot(&self.left),
            right: foot(&self.right),
            heartbeat_timeout_ms: self.heartbeat_timeout_ms,
            velocity_timeout_ms: self.velocity_timeout_ms,
            max_rx: self.max_rx,
            max_frames: self.max_frames,
            max_plans: self.max_plans,
            work_budget: self.work_budget,
            reach: self.reach.cast(),
            adjust: self.adjust.cast(),
            entropy: self.entropy,
        }
    }
}
