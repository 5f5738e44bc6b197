//! The `host-sim` command line, run as a process: `run` prints every command that failed
//! (time, step id, reason) and exits 1 unless the scenario expects it; step ids that do not
//! fit the bus are refused when the file is read, naming the entry; clap's `--help`,
//! `--version` and usage errors; errors that name the path they concern.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use host_sim::scenario::Failure;
use planner_core::wire::Reason;

/// A fresh directory of this test process.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("host-sim-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temporary directory");
    d
}

fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("run host-sim")
}

/// Standard output and standard error together.
fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// Writes `toml` as `<name>.toml` and runs it into `<dir>/out`.
fn run_toml(name: &str, toml: &str) -> (Output, String, PathBuf) {
    let dir = temp_dir(name);
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, toml).expect("scenario file");
    let out = dir.join("out");
    let o = host_sim(&[
        "run",
        file.to_str().expect("UTF-8 path"),
        "--out",
        out.to_str().expect("UTF-8 path"),
    ]);
    let t = text(&o);
    (o, t, out)
}

fn step(id: i64, side: &str, x: f64, y: f64, extra: &str) -> String {
    format!("[[step]]\nid = {id}\nside = \"{side}\"\nx = {x}\ny = {y}\n{extra}\n")
}

const START_STOP: &str =
    "[[command]]\nat_s = 0.1\nkind = \"start\"\n\n[[command]]\nat_s = 0.1\nkind = \"stop\"\n";

/// Two 0.2 m steps, then a left step 0.7 m ahead of the right one (out of reach).
fn out_of_reach(expect: &str) -> String {
    format!(
        "name = \"reach\"\n{}{}{}{START_STOP}",
        step(0, "right", 0.2, -0.1, ""),
        step(1, "left", 0.4, 0.1, ""),
        step(2, "right", 1.1, -0.1, expect),
    )
}

fn assert_has(t: &str, needles: &[&str]) {
    for n in needles {
        assert!(t.contains(n), "output does not mention {n:?}:\n{t}");
    }
}

fn summary(out: &Path) -> serde_json::Value {
    let s = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    serde_json::from_str(&s).expect("summary.json is JSON")
}

#[test]
fn a_refusal_is_printed_and_fails_the_run() {
    let (o, t, out) = run_toml("reach", &out_of_reach(""));
    assert_eq!(o.status.code(), Some(1), "{t}");
    // Time sent, entry (with its line), step id, reason name and code.
    assert_has(
        &t,
        &[
            "0.000 s, [[step]] #3 (id 2) at line 14",
            "step 2 (append, right at (1.1000, -0.1000) m",
            "refused: reach (code 12)",
            "UNEXPECTED",
            // the limit it broke, with the value and the robot file's bound
            "refused: reach (code 12): forward step 0.700 m > max_forward 0.300 m",
        ],
    );
    // The outputs are still written, and the summary has the step id and the reason.
    let s = summary(&out);
    let refused = s["refused_commands"].as_array().expect("list");
    assert_eq!(refused.len(), 1, "{s}");
    assert_eq!(refused[0]["step_id"], 2);
    assert_eq!(refused[0]["failure"], "reach");
    assert_eq!(refused[0]["as_expected"], false);
    assert_eq!(s["unexpected_outcomes"], 1);
}

#[test]
fn an_expected_refusal_passes() {
    for name in ["reach", "out_of_reach"] {
        let (o, t, out) = run_toml(
            &format!("expect-{name}"),
            &out_of_reach(&format!("expect = \"{name}\"")),
        );
        assert_eq!(o.status.code(), Some(0), "{t}");
        assert_has(
            &t,
            &[
                "step 2 (append",
                "refused: reach (code 12): forward step 0.700 m > max_forward 0.300 m \
                 (expected reach)",
            ],
        );
        assert!(!t.contains("UNEXPECTED"), "{t}");
        assert_eq!(summary(&out)["unexpected_outcomes"], 0);
    }
}

#[test]
fn an_expectation_that_does_not_happen_fails_the_run() {
    let text = format!(
        "name = \"wrong\"\n{}{}{START_STOP}",
        step(0, "right", 0.2, -0.1, "expect = \"reach\""),
        step(1, "left", 0.2, 0.1, ""),
    );
    let (o, t, _) = run_toml("wrong-expectation", &text);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert_has(&t, &["step 0 (append", "carried out, but expected reach"]);
}

#[test]
fn ids_from_one_are_a_sequence_gap() {
    let text = format!(
        "name = \"from1\"\n{}{}{START_STOP}",
        step(1, "right", 0.2, -0.1, ""),
        step(2, "left", 0.2, 0.1, ""),
    );
    let (o, t, _) = run_toml("from1", &text);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert_has(
        &t,
        &[
            "[[step]] #1 (id 1) at line 2: step 1 (append",
            "refused: sequence_gap (code 10)",
        ],
    );
}

#[test]
fn steps_without_a_start_never_take_effect() {
    let text = format!(
        "name = \"nostart\"\n{}{}",
        step(0, "right", 0.2, -0.1, ""),
        step(1, "left", 0.2, 0.1, ""),
    );
    let (o, t, _) = run_toml("nostart", &text);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert_has(
        &t,
        &[
            "step 0 (append",
            "step 1 (append",
            "accepted, never walked: still queued",
            "no start",
        ],
    );
    // Expected, it passes.
    let text = format!(
        "name = \"nostart\"\n{}{}",
        step(0, "right", 0.2, -0.1, "expect = \"not_walked\""),
        step(1, "left", 0.2, 0.1, "expect = \"not_walked\""),
    );
    let (o, t, _) = run_toml("nostart-expected", &text);
    assert_eq!(o.status.code(), Some(0), "{t}");
}

#[test]
fn a_walk_cut_by_max_time_is_reported() {
    let text = format!(
        "name = \"cut\"\nmax_time_s = 2.0\n{}{}{}{START_STOP}",
        step(0, "right", 0.2, -0.1, ""),
        step(1, "left", 0.4, 0.1, ""),
        step(2, "right", 0.4, -0.1, ""),
    );
    let (o, t, out) = run_toml("cut", &text);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert_has(
        &t,
        &[
            "ended by max_time_s",
            "step 2 (append",
            "accepted, never walked: still queued when max_time_s (2.000 s) ended the run",
        ],
    );
    assert!(!t.contains("step 0 (append"), "step 0 was walked:\n{t}");
    assert_eq!(summary(&out)["ended_by_max_time"], true);
}

#[test]
fn a_step_id_beyond_the_step_numbers_is_refused_when_the_file_is_read() {
    let text = format!("name = \"big\"\n{}", step(65535, "right", 0.2, -0.1, ""));
    let (o, t, out) = run_toml("id65535", &text);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert_has(
        &t,
        &[
            "id65535.toml",
            "[[step]] #1 (id 65535) at line 2",
            "step id 65535 does not fit the bus",
            "0 … 65534",
        ],
    );
    assert!(!out.exists(), "nothing is run");
    // The same for a modification, and 65534 is read (the node refuses it as a first step).
    let e = host_sim::scenario::file::parse(
        "name = \"m\"\n[[modify]]\nat_s = 0.0\nid = 70000\nside = \"left\"\nx = 0.0\ny = 0.0\n",
    )
    .unwrap_err();
    assert!(e.contains("[[modify]] #1 (id 70000) at line 2"), "{e}");
    let s = host_sim::scenario::file::parse(&format!(
        "name = \"ok\"\n{}",
        step(65534, "right", 0.2, -0.1, "")
    ))
    .expect("id 65534 fits");
    assert_eq!(s.timeline.len(), 1);
}

#[test]
fn a_modification_the_bus_cannot_carry_is_refused_naming_the_entry() {
    let text = format!(
        "name = \"far\"\n{}\n[[modify]]\nat_s = 0.05\nid = 0\nx = 5.0\ny = -0.1\n",
        step(0, "right", 0.2, -0.1, "")
    );
    let (o, t, _) = run_toml("far", &text);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert_has(
        &t,
        &[
            "far.toml",
            "[[modify]] #1 (id 0) at line 9",
            "(+4.8000, +0.0000) m from the appended",
            "-4.096 … 4.0955 m",
        ],
    );
}

#[test]
fn every_dbc_reason_name_is_an_expectation() {
    let dbc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("can/walking.dbc"))
            .expect("walking.dbc");
    let table = dbc
        .lines()
        .find(|l| l.starts_with("VAL_ 128 reason "))
        .expect("the reason value table");
    let names: Vec<&str> = table.split('"').skip(1).step_by(2).collect();
    assert_eq!(names.len(), Reason::CODES, "{table}");
    for name in names.iter().filter(|&&n| n != "accepted") {
        let f = Failure::from_name(name).unwrap_or_else(|| panic!("{name}"));
        assert_eq!(f.name(), *name);
        let text = format!(
            "name = \"n\"\n{}",
            step(0, "right", 0.2, -0.1, &format!("expect = \"{name}\""))
        );
        host_sim::scenario::file::parse(&text).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    let e = host_sim::scenario::file::parse(&format!(
        "name = \"n\"\n{}",
        step(0, "right", 0.2, -0.1, "expect = \"far\"")
    ))
    .unwrap_err();
    assert!(
        e.contains("unknown expect = \"far\"") && e.contains("not_walked"),
        "{e}"
    );
}

#[test]
fn help_lists_every_subcommand() {
    let o = host_sim(&["--help"]);
    assert!(o.status.success());
    let t = text(&o);
    for sub in [
        "list",
        "run",
        "replay",
        "tables",
        "physics",
        "physics-tables",
        "physics-faults",
        "physics-sequence",
        "push-map",
        "robot",
        "node",
    ] {
        assert!(
            t.lines().any(|l| l.trim_start().starts_with(sub)),
            "--help does not list {sub}:\n{t}"
        );
    }
    // The book's sentence on `--help` names every subcommand `--help` lists.
    let listed: Vec<&str> = t
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(listed.len() >= 11, "{t}");
    let book = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/src/host-sim.md"),
    )
    .expect("the book's host-sim chapter");
    let from = book.find("lists the subcommands").expect("the sentence");
    let sentence = &book[from..from + book[from..].find("exit status").expect("its end")];
    for c in &listed {
        assert!(
            sentence.contains(&format!("`{c}`")),
            "docs/src/host-sim.md does not list `{c}`: {sentence}"
        );
    }
    // The exit status of every command that can fail its run.
    assert_has(&t, &["1 `run`", "1 `replay`"]);
    // `tables` promises what it prints.
    let tables = text(&host_sim(&["tables", "--help"]));
    assert!(!tables.contains("Fig. 4"), "{tables}");
    let o = host_sim(&["--version"]);
    assert!(o.status.success());
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        format!("host-sim {}", env!("CARGO_PKG_VERSION"))
    );
}

#[test]
fn usage_errors() {
    for (args, needle) in [
        (&["run", "straight", "--bogus"][..], "--bogus"),
        (&["--bogus"][..], "--bogus"),
        (&["run", "straight", "--out"][..], "--out"),
        (&["run"][..], "SCENARIO"),
        (&["jump"][..], "jump"),
        (&["node", "can0", "--seconds", "-1"][..], "-1"),
        (&["physics-faults", "--walk", "sideways"][..], "sideways"),
    ] {
        let o = host_sim(args);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {t}");
        assert!(t.contains("error") && t.contains(needle), "{args:?}: {t}");
    }
    let o = host_sim(&["run", "nonexistent"]);
    assert_eq!(o.status.code(), Some(2));
    assert_has(&text(&o), &["unknown scenario \"nonexistent\"", "straight"]);
    let o = host_sim(&["run", "/nonexistent/walk.toml"]);
    assert_eq!(o.status.code(), Some(2));
    assert_has(&text(&o), &["/nonexistent/walk.toml"]);
}

#[test]
fn an_unwritable_out_names_the_path() {
    let dir = temp_dir("unwritable");
    // A path through a regular file cannot be a directory, whoever runs the test (root too).
    let blocker = dir.join("file");
    std::fs::write(&blocker, "").expect("file");
    let out = blocker.join("out");
    let out = out.to_str().expect("UTF-8 path");
    for args in [
        &["run", "straight", "--out", out][..],
        &["tables", "--out", out][..],
    ] {
        let o = host_sim(args);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {t}");
        assert_has(&t, &[out, "output directory"]);
    }
}

#[cfg(not(feature = "socketcan"))]
#[test]
fn node_without_the_feature_names_the_interface() {
    let o = host_sim(&["node", "can7"]);
    assert_eq!(o.status.code(), Some(2));
    assert_has(&text(&o), &["can7", "socketcan"]);
}

#[test]
fn the_built_in_scenarios_pass() {
    let dir = temp_dir("built-in");
    for name in host_sim::scenario::BUILT_IN {
        let out = dir.join(name);
        let o = host_sim(&["run", name, "--out", out.to_str().expect("UTF-8 path")]);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", text(&o));
        assert_eq!(summary(&out)["unexpected_outcomes"], 0, "{name}");
    }
    let scenarios = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios");
    for f in ["fig4.toml", "lateral.toml"] {
        let o = host_sim(&[
            "run",
            scenarios.join(f).to_str().expect("UTF-8 path"),
            "--out",
            dir.join(f).to_str().expect("UTF-8 path"),
        ]);
        assert_eq!(o.status.code(), Some(0), "{f}: {}", text(&o));
    }
}

/// `replay` names a refused command by its DBC name (here the out-of-reach `STEP_APPEND` of a
/// recorded run), on the terminal and in its `summary.json`.
#[test]
fn replay_names_refused_commands_by_their_dbc_name() {
    let (_, _, out) = run_toml("replay-names", &out_of_reach(""));
    let log = out.join("can.log");
    let replayed = out.join("replay");
    let o = host_sim(&[
        "replay",
        log.to_str().expect("UTF-8 path"),
        "--out",
        replayed.to_str().expect("UTF-8 path"),
    ]);
    let t = text(&o);
    assert_has(&t, &["command STEP_APPEND seq/id 2: reach"]);
    assert!(!t.contains("command 0x"), "{t}");
    let s = summary(&replayed);
    let refused = s["refused"].as_array().expect("list");
    assert!(refused.iter().any(|r| r["command"] == "STEP_APPEND"), "{s}");
}

/// One out-of-reach append and what follows from it: the later append (`sequence_gap`) and a
/// modification of the refused step (`unknown_step`) are printed as following from it, not as
/// unexpected, and the run counts one unexpected outcome.
#[test]
fn the_consequences_of_a_refusal_are_grouped_under_it() {
    let toml = format!(
        "{}{}[[modify]]\nat_s = 0.05\nid = 2\nx = 1.0\ny = -0.1\n\n",
        out_of_reach(""),
        step(3, "left", 1.3, 0.1, "")
    );
    let (o, t, out) = run_toml("consequences", &toml);
    assert_eq!(o.status.code(), Some(1), "{t}");
    let marked = t
        .lines()
        .filter(|l| l.trim_start().starts_with("UNEXPECTED"))
        .count();
    assert_eq!(marked, 1, "{t}");
    assert_has(
        &t,
        &[
            "refused: sequence_gap (code 10) (follows from the refusal of step 2)",
            "refused: unknown_step (code 6) (follows from the refusal of step 2)",
            "1 command did not go as the scenario expected",
        ],
    );
    let s = summary(&out);
    assert_eq!(s["unexpected_outcomes"], 1, "{s}");
    let refused = s["refused_commands"].as_array().expect("list");
    let follows: Vec<_> = refused
        .iter()
        .map(|r| r["follows_from_step"].clone())
        .collect();
    assert_eq!(
        follows,
        [serde_json::Value::Null, 2.into(), 2.into()],
        "{s}"
    );
}

/// `host-sim ARGS` with its standard output a socket whose reader has gone away (as `| head`
/// leaves it once it has read enough): every write to it fails with a broken pipe.
#[cfg(unix)]
fn with_closed_stdout(args: &[&str]) -> Output {
    use std::os::fd::OwnedFd;
    use std::os::unix::net::UnixStream;
    let (writer, reader) = UnixStream::pair().expect("a socket pair");
    drop(reader);
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .stdout(std::process::Stdio::from(OwnedFd::from(writer)))
        .output()
        .expect("run host-sim")
}

/// The same with standard error into the same closed socket (`2>&1 | head`): its exit status.
#[cfg(unix)]
fn with_closed_stdout_and_stderr(args: &[&str]) -> Option<i32> {
    use std::os::fd::OwnedFd;
    use std::os::unix::net::UnixStream;
    let (writer, reader) = UnixStream::pair().expect("a socket pair");
    drop(reader);
    let err = writer.try_clone().expect("a second handle");
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .stdout(std::process::Stdio::from(OwnedFd::from(writer)))
        .stderr(std::process::Stdio::from(OwnedFd::from(err)))
        .status()
        .expect("run host-sim")
        .code()
}

/// A reader that stops reading (`host-sim … | head`) ends the printing, not the command: no
/// panic, the command's own exit status, its files written.
#[cfg(unix)]
#[test]
fn a_closed_standard_output_is_no_crash() {
    let dir = temp_dir("closed-stdout");
    let out = dir.join("fig4");
    let cases: [(&[&str], i32); 3] = [
        (&["list"], 0),
        (
            &["run", "fig4", "--out", out.to_str().expect("UTF-8 path")],
            0,
        ),
        (&["run", "nonsense"], 2),
    ];
    for (args, status) in cases {
        let o = with_closed_stdout(args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(o.status.code(), Some(status), "{args:?}: {err}");
    }
    assert!(out.join("summary.json").is_file(), "run wrote its results");
    // Its error message into a closed pipe too: still its own status, no panic (101).
    assert_eq!(with_closed_stdout_and_stderr(&["run", "nonsense"]), Some(2));
    assert_eq!(with_closed_stdout_and_stderr(&["list"]), Some(0));
}

/// No line of the command line is printed with `println!`, `print!`, `eprintln!` or `eprint!`
/// (which panic when the reader has gone away): every one goes through `host_sim::console`.
#[test]
fn every_printed_line_survives_a_closed_pipe() {
    fn walk(dir: &Path, found: &mut Vec<String>) {
        for e in std::fs::read_dir(dir).expect("host-sim/src") {
            let p = e.expect("an entry").path();
            if p.is_dir() {
                walk(&p, found);
            } else if p.extension().is_some_and(|x| x == "rs") && !p.ends_with("console.rs") {
                let text = std::fs::read_to_string(&p).expect("a source file");
                for (i, line) in text.lines().enumerate() {
                    let code = line.split("//").next().unwrap_or("");
                    let bare = |m: &str| {
                        code.match_indices(m).any(|(at, _)| {
                            !code[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_')
                        })
                    };
                    if ["println!", "print!", "eprintln!", "eprint!"]
                        .iter()
                        .any(|m| bare(m))
                    {
                        found.push(format!("{}:{}: {line}", p.display(), i + 1));
                    }
                }
            }
        }
    }
    let mut found = Vec::new();
    walk(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src"),
        &mut found,
    );
    assert!(
        found.is_empty(),
        "print with host_sim::outln!:\n{}",
        found.join("\n")
    );
}

/// The long engine commands draw their progress on standard error only when it is a
/// terminal: piped, it carries nothing but their one-line error (here: no Python to run the
/// engine).
#[test]
fn progress_is_not_written_to_a_pipe() {
    let dir = temp_dir("progress");
    let cases: [&[&str]; 3] = [
        &["physics-tables", "--cells", "0,0"],
        &["physics-faults", "--rows", "0"],
        &[
            "push-map",
            "--quick",
            "--phases",
            "double",
            "--directions",
            "0",
        ],
    ];
    for args in cases {
        let o = Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(args)
            .args(["--out", dir.to_str().expect("UTF-8 path")])
            .env("HOST_SIM_PYTHON", dir.join("no-python"))
            .output()
            .expect("run host-sim");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(!err.contains('\r'), "{args:?}: {err:?}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err:?}");
    }
}

/// A log recorded on a robot's bus, with other nodes' extended and remote frames among the
/// node's: `replay` skips them, says how many, and answers as without them; a log with
/// nothing for the node is refused, naming why.
#[test]
fn replay_skips_other_nodes_frames_and_refuses_an_empty_log() {
    let dir = temp_dir("replay-foreign");
    let run = dir.join("run");
    let o = host_sim(&["run", "fig4", "--out", run.to_str().expect("UTF-8 path")]);
    assert!(o.status.success(), "{}", text(&o));
    let log = std::fs::read_to_string(run.join("can.log")).expect("can.log");
    let mut mixed = String::new();
    let mut skipped = 0;
    for (i, line) in log.lines().enumerate() {
        mixed += line;
        mixed += "\n";
        if i % 100 == 7 {
            let time = line.split_whitespace().next().expect("a time");
            mixed += &format!("{time} can0 18FF0A01#0102\n{time} can0 123#R\n");
            skipped += 2;
        }
    }
    assert!(skipped > 2);
    let replay = |name: &str, text: &str| {
        let file = dir.join(name);
        std::fs::write(&file, text).expect("a log");
        let out = dir.join(format!("{name}.out"));
        let o = host_sim(&[
            "replay",
            file.to_str().expect("UTF-8 path"),
            "--out",
            out.to_str().expect("UTF-8 path"),
        ]);
        (o, out)
    };
    let (plain, plain_out) = replay("plain.log", &log);
    let (o, out) = replay("mixed.log", &mixed);
    let t = text(&o);
    assert_eq!(o.status.code(), plain.status.code(), "{t}");
    assert_has(&t, &[&format!("{skipped} frames skipped")]);
    let (a, b) = (summary(&plain_out), summary(&out));
    assert_eq!(b["frames_skipped"], skipped, "{b}");
    assert_eq!(a["frames_replayed"], b["frames_replayed"]);
    assert_eq!(a["refused"], b["refused"]);
    for empty in ["", "\n\n", "(1767225600.000000) can0 18FF0A01#01\n"] {
        let (o, _) = replay("empty.log", empty);
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{empty:?}: {t}");
        assert_has(&t, &["nothing to replay"]);
    }
}

/// An append numbered 128 or more past the node's next step number cannot be read by the node
/// (a frame carries the number's low byte) and is answered `bad_crc`; `run`, which numbered
/// it, names the cause: the number is not the next one. Within the window the node answers
/// `sequence_gap` itself.
#[test]
fn a_step_number_out_of_the_nodes_window_is_named_as_such() {
    for (id, read_as) in [(256, 0), (200, 65480)] {
        let toml = format!(
            "name = \"gap\"\n{}{}{START_STOP}",
            step(0, "right", 0.2, -0.1, ""),
            step(id, "left", 0.4, 0.1, ""),
        );
        let (_, t, _) = run_toml(&format!("gap-{id}"), &toml);
        assert_has(
            &t,
            &[
                "refused: bad_crc (code 16)",
                &format!("step {id} is not the node's next step number (1)"),
                &format!("(here as step {read_as})"),
            ],
        );
    }
    let toml = format!(
        "name = \"gap\"\n{}{}{START_STOP}",
        step(0, "right", 0.2, -0.1, ""),
        step(128, "left", 0.4, 0.1, ""),
    );
    let (_, t, _) = run_toml("gap-128", &toml);
    assert_has(&t, &["refused: sequence_gap (code 10)"]);
    assert!(!t.contains("bad_crc"), "{t}");
}

/// A `start` refused `wrong_state` because the only step was refused follows from that
/// refusal: not marked UNEXPECTED, and the run exits 0 when the scenario expects the first.
#[test]
fn a_start_after_a_refused_first_step_follows_from_it() {
    let toml = format!(
        "name = \"first\"\n{}{}[[command]]\nat_s = 0.1\nkind = \"start\"\n",
        step(0, "right", 1.2, -0.1, "expect = \"reach\""),
        step(1, "left", 0.2, 0.1, ""),
    );
    let (o, t, out) = run_toml("first-refused", &toml);
    assert_eq!(o.status.code(), Some(0), "{t}");
    assert_has(
        &t,
        &["start: refused: wrong_state (code 9) (follows from the refusal of step 0)"],
    );
    assert!(!t.contains("UNEXPECTED"), "{t}");
    let s = summary(&out);
    assert_eq!(s["unexpected_outcomes"], 0, "{s}");
}

/// `push-map --directions` takes directions in degrees, -180 … 360: anything else is a usage
/// error naming the value, before any engine run.
#[test]
fn push_map_refuses_directions_out_of_range() {
    let dir = temp_dir("directions");
    for bad in ["400", "-200", "nan", "inf", "x", "0,361"] {
        let o = Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(["push-map", "--directions", bad, "--out"])
            .arg(&dir)
            .env("HOST_SIM_PYTHON", dir.join("no-python"))
            .output()
            .expect("run host-sim");
        let t = text(&o);
        assert_eq!(o.status.code(), Some(2), "{bad}: {t}");
        assert_has(&t, &["is not a direction in degrees (-180 … 360"]);
    }
}

/// `push-map --scan` pushes with forces: with `--push velocity` it is an error naming both
/// (before any engine run).
#[test]
fn push_map_scan_needs_force_pushes() {
    let o = host_sim(&["push-map", "--scan", "--push", "velocity"]);
    assert!(!o.status.success());
    let t = text(&o);
    assert!(t.contains("--scan") && t.contains("--push velocity"), "{t}");
}
