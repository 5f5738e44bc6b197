//! QEMU's instruction trace of a firmware image, cut into calls of one function: what
//! `qemu-attribute` (per function) and `qemu-cycles` (estimated core cycles) read.
//!
//! [`run`] runs an image under `qemu-system-arm -icount shift=0 -d in_asm,exec,nochain`
//! (QEMU prints every translated block's instructions once, `in_asm`, and a line for every
//! execution of a block, `exec`; `nochain` makes it print every one), follows the trace as it
//! streams and cuts it into *calls* of one function (by default the QEMU image's
//! `board_core::control::poll`, the wrapper around one `Node::poll`): a call starts when a
//! block at the function's entry runs, entered by a branch-and-link, and ends when the block
//! at its return address (the address after that branch-and-link) runs. Each call is handed
//! to a callback with the blocks it ran, in order.
//!
//! [`write_log`] records the replay log the image reads (`replay.wlog`): host-sim's run of a
//! scenario (a built-in one, a TOML file or a fault row of the QEMU test such as
//! `fault-mixed-0`).

use std::borrow::Cow;
use std::collections::HashMap;
use std::io::{BufRead, BufReader};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The instructions of one translated block: their addresses, and the address after the last.
#[derive(Clone, Debug, Default)]
pub struct Block {
    /// The guest address of every instruction, in order.
    pub addrs: Vec<u32>,
    /// The address after the last instruction.
    pub end: u32,
    /// The last instruction is a branch-and-link (`bl`, `blx`): the block calls a function
    /// and `end` is its return address.
    pub calls: bool,
}

/// A function's name without its `::h…` hash.
pub fn clean(name: &str) -> String {
    match name.rfind("::h") {
        Some(i) if name.len() - i == 19 => name[..i].to_string(),
        _ => name.to_string(),
    }
}

/// Symbol lookups in an image's symbol table and DWARF, cached per address.
pub struct Symbols {
    /// The image's symbols and debug information.
    pub loader: addr2line::Loader,
    symbol: HashMap<u32, String>,
    inner: HashMap<u32, (String, String)>,
    entry: HashMap<(u32, String), bool>,
}

impl Symbols {
    /// The symbols of the ELF file `elf`.
    pub fn new(elf: &Path) -> Result<Symbols, String> {
        let loader = addr2line::Loader::new(elf)
            .map_err(|e| format!("cannot read {}: {e}", elf.display()))?;
        Ok(Symbols {
            loader,
            symbol: HashMap::new(),
            inner: HashMap::new(),
            entry: HashMap::new(),
        })
    }

    /// The (non-inlined) symbol that contains `addr`.
    pub fn symbol(&mut self, addr: u32) -> String {
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

    /// Whether `pc` is the entry (the symbol's own address) of a function whose name contains
    /// `function`.
    pub fn is_entry(&mut self, pc: u32, function: &str) -> bool {
        let key = (pc, function.to_string());
        if let Some(&e) = self.entry.get(&key) {
            return e;
        }
        let s = self.symbol(pc);
        let e = s.contains(function)
            && self
                .loader
                .find_symbol_info(u64::from(pc | 1))
                .is_some_and(|i| i.address() & !1 == u64::from(pc));
        self.entry.insert(key, e);
        e
    }

    /// The innermost source function at `addr` (inlined ones included) and its `file:line`.
    pub fn inner(&mut self, addr: u32) -> (String, String) {
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
pub fn instruction(line: &str) -> Option<(u32, u32, bool)> {
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
pub fn trace(line: &str) -> Option<(u64, u32)> {
    let rest = line.strip_prefix("Trace ")?;
    let (_, rest) = rest.split_once(": 0x")?;
    let (host, rest) = rest.split_once(" [")?;
    let host = u64::from_str_radix(host, 16).ok()?;
    let mut fields = rest.split('/');
    fields.next()?;
    let pc = u32::from_str_radix(fields.next()?, 16).ok()?;
    Some((host, pc))
}

/// One call of the function: the blocks it ran (their host addresses, keys of
/// [`Traced::blocks`] and of the map handed to [`run`]'s callback), in order, and its number
/// of instructions.
#[derive(Default)]
pub struct Call {
    /// The blocks it ran, in order.
    pub blocks: Vec<u64>,
    /// Its instructions (every block counted in full).
    pub instructions: u64,
}

/// Records host-sim's run of `scenario` as the image's `replay.wlog`, in a new temporary
/// directory named after `tool` (returned): a fault-sweep row the QEMU test replays
/// (`fault-drop-0.05`, `fault-mixed-0`, …: fig4, seed 1, the node as
/// `faults::run_case_logged` runs it), a worst admissible cycle (`worst-start`,
/// `worst-adjusting`, `worst-report`, `worst-reach`, `worst-measured`, `worst-velocity`, `worst-velocity-start`, `worst-goal-start`, `worst-goal`, `worst-resume`: `crate::logs::WORST`), a TOML file (`….toml`) or a built-in scenario; `all`:
/// every log the QEMU tests replay, in their order (`crate::logs::cases`).
pub fn write_log(tool: &str, scenario: &str) -> Result<PathBuf, String> {
    let fail = |e: String| format!("scenario {scenario}: {e}");
    let dir = std::env::temp_dir().join(format!("{tool}-{}", std::process::id()));
    if scenario == "all" {
        let bytes: Vec<u8> = crate::logs::cases()
            .iter()
            .flat_map(crate::logs::binary)
            .collect();
        std::fs::create_dir_all(&dir).map_err(|e| fail(e.to_string()))?;
        std::fs::write(dir.join("replay.wlog"), bytes).map_err(|e| fail(e.to_string()))?;
        return Ok(dir);
    }
    let fault = crate::logs::fault_runs()
        .into_iter()
        .find(|(name, _, _)| name == scenario);
    let worst = host_sim::sim::worst::Path::named(scenario);
    let (log, cfg) = if let Some(path) = worst {
        let cfg = planner_core::node::NodeConfig::hrp2();
        let w = host_sim::sim::worst::worst_cycle(&cfg, path).map_err(fail)?;
        (w.can_log, w.cfg)
    } else if let Some((_, kind, rate)) = fault {
        let fig4 = host_sim::scenario::built_in("fig4").ok_or_else(|| fail("no fig4".into()))?;
        let (_, log) = host_sim::eval::faults::run_case_logged(&fig4, kind, rate, 1)
            .map_err(|e| fail(e.to_string()))?;
        (log, planner_core::node::NodeConfig::hrp2())
    } else {
        let s = if scenario.ends_with(".toml") {
            host_sim::scenario::file::load(Path::new(scenario)).map_err(|e| fail(e.to_string()))?
        } else {
            host_sim::scenario::built_in(scenario).ok_or_else(|| fail("not built in".into()))?
        };
        let sim = host_sim::sim::SimConfig::default();
        let run = host_sim::sim::simulate(&s, &sim).map_err(fail)?;
        (run.can_log, host_sim::sim::start_config(&s, &sim.node))
    };
    let name = log_name(scenario);
    let bytes = host_sim::sim::replay::binary_log(&name, &log, &cfg).map_err(fail)?;
    std::fs::create_dir_all(&dir).map_err(|e| fail(e.to_string()))?;
    std::fs::write(dir.join("replay.wlog"), bytes).map_err(|e| fail(e.to_string()))?;
    Ok(dir)
}

/// The name [`write_log`] gives the log of `scenario` (the image's `scenario=`): the file
/// name without `.toml`, at most 32 characters.
pub fn log_name(scenario: &str) -> String {
    scenario
        .rsplit('/')
        .next()
        .unwrap_or(scenario)
        .trim_end_matches(".toml")
        .chars()
        .take(32)
        .collect()
}

/// What [`run`] traces.
pub struct Run<'a> {
    /// The QEMU machine (`mps2-an500`, `mps2-an386`).
    pub machine: &'a str,
    /// The image (an absolute path: QEMU runs in `dir`).
    pub elf: &'a Path,
    /// QEMU's working directory, which holds the image's `replay.wlog`.
    pub dir: &'a Path,
    /// A substring of the name of the function whose calls are cut out.
    pub function: &'a str,
    /// Where the image's own output goes (`None`: discarded).
    pub stdout: Option<&'a Path>,
}

/// What [`run`] saw: every translated block by host address (the latest translation at each),
/// and every completed call's instruction count, in call order.
pub struct Traced {
    /// Translated blocks by host address.
    pub blocks: HashMap<u64, Block>,
    /// Every completed call's instructions, in call order.
    pub counts: Vec<u64>,
}

/// Runs `r.elf` under QEMU's instruction trace and hands every completed call of
/// `r.function` to `on_call` (its index from 0, the call, and the translated blocks by host
/// address as they are when the call ends); `on_call` returning `Break` stops QEMU.
pub fn run(
    r: &Run,
    syms: &mut Symbols,
    mut on_call: impl FnMut(usize, Call, &HashMap<u64, Block>) -> ControlFlow<()>,
) -> Result<Traced, String> {
    let stdout = match r.stdout {
        Some(path) => Stdio::from(
            std::fs::File::create(path)
                .map_err(|e| format!("cannot create {}: {e}", path.display()))?,
        ),
        None => Stdio::null(),
    };
    let mut qemu = Command::new("qemu-system-arm")
        .current_dir(r.dir)
        .args(["-M", r.machine, "-nographic", "-icount", "shift=0"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args(["-d", "in_asm,exec,nochain", "-kernel"])
        .arg(r.elf)
        .stdout(stdout)
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start qemu-system-arm: {e}"))?;
    let log = BufReader::with_capacity(1 << 20, qemu.stderr.take().expect("piped stderr"));

    // Translated blocks by host address (a block translated again gets a new one, or replaces
    // a freed one: the latest `IN:` before its first execution wins).
    let mut blocks: HashMap<u64, Block> = HashMap::new();
    let mut pending: Option<Block> = None;
    let mut previous: Option<u64> = None;
    // The call being recorded: its return address, its blocks.
    let mut open: Option<(u32, Call)> = None;
    let mut calls = 0;
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
            if syms.is_entry(pc, r.function) {
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
                let flow = on_call(calls, call, &blocks);
                calls += 1;
                if flow.is_break() {
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
    Ok(Traced { blocks, counts })
}
