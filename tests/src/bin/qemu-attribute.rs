//! `qemu-attribute`: where the instructions of one control cycle go, per function, on the
//! emulated target.
//!
//! Runs a firmware image under `qemu-system-arm -icount shift=0 -d in_asm,exec,nochain`
//! (QEMU prints every translated block's instructions once, `in_asm`, and a line for every
//! execution of a block, `exec`; `nochain` makes it print every one), follows the trace as it
//! streams, and cuts it into *calls* of one function (`--function`, by default the QEMU
//! image's `board_core::control::poll`, the wrapper around one `Node::poll`): a call starts when a
//! block at the function's entry runs and ends when the block at its return address (the
//! address after the branch-and-link that entered it) runs. (The parsing and the cutting are
//! `walk_tests::trace`'s, shared with `qemu-cycles`.)
//!
//! For the call that ran the most instructions (or the `--call`-th one) it prints:
//! * its number of instructions (QEMU's count of executed instructions: a block cut short by an
//!   I/O access counts in full, so the figure can exceed the image's own timer count by a few);
//! * **inclusive** instructions per function on the real call stack (a shadow stack of the
//!   branch-and-links taken and their returns), the way a profiler's call tree does;
//! * **self** instructions per source function, inlined functions included (DWARF inline
//!   frames through the `addr2line` crate), and per source line with `--lines`.
//!
//! Usage: `qemu-attribute [--machine M] [--function SUBSTR] [--call N] [--stop-after N]
//! [--top K] [--lines] [--counts FILE] [--stdout FILE] ELF` (see `firmware/qemu/attribute.sh`).
//! `--counts FILE` writes every call's instruction count, one per line, in call order;
//! `--stdout FILE` keeps what the image printed over semihosting.
//!
//! The image replays recorded CAN logs (`replay.wlog` in its working directory, see
//! `gait_loop::binlog`): the tool records them, host-sim's run of `--scenario` (a built-in
//! scenario, a TOML file, a fault row of the QEMU test such as `fault-mixed-0` or a worst
//! admissible cycle, `worst-start`, `worst-adjusting`, `worst-report`, `worst-reach`, `worst-measured`, `worst-velocity`, `worst-velocity-start`, `worst-goal-start`, `worst-goal` or `worst-resume`; `fig4` by
//! default; `all`: every log the QEMU test replays, in its order), in a directory of its own
//! and runs QEMU there. `--stop-after N` kills QEMU after N calls (for a quick look at the
//! first cycles, and for the smoke test in `tests/tests/attribute.rs`).

use std::collections::HashMap;
use std::io::Write;
use std::ops::ControlFlow;
use std::path::PathBuf;

use walk_tests::trace::{self, Call, Symbols};

/// Command-line options.
#[derive(Debug)]
struct Options {
    machine: String,
    function: String,
    call: Option<usize>,
    stop_after: Option<usize>,
    top: usize,
    lines: bool,
    counts: Option<PathBuf>,
    stdout: Option<PathBuf>,
    scenario: String,
    elf: PathBuf,
}

fn usage() -> ! {
    eprintln!(
        "usage: qemu-attribute [--machine M] [--function SUBSTR] [--call N] [--stop-after N] \
         [--top K] [--lines] [--counts FILE] [--stdout FILE] [--scenario NAME|FILE.toml|fault-KIND-RATE|worst-PATH] ELF"
    );
    std::process::exit(2)
}

fn parse_options() -> Options {
    let mut o = Options {
        machine: "mps2-an500".into(),
        function: "board_core::control::poll".into(),
        call: None,
        stop_after: None,
        top: 25,
        lines: false,
        counts: None,
        stdout: None,
        scenario: "fig4".into(),
        elf: PathBuf::new(),
    };
    let mut args = std::env::args().skip(1);
    let mut elf = None;
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| usage());
        match a.as_str() {
            "--machine" => o.machine = value(),
            "--function" => o.function = value(),
            "--call" => o.call = Some(value().parse().unwrap_or_else(|_| usage())),
            "--stop-after" => o.stop_after = Some(value().parse().unwrap_or_else(|_| usage())),
            "--top" => o.top = value().parse().unwrap_or_else(|_| usage()),
            "--lines" => o.lines = true,
            "--counts" => o.counts = Some(PathBuf::from(value())),
            "--stdout" => o.stdout = Some(PathBuf::from(value())),
            "--scenario" => o.scenario = value(),
            s if s.starts_with("--") => usage(),
            _ => elf = Some(PathBuf::from(a)),
        }
    }
    // Absolute: QEMU runs in the log's directory.
    let elf = elf.unwrap_or_else(|| usage());
    o.elf = std::fs::canonicalize(&elf).unwrap_or(elf);
    o
}

fn main() {
    let o = parse_options();
    let fail = |e: String| -> ! {
        eprintln!("qemu-attribute: {e}");
        std::process::exit(1)
    };
    let mut syms = Symbols::new(&o.elf).unwrap_or_else(|e| fail(e));
    let dir = trace::write_log("qemu-attribute", &o.scenario).unwrap_or_else(|e| fail(e));
    let mut best: Option<(usize, Call)> = None;
    let run = trace::Run {
        machine: &o.machine,
        elf: &o.elf,
        dir: &dir,
        function: &o.function,
        stdout: o.stdout.as_deref(),
    };
    let traced = trace::run(&run, &mut syms, |index, call, _| {
        let wanted = match o.call {
            Some(k) => index == k,
            None => best
                .as_ref()
                .is_none_or(|(_, b)| call.instructions > b.instructions),
        };
        if wanted {
            best = Some((index, call));
        }
        if o.stop_after.is_some_and(|s| index + 1 >= s) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    let _ = std::fs::remove_dir_all(&dir);
    let trace::Traced { blocks, counts } = traced.unwrap_or_else(|e| fail(e));

    if let Some(path) = &o.counts {
        let text: String = counts.iter().map(|c| format!("{c}\n")).collect();
        if let Err(e) = std::fs::write(path, text) {
            eprintln!("qemu-attribute: cannot write {}: {e}", path.display());
            std::process::exit(1)
        }
    }
    let Some((index, call)) = best else {
        eprintln!("qemu-attribute: no call of `{}` completed", o.function);
        std::process::exit(1)
    };
    // A closed pipe (`| head`) ends the output, not the program with a panic.
    let mut out = std::io::stdout().lock();
    let total = call.instructions;
    let mean = counts.iter().sum::<u64>() as f64 / counts.len().max(1) as f64;
    let _ = writeln!(
        out,
        "CALLS function={} n={} mean={mean:.0} max={}",
        o.function,
        counts.len(),
        counts.iter().max().copied().unwrap_or(0)
    );
    let _ = writeln!(out, "CALL index={index} instructions={total}");

    // Inclusive, on the shadow call stack; self, per innermost (inlined) function and line.
    let mut inclusive: HashMap<String, u64> = HashMap::new();
    let mut own: HashMap<String, u64> = HashMap::new();
    let mut per_line: HashMap<String, u64> = HashMap::new();
    // Inclusive per call site (callee, and the source line of the branch-and-link).
    let mut per_site: HashMap<String, u64> = HashMap::new();
    // (return address, callee symbol, `callee ← file:line` of the call)
    let mut stack: Vec<(u32, String, String)> = Vec::new();
    let mut root = None;
    let mut pending_return: Option<(u32, u32)> = None;
    for host in &call.blocks {
        let block = &blocks[host];
        let pc = block.addrs[0];
        if let Some(k) = stack.iter().rposition(|(ret, _, _)| *ret == pc) {
            stack.truncate(k);
        }
        if let Some((ret, site)) = pending_return.take() {
            let callee = syms.symbol(pc);
            let (_, line) = syms.inner(site);
            let key = format!("{callee} <- {line}");
            stack.push((ret, callee, key));
        }
        let here = root.get_or_insert_with(|| syms.symbol(pc)).clone();
        let mut on_stack: Vec<&str> = vec![here.as_str()];
        let mut sites: Vec<&str> = Vec::new();
        for (_, s, site) in &stack {
            if !on_stack.contains(&s.as_str()) {
                on_stack.push(s);
            }
            if !sites.contains(&site.as_str()) {
                sites.push(site);
            }
        }
        for s in sites {
            *per_site.entry(s.to_string()).or_default() += block.addrs.len() as u64;
        }
        for s in on_stack {
            *inclusive.entry(s.to_string()).or_default() += block.addrs.len() as u64;
        }
        for a in &block.addrs {
            let (f, l) = syms.inner(*a);
            *own.entry(f).or_default() += 1;
            if o.lines {
                *per_line.entry(l).or_default() += 1;
            }
        }
        if block.calls {
            pending_return = block.addrs.last().map(|last| (block.end, *last));
        }
    }
    let mut table = |title: &str, map: HashMap<String, u64>| {
        let mut v: Vec<_> = map.into_iter().collect();
        v.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
        let _ = writeln!(out, "\n{title}");
        for (name, n) in v.into_iter().take(o.top) {
            let _ = writeln!(
                out,
                "{n:>9} {:>5.1}%  {name}",
                100.0 * n as f64 / total.max(1) as f64
            );
        }
    };
    table("INCLUSIVE (call stack)", inclusive);
    if o.lines {
        table(
            "INCLUSIVE (call site: callee <- file:line of the call)",
            per_site,
        );
    }
    table("SELF (source function, inlined included)", own);
    if o.lines {
        table(
            "SELF (source line: the innermost one in the project)",
            per_line,
        );
    }
}
