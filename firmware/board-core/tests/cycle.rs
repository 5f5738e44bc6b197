//! The board's cycle bookkeeping with planner-core's node: a late cycle is counted and reaches
//! `STATUS.overruns`; the window closes every `SUMMARY_EVERY` cycles with its sums.

use board_core::cycle::{Stats, SUMMARY_EVERY};
use planner_core::node::{Node, NodeConfig, PollReport};
use planner_core::wire::{ids, RawFrame, Status};

#[derive(Default)]
struct Sink(Vec<RawFrame>);

impl embedded_can::nb::Can for Sink {
    type Frame = RawFrame;
    type Error = core::convert::Infallible;
    fn transmit(&mut self, f: &RawFrame) -> nb::Result<Option<RawFrame>, Self::Error> {
        self.0.push(*f);
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<RawFrame, Self::Error> {
        Err(nb::Error::WouldBlock)
    }
}

#[test]
fn late_cycles_reach_status_and_the_window_closes_each_second() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let mut bus = Sink::default();
    let mut stats = Stats::default();
    let mut summaries = vec![];
    for k in 0..(2 * SUMMARY_EVERY) {
        let report: PollReport = node.poll(5 * k, &mut bus);
        let late = k % 50 == 7; // 8 late cycles in 400
        let spent = 1000 + k;
        let out = stats.record(&mut node, &report, spent, late);
        assert_eq!(out.overrun, late);
        if let Some(s) = out.summary {
            summaries.push((k, s));
        }
    }
    assert_eq!(stats.overruns, 8);
    assert_eq!(node.counters().overruns, 8);
    let last = bus
        .0
        .iter()
        .rev()
        .find_map(|f| (f.id == ids::STATUS).then(|| Status::decode(f).unwrap()));
    // The last STATUS (cycle 400) carries the 8 overruns counted before it.
    assert_eq!(last.unwrap().overruns, 8);
    assert_eq!(summaries.len(), 2);
    let (k, s) = summaries[1];
    assert_eq!(k, 2 * SUMMARY_EVERY - 1);
    assert_eq!(s.cycles, SUMMARY_EVERY);
    assert_eq!(s.worst, 1000 + k);
    let first = 1000 + SUMMARY_EVERY;
    let sum: u64 = (first..=1000 + k).map(u64::from).sum();
    assert_eq!(s.sum, sum);
    assert_eq!(s.mean(), sum / u64::from(SUMMARY_EVERY));
    assert!(s.sent >= 5 * SUMMARY_EVERY, "{}", s.sent);
}
