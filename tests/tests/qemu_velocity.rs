//! A walk by velocity on the firmware's M7 QEMU image (`firmware/qemu`, as `qemu.rs` replays
//! the footstep walks): the built-in `velocity` scenario (forward, a step change to sideways,
//! a turn and its reversal, zero: the node generates every step and re-plans the queued ones
//! at each change) recorded by host-sim, replayed on the image under `-icount shift=0`. The
//! target's node sends the frames the host's does, bit for bit, and its worst control cycle
//! is within the worst admissible cycle's bound (the node's work budget spent: the velocity
//! walk's work is charged to it). `cargo test -p walk-tests --test qemu_velocity --
//! --nocapture` prints the cycle figures.

use walk_tests::figures::{thousands, Quotes};
use walk_tests::logs::{self, compare, expected, Case};
use walk_tests::report;
use walk_tests::{build_firmware, qemu_available};

use host_sim::scenario::built_in;
use host_sim::sim::{simulate, start_config, SimConfig};

/// The QEMU machine of the M7 image.
const MACHINE: &str = "mps2-an500";
/// The bound of the worst admissible control cycle on the M7 (instructions), as `qemu.rs`.
const WORST_CEILING: u64 = 50_000;

#[test]
fn a_velocity_walk_replays_on_the_m7_image_within_the_cycle_bound() {
    if !qemu_available() {
        return;
    }
    let elf = build_firmware("qemu", "qemu");
    let s = built_in("velocity").expect("built in");
    let sim = SimConfig::default();
    let run = simulate(&s, &sim).expect("simulated");
    let case = Case {
        name: "velocity".into(),
        cfg: start_config(&s, &sim.node),
        log: run.can_log,
        adjusts: false,
    };
    let bytes = logs::binary(&case);
    let want = expected(&case, &bytes);
    let dir = std::env::temp_dir().join(format!("walk-qemu-velocity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("replay.wlog"), &bytes).unwrap();
    let q = report::run_qemu(MACHINE, &elf, &dir);
    let _ = std::fs::remove_dir_all(&dir);
    compare(&q, &case, &want);
    for r in q.all("TIMING").filter(|r| r.get("scenario") == "velocity") {
        println!(
            "velocity: {} cycles: max {} instructions (tick {}), mean {}",
            r.get("kind"),
            r.get("max"),
            r.get("max_tick"),
            r.get("mean")
        );
    }
    let cycle = q
        .timing("all", "cycle")
        .expect("no TIMING line for the whole cycle");
    let worst: u64 = cycle.num("max");
    assert!(
        worst <= WORST_CEILING,
        "the velocity walk's worst cycle: {worst} instructions (bound {WORST_CEILING})"
    );
    // The velocity chapter quotes these figures (exactly, as the image counts them).
    const DOC: &str = "docs/src/velocity.md";
    let kind = |k: &str| q.timing("velocity", k).map(|r| r.num::<u64>("max"));
    let mean = |k: &str| {
        q.timing("velocity", k)
            .map(|r| r.num::<f64>("mean").round() as u64)
    };
    let mut quotes = Quotes::new("cargo test -p walk-tests --test qemu_velocity -- --nocapture")
        .line(
            DOC,
            "its worst control cycle is",
            &format!("over {} cycles", thousands(want.cycles)),
        )
        .line(
            DOC,
            "its worst control cycle is",
            &format!("**{} instructions**", thousands(worst)),
        )
        .line(
            DOC,
            "within the worst admissible cycle's bound of",
            &format!("bound of {}.", thousands(WORST_CEILING)),
        );
    if let (Some(replan), Some(steady), Some(steady_mean)) =
        (kind("replan"), kind("steady"), mean("steady"))
    {
        quotes = quotes
            .line(
                DOC,
                "the re-plans' cycles: at most",
                &format!("at most {}", thousands(replan)),
            )
            .line(
                DOC,
                "within the worst admissible cycle's bound of",
                &format!("{}, mean {}", thousands(steady), thousands(steady_mean)),
            );
    }
    quotes.assert();
}
