//! The sweep: every row ([`SWEEP`], then the [`HEAVY`] mixes) over the sweep's scenarios and
//! seeds, summed per row ([`SweepRow`]), and its Markdown table.

use std::fmt::Write as _;

use super::{run_case, FaultKind, HEAVY, SCENARIOS, SWEEP};
use crate::scenario::{self, Scenario};

/// One row of the table: one fault kind at one rate over scenarios and seeds.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRow {
    /// Fault kind.
    pub kind: FaultKind,
    /// Rate.
    pub rate: f64,
    /// Runs.
    pub runs: usize,
    /// Runs that fell.
    pub falls: usize,
    /// Lost commands, summed.
    pub lost: usize,
    /// Footsteps cancelled by a safety stop, summed.
    pub cancelled: usize,
    /// Footsteps whose version in force the controller got wrong (it believed another version
    /// taken, or one taken that was not), summed: what an unlucky controller would not know.
    pub misinformed: usize,
    /// Commands unanswered after every retransmission, summed.
    pub unanswered: usize,
    /// Retransmissions, summed.
    pub retransmissions: usize,
    /// Runs with a safety stop of the node.
    pub safety_stops: usize,
    /// Largest multi-body ZMP error \[m\].
    pub max_zmp_error: f64,
    /// Largest distance of the multi-body ZMP outside the support polygon \[m\].
    pub max_outside: f64,
    /// Node cycles without exactly one finite reference, summed.
    pub ticks_without_reference: usize,
    /// Ticks whose reference the controller did not receive, summed.
    pub stream_gaps: usize,
    /// Ticks run, summed.
    pub ticks: usize,
    /// Runs the model could not follow to the end (a leg out of reach).
    pub out_of_reach: usize,
    /// Largest bus load of a run.
    pub max_bus_load: f64,
    /// Model errors seen.
    pub model_errors: Vec<String>,
}

/// Runs the sweep over [`SWEEP`] × [`SCENARIOS`] × `seeds` seeds (1 … seeds), then the
/// [`HEAVY`] rows with `heavy_seeds` seeds.
pub fn sweep(seeds: u64, heavy_seeds: u64) -> Result<Vec<SweepRow>, String> {
    let scenarios: Vec<Scenario> = SCENARIOS
        .iter()
        .map(|n| scenario::built_in(n).ok_or_else(|| format!("no scenario {n}")))
        .collect::<Result<_, _>>()?;
    let mut rows = Vec::new();
    let heavy: Vec<(FaultKind, &[f64])> = (0..HEAVY.len())
        .map(|i| (FaultKind::Mixed(i), &[0.0][..]))
        .collect();
    for (kind, rates) in SWEEP.iter().copied().chain(heavy) {
        for &rate in rates {
            let mut row = SweepRow {
                kind,
                rate,
                runs: 0,
                falls: 0,
                lost: 0,
                cancelled: 0,
                unanswered: 0,
                misinformed: 0,
                retransmissions: 0,
                safety_stops: 0,
                max_zmp_error: 0.0,
                max_outside: 0.0,
                ticks_without_reference: 0,
                stream_gaps: 0,
                ticks: 0,
                out_of_reach: 0,
                max_bus_load: 0.0,
                model_errors: Vec::new(),
            };
            let seeds_here = match kind {
                FaultKind::None => 1,
                FaultKind::Mixed(_) => heavy_seeds,
                _ => seeds,
            };
            for s in &scenarios {
                for seed in 1..=seeds_here {
                    let r = run_case(s, kind, rate, seed)?;
                    row.runs += 1;
                    row.falls += usize::from(r.fell);
                    row.lost += r.lost;
                    row.cancelled += r.cancelled;
                    row.unanswered += r.unanswered;
                    row.misinformed += r.misinformed;
                    row.retransmissions += r.retransmissions;
                    row.safety_stops += usize::from(r.safety_stop);
                    row.max_zmp_error = row.max_zmp_error.max(r.max_zmp_error);
                    row.max_outside = row.max_outside.max(r.max_outside);
                    row.ticks_without_reference += r.ticks_without_reference;
                    row.stream_gaps += r.stream_gaps;
                    row.ticks += r.ticks;
                    row.out_of_reach += usize::from(r.model_error.is_some());
                    row.max_bus_load = row.max_bus_load.max(r.bus_load);
                    if let Some(e) = r.model_error {
                        row.model_errors
                            .push(format!("{} seed {seed}: {e}", s.name));
                    }
                }
            }
            rows.push(row);
        }
    }
    Ok(rows)
}

/// The table of [`sweep`] rows as Markdown.
pub fn markdown(rows: &[SweepRow]) -> String {
    let mut out = String::from(
        "| fault | rate | runs | falls | lost commands | max multi-body ZMP error (mm) | \
         max ZMP outside polygon (mm) | leg out of reach (runs) | cancelled by safety stop | \
         unanswered | controller misinformed | retransmissions | safety stops | \
         cycles without reference | stream ticks missed by controller | max bus load |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {:.1} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} / {} | {:.0} % |",
            r.kind.name(),
            r.kind.rate_label(r.rate),
            r.runs,
            r.falls,
            r.lost,
            r.max_zmp_error * 1e3,
            r.max_outside * 1e3,
            r.out_of_reach,
            r.cancelled,
            r.unanswered,
            r.misinformed,
            r.retransmissions,
            r.safety_stops,
            r.ticks_without_reference,
            r.stream_gaps,
            r.ticks,
            r.max_bus_load * 100.0,
        );
    }
    out
}

/// The sweep with 3 seeds, as Markdown (or the error).
pub fn sweep_markdown() -> String {
    match sweep(3, 10) {
        Ok(rows) => markdown(&rows),
        Err(e) => format!("sweep failed: {e}\n"),
    }
}
