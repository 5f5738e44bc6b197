//! `qemu-attribute`: where the instructions of one control cycle go, per function, on the
//! emulated target.
//!
//! Runs a firmware image under `qemu-system-arm -icount shift=0 -d in_asm,exec,nochain`
//! (QEMU prints every translated block's instructions once, `in_asm`, and a line for every
//! execution of a block, `exec`; `nochain` makes it print every one), follows the trace as it
//! streams, and cuts it into *calls* of one function (`--function`, by default the QEMU
//! image's `board_core::control::poll`, the wrapper around one `Node::poll`): a call starts when a
//! block at the function's entry runs and ends when the block at its return address (the
//! address after the branch-and-link that entered it) runs.
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
//! `gait_loop::binlog`): the tool records one, host-sim's run of `--scenario` (a built-in
//! scenario, a TOML file or a fault row of the QEMU test such as `fault-mixed-0`; `fig4` by
//! default), in a directory of its own and runs QEMU there. `--stop-after N` kills QEMU
//! after N calls (for a quick look at the first cycles, and for the smoke test in
//! `tests/tests/qemu.rs`).

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// The instructions of one translated block: their addresses, and the address after the last.
#[derive(Clone, Debug, Default)]
struct Block {
    addrs: Vec<u32>,
    end: u32,
    /// The last instruction is a branch-and-link (`bl`, `blx`): the block calls a function
    /// and `end` is its return address.
    calls: bool,
}

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
         [--top K] [--lines] [--counts FILE] [--stdout FILE] [--scenario NAME|FILE.toml|fault-KIND-RATE] ELF"
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

/// A function's name without its `::h…` hash.
fn clean(name: &str) -> String {
    match name.rfind("::h") {
        Some(i) if name.len() - i == 19 => name[..i].to_string(),
        _ => name.to_string(),
    }
}

/// Symbol lookups, cached per address.
struct Symbols {
    loader: addr2line::Loader,
    symbol: HashMap<u32, String>,
    inner: HashMap<u32, (String, String)>,
}

impl Symbols {
    /// The (non-inlined) symbol that contains `addr`.
    fn symbol(&mut self, addr: u32) -> String {
        if let Some(s) = self.symbol.get(&addr) {
            return s.clone();
        }
        // Thumb symbols carry the low bit set: probe with it.
        let name = match self.loader.find_symbol(u64::from(addr | 1)) {
            Some(raw) => clean(&addr2line::demangle_auto(Cow::from(raw), None)),
            None => format!("{addr:#010x}"),
        };
        self.symbol.insert(addr, name.clone());
        name
    }

    /// The innermost source function at `addr` (inlined ones included) and its `file:line`.
    fn inner(&mut self, addr: u32) -> (String, String) {
        if let Some(s) = self.inner.get(&addr) {
            return s.clone();
        }
        let mut function = None;
        let mut line = String::from("?");
        if let Ok(mut frames) = self.loader.find_frames(u64::from(addr)) {
            // Innermost first: the function is the innermost frame's; the line is that of the
            // innermost frame in the project's own code (not the standard library's or a
            // dependency's), which says where an inlined `+` or `Option::map` was written.
            let mut first = true;
            while let Ok(Some(frame)) = frames.next() {
                if first {
                    function = frame
                        .function
                        .as_ref()
                        .and_then(|f| f.demangle().ok())
                        .map(|f| clean(&f));
                }
                if let Some(l) = frame.location {
                    let file = l.file.unwrap_or("?");
                    let foreign = file.starts_with("/rustc/") || file.contains("/.cargo/registry/");
                    if first || !foreign {
                        let short = file.rsplit('/').take(2).collect::<Vec<_>>();
                        let short = short.into_iter().rev().collect::<Vec<_>>().join("/");
                        line = format!("{short}:{}", l.line.unwrap_or(0));
                    }
                    if !foreign {
                        break;
                    }
                }
                first = false;
            }
        }
        let function = function.unwrap_or_else(|| self.symbol(addr));
        let v = (function, line);
        self.inner.insert(addr, v.clone());
        v
    }
}

/// Parses one `in_asm` instruction line (`0x0000d600:  b5f0  push {r4, lr}`): its address,
/// size in bytes and whether it is a branch-and-link.
fn instruction(line: &str) -> Option<(u32, u32, bool)> {
    let rest = line.strip_prefix("0x")?;
    let (addr, rest) = rest.split_once(':')?;
    let addr = u32::from_str_radix(addr, 16).ok()?;
    let mut words = rest.split_whitespace();
    let mut size = 0;
    let mut mnemonic = "";
    for w in words.by_ref() {
        if w.len() == 4 && w.chars().all(|c| c.is_ascii_hexdigit()) && mnemonic.is_empty() {
            size += 2;
        } else {
            mnemonic = w;
            break;
        }
    }
    // A mnemonic that is itself four hex digits (`adds`?) cannot occur: ARM mnemonics have
    // letters outside a-f after the first ones, but guard anyway: a Thumb instruction is one
    // or two half-words.
    if size == 0 || size > 4 {
        return None;
    }
    let calls = mnemonic == "bl" || mnemonic.starts_with("blx");
    Some((addr, size, calls))
}

/// Parses an `exec` line (`Trace 0: 0x7f… [00800408/00000400/00000110/ff020200] Reset`): the
/// translated block's host address and its guest pc.
fn trace(line: &str) -> Option<(u64, u32)> {
    let rest = line.strip_prefix("Trace ")?;
    let (_, rest) = rest.split_once(": 0x")?;
    let (host, rest) = rest.split_once(" [")?;
    let host = u64::from_str_radix(host, 16).ok()?;
    let mut fields = rest.split('/');
    fields.next()?;
    let pc = u32::from_str_radix(fields.next()?, 16).ok()?;
    Some((host, pc))
}

/// One call of the function: the blocks it ran, in order, with their call depth.
#[derive(Default)]
struct Call {
    blocks: Vec<u64>,
    instructions: u64,
}

/// Records host-sim's run of `scenario` as the image's `replay.wlog`, in a new temporary
/// directory (returned).
fn write_log(scenario: &str) -> PathBuf {
    let fail = |e: String| -> ! {
        eprintln!("qemu-attribute: scenario {scenario}: {e}");
        std::process::exit(1)
    };
    // A fault-sweep row the QEMU test replays (`fault-drop-0.05`, `fault-mixed-0`, …: fig4,
    // seed 1, the node as `faults::run_case_logged` runs it).
    let fault = walk_tests::logs::fault_runs()
        .into_iter()
        .find(|(name, _, _)| name == scenario);
    let (log, cfg) = if let Some((_, kind, rate)) = fault {
        let fig4 = host_sim::scenario::built_in("fig4").unwrap_or_else(|| fail("no fig4".into()));
        let (_, log) = host_sim::eval::faults::run_case_logged(&fig4, kind, rate, 1)
            .unwrap_or_else(|e| fail(e.to_string()));
        (log, planner_core::node::NodeConfig::hrp2())
    } else {
        let s = if scenario.ends_with(".toml") {
            host_sim::scenario::file::load(std::path::Path::new(scenario))
                .unwrap_or_else(|e| fail(e.to_string()))
        } else {
            host_sim::scenario::built_in(scenario).unwrap_or_else(|| fail("not built in".into()))
        };
        let sim = host_sim::sim::SimConfig::default();
        let run = host_sim::sim::simulate(&s, &sim).unwrap_or_else(|e| fail(e));
        (run.can_log, host_sim::sim::start_config(&s, &sim.node))
    };
    let name: String = scenario
        .rsplit('/')
        .next()
        .unwrap_or(scenario)
        .trim_end_matches(".toml")
        .chars()
        .take(32)
        .collect();
    let bytes = host_sim::sim::replay::binary_log(&name, &log, &cfg).unwrap_or_else(|e| fail(e));
    let dir = std::env::temp_dir().join(format!("qemu-attribute-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| fail(e.to_string()));
    std::fs::write(dir.join("replay.wlog"), bytes).unwrap_or_else(|e| fail(e.to_string()));
    dir
}

fn main() {
    let o = parse_options();
    let loader = addr2line::Loader::new(&o.elf).unwrap_or_else(|e| {
        eprintln!("qemu-attribute: cannot read {}: {e}", o.elf.display());
        std::process::exit(1)
    });
    let mut syms = Symbols {
        loader,
        symbol: HashMap::new(),
        inner: HashMap::new(),
    };

    let dir = write_log(&o.scenario);
    let mut qemu = Command::new("qemu-system-arm")
        .current_dir(&dir)
        .args(["-M", &o.machine, "-nographic", "-icount", "shift=0"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-d", "in_asm,exec,nochain", "-kernel"])
        .arg(&o.elf)
        .stdout(match &o.stdout {
            Some(path) => Stdio::from(std::fs::File::create(path).unwrap_or_else(|e| {
                eprintln!("qemu-attribute: cannot create {}: {e}", path.display());
                std::process::exit(1)
            })),
            None => Stdio::null(),
        })
        .stderr(Stdio::piped())
        .spawn()
        .unwrap_or_else(|e| {
            eprintln!("qemu-attribute: cannot start qemu-system-arm: {e}");
            std::process::exit(1)
        });
    let log = BufReader::with_capacity(1 << 20, qemu.stderr.take().expect("piped stderr"));

    // Translated blocks by host address (a block translated again gets a new one, or replaces
    // a freed one: the latest `IN:` before its first execution wins).
    let mut blocks: HashMap<u64, Block> = HashMap::new();
    let mut pending: Option<Block> = None;
    let mut entry_seen: HashMap<u32, bool> = HashMap::new();
    let mut previous: Option<u64> = None;
    // The call being recorded: its return address, its blocks.
    let mut open: Option<(u32, Call)> = None;
    let (mut calls, mut best): (usize, Option<(usize, Call)>) = (0, None);
    let mut counts: Vec<u64> = Vec::new();
    for line in log.lines() {
        let Ok(line) = line else { break };
        if line.starts_with("IN:") {
            pending = Some(Block::default());
            continue;
        }
        if let Some((addr, size, calls_)) = instruction(&line) {
            if let Some(b) = pending.as_mut() {
                b.addrs.push(addr);
                b.end = addr + size;
                b.calls = calls_;
            }
            continue;
        }
        let Some((host, pc)) = trace(&line) else {
            continue;
        };
        if let Some(b) = pending.take() {
            if b.addrs.first() == Some(&pc) {
                blocks.insert(host, b);
            }
        }
        let Some(block) = blocks.get(&host) else {
            previous = None;
            continue;
        };
        let n = block.addrs.len() as u64;
        // Does this block start a call of the function? (Its entry block: the symbol's
        // address, entered by a branch-and-link.)
        if open.is_none() {
            let is_entry = *entry_seen.entry(pc).or_insert_with(|| {
                let s = syms.symbol(pc);
                s.contains(&o.function)
                    && syms
                        .loader
                        .find_symbol_info(u64::from(pc | 1))
                        .is_some_and(|i| i.address() & !1 == u64::from(pc))
            });
            if is_entry {
                let ret = previous
                    .and_then(|p| blocks.get(&p))
                    .filter(|b| b.calls)
                    .map(|b| b.end);
                if let Some(ret) = ret {
                    open = Some((ret, Call::default()));
                }
            }
        } else if let Some((ret, _)) = &open {
            if pc == *ret {
                let (_, call) = open.take().expect("open call");
                counts.push(call.instructions);
                let wanted = match o.call {
                    Some(k) => calls == k,
                    None => best
                        .as_ref()
                        .is_none_or(|(_, b)| call.instructions > b.instructions),
                };
                if wanted {
                    best = Some((calls, call));
                }
                calls += 1;
                if o.stop_after.is_some_and(|s| calls >= s) {
                    break;
                }
            }
        }
        if let Some((_, call)) = open.as_mut() {
            call.blocks.push(host);
            call.instructions += n;
        }
        previous = Some(host);
    }
    let _ = qemu.kill();
    let _ = qemu.wait();
    let _ = std::fs::remove_dir_all(&dir);

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
