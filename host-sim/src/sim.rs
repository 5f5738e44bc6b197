//! The simulation over the virtual CAN link: a controller (the scenario's timeline) on port 0,
//! the node (the same `planner_core::node::Node` as the firmware) on port 1.
//!
//! Per 5 ms tick `k` (time `t_k = 5k ms`):
//! 1. the controller sends the commands due at tick `k` (and a heartbeat every 100 ms);
//! 2. the bus runs to `t_k + 2.5 ms` and the node polls (handles what arrived, advances the
//!    gait by one tick, publishes the reference and its answers);
//! 3. the bus runs to `t_{k+1}` and the controller reads the answers and the stream.
//!
//! The trajectory is the node's reference at full precision; the stream decoded by the
//! controller (1 µm units) is kept to check the link.

use planner_core::gait::Reference;
use planner_core::node::{Counters, Node, NodeConfig};
use planner_core::wire::{Ack, Command, ControlOp, RawFrame, StepBook, Stream};

use crate::bus::{Bus, BusStats, Faults};
use crate::scenario::{self, Adjustment, Event, Run, Scenario};

use embedded_can::nb::Can;

/// Simulation settings.
#[derive(Clone, Copy, Debug)]
pub struct SimConfig {
    /// The node's configuration.
    pub node: NodeConfig,
    /// Bitrate \[bit/s\].
    pub bitrate: u32,
    /// Faults on the bus.
    pub faults: Faults,
    /// Seed of the fault generator.
    pub seed: u64,
    /// Record a candump log.
    pub record: bool,
    /// The controller sends a heartbeat every this many ticks (0: never).
    pub heartbeat_ticks: u64,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            node: NodeConfig::hrp2(),
            bitrate: 1_000_000,
            faults: Faults::default(),
            seed: 1,
            record: true,
            heartbeat_ticks: 20,
        }
    }
}

/// What a simulation produced.
#[derive(Clone, Debug)]
pub struct SimRun {
    /// Trajectory, events (the node's answers) and adjustments, as for [`scenario::run`].
    pub run: Run,
    /// The stream as the controller decoded it, one per tick (the last values received).
    pub stream: Vec<Stream>,
    /// Every answer the controller received, with its tick.
    pub acks: Vec<(u64, Ack)>,
    /// The candump log.
    pub can_log: Vec<String>,
    /// Fraction of the time the bus was busy.
    pub bus_load: f64,
    /// Bus counters.
    pub bus: BusStats,
    /// The node's counters at the end.
    pub counters: Counters,
}

fn send(port: &mut crate::bus::Port, f: RawFrame) {
    // The mailbox holds 64 frames; a scenario never sends that many in one tick.
    let _ = port.transmit(&f);
}

/// Plays a scenario through the virtual bus and the node.
pub fn simulate(s: &Scenario, cfg: &SimConfig) -> Result<SimRun, String> {
    let mut node: Node<64> =
        Node::new(cfg.node).map_err(|e| format!("node start-up failed: {e:?}"))?;
    let bus = Bus::new(cfg.bitrate, 2, cfg.faults, cfg.seed);
    if cfg.record {
        bus.record();
    }
    let (mut ctl, mut nport) = (bus.port(0), bus.port(1));
    let mut trajectory = vec![*node.gait().last()];
    let mut stream = Stream::default();
    let mut streams = vec![stream];
    let mut acks = Vec::new();
    let mut events = Vec::new();
    let mut adjustments = Vec::new();
    let mut footsteps: Vec<(u16, planner_core::gait::Footstep<f64>)> = Vec::new();
    let mut seq: u8 = 0;
    let mut book = StepBook::new();
    let mut next = 0;
    let mut last_replan = None;
    let last_command = s.timeline.last().map(|(t, _)| *t).unwrap_or(0);
    let ms = 1_000_000u64;
    for k in 0..s.max_ticks {
        let t0 = k * 5 * ms;
        bus.advance(t0);
        while next < s.timeline.len() && s.timeline[next].0 <= k {
            let (_, command) = s.timeline[next];
            let wire = match command {
                scenario::Command::Push(id, f) | scenario::Command::Modify(id, f) => {
                    let left = f.side == planner_core::gait::Side::Left;
                    let Ok(wid) = u8::try_from(id) else {
                        return Err(format!("footstep id {id} does not fit the bus (0 … 255)"));
                    };
                    let wire = if matches!(command, scenario::Command::Push(..)) {
                        book.append(wid, left, f.x, f.y, f.yaw)
                    } else {
                        book.modify(wid, f.x, f.y, f.yaw)
                    };
                    let Some(w) = wire else {
                        return Err(format!(
                            "footstep {id} at ({:.4}, {:.4}) m is not representable on the bus \
                             (x, y within ±32.77 m; a modification within ±4.096 m of the append)",
                            f.x, f.y
                        ));
                    };
                    w
                }
                scenario::Command::Start => {
                    seq = seq.wrapping_add(1);
                    Command::Control {
                        seq,
                        op: ControlOp::Start,
                    }
                }
                scenario::Command::Stop => {
                    seq = seq.wrapping_add(1);
                    Command::Control {
                        seq,
                        op: ControlOp::Stop,
                    }
                }
                scenario::Command::StopNow => {
                    seq = seq.wrapping_add(1);
                    Command::Control {
                        seq,
                        op: ControlOp::StopNow,
                    }
                }
            };
            send(&mut ctl, wire.encode());
            events.push((k, command, wire));
            next += 1;
        }
        if cfg.heartbeat_ticks > 0 && k % cfg.heartbeat_ticks == 0 {
            send(
                &mut ctl,
                Command::Control {
                    // A new sequence number for every heartbeat (a repeat proves nothing).
                    seq: (k / cfg.heartbeat_ticks) as u8,
                    op: ControlOp::Heartbeat,
                }
                .encode(),
            );
        }
        bus.advance(t0 + 5 * ms / 2);
        let now_ms = (t0 / ms) as u32 + 2;
        let report = node.poll(now_ms, &mut nport);
        trajectory.push(report.reference);
        if let Some(info) = node.gait().last_replan() {
            if last_replan != Some(info.tick) {
                last_replan = Some(info.tick);
                if info.adjust_ticks != 0 || info.ratio != 1.0 {
                    adjustments.push(Adjustment {
                        tick: info.tick,
                        adjust_s: f64::from(info.adjust_ticks) * cfg.node.params.dt,
                        ratio: info.ratio,
                        plane: info.plane,
                    });
                }
            }
        }
        bus.advance(t0 + 5 * ms);
        while let Ok(f) = ctl.receive() {
            if let Some(a) = Ack::decode(&f) {
                acks.push((k, a));
            } else {
                stream.decode_into(&f);
            }
        }
        streams.push(stream);
        if node.gait().is_standing() && k > last_command && next >= s.timeline.len() {
            break;
        }
    }
    // Pair every command with its answer (first answer with the same code and sequence).
    let mut used = vec![false; acks.len()];
    let mut out_events = Vec::new();
    for (k, command, wire) in events {
        let code = wire.code();
        let key = wire.key();
        let found = acks.iter().enumerate().find(|(i, (t, a))| {
            !used[*i] && *t >= k && a.command == code && a.seq == key && a.echo == wire.echo()
        });
        let result = match found {
            Some((i, (_, a))) => {
                used[i] = true;
                match a.reason {
                    None => Ok(()),
                    Some(r) => Err(format!("{r:?}")),
                }
            }
            None => Err("no answer".to_string()),
        };
        if let (Ok(()), scenario::Command::Push(id, f) | scenario::Command::Modify(id, f)) =
            (&result, command)
        {
            if let Some(e) = footsteps.iter_mut().find(|(i, _)| *i == id) {
                e.1 = f;
            } else {
                footsteps.push((id, f));
            }
        }
        out_events.push(Event {
            tick: k,
            command,
            result,
        });
    }
    Ok(SimRun {
        run: Run {
            trajectory,
            events: out_events,
            adjustments,
            footsteps,
        },
        stream: streams,
        acks,
        can_log: bus.log(),
        bus_load: bus.load(),
        bus: bus.stats(),
        counters: *node.counters(),
    })
}

/// The reference trajectory a run published.
pub fn references(run: &SimRun) -> &[Reference<f64>] {
    &run.run.trajectory
}
