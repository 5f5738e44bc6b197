//! `qemu-attribute` (tests/src/bin, run by `firmware/qemu/attribute.sh`) on the QEMU image: a
//! smoke test of the per-function attribution, cheap enough for CI (the image replays the log of
//! host-sim's fig4 run that the tool records; the first 330 polls only, which include fig4's
//! first re-plan at the start of single support).
//!
//! The tool cuts QEMU's instruction trace into polls by the call and return of the image's
//! poll function. Checked: every poll the image itself timed and printed (its `REPLAN` lines,
//! counted by the image's timer in units of 40 instructions) has the tool's count to within
//! two timer ticks and the timer reads (±100 instructions); the worst poll's inclusive table
//! starts with the poll function at 100 %; its self table names planner-core functions; and
//! the self counts add up to at most the poll's total.

use std::process::Command;

/// Polls traced: fig4's first re-plan is the poll of tick 320 (the 322nd poll: the first is the
/// handshake's, which does not tick).
const POLLS: usize = 330;
/// The image's timer resolution (40 instructions per tick) twice, and the timer reads.
const SLACK: i64 = 100;

#[test]
fn attribution_agrees_with_the_image_timer() {
    if !walk_tests::qemu_available() {
        return;
    }
    let elf = walk_tests::build_firmware("qemu", "qemu");
    let dir = std::env::temp_dir().join(format!("walk-attribute-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (counts, stdout) = (dir.join("counts.txt"), dir.join("stdout.txt"));
    let out = Command::new(env!("CARGO_BIN_EXE_qemu-attribute"))
        .args(["--stop-after", &POLLS.to_string(), "--top", "200"])
        .arg("--counts")
        .arg(&counts)
        .arg("--stdout")
        .arg(&stdout)
        .arg(&elf)
        .output()
        .expect("cannot run qemu-attribute");
    let report = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "qemu-attribute failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );

    let counts: Vec<i64> = std::fs::read_to_string(&counts)
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(counts.len(), POLLS, "polls traced");
    let image = std::fs::read_to_string(&stdout).unwrap();
    let mut compared = 0;
    for line in image.lines().filter(|l| l.starts_with("REPLAN ")) {
        let field = |k: &str| -> i64 {
            line.split_whitespace()
                .find_map(|w| w.strip_prefix(k)?.strip_prefix('=')?.parse().ok())
                .unwrap_or_else(|| panic!("no {k} in {line}"))
        };
        // The gait's tick count after the poll; the first poll (the handshake's) ticks not.
        let tick = field("tick") as usize;
        if tick == 0 || tick >= POLLS {
            continue;
        }
        let (timer, traced) = (field("instructions"), counts[tick]);
        assert!(
            (timer - traced).abs() <= SLACK,
            "tick {tick}: the image's timer says {timer} instructions, the trace {traced}"
        );
        compared += 1;
    }
    assert!(
        compared >= 1,
        "no REPLAN line within the first {POLLS} polls"
    );

    let max = *counts.iter().max().unwrap();
    assert!(report.contains(&format!("instructions={max}")), "{report}");
    let section = |title: &str| -> Vec<(i64, String)> {
        report
            .split(title)
            .nth(1)
            .unwrap_or_else(|| panic!("no {title} table:\n{report}"))
            .lines()
            .skip(1)
            .take_while(|l| !l.trim().is_empty())
            .map(|l| {
                let mut w = l.split_whitespace();
                let n = w.next().unwrap().parse().unwrap();
                let name = w.skip(1).collect::<Vec<_>>().join(" ");
                (n, name)
            })
            .collect()
    };
    let inclusive = section("INCLUSIVE");
    assert_eq!(inclusive[0].0, max, "{report}");
    assert!(inclusive[0].1.contains("control::poll"), "{report}");
    let own = section("SELF");
    assert!(own.iter().map(|(n, _)| n).sum::<i64>() <= max, "{report}");
    assert!(
        own.iter().any(|(_, f)| f.starts_with("planner_core::")),
        "{report}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
