//! Cycle times (see the docs of `main.rs`).

use super::*;

pub(crate) const CYCLE_TIME: &str = "GenMsgCycleTime";

pub(crate) fn cycle_time_ms(d: &Dbc, id: u16) -> u64 {
    match d.resolved_message_attribute(MessageId::Standard(id), CYCLE_TIME) {
        Some(AttributeValue::Uint(v)) => *v,
        Some(AttributeValue::Int(v)) => u64::try_from(*v).unwrap(),
        other => panic!("{}: {CYCLE_TIME} {other:?}", message(d, id).name),
    }
}

/// The periods the node's documentation states: the reference every control cycle (5 ms),
/// `STATUS` and `DIAG` every 20 cycles (100 ms), commands and answers on events (0).
#[test]
fn every_message_has_its_cycle_time() {
    let d = dbc();
    assert!(d.attribute_definitions.iter().any(|a| matches!(
        a,
        AttributeDefinition::Message(name, AttributeValueType::Int(..)) if name == CYCLE_TIME
    )));
    assert_eq!(
        d.attribute_default(CYCLE_TIME),
        Some(&AttributeValue::Uint(0))
    );
    let cycle = (cycle_s() * 1000.0).round() as u64;
    let mut want: BTreeMap<u16, u64> = BTreeMap::new();
    for id in ids::COMMANDS.into_iter().chain([ids::ACK]) {
        want.insert(id, 0);
    }
    for id in [
        ids::MEASURED, // the estimator's, up to every cycle
        ids::COG,
        ids::ZMP,
        ids::COG_VEL,
        ids::FOOT_LEFT,
        ids::FOOT_RIGHT,
    ] {
        want.insert(id, cycle);
    }
    for id in [ids::STATUS, ids::DIAG, ids::LINK, ids::SESSION, ids::ADJUST] {
        want.insert(id, 20 * cycle);
    }
    let got: BTreeMap<u16, u64> = d
        .messages
        .iter()
        .map(|m| (m.id.raw() as u16, cycle_time_ms(&d, m.id.raw() as u16)))
        .collect();
    assert_eq!(got, want);
    assert_eq!((want[&ids::COG], want[&ids::STATUS]), (5, 100));
}

// ---------------------------------------------------------------------------------------------
// A running node, heard through the DBC.

/// A loop-back device: what the test puts in `rx` the node receives; what it sends lands in
/// `tx`, unless the device is `blocked` (a full mailbox).
#[derive(Default)]
pub(crate) struct Device {
    pub(crate) rx: VecDeque<RawFrame>,
    pub(crate) tx: Vec<RawFrame>,
    pub(crate) blocked: bool,
}

#[derive(Debug)]
pub(crate) struct DeviceError;

impl embedded_can::Error for DeviceError {
    fn kind(&self) -> embedded_can::ErrorKind {
        embedded_can::ErrorKind::Other
    }
}

impl embedded_can::nb::Can for Device {
    type Frame = RawFrame;
    type Error = DeviceError;
    fn transmit(&mut self, f: &RawFrame) -> nb::Result<Option<RawFrame>, DeviceError> {
        if self.blocked {
            return Err(nb::Error::WouldBlock);
        }
        self.tx.push(*f);
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<RawFrame, DeviceError> {
        self.rx.pop_front().ok_or(nb::Error::WouldBlock)
    }
}

/// A node, a controller that keeps count of its sequence numbers, and everything the node sent,
/// each frame decoded with the DBC and compared, name for name, with what the node means.
pub(crate) struct Rig {
    pub(crate) dbc: Dbc,
    pub(crate) node: Node<8>,
    pub(crate) dev: Device,
    pub(crate) now_ms: u32,
    pub(crate) cycle: u32,
    pub(crate) seq: u32,
    /// The session epoch the controller speaks in (from `SESSION`; one more after a `Reset`).
    pub(crate) epoch: u32,
    /// Where the last step was appended.
    pub(crate) last_step: Option<(f64, f64)>,
    /// The link health reported to the node before each cycle, as the board firmware does
    /// (`None`: not reported, the node sends no `LINK`).
    pub(crate) link: Option<LinkHealth>,
    /// Cycles in which each identifier was sent.
    pub(crate) sent: BTreeMap<u16, Vec<u32>>,
    /// Cycles in which a command was received.
    pub(crate) commanded: Vec<u32>,
    /// The names seen of each enumerated signal.
    pub(crate) seen: BTreeMap<&'static str, BTreeSet<String>>,
}

impl Rig {
    pub(crate) fn new(cfg: NodeConfig) -> Self {
        Self {
            dbc: dbc(),
            node: Node::new(cfg).unwrap(),
            dev: Device::default(),
            now_ms: 0,
            cycle: 0,
            seq: 0,
            epoch: 0,
            last_step: None,
            link: None,
            sent: BTreeMap::new(),
            commanded: vec![],
            seen: BTreeMap::new(),
        }
    }

    pub(crate) fn name(&self, id: u16, sig: &str, raw: f64) -> String {
        table(&self.dbc, id, sig)
            .get(&(raw as i64))
            .unwrap_or_else(|| {
                panic!(
                    "{}.{sig} {raw}: not in the value table",
                    message(&self.dbc, id).name
                )
            })
            .clone()
    }

    /// One 5 ms cycle; the decoded frames the node sent.
    pub(crate) fn cycle(&mut self) -> Vec<(u16, HashMap<String, f64>)> {
        self.now_ms += 5;
        self.cycle += 1;
        if !self.dev.rx.is_empty() {
            self.commanded.push(self.cycle);
        }
        if let Some(l) = &mut self.link {
            // A different bus state and reset reason every 100 ms: every name is heard. The
            // state only in the cycle that publishes `LINK` (error-active between): a link
            // bus-off for more than a few cycles in a row would stop the walk.
            let k = self.cycle / 20;
            l.bus_state = if self.cycle % 20 == 1 {
                (k % 4) as u8
            } else {
                0
            };
            l.reset = (k % board_core::ResetReason::ALL.len() as u32) as u8;
            l.tec = self.cycle as u8;
            self.node.set_link_health(*l);
        }
        let rep = self.node.poll(self.now_ms, &mut self.dev);
        let mut out = vec![];
        for f in std::mem::take(&mut self.dev.tx) {
            self.sent.entry(f.id).or_default().push(self.cycle);
            let s = decode(&self.dbc, &f);
            let mut notes: Vec<(&'static str, String)> = vec![];
            let mut note = |key: &'static str, name: String| notes.push((key, name));
            match f.id {
                ids::COG_VEL => {
                    let name = self.name(f.id, "phase", s["phase"]);
                    assert_eq!(name, name_of(&rep.reference.phase), "cycle {}", self.cycle);
                    assert_eq!(s["phase"] as usize, phase_position(rep.reference.phase));
                    note("phase", name);
                }
                ids::STATUS => {
                    let name = self.name(f.id, "state", s["state"]);
                    assert_eq!(name, name_of(&self.node.state()), "cycle {}", self.cycle);
                    note("state", name);
                    let g = self.node.gait();
                    let flags = [
                        ("shaping", g.params().shaping),
                        ("replan_failed", g.replan_failed()),
                        ("tx_overflow", self.node.counters().tx_dropped > 0),
                        ("clock_fault", self.node.clock_fault()),
                        (
                            "velocity_cut",
                            self.node.drive_velocity().is_some_and(|(_, c)| c.any()),
                        ),
                        ("at_goal", self.node.at_goal()),
                    ];
                    for (flag, on) in flags {
                        assert_eq!(s[flag], f64::from(u8::from(on)), "{flag}");
                        note(flag, on.to_string());
                    }
                    let name = self.name(f.id, "next_side", s["next_side"]);
                    let side = self.node.gait().next_side();
                    assert_eq!(name, next_side_name(side), "cycle {}", self.cycle);
                    assert_eq!(s["next_side"] as usize, next_side_position(side));
                    note("next_side", name);
                }
                ids::DIAG => {
                    assert_eq!(s["next_step"], f64::from(self.node.next_step()));
                }
                ids::SESSION => {
                    let e = Session::decode(&f).unwrap();
                    assert_eq!(e, self.node.session());
                    assert_eq!(s["epoch"], f64::from(e.epoch));
                    self.epoch = e.epoch;
                }
                ids::LINK => {
                    let l = self.link.expect("LINK from a node without a report");
                    assert_eq!(LinkHealth::decode(&f), Some(l));
                    assert_eq!(s["bus_state"], f64::from(l.bus_state));
                    assert_eq!(s["reset"], f64::from(l.reset));
                    assert_eq!(s["tec"], f64::from(l.tec));
                    assert_eq!(s["ram_faults"], f64::from(l.ram_faults));
                    assert_eq!(s["backoff"], f64::from(l.backoff));
                    note("bus_state", self.name(f.id, "bus_state", s["bus_state"]));
                    note("reset", self.name(f.id, "reset", s["reset"]));
                }
                ids::ACK => {
                    note("command", self.name(f.id, "command", s["command"]));
                    note("reason", self.name(f.id, "reason", s["reason"]));
                }
                _ => {}
            }
            for (key, name) in notes {
                self.seen.entry(key).or_default().insert(name);
            }
            out.push((f.id, s));
        }
        out
    }

    pub(crate) fn cycles(&mut self, n: u32, heartbeat: bool) {
        for k in 0..n {
            if heartbeat && k % 20 == 0 {
                self.control(ControlOp::Heartbeat);
            } else {
                self.cycle();
            }
        }
    }

    /// Sends one command, runs one cycle; the reason of its answer (`"accepted"`…).
    pub(crate) fn ask(&mut self, c: Command) -> String {
        self.dev.rx.push_back(c.encode());
        let acks: Vec<_> = self
            .cycle()
            .into_iter()
            .filter(|(id, _)| *id == ids::ACK)
            .collect();
        assert_eq!(acks.len(), 1, "{c:?}");
        let s = &acks[0].1;
        assert_eq!(s["command"], f64::from(c.code()));
        self.name(ids::ACK, "reason", s["reason"])
    }

    pub(crate) fn control(&mut self, op: ControlOp) -> String {
        self.seq += 1;
        let answer = self.ask(Command::Control {
            session: self.epoch as u16,
            seq: self.seq,
            op,
        });
        if op == ControlOp::Reset && answer == "accepted" {
            self.epoch += 1; // a new session: one more
        }
        answer
    }

    /// Appends the `id`-th step of a walk (right foot first) as the node's next step number,
    /// 0.15 m ahead of the step before it (for step 0, of the left foot where it stands).
    pub(crate) fn step(&mut self, id: u16) -> String {
        let left = id % 2 == 1;
        let (x, y) = match self.last_step {
            Some(p) if id > 0 => p,
            _ => {
                let l = self.node.gait().feet()[0];
                (l.x, l.y)
            }
        };
        let (x, y) = (x + 0.15, y + if left { 0.2 } else { -0.2 });
        self.last_step = Some((x, y));
        let s = WireStep::from_si(self.node.next_step(), left, x, y, 0.0).unwrap();
        self.ask(Command::Append(s))
    }

    /// Runs (with heartbeats) until the node stands.
    pub(crate) fn until_standing(&mut self, heartbeat: bool) {
        for _ in 0..4000 {
            if self.node.gait().is_standing() {
                return;
            }
            self.cycles(1, heartbeat && self.cycle % 20 == 0);
        }
        panic!("never stood");
    }
}

/// A node walks, stops, is emergency-stopped, reset, walks again and loses its controller: every
/// frame it sends decodes with the DBC to names that are the node's own (phase, state, next
/// side, flags), every value of the tables is seen, and every message comes at its
/// `GenMsgCycleTime`.
#[test]
fn a_running_node_speaks_the_dbc() {
    let mut r = Rig::new(NodeConfig::hrp2());
    r.link = Some(LinkHealth {
        bus_offs: 3,
        backoff: 3,
        ram_faults: 1,
        ..LinkHealth::default()
    });
    // No session first (the state is published), then the handshake.
    r.cycles(40, false);
    assert_eq!(r.step(0), "no_session");
    assert_eq!(r.control(ControlOp::Reset), "accepted");
    let opened = r.cycle;
    r.cycles(40, false);
    assert_eq!(r.step(0), "accepted"); // a right step: the left foot is next
    r.cycles(20, false);
    assert_eq!(r.step(1), "accepted");
    r.cycles(20, false);
    for id in 2..5 {
        assert_eq!(r.step(id), "accepted");
    }
    assert_eq!(r.control(ControlOp::Start), "accepted");
    r.cycles(400, true);
    assert_eq!(r.control(ControlOp::Stop), "accepted");
    r.cycles(100, true);
    r.until_standing(true);
    r.cycles(40, false);
    assert_eq!(r.ask(Command::EmergencyStop { seq: 1 }), "accepted");
    r.cycles(40, false);
    assert_eq!(r.control(ControlOp::Start), "emergency_stopped");
    assert_eq!(r.control(ControlOp::Reset), "accepted");
    r.cycles(40, false);
    // Walk again, then fall silent: the node stops on its own.
    for id in 0..3 {
        assert_eq!(r.step(id), "accepted");
    }
    assert_eq!(r.control(ControlOp::Start), "accepted");
    r.cycles(200, true);
    r.cycles(200, false);
    r.until_standing(false);
    r.cycles(40, false);
    assert_eq!(r.control(ControlOp::Reset), "accepted");
    r.cycles(40, false);

    // Every value of the node's tables was seen.
    let all =
        |id: u16, sig: &str| -> BTreeSet<String> { table(&r.dbc, id, sig).into_values().collect() };
    assert_eq!(r.seen["phase"], all(ids::COG_VEL, "phase"));
    assert_eq!(r.seen["state"], all(ids::STATUS, "state"));
    assert_eq!(r.seen["next_side"], all(ids::STATUS, "next_side"));
    assert_eq!(r.seen["bus_state"], all(ids::LINK, "bus_state"));
    assert_eq!(r.seen["reset"], all(ids::LINK, "reset"));
    assert!(r.seen["command"].contains("control") && r.seen["command"].contains("estop"));
    assert!(r.seen["command"].contains("append"));

    // The periods: frames in every cycle, every 20th, or only in answer to a command.
    let cycle_ms = (cycle_s() * 1000.0).round() as u32;
    for m in &r.dbc.messages {
        let id = m.id.raw() as u16;
        let want = cycle_time_ms(&r.dbc, id);
        if id == ids::ADJUST {
            // Every 100 ms only while a walk adjusts or a shift is in force, and none of the
            // walks here adjusts (planner-core/tests/adjust.rs has the adjusting walks).
            assert!(
                !r.sent.contains_key(&id),
                "ADJUST outside an adjusting walk"
            );
            assert_eq!(want, 100, "ADJUST: every 100 ms while adjusting");
            continue;
        }
        let Some(cycles) = r.sent.get(&id) else {
            assert!(ids::is_command(id), "{}: never sent", m.name);
            // (the estimator's measured state: up to every cycle)
            let event = if id == ids::MEASURED { 5 } else { 0 };
            assert_eq!(want, event, "{}: a command", m.name);
            continue;
        };
        if id == ids::ACK {
            assert_eq!(*cycles, r.commanded, "ACK: one per command, in its cycle");
            assert_eq!(want, 0, "ACK: on events");
            continue;
        }
        let gaps: BTreeSet<u32> = cycles.windows(2).map(|w| w[1] - w[0]).collect();
        assert_eq!(gaps.len(), 1, "{}: irregular {gaps:?}", m.name);
        let period = gaps.into_iter().next().unwrap() * cycle_ms;
        assert_eq!(
            u64::from(period),
            want,
            "{}: sent every {period} ms",
            m.name
        );
        // The stream from the cycle that opened the session; the reports from the first.
        if (ids::COG..ids::STATUS).contains(&id) {
            assert_eq!(
                cycles[0], opened,
                "{}: not from the session's first cycle",
                m.name
            );
        } else if id == ids::ADJUST {
            // (half-way between the reports)
            assert_eq!(cycles[0], 11, "{}: not from the 11th cycle", m.name);
        } else {
            assert_eq!(cycles[0], 1, "{}: not from the first cycle", m.name);
        }
    }
}

/// The flags of `STATUS` are the node's: shaping from its configuration, transmit overflow
/// once its backlog overflowed.
#[test]
fn status_flags_are_the_nodes() {
    for shaping in [true, false] {
        let mut cfg = NodeConfig::hrp2();
        cfg.params.shaping = shaping;
        let mut r = Rig::new(cfg);
        r.cycles(20, false);
        assert_eq!(r.control(ControlOp::Reset), "accepted");
        assert!(r.seen["shaping"].contains(&shaping.to_string()));
        assert!(r.seen["tx_overflow"].contains("false"));
        // A blocked mailbox and a burst of commands: the backlog overflows.
        r.dev.blocked = true;
        let burst = TX_BACKLOG + 8;
        for _ in 0..burst {
            r.seq += 1;
            r.dev.rx.push_back(
                Command::Control {
                    session: r.epoch as u16,
                    seq: r.seq,
                    op: ControlOp::Heartbeat,
                }
                .encode(),
            );
        }
        let per_cycle = r.node.config().max_rx;
        r.cycles(burst.div_ceil(per_cycle) as u32, false);
        assert!(r.dev.rx.is_empty());
        r.dev.blocked = false;
        r.cycles(40, false);
        assert!(r.node.counters().tx_dropped > 0);
        assert!(r.seen["tx_overflow"].contains("true"));
    }
}
