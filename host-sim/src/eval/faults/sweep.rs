//! The sweep: every row of a walk ([`super::rows`]: [`super::SWEEP`], the adjusting walk's own rows,
//! then the [`super::HEAVY`] mixes) over the sweep's scenarios and seeds, summed per row
//! ([`SweepRow`]), and its Markdown tables.

use std::fmt::Write as _;

use super::{
    rows, run_walk, FaultKind, MeasuredCount, VelocityRun, Walk, SCENARIOS, VELOCITY_SCENARIO,
};
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
    /// Runs whose pendulum robot fell (adjusting walks).
    pub pendulum_falls: usize,
    /// The node's answers to `MEASURED`, summed.
    pub measured: MeasuredCount,
    /// `MEASURED` states taken older than the node's `max_age`, summed.
    pub measured_too_old: usize,
    /// Changes of the node's shift, summed.
    pub adjustments: usize,
    /// Runs in which the node adjusted.
    pub adjusted_runs: usize,
    /// Steps walked at a shift other than zero, summed.
    pub shifted_landings: usize,
    /// Walked steps whose shift the controller's book got wrong, summed.
    pub shift_unheard: usize,
    /// The velocity walk's counts, summed (the ages and delays: the largest).
    pub velocity: VelocityRun,
}

/// Runs the sweep over [`super::SWEEP`] × [`SCENARIOS`] × `seeds` seeds (1 … seeds), then the
/// [`super::HEAVY`] rows with `heavy_seeds` seeds.
pub fn sweep(seeds: u64, heavy_seeds: u64) -> Result<Vec<SweepRow>, String> {
    sweep_walk(Walk::Plain, seeds, heavy_seeds)
}

/// [`sweep`] of `walk`'s rows ([`super::rows`]).
pub fn sweep_walk(walk: Walk, seeds: u64, heavy_seeds: u64) -> Result<Vec<SweepRow>, String> {
    let names: &[&str] = match walk {
        Walk::Velocity => &[VELOCITY_SCENARIO],
        _ => &SCENARIOS,
    };
    let scenarios: Vec<Scenario> = names
        .iter()
        .map(|n| scenario::built_in(n).ok_or_else(|| format!("no scenario {n}")))
        .collect::<Result<_, _>>()?;
    let mut out = Vec::new();
    for (kind, rate) in rows(walk) {
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
            pendulum_falls: 0,
            measured: MeasuredCount::default(),
            measured_too_old: 0,
            adjustments: 0,
            adjusted_runs: 0,
            shifted_landings: 0,
            shift_unheard: 0,
            velocity: VelocityRun::default(),
        };
        let seeds_here = match kind {
            FaultKind::None => 1,
            FaultKind::Mixed(_) => heavy_seeds,
            _ => seeds,
        };
        for s in &scenarios {
            for seed in 1..=seeds_here {
                let r = run_walk(s, walk, kind, rate, seed)?;
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
                row.pendulum_falls += usize::from(r.pendulum_fell);
                row.measured += r.measured;
                row.measured_too_old += r.measured_too_old;
                row.adjustments += r.adjustments;
                row.adjusted_runs += usize::from(r.adjustments > 0);
                row.shifted_landings += r.shifted_landings;
                row.shift_unheard += r.shift_unheard;
                if let Some(v) = r.velocity {
                    row.velocity += v;
                }
                if let Some(e) = r.model_error {
                    row.model_errors
                        .push(format!("{} seed {seed}: {e}", s.name));
                }
            }
        }
        out.push(row);
    }
    Ok(out)
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

/// The table of an adjusting walk's [`sweep_walk`] rows as Markdown: the falls (the
/// multi-body ZMP's and the pendulum robot's), the footsteps, and what the node did with the
/// estimator's `MEASURED` frames.
pub fn markdown_adjusting(rows: &[SweepRow]) -> String {
    let mut out = String::from(
        "| fault | rate | runs | falls | pendulum falls | leg out of reach (runs) | lost | \
         shift unheard | runs adjusted | adjustments | shifted landings | MEASURED taken | \
         refused stale | refused duplicate | refused bad CRC | refused otherwise | \
         taken too old | cancelled by safety stop | safety stops | cycles without reference |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let m = r.measured;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.kind.name(),
            r.kind.rate_label(r.rate),
            r.runs,
            r.falls,
            r.pendulum_falls,
            r.out_of_reach,
            r.lost,
            r.shift_unheard,
            r.adjusted_runs,
            r.adjustments,
            r.shifted_landings,
            m.taken,
            m.stale,
            m.duplicate,
            m.bad_crc,
            m.other,
            r.measured_too_old,
            r.cancelled,
            r.safety_stops,
            r.ticks_without_reference,
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

/// The table of a velocity walk's [`sweep_walk`] rows as Markdown: the falls, the references,
/// what the node did with the stick's `VELOCITY` frames, and (`silence`) how soon it stopped.
pub fn markdown_velocity(rows: &[SweepRow]) -> String {
    let mut out = String::from(
        "| fault | rate | runs | falls | max ZMP outside polygon (mm) | leg out of reach (runs) | \
         cycles without reference | VELOCITY sent | taken | refused stale or duplicate | \
         refused bad CRC | refused otherwise | old frame taken | taken after controller lost | \
         velocity not held | oldest taken (ms) | safety stops | silence: lost after / standing \
         after (s, worst) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let s = |t: Option<u64>| t.map_or("—".into(), |t| format!("{:.2}", t as f64 * 0.005));
    for r in rows {
        let v = r.velocity;
        let silence = if r.kind == FaultKind::Silence {
            format!("{} / {}", s(v.lost_after), s(v.standing_after))
        } else {
            "—".into()
        };
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {:.1} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.kind.name(),
            r.kind.rate_label(r.rate),
            r.runs,
            r.falls,
            r.max_outside * 1e3,
            r.out_of_reach,
            r.ticks_without_reference,
            v.sent,
            v.taken,
            v.refused_old,
            v.refused_crc,
            v.refused_other,
            v.old_taken,
            v.taken_after_lost,
            v.wrong_velocity,
            v.max_age_taken * 5,
            r.safety_stops,
            silence,
        );
    }
    out
}
