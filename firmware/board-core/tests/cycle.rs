//! The board's cycle bookkeeping with planner-core's node: a late cycle is counted and reaches
//! `STATUS.overruns`; the window closes every `SUMMARY_EVERY` cycles with its sums.

use board_core::cycle::{Stats, Summary, SUMMARY_EVERY};
use planner_core::node::{Node, NodeConfig, PollReport};
use planner_core::wire::{ids, Command, ControlOp, RawFrame, Status};

/// What the node sends; and what it receives: the handshake (the start-up's session, epoch 0).
#[derive(Default)]
struct Sink(Vec<RawFrame>, Vec<RawFrame>);

impl embedded_can::nb::Can for Sink {
    type Frame = RawFrame;
    type Error = core::convert::Infallible;
    fn transmit(&mut self, f: &RawFrame) -> nb::Result<Option<RawFrame>, Self::Error> {
        self.0.push(*f);
        Ok(None)
    }
    fn receive(&mut self) -> nb::Result<RawFrame, Self::Error> {
        self.1.pop().ok_or(nb::Error::WouldBlock)
    }
}

#[test]
fn late_cycles_reach_status_and_the_window_closes_each_second() {
    let mut node = Node::<16>::new(NodeConfig::hrp2()).unwrap();
    let open = Command::Control {
        session: 0,
        seq: 1,
        op: ControlOp::Reset,
    };
    let mut bus = Sink(vec![], vec![open.encode()]);
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
    // The last STATUS (cycle 381) carries the 8 overruns counted before it.
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

/// `Summary::mean` (in `f64`) is `sum / cycles` exactly below `sum = 2⁵³` (the extremes and a
/// pseudo-random sample of every magnitude and divisor), and within 2⁻⁵² of it (and one) above.
#[test]
fn the_mean_is_the_integer_quotient() {
    let mean = |sum: u64, cycles: u32| {
        Summary {
            sum,
            cycles,
            ..Summary::default()
        }
        .mean()
    };
    assert_eq!(mean(0, 0), 0);
    assert_eq!(mean(7, 0), 7);
    let top = (1_u64 << 53) - 1;
    for (sum, cycles) in [
        (top, 1),
        (top, 3),
        (top, u32::MAX),
        (top - 1, 2),
        (199, 200),
    ] {
        assert_eq!(
            mean(sum, cycles),
            sum / u64::from(cycles),
            "{sum} / {cycles}"
        );
    }
    let mut x = 0x2545_F491_4F6C_DD1D_u64;
    for _ in 0..200_000 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        let sum = x >> (11 + x % 53);
        let cycles = ((x >> 7) as u32 >> (x % 32)).max(1);
        assert_eq!(
            mean(sum, cycles),
            sum / u64::from(cycles),
            "{sum} / {cycles}"
        );
        // Above 2⁵³: within 2⁻⁵² (relative) and one of the quotient.
        let big = x | 1 << 63;
        let (got, want) = (mean(big, cycles), big / u64::from(cycles));
        let off = got.abs_diff(want) as f64;
        assert!(
            off <= want as f64 * 2.0_f64.powi(-52) + 1.0,
            "{big} / {cycles}"
        );
    }
    assert_eq!(mean(u64::MAX, 1), u64::MAX);
}
