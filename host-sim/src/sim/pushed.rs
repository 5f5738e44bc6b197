//! A pushed walk with the node's step adjustment, over the virtual bus and recorded: the log
//! that puts `MEASURED` frames and the adjustment into the target's replay (the QEMU image),
//! without a physics engine.
//!
//! The robot is a linear inverted pendulum per plane, `ẍ = ω² (x − p)`, integrated exactly
//! over each 5 ms cycle with its ZMP `p` held; its stabilizer tracks the node's reference by
//! the divergent component `ξ = x + ẋ/ω`: `p = p_ref + (1 + k/ω)(ξ − ξ_ref)` with `k` =
//! [`K_DCM`], `p` kept inside the support sole (the box around both soles in double support).
//! Its state estimator sends `ξ − ξ_ref` in `MEASURED` every cycle, against the reference of
//! the cycle it tracked (one cycle old when the node reads it). The controller appends a
//! straight walk, starts it with `start_adjusting` (or `start`) and `stop`, and heartbeats every
//! 100 ms; the robot is pushed once (a velocity step) [`PUSH_DELAY_TICKS`] after the third
//! lift-off.

use planner_core::gait::{GaitParams, Phase, Reference, Side};
use planner_core::node::{Node, NodeConfig};
use planner_core::wire::{Adjust, ControlOp, Measured, StepBook};

use super::bus::{Bus, Faults};
use embedded_can::nb::Can;

/// The stabilizer's DCM gain `k` \[1/s\].
pub const K_DCM: f64 = 3.0;
/// The push comes this many cycles after the third lift-off (0.15 s into its single support).
pub const PUSH_DELAY_TICKS: u64 = 30;
/// A DCM deviation beyond this is a fall \[m\].
pub const FALLEN_M: f64 = 0.35;

/// One plane of the pendulum.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Plane {
    x: f64,
    v: f64,
}

impl Plane {
    /// Exact over `dt` with the ZMP held at `p`.
    fn step(&mut self, p: f64, w: f64, dt: f64) {
        let (c, s) = ((w * dt).cosh(), (w * dt).sinh());
        let x = p + (self.x - p) * c + self.v / w * s;
        self.v = (self.x - p) * w * s + self.v * c;
        self.x = x;
    }
}

/// The pushed robot of the module docs: a linear inverted pendulum per plane (x, y) whose
/// stabilizer tracks the node's reference; also the fault sweep's robot
/// ([`crate::eval::faults`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Pendulum([Plane; 2]);

impl Pendulum {
    /// At rest at the COG of the reference `r`.
    pub(crate) fn at(r: &Reference<f64>) -> Self {
        Pendulum([
            Plane {
                x: r.x.cog,
                v: r.x.cog_vel,
            },
            Plane {
                x: r.y.cog,
                v: r.y.cog_vel,
            },
        ])
    }

    /// The deviation of its DCM from the reference `r`'s, `ξ − ξ_ref` \[m\] (`w`: ω).
    pub(crate) fn deviation(&self, r: &Reference<f64>, w: f64) -> [f64; 2] {
        let refs = [r.x, r.y];
        [0, 1].map(|i| (self.0[i].x + self.0[i].v / w) - (refs[i].cog + refs[i].cog_vel / w))
    }

    /// One cycle tracking the reference `r` whose DCM it misses by `e`: the stabilizer's ZMP
    /// `p_ref + (1 + k/ω) e`, kept inside the support sole (the box around both soles in
    /// double support).
    pub(crate) fn track(&mut self, r: &Reference<f64>, e: [f64; 2], p: &GaitParams<f64>) {
        let (w, dt) = (p.omega, p.dt);
        let (hl, hw) = (p.sole_half_length, p.sole_half_width);
        let refs = [r.x, r.y];
        let feet = r.feet;
        let (lo, hi) = match r.phase {
            Phase::Single(support) => {
                let f = feet[usize::from(support == Side::Right)];
                ([f.x - hl, f.y - hw], [f.x + hl, f.y + hw])
            }
            _ => (
                [feet[0].x.min(feet[1].x) - hl, feet[0].y.min(feet[1].y) - hw],
                [feet[0].x.max(feet[1].x) + hl, feet[0].y.max(feet[1].y) + hw],
            ),
        };
        for i in 0..2 {
            let zmp = refs[i].zmp + (1.0 + K_DCM / w) * e[i];
            self.0[i].step(zmp.clamp(lo[i], hi[i]), w, dt);
        }
    }

    /// A push: a step `dv` (x, y) of its velocity \[m/s\].
    pub(crate) fn push(&mut self, dv: [f64; 2]) {
        self.0[0].v += dv[0];
        self.0[1].v += dv[1];
    }
}

/// What the pushed walk gave.
#[derive(Clone, Debug)]
pub struct PushedRun {
    /// The node's configuration (the controller's side needs nothing else to replay it).
    pub cfg: NodeConfig,
    /// The bus, as candump lines (`sim::bus::log_line`).
    pub can_log: Vec<String>,
    /// Every `ADJUST` the node sent.
    pub adjusts: Vec<Adjust>,
    /// The pendulum fell (its DCM left the reference by [`FALLEN_M`]).
    pub fallen: bool,
    /// The node's last shift other than 0 during the walk \[0.5 mm\] (the shift ends with
    /// the walk: 0 once standing).
    pub shift: [i32; 2],
    /// Control cycles run.
    pub ticks: u64,
}

/// A straight walk of `steps` steps of `length` \[m\] with HRP-2's node, pushed by `dv` (x, y)
/// \[m/s\]; `adjusting`: started with `start_adjusting`.
pub fn pushed_walk(
    cfg: &NodeConfig,
    steps: u16,
    length: f64,
    dv: [f64; 2],
    adjusting: bool,
) -> Result<PushedRun, String> {
    let mut node: Node<16> = Node::new(*cfg).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let bus = Bus::new(1_000_000, 2, Faults::default(), 1);
    bus.record();
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let ms = 1_000_000u64;
    // The handshake, as `simulate` does it.
    let mut c = super::handshake(&bus, &mut node, &mut ctl, &mut nport);
    // The walk, sent at tick 0.
    let mut book = StepBook::new();
    let mut first = Vec::new();
    for i in 0..steps {
        let left = i % 2 == 1;
        let foot = if left { cfg.left } else { cfg.right };
        let along = length * f64::from(i + 1).min(f64::from(steps.saturating_sub(1)));
        let id = node.next_step().wrapping_add(i);
        let command = book
            .append(id, left, foot.x + along, foot.y, 0.0)
            .ok_or("a step of the walk does not fit the bus")?;
        first.push(command.encode_in(c.epoch));
    }
    let op = if adjusting {
        ControlOp::StartAdjusting
    } else {
        ControlOp::Start
    };

    let p = cfg.params;
    let mut robot = Pendulum::at(node.gait().last());
    let mut out = PushedRun {
        cfg: *cfg,
        can_log: Vec::new(),
        adjusts: Vec::new(),
        fallen: false,
        shift: [0, 0],
        ticks: 0,
    };
    let (mut swinging, mut liftoffs, mut push_at) = (None, 0u32, None);
    let mut tracked: Option<(u32, [f64; 2])> = None;
    let max_ticks = 4000u64;
    for k in 0..max_ticks {
        let t0 = (k + 1) * 5 * ms;
        bus.advance(t0);
        // The steps first, the start and the stop a cycle later (the bus sends the lower
        // identifier first: `CONTROL` would overtake the appends).
        if k == 0 {
            for f in &first {
                let _ = ctl.transmit(f);
            }
        }
        if k == 1 {
            let _ = ctl.transmit(&c.control(op).encode());
            let _ = ctl.transmit(&c.control(ControlOp::Stop).encode());
        }
        if k % 20 == 0 {
            let _ = ctl.transmit(&c.control(ControlOp::Heartbeat).encode());
        }
        // The estimator: the deviation against the reference the robot tracked.
        if let Some((stamp, e)) = tracked {
            if let Some(m) = Measured::from_si(stamp, e) {
                let _ = ctl.transmit(&m.encode(c.epoch));
            }
        }
        bus.advance(t0 + 5 * ms / 2);
        let now_ms = (t0 / ms) as u32 + 2;
        let report = node.poll(now_ms, &mut nport);
        let reference = report.reference;
        let stamp = node.cycles();
        // The robot over this cycle: the stabilizer's ZMP inside the support polygon.
        let e = robot.deviation(&reference, p.omega);
        if e[0].hypot(e[1]) > FALLEN_M {
            out.fallen = true;
        }
        robot.track(&reference, e, &p);
        tracked = Some((stamp, e));
        // The push.
        let s = node.gait().swinging();
        if s.is_some() && s != swinging {
            liftoffs += 1;
            if liftoffs == 3 {
                push_at = Some(k + PUSH_DELAY_TICKS);
            }
        }
        swinging = s;
        if push_at == Some(k) {
            robot.push(dv);
        }
        bus.advance(t0 + 5 * ms);
        while let Ok(f) = ctl.receive() {
            if let Some(a) = Adjust::decode(&f) {
                out.adjusts.push(a);
            }
        }
        if node.shift() != [0, 0] {
            out.shift = node.shift();
        }
        out.ticks = k + 1;
        if out.fallen
            || (liftoffs > 0 && node.gait().is_standing() && push_at.is_some_and(|t| k > t + 200))
        {
            break;
        }
    }
    out.can_log = bus.log();
    Ok(out)
}
