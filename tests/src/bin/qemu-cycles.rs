//! `qemu-cycles`: the control cycles of a replayed log in **estimated core cycles** of a
//! Cortex-M7 (or, with `--m4f`, of the M4F image on a Cortex-M4), not instructions.
//!
//! QEMU counts instructions; a Cortex-M7 issues up to two a cycle, but an `f64` multiply-add
//! or divide takes many. This tool weights what QEMU executed by LLVM's scheduling model of the
//! core:
//!
//! 1. it records host-sim's run of `--scenario` (`fig4` by default; the same selection as
//!    `qemu-attribute`: a built-in scenario, a TOML file, a fault row such as
//!    `fault-mixed-0`, or `all`, every log the QEMU tests replay, in their order) as the
//!    image's `replay.wlog` and runs the image on it once untraced: the image's `TIMING`
//!    lines give each kind's worst poll (over every log: the first log with that worst, and
//!    its tick there, `max_tick`); the tool plays the logs on the host into the image's node
//!    (as `walk_tests::logs::play`) to learn which poll ended at that tick (a poll that does
//!    not tick, the handshake's or a standing one, keeps the tick before it);
//! 2. it runs the image again under QEMU's instruction trace (`walk_tests::trace`, as
//!    `qemu-attribute` does) up to the last poll wanted, and takes for each wanted poll its
//!    translated blocks (QEMU's blocks with `nochain`: straight-line code up to a branch) with
//!    their execution counts; the traced instruction count must agree with the image's timer
//!    (within 100 instructions and 1 %), or the tool fails;
//! 3. it disassembles the image's bytes of every distinct block (`llvm-objdump`, LLVM's own
//!    syntax) and feeds every block to `llvm-mca -mtriple=thumbv7em-none-eabihf -mcpu=…` as a
//!    code region of its own, twice: **high**, a single cold pass (`-iterations=1`: the block
//!    from an empty pipeline until its last instruction has written back, so every block pays
//!    its whole latency tail and nothing overlaps the next block), and **low**, the steady
//!    state (`-iterations=100`, Total Cycles / Iterations: the block run back to back, its tail
//!    overlapping the next pass, as a block's tail overlaps the following block on the core);
//! 4. it weights each block's cycles by its execution count and prints per kind of cycle
//!    (steady, re-plan, adjusted re-plan, `Start`, worst; `--kinds`; `--call N` adds the
//!    N-th poll of the file, from 0, as `qemu-attribute --call` counts) the instructions, the estimated cycles (low–high), cycles per instruction and
//!    the share of the budget: 5 % of 5 ms at the core clock (480 MHz: 120,000 cycles; the
//!    M4F at 168 MHz: 42,000).
//!
//! The assumptions (printed as `ASSUME` lines): no cache misses and no flash wait states (code
//! and read-only data hit the caches; the board's code is in flash behind the I-cache),
//! branches predicted (llvm-mca models no branch penalty), loads at the model's latency, LLVM's
//! model of the FP divider and square root as it is (its latencies are printed), and these
//! adaptations to llvm-mca 14: calls are costed as branches (`bl`→`b`, `blx`→`bx`: llvm-mca 14
//! gives a call a fixed latency of 100 cycles and has no option to change it), an `IT` as a
//! `nop` and the instructions it predicates as unconditional ones (the Cortex-M models have no
//! scheduling class for `IT`), a `vcmp` with `#0` as the register form, and any other
//! instruction without a scheduling class (`cpsid`, …) as a `nop` (counted and printed).
//!
//! It also counts the 32-byte lines of code a poll runs: beyond the 512 lines of the H743's
//! 16 KiB I-cache, each is at least one line fill from flash per poll (at least 10 core
//! cycles), which the estimate leaves out; the estimate **including the fills** adds them
//! (a stated bound: the fewest fills, each at its least). For the M4F the lines are the
//! 16-byte lines of an STM32F407-class part's ART accelerator (1 KiB, 64 lines), each beyond
//! them a fetch with the flash's 5 wait states at 168 MHz (assumed not hidden by the prefetch).
//!
//! Output: `METHOD` and `ASSUME …` lines, a table, and one line per estimated poll:
//! `ESTIMATE kind=… label=… log=… poll=… instructions=… image=… low=… high=… cpi_low=…
//! cpi_high=… budget=… share_low=… share_high=… lines=… fills_min=… fill_cycles_min=…
//! low_fills=… high_fills=… blocks=… nops=… mcpu=… mhz=…` (`low`, `high`: estimated cycles,
//! rounded; `poll`: its index in its log; `image`: the image's own count; `lines`: the code
//! lines the poll ran (32 bytes on the M7, 16 on the M4F); `fills_min`: those beyond the
//! cache's lines; `low_fills`, `high_fills`: the estimate with their cycles; `nops`: executions costed as a
//! `nop`). The estimate is deterministic: the same image, log and llvm-mca give the same
//! numbers.
//!
//! Usage: `qemu-cycles [--m4f] [--machine M] [--mcpu CPU] [--mhz F] [--scenario S]
//! [--kinds K,…|none] [--call N] [--iterations N] [--top K] [--function SUBSTR] ELF` (see
//! `firmware/qemu/cycles.sh`, which builds the images; `tests/tests/cycles.rs` runs it).
//! `--top K` lists, per poll, the K blocks with the most estimated cycles. `LLVM_MCA` and
//! `LLVM_OBJDUMP` name other binaries than `llvm-mca` and `llvm-objdump`.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::io::Write as _;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::process::Command;

use walk_tests::figures::thousands;
use walk_tests::report::{self, Record};
use walk_tests::trace::{self, Symbols};

/// The kinds of cycle estimated by default (the image's names) and how the table calls them.
const KINDS: [(&str, &str); 6] = [
    ("steady", "steady"),
    ("replan", "re-plan"),
    ("adjust", "adjusted re-plan"),
    ("step-adjust", "step adjustment"),
    ("start", "Start"),
    ("cycle", "worst"),
];
/// The traced poll and the image's timer agree within this many instructions and 1 % (the
/// timer's resolution is 40 instructions, the trace counts the whole poll function and every
/// block in full; the worst re-plans differ by about 100).
const SLACK: u64 = 100;
/// A cache line of the Cortex-M7's caches \[bytes\].
const LINE: u32 = 32;
/// The lines of the STM32H743's 16 KiB I-cache.
const ICACHE_LINES: u64 = 16 * 1024 / LINE as u64;
/// The least an I-cache line fill from the H743's flash takes \[core cycles\]: 4 wait states
/// and the access, 5 cycles of the 240 MHz AXI clock.
const FILL_CYCLES: u64 = 10;
/// A line of the STM32F407-class part's ART accelerator (its instruction cache) \[bytes\].
const M4F_LINE: u32 = 16;
/// The lines of that cache (1 KiB).
const M4F_CACHE_LINES: u64 = 1024 / M4F_LINE as u64;
/// The core cycles a fetch from that part's flash waits at 168 MHz: 5 wait states.
const M4F_FILL_CYCLES: u64 = 5;

/// Command-line options.
#[derive(Debug)]
struct Options {
    machine: String,
    mcpu: String,
    mhz: u64,
    function: String,
    scenario: String,
    kinds: Vec<String>,
    call: Option<usize>,
    iterations: u64,
    top: usize,
    elf: PathBuf,
}

fn usage() -> ! {
    eprintln!(
        "usage: qemu-cycles [--m4f] [--machine M] [--mcpu CPU] [--mhz F] \
         [--scenario NAME|FILE.toml|fault-KIND-RATE] [--kinds K,...|none] [--call N] \
         [--iterations N] [--top K] [--function SUBSTR] ELF"
    );
    std::process::exit(2)
}

fn parse_options() -> Options {
    let mut o = Options {
        machine: "mps2-an500".into(),
        mcpu: "cortex-m7".into(),
        mhz: 480,
        function: "board_core::control::poll".into(),
        scenario: "fig4".into(),
        kinds: KINDS.iter().map(|(k, _)| k.to_string()).collect(),
        call: None,
        iterations: 100,
        top: 0,
        elf: PathBuf::new(),
    };
    let mut args = std::env::args().skip(1);
    let mut elf = None;
    while let Some(a) = args.next() {
        let mut value = || args.next().unwrap_or_else(|| usage());
        match a.as_str() {
            "--m4f" => {
                o.machine = "mps2-an386".into();
                o.mcpu = "cortex-m4".into();
                o.mhz = 168;
            }
            "--machine" => o.machine = value(),
            "--mcpu" => o.mcpu = value(),
            "--mhz" => o.mhz = value().parse().unwrap_or_else(|_| usage()),
            "--function" => o.function = value(),
            "--scenario" => o.scenario = value(),
            "--kinds" => {
                let v = value();
                o.kinds = if v == "none" {
                    vec![]
                } else {
                    v.split(',').map(str::to_string).collect()
                };
            }
            "--call" => o.call = Some(value().parse().unwrap_or_else(|_| usage())),
            "--iterations" => o.iterations = value().parse().unwrap_or_else(|_| usage()),
            "--top" => o.top = value().parse().unwrap_or_else(|_| usage()),
            s if s.starts_with("--") => usage(),
            _ => elf = Some(PathBuf::from(a)),
        }
    }
    if o.iterations < 2 || o.mhz == 0 {
        usage();
    }
    // Absolute: QEMU runs in the log's directory.
    let elf = elf.unwrap_or_else(|| usage());
    o.elf = std::fs::canonicalize(&elf).unwrap_or(elf);
    o
}

fn fail(e: impl std::fmt::Display) -> ! {
    eprintln!("qemu-cycles: {e}");
    std::process::exit(1)
}

fn tool(var: &str, default: &str) -> String {
    std::env::var(var).unwrap_or_else(|_| default.to_string())
}

// ---------------------------------------------------------------------------------------
// The image's instructions in llvm-mca's input syntax.

/// The condition that inverts `c` (for the `e` slots of an `IT` block).
fn inverse(c: &str) -> &'static str {
    match c {
        "eq" => "ne",
        "ne" => "eq",
        "hs" | "cs" => "lo",
        "lo" | "cc" => "hs",
        "mi" => "pl",
        "pl" => "mi",
        "vs" => "vc",
        "vc" => "vs",
        "hi" => "ls",
        "ls" => "hi",
        "ge" => "lt",
        "lt" => "ge",
        "gt" => "le",
        "le" => "gt",
        _ => "al",
    }
}

/// The conditions of the instructions an `IT` instruction (`mnemonic` `it`, `itte`, …,
/// `cond` its operand) predicates, in order; `None` if it is not one.
fn it_block(mnemonic: &str, cond: &str) -> Option<Vec<String>> {
    let mask = mnemonic.strip_prefix("it")?;
    if mask.len() > 3 || !mask.chars().all(|c| c == 't' || c == 'e') {
        return None;
    }
    let cond = cond.trim();
    let mut v = vec![cond.to_string()];
    for c in mask.chars() {
        v.push(if c == 't' { cond } else { inverse(cond) }.to_string());
    }
    Some(v)
}

/// One instruction of `llvm-objdump`'s output (`mnemonic`, `operands` as it prints them) as
/// llvm-mca is given it: `cond`, the condition of an `IT` block that predicates it (dropped:
/// the instruction becomes unconditional); an `IT` itself becomes a `nop`; a call a branch
/// (llvm-mca 14 costs a call 100 cycles); a branch target (a bare address) a label.
fn to_mca(mnemonic: &str, operands: &str, cond: Option<&str>) -> String {
    if it_block(mnemonic, operands).is_some() {
        return "nop".to_string();
    }
    // Without the comment (`@ imm = #2`, `@ 0x450`) and the symbolic addresses (`<main+0x4>`).
    let mut ops = String::new();
    let mut depth = 0;
    for ch in operands.split('@').next().unwrap_or("").chars() {
        match ch {
            '<' => depth += 1,
            '>' if depth > 0 => depth -= 1,
            _ if depth == 0 => ops.push(ch),
            _ => {}
        }
    }
    let mut ops = ops.trim().to_string();
    let mut m = mnemonic.to_string();
    if let Some(c) = cond {
        let (base, suffix) = match m.find('.') {
            Some(i) => m.split_at(i),
            None => (m.as_str(), ""),
        };
        if let Some(b) = base.strip_suffix(c) {
            m = format!("{b}{suffix}");
        }
    }
    // A branch target: the last operand a bare address (immediates are written `#…`).
    let last_start = ops.rfind([',', ' ']).map_or(0, |i| i + 1);
    let last = ops[last_start..].trim();
    if last.starts_with("0x") && last[2..].chars().all(|c| c.is_ascii_hexdigit()) {
        ops.truncate(last_start);
        ops = ops.trim_end().to_string();
        ops.push_str(if ops.is_empty() { ".Lt" } else { " .Lt" });
    }
    // A compare with zero (`vcmp.f64 d0, #0`) has no scheduling class in llvm-mca 14: the
    // register form, the register compared with itself.
    if m.starts_with("vcmp") {
        if let Some(reg) = ops.strip_suffix(", #0").map(str::to_string) {
            ops = format!("{reg}, {reg}");
        }
        if let Some(rest) = m.strip_prefix("vcmpe") {
            m = format!("vcmp{rest}");
        }
    }
    match m.as_str() {
        "bl" => m = "b".into(),
        "blx" if ops.starts_with('r') || ops.starts_with("lr") => m = "bx".into(),
        "blx" => m = "b".into(),
        _ => {}
    }
    if ops.is_empty() {
        m
    } else {
        format!("{m}\t{ops}")
    }
}

/// The image's instructions by address, as llvm-mca is given them (`llvm-objdump -d` of the
/// ELF for `mcpu`, `IT` blocks followed).
fn disassemble(elf: &Path, mcpu: &str) -> Result<BTreeMap<u32, String>, String> {
    let objdump = tool("LLVM_OBJDUMP", "llvm-objdump");
    let out = Command::new(&objdump)
        .args(["-d", "--no-show-raw-insn", "--triple=thumbv7em-none-eabihf"])
        .arg(format!("--mcpu={mcpu}"))
        .arg(elf)
        .output()
        .map_err(|e| format!("cannot run {objdump} (Debian's llvm package): {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{objdump} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(parse_disassembly(&String::from_utf8_lossy(&out.stdout)))
}

/// [`disassemble`]'s parsing of `llvm-objdump -d --no-show-raw-insn` output.
fn parse_disassembly(text: &str) -> BTreeMap<u32, String> {
    let mut map = BTreeMap::new();
    let mut pending: Vec<String> = vec![];
    for line in text.lines() {
        // `     40c:      \tbeq\t0x412 <__stext+0x12>    @ imm = #2`
        let Some((addr, rest)) = line.split_once(':') else {
            continue;
        };
        let Ok(addr) = u32::from_str_radix(addr.trim(), 16) else {
            continue;
        };
        let mut fields = rest.split('\t');
        let lead = fields.next().unwrap_or("");
        let mnemonic = fields.next().unwrap_or("").trim();
        let operands = fields.collect::<Vec<_>>().join(" ");
        // Data (`00 00 01 20\t.word\t…`): not code, and not inside an IT block.
        if !lead.trim().is_empty() || mnemonic.is_empty() || mnemonic.starts_with('.') {
            pending.clear();
            continue;
        }
        let cond = if pending.is_empty() {
            None
        } else {
            Some(pending.remove(0))
        };
        map.insert(addr, to_mca(mnemonic, &operands, cond.as_deref()));
        if let Some(conds) = it_block(mnemonic, &operands) {
            pending = conds;
        }
    }
    map
}

// ---------------------------------------------------------------------------------------
// llvm-mca.

/// llvm-mca's verdict on a file of code regions.
enum Mca {
    /// Total Cycles per region, by name.
    Cycles(BTreeMap<String, u64>),
    /// It refused an instruction it has no scheduling class for (its mnemonic).
    Unsupported(String),
}

/// Runs llvm-mca for `mcpu` on the file `input` (code regions) for `iterations`.
fn mca(input: &Path, mcpu: &str, iterations: u64) -> Result<Mca, String> {
    let bin = tool("LLVM_MCA", "llvm-mca");
    let out = Command::new(&bin)
        .args(["-mtriple=thumbv7em-none-eabihf", "-instruction-info=false"])
        .args(["-resource-pressure=false"])
        .arg(format!("-mcpu={mcpu}"))
        .arg(format!("-iterations={iterations}"))
        .arg(input)
        .output()
        .map_err(|e| format!("cannot run {bin} (Debian's llvm package): {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if let Some(i) = stderr.find("found an unsupported instruction") {
        let note = stderr[i..]
            .lines()
            .find_map(|l| l.trim().strip_prefix("note: instruction:"))
            .and_then(|s| s.split_whitespace().next())
            .ok_or_else(|| format!("{bin}: {stderr}"))?;
        return Ok(Mca::Unsupported(note.to_string()));
    }
    if !out.status.success() || stderr.contains("error:") {
        return Err(format!("{bin} failed on {}:\n{stderr}", input.display()));
    }
    let mut cycles = BTreeMap::new();
    let mut region = String::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        if let Some((_, name)) = line.split_once("Code Region - ") {
            region = name.trim().to_string();
        } else if let Some(v) = line.strip_prefix("Total Cycles:") {
            let v = v.trim().parse().map_err(|_| format!("{bin}: `{line}`"))?;
            cycles.insert(region.clone(), v);
        }
    }
    Ok(Mca::Cycles(cycles))
}

/// Code regions for llvm-mca: one per block (`name`, its instructions).
fn regions_file(regions: &[(String, Vec<String>)]) -> String {
    let mut s = String::new();
    for (name, lines) in regions {
        let _ = writeln!(s, "# LLVM-MCA-BEGIN {name}");
        for l in lines {
            let _ = writeln!(s, "{l}");
        }
        let _ = writeln!(s, "# LLVM-MCA-END");
    }
    s
}

/// Total Cycles of every region at `iterations`, with every instruction llvm-mca has no
/// scheduling class for replaced by a `nop` (their mnemonics are added to `nops`).
fn cycles(
    dir: &Path,
    regions: &mut [(String, Vec<String>)],
    mcpu: &str,
    iterations: u64,
    nops: &mut BTreeSet<String>,
) -> Result<BTreeMap<String, u64>, String> {
    let input = dir.join("blocks.s");
    for _ in 0..100 {
        std::fs::write(&input, regions_file(regions)).map_err(|e| e.to_string())?;
        match mca(&input, mcpu, iterations)? {
            Mca::Cycles(c) => return Ok(c),
            Mca::Unsupported(m) => {
                let mut replaced = 0;
                for (_, lines) in regions.iter_mut() {
                    for l in lines.iter_mut() {
                        if l.split_whitespace().next() == Some(m.as_str()) {
                            *l = "nop".into();
                            replaced += 1;
                        }
                    }
                }
                if replaced == 0 {
                    return Err(format!("llvm-mca refuses `{m}`, which no block has"));
                }
                nops.insert(m);
            }
        }
    }
    Err("llvm-mca refuses too many instructions".into())
}

/// The latencies llvm-mca's model of `mcpu` gives the instructions `lines` (its
/// instruction-info table).
fn latencies(dir: &Path, mcpu: &str, lines: &[String]) -> Result<Vec<u64>, String> {
    let bin = tool("LLVM_MCA", "llvm-mca");
    let input = dir.join("probe.s");
    std::fs::write(&input, lines.join("\n") + "\n").map_err(|e| e.to_string())?;
    let out = Command::new(&bin)
        .args(["-mtriple=thumbv7em-none-eabihf", "-resource-pressure=false"])
        .arg(format!("-mcpu={mcpu}"))
        .args(["-iterations=1"])
        .arg(&input)
        .output()
        .map_err(|e| format!("cannot run {bin}: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let table = stdout
        .split_once("Instructions:\n")
        .map(|(_, t)| t)
        .ok_or_else(|| format!("{bin}: no instruction info:\n{stdout}"))?;
    table
        .lines()
        .take(lines.len())
        .map(|l| {
            l.split_whitespace()
                .nth(1)
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| format!("{bin}: `{l}`"))
        })
        .collect()
}

/// What llvm-mca's model of `mcpu` says of the instructions that matter most here: the
/// latencies of the FP operations and loads, and the cycles of two independent divides with
/// an `add` between them.
fn model_notes(dir: &Path, mcpu: &str) -> Result<Vec<String>, String> {
    let (r, t) = if mcpu == "cortex-m7" {
        ("d", "f64")
    } else {
        ("s", "f32")
    };
    let probes: Vec<(String, String)> = [
        ("vdiv", 3),
        ("vsqrt", 2),
        ("vfma", 3),
        ("vmul", 3),
        ("vadd", 3),
    ]
    .into_iter()
    .map(|(op, n)| {
        let regs: Vec<String> = (0..n).map(|i| format!("{r}{}", i * 2 + 2)).collect();
        (
            format!("{op}.{t}"),
            format!("{op}.{t}\t{}", regs.join(", ")),
        )
    })
    .chain([
        (format!("vldr {r}"), format!("vldr\t{r}2, [r1]")),
        ("ldr".to_string(), "ldr\tr0, [r1]".to_string()),
    ])
    .collect();
    let lines: Vec<String> = probes.iter().map(|(_, l)| l.clone()).collect();
    let lat = latencies(dir, mcpu, &lines)?;
    let notes: Vec<String> = probes
        .iter()
        .zip(&lat)
        .map(|((name, _), l)| format!("{name} {l}"))
        .collect();
    let mut regions = vec![(
        "div_add".to_string(),
        vec![
            format!("vdiv.{t}\t{r}0, {r}2, {r}4"),
            "add\tr0, r1".to_string(),
            format!("vdiv.{t}\t{r}6, {r}8, {r}10"),
        ],
    )];
    let div = cycles(dir, &mut regions, mcpu, 1, &mut BTreeSet::new())?["div_add"];
    Ok(vec![
        format!("the model's latencies [cycles]: {}", notes.join(", ")),
        format!(
            "two independent vdiv.{t} with an add between them take {div} cycles in a cold \
             pass: the model writes back in order, so what follows a divide waits for it (the \
             divider occupied for the divide's whole latency)"
        ),
    ])
}

// ---------------------------------------------------------------------------------------
// The polls.

/// The gait's tick count after every poll of every log in the file `bytes` (the image's
/// `replay.wlog`), by log name, in file order: the logs played on the host into the image's
/// node (`f32`: the M4F's) with the target's player, as `walk_tests::logs::play` does (the
/// QEMU tests check that the image does the same, tick for tick). The image names a kind's
/// worst poll by its tick (`max_tick`); a poll that does not tick (the handshake's, a standing
/// or silent one) has the tick of the poll before it, so the worst poll is the first with
/// that tick after it (checked against the image's count).
fn ticks_per_poll(bytes: &[u8], f32: bool) -> Result<Vec<(String, Vec<u64>)>, String> {
    use gait_loop::binlog::{Frames, Header, SliceBytes};
    use gait_loop::Player;
    use planner_core::node::Node;
    use planner_core::playback::LogClock;

    fn play<const Q: usize, G, T>(
        header: &Header,
        src: &mut SliceBytes,
        node: &mut Node<Q, G, T>,
    ) -> Result<Vec<u64>, String>
    where
        G: std::borrow::Borrow<
            planner_core::shaping::PreviewGains<T, { planner_core::gait::PREVIEW }>,
        >,
        T: planner_core::Real,
    {
        let mut frames = Frames::new(header, src);
        let clock = LogClock::new(header.first_us, u64::from(header.period_us))
            .ok_or_else(|| format!("{}: no log clock", header.name()))?;
        let mut player = Player::new(clock, header.count, header.last_us);
        let mut ticks = vec![];
        while !player.done() {
            player
                .cycle(node, &mut frames, |n, ms, bus| n.poll(ms, bus), |_, _| {})
                .map_err(|_| format!("{}: log truncated", header.name()))?;
            ticks.push(node.gait().ticks());
        }
        Ok(ticks)
    }

    let mut src = SliceBytes::new(bytes);
    let mut out = vec![];
    while let Some(header) = Header::read(&mut src).map_err(|e| format!("replay.wlog: {e:?}"))? {
        let ticks = if f32 {
            let mut node: walk_robot::NodeF32<16> =
                Node::with_gains(walk_robot::NODE_CONFIG_F32, walk_robot::GainsF32)
                    .map_err(|e| format!("{e:?}"))?;
            play(&header, &mut src, &mut node)?
        } else {
            let mut node: walk_robot::Node<16> =
                Node::with_gains(walk_robot::NODE_CONFIG, walk_robot::Gains)
                    .map_err(|e| format!("{e:?}"))?;
            play(&header, &mut src, &mut node)?
        };
        out.push((header.name().to_string(), ticks));
    }
    Ok(out)
}

/// A block of the guest's code: the address of its first instruction and the address after
/// its last.
type Key = (u32, u32);

/// One poll to estimate.
struct Poll {
    /// The kinds whose worst poll it is (`cycle`, …), or `call`.
    kinds: Vec<String>,
    /// The log it is in.
    log: String,
    /// Its index in that log (0: the handshake's poll).
    index: usize,
    /// The image's own count (its timer), if a kind's.
    image: Option<u64>,
    /// The executions of every block.
    counts: BTreeMap<Key, u64>,
    /// Its instructions, from the trace.
    instructions: u64,
}

fn label(kind: &str) -> String {
    KINDS
        .iter()
        .find(|(k, _)| *k == kind)
        .map_or_else(|| kind.to_string(), |(_, l)| l.to_string())
}

fn main() {
    let mut o = parse_options();
    // A copy of the image, taken first, so that QEMU, the symbols and the disassembly all read
    // the same one even if the image is rebuilt meanwhile.
    let copy = std::env::temp_dir().join(format!("qemu-cycles-{}.elf", std::process::id()));
    if let Err(e) = std::fs::copy(&o.elf, &copy) {
        fail(format!("cannot copy {}: {e}", o.elf.display()));
    }
    o.elf = copy.clone();
    let result = trace::write_log("qemu-cycles", &o.scenario).and_then(|dir| {
        let r = Symbols::new(&o.elf).and_then(|mut syms| estimate(&o, &mut syms, &dir));
        let _ = std::fs::remove_dir_all(&dir);
        r
    });
    let _ = std::fs::remove_file(&copy);
    if let Err(e) = result {
        fail(e);
    }
}

fn estimate(o: &Options, syms: &mut Symbols, dir: &Path) -> Result<(), String> {
    // The image's own report: the poll with the most instructions of every kind.
    let out = report::qemu(&o.machine, &o.elf, dir);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() || !stdout.contains("DONE") {
        return Err(format!(
            "the image failed on {} (exit {:?}):\n{}",
            o.scenario,
            out.status.code(),
            report::tail(&stdout, 10)
        ));
    }
    let records: Vec<Record> = stdout.lines().filter_map(Record::parse).collect();
    let f32 = records
        .iter()
        .any(|r| r.kind == "MACHINE" && r.fields.get("scalar").is_some_and(|s| s == "f32"));
    let bytes = std::fs::read(dir.join("replay.wlog")).map_err(|e| e.to_string())?;
    let played = ticks_per_poll(&bytes, f32)?;
    // The logs in file order, with the index of their first poll in the file and the tick
    // count after each of their polls.
    let mut logs: Vec<(String, usize, Vec<u64>)> = vec![];
    let mut first = 0;
    for r in records.iter().filter(|r| r.kind == "END") {
        let name = r.get("scenario").to_string();
        let cycles: usize = r.num("cycles");
        let ticks = played
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| t.clone())
            .ok_or_else(|| format!("{name}: not played on the host"))?;
        if ticks.len() != cycles {
            return Err(format!(
                "{name}: the image ran {cycles} polls, the host {}",
                ticks.len()
            ));
        }
        logs.push((name, first, ticks));
        first += cycles;
    }
    let timing = |log: &str, kind: &str| {
        records
            .iter()
            .find(|r| r.kind == "TIMING" && r.get("scenario") == log && r.get("kind") == kind)
    };
    let mut polls: BTreeMap<usize, Poll> = BTreeMap::new();
    let mut absent = vec![];
    for kind in &o.kinds {
        let Some(all) = timing("all", kind) else {
            absent.push(kind.clone());
            continue;
        };
        // The first log with the worst poll of the kind (as the QEMU test's "worst in").
        let max: u64 = all.num("max");
        let (log, r, first, ticks) = logs
            .iter()
            .find_map(|(log, first, ticks)| {
                timing(log, kind)
                    .filter(|r| r.num::<u64>("max") == max)
                    .map(|r| (log.clone(), r, *first, ticks))
            })
            .ok_or_else(|| format!("no log has the worst {kind} poll"))?;
        let tick: u64 = r.num("max_tick");
        let index = first
            + ticks
                .iter()
                .position(|&t| t == tick)
                .ok_or_else(|| format!("{log}: no poll ends at tick {tick}"))?;
        let p = polls.entry(index).or_insert_with(|| Poll {
            kinds: vec![],
            log: log.clone(),
            index: index - first,
            image: Some(max),
            counts: BTreeMap::new(),
            instructions: 0,
        });
        p.kinds.push(kind.clone());
    }
    if let Some(index) = o.call {
        // Of the whole file: the log it falls in, and its index there.
        let (log, first) = logs
            .iter()
            .rev()
            .find(|(_, first, _)| *first <= index)
            .map(|(log, first, _)| (log.clone(), *first))
            .unwrap_or_default();
        polls
            .entry(index)
            .or_insert_with(|| Poll {
                kinds: vec![],
                log,
                index: index - first,
                image: None,
                counts: BTreeMap::new(),
                instructions: 0,
            })
            .kinds
            .push("call".into());
    }
    let Some(&last) = polls.keys().last() else {
        return Err(format!(
            "no poll to estimate (kinds {:?} not in the log)",
            o.kinds
        ));
    };

    // The trace, up to the last poll wanted: every wanted poll's blocks and their counts.
    let mut code: BTreeMap<Key, Vec<u32>> = BTreeMap::new();
    let run = trace::Run {
        machine: &o.machine,
        elf: &o.elf,
        dir,
        function: &o.function,
        stdout: None,
    };
    let traced = trace::run(&run, syms, |index, call, blocks| {
        if let Some(p) = polls.get_mut(&index) {
            for host in &call.blocks {
                let b = &blocks[host];
                let key = (b.addrs[0], b.end);
                *p.counts.entry(key).or_default() += 1;
                code.entry(key).or_insert_with(|| b.addrs.clone());
            }
            p.instructions = call.instructions;
        }
        if index >= last {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })?;
    for (&index, p) in &polls {
        if index >= traced.counts.len() {
            return Err(format!(
                "poll {index} not traced ({} polls)",
                traced.counts.len()
            ));
        }
        if let Some(image) = p.image {
            if image.abs_diff(p.instructions) > SLACK + image / 100 {
                return Err(format!(
                    "{} poll {} ({:?}): the image's timer says {image} instructions, the trace {}",
                    p.log, p.index, p.kinds, p.instructions
                ));
            }
        }
    }

    // Every distinct block as a code region, through llvm-mca twice.
    let text = disassemble(&o.elf, &o.mcpu)?;
    let mut regions: Vec<(String, Vec<String>)> = vec![];
    let mut name_of: BTreeMap<Key, String> = BTreeMap::new();
    for (key, addrs) in &code {
        let mut lines = vec![];
        for a in addrs {
            let l = text.get(a).ok_or_else(|| {
                format!(
                    "the instruction at {a:#x} (block {:#x}..{:#x}) is not in the image's disassembly",
                    key.0, key.1
                )
            })?;
            lines.push(l.clone());
        }
        let name = format!("b{:x}_{:x}", key.0, key.1);
        name_of.insert(*key, name.clone());
        regions.push((name, lines));
    }
    let original = regions.clone();
    let mut nops = BTreeSet::new();
    let cold = cycles(dir, &mut regions, &o.mcpu, 1, &mut nops)?;
    let warm = cycles(dir, &mut regions, &o.mcpu, o.iterations, &mut nops)?;
    // The instructions costed as nops in every block (none, mostly).
    let nopped: BTreeMap<&str, u64> = original
        .iter()
        .zip(&regions)
        .map(|((name, before), (_, after))| {
            let n = before.iter().zip(after).filter(|(b, a)| b != a).count();
            (name.as_str(), n as u64)
        })
        .collect();
    let notes = model_notes(dir, &o.mcpu)?;
    let version = Command::new(tool("LLVM_MCA", "llvm-mca"))
        .arg("--version")
        .output()
        .ok()
        .and_then(|v| {
            String::from_utf8_lossy(&v.stdout)
                .lines()
                .find(|l| l.contains("version"))
                .map(|l| l.trim().to_string())
        })
        .unwrap_or_else(|| "?".into());

    let budget = o.mhz * 250;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(
        out,
        "qemu-cycles: log {} on QEMU {}, the image's poll function `{}`; llvm-mca \
         -mcpu={} ({version}); budget {} cycles = 5 % of 5 ms at {} MHz",
        o.scenario,
        o.machine,
        o.function,
        o.mcpu,
        thousands(budget),
        o.mhz
    );
    for a in assumptions(o, &notes, &nops) {
        let _ = writeln!(out, "{a}");
    }
    if !absent.is_empty() {
        let _ = writeln!(out, "not in the log: {}", absent.join(", "));
    }
    let m7 = o.mcpu == "cortex-m7";
    let _ = writeln!(
        out,
        "\n{:<18} {:<20} {:>5} {:>12} {:>15} {:>12} {:>13} {:>5} {:>8} {:>17}",
        "kind",
        "log",
        "poll",
        "instructions",
        "est. cycles",
        "cycles/instr",
        "of budget",
        "lines",
        "fills >=",
        "incl. fills"
    );
    // The cache the code runs behind: its line, its lines, a fill's least cycles.
    let (line, cache_lines, fill_cycles) = if m7 {
        (LINE, ICACHE_LINES, FILL_CYCLES)
    } else {
        (M4F_LINE, M4F_CACHE_LINES, M4F_FILL_CYCLES)
    };
    let mut estimates = vec![];
    // In the order of the kinds asked for, then the poll asked for.
    let mut order: Vec<&Poll> = polls.values().collect();
    let rank = |p: &Poll| {
        o.kinds
            .iter()
            .position(|k| p.kinds.contains(k))
            .unwrap_or(o.kinds.len())
    };
    order.sort_by_key(|p| rank(p));
    for p in order {
        let mut high: u64 = 0;
        let mut low_sum: u128 = 0;
        let mut instructions = 0;
        let mut nop_executions = 0;
        let mut touched = BTreeSet::new();
        for (key, &n) in &p.counts {
            let name = name_of[key].as_str();
            high += n * cold[name];
            low_sum += u128::from(n) * u128::from(warm[name]);
            nop_executions += n * nopped[name];
            let addrs = &code[key];
            instructions += n * addrs.len() as u64;
            for &a in addrs {
                touched.insert(a / line);
            }
            touched.insert((key.1 - 1) / line);
        }
        if instructions != p.instructions {
            return Err(format!(
                "poll {}: its blocks hold {instructions} instructions, the trace counted {}",
                p.index, p.instructions
            ));
        }
        let low_exact = low_sum as f64 / o.iterations as f64;
        let low = low_exact.round() as u64;
        let cpi = |c: f64| c / instructions.max(1) as f64;
        let share = |c: f64| c / budget as f64;
        let names = p.kinds.iter().map(|k| label(k)).collect::<Vec<_>>();
        // The lines a poll runs that the cache cannot have held since the last one.
        let fills = (touched.len() as u64).saturating_sub(cache_lines);
        let (low_f, high_f) = (low + fills * fill_cycles, high + fills * fill_cycles);
        let _ = writeln!(
            out,
            "{:<18} {:<20} {:>5} {:>12} {:>15} {:>12} {:>13} {:>5} {:>8} {:>17}",
            names.join(", "),
            p.log,
            p.index,
            thousands(instructions),
            format!("{}-{}", thousands(low), thousands(high)),
            format!("{:.2}-{:.2}", cpi(low_exact), cpi(high as f64)),
            format!("{:.3}-{:.3}", share(low_exact), share(high as f64)),
            touched.len(),
            thousands(fills),
            format!("{}-{}", thousands(low_f), thousands(high_f)),
        );
        for k in &p.kinds {
            estimates.push(format!(
                "ESTIMATE kind={k} label={} log={} poll={} instructions={instructions} image={} \
                 low={low} high={high} cpi_low={:.3} cpi_high={:.3} budget={budget} \
                 share_low={:.4} share_high={:.4} lines={} fills_min={} fill_cycles_min={} \
                 low_fills={low_f} high_fills={high_f} blocks={} nops={nop_executions} mcpu={} \
                 mhz={}",
                label(k).replace(' ', "_"),
                p.log,
                p.index,
                p.image.map_or_else(|| "-".to_string(), |i| i.to_string()),
                cpi(low_exact),
                cpi(high as f64),
                share(low_exact),
                share(high as f64),
                touched.len(),
                fills,
                fills * fill_cycles,
                p.counts.len(),
                o.mcpu,
                o.mhz
            ));
        }
        if o.top > 0 {
            let mut v: Vec<(u64, Key)> = p
                .counts
                .iter()
                .map(|(key, &n)| (n * cold[&name_of[key]], *key))
                .collect();
            v.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
            for (c, key) in v.into_iter().take(o.top) {
                let name = &name_of[&key];
                let _ = writeln!(
                    out,
                    "    {c:>7} cy (high): {:>5} x {:>3} instr., {:>4} / {:>7.2} cy per pass  {:#07x} {}",
                    p.counts[&key],
                    code[&key].len(),
                    cold[name],
                    warm[name] as f64 / o.iterations as f64,
                    key.0,
                    syms.symbol(key.0)
                );
            }
        }
    }
    let _ = writeln!(
        out,
        "\nest. cycles: low (steady state) - high (cold pass); of budget: of {} cycles; lines: \
         the lines of code the poll executed{}",
        thousands(budget),
        if m7 {
            format!(
                "; fills >=: the fewest I-cache line fills the poll needs (its lines beyond \
                 the {ICACHE_LINES} of the 16 KiB I-cache), at least {FILL_CYCLES} core cycles \
                 each from flash; incl. fills: the estimate with them"
            )
        } else {
            format!(
                "; lines and fills >=: the {M4F_LINE}-byte lines of the ART accelerator's \
                 1 KiB cache, those beyond its {M4F_CACHE_LINES} each a fetch from flash \
                 with its {M4F_FILL_CYCLES} wait states (not hidden by the prefetch, assumed); \
                 incl. fills: the estimate with them"
            )
        }
    );
    for l in estimates {
        let _ = writeln!(out, "{l}");
    }
    Ok(())
}

/// The `METHOD` and `ASSUME` lines: how the cycles are estimated and what is assumed.
fn assumptions(o: &Options, notes: &[String], nops: &BTreeSet<String>) -> Vec<String> {
    let memory = if o.mcpu == "cortex-m4" {
        "ASSUME no cache misses and no flash wait states: every fetch and load at the model's \
         latency (on an STM32F407-class part at 168 MHz the flash has 5 wait states behind the \
         ART accelerator: its prefetch covers straight-line code, its 1 KiB instruction cache \
         is smaller than a poll's code; the stalls of taken branches to uncached lines are not \
         estimated)"
    } else {
        "ASSUME no cache misses and no flash wait states: every fetch and load at the model's \
         latency (the board's code runs from flash behind the 16 KiB I-cache, not from ITCM; \
         at ACLK 240 MHz the flash has 4 wait states, a line fill at least 10 core cycles, not \
         estimated; the node and the stack are in the zero-wait-state DTCM, the preview gains \
         in flash behind the 16 KiB D-cache)"
    };
    vec![
        format!(
            "METHOD every block QEMU executed in the poll (its translated blocks, `-d \
             in_asm,exec,nochain`: straight-line code up to a branch), disassembled from the \
             image by llvm-objdump, is a code region for llvm-mca -mcpu={}; its cycles are \
             weighted by its executions. high: a cold pass (-iterations=1: from an empty \
             pipeline to the last write-back, every block pays its latency tail and nothing \
             overlaps the next block); low: the steady state (Total Cycles / Iterations at \
             -iterations={}: the tail overlaps the next pass, as it overlaps the next block on \
             the core)",
            o.mcpu, o.iterations
        ),
        memory.to_string(),
        "ASSUME branches predicted: llvm-mca models no misprediction or refetch penalty"
            .to_string(),
        format!(
            "ASSUME LLVM's {} scheduling model as it is, the FP divider's and square root's \
             occupancy included; {}",
            o.mcpu, notes[0]
        ),
        format!("ASSUME {}", notes[1]),
        "ASSUME for llvm-mca 14: calls costed as branches (bl as b, blx as bx: llvm-mca 14 costs \
         a call 100 cycles and has no option to change it); an IT as a nop and the \
         instructions it predicates as unconditional ones, vcmp with #0 as vcmp with a \
         register (neither has a scheduling class)"
            .to_string(),
        if nops.is_empty() {
            "ASSUME every other executed instruction has a scheduling class".to_string()
        } else {
            format!(
                "ASSUME without a scheduling class, costed as a nop (executions: nops=): {}",
                nops.iter().cloned().collect::<Vec<_>>().join(", ")
            )
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objdump_lines_become_llvm_mca_input() {
        let text = "\n00000400 <__stext>:\n\
             \x20    400:      \tbl\t0x1a3a0 <__pre_init>    @ imm = #106396\n\
             \x20    404:      \tldr\tr0, [pc, #72]           @ 0x450 <$d>\n\
             \x20    40c:      \tbeq\t0x412 <__stext+0x12>    @ imm = #2\n\
             \x20    40e:      \tite\tne\n\
             \x20    410:      \tmovne\tr2, #1\n\
             \x20    412:      \tlslseq.w\tr0, r1, #2\n\
             \x20    416:      \tcbz\tr2, 0xe60 <poll+0x9f0> @ imm = #98\n\
             \x20    418:      \tvseleq.f64\td0, d0, d1\n\
             \x20    41c:      \tblx\tr3\n\
             \x20    450: 00 00 01 20  \t.word\t0x20010000\n\
             \x20    454:      \tittt\tlo\n\
             \x20    456:      \tvmovlo.f64\td0, d1\n\
             \x20    45a:      \tpoplo\t{r4, pc}\n\
             \x20    45c:      \tvcmp.f64\td8, #0\n\
             \x20    460:      \tvcmpe.f32\ts0, s2\n";
        let m = parse_disassembly(text);
        let at = |a: u32| m[&a].as_str();
        assert_eq!(at(0x400), "b\t.Lt");
        assert_eq!(at(0x404), "ldr\tr0, [pc, #72]");
        assert_eq!(at(0x40c), "beq\t.Lt");
        assert_eq!(at(0x40e), "nop");
        assert_eq!(at(0x410), "mov\tr2, #1");
        assert_eq!(at(0x412), "lsls.w\tr0, r1, #2");
        assert_eq!(at(0x416), "cbz\tr2, .Lt");
        // Not in an IT block: vsel's condition is its own.
        assert_eq!(at(0x418), "vseleq.f64\td0, d0, d1");
        assert_eq!(at(0x41c), "bx\tr3");
        assert!(!m.contains_key(&0x450));
        assert_eq!(at(0x456), "vmov.f64\td0, d1");
        assert_eq!(at(0x45a), "pop\t{r4, pc}");
        assert_eq!(at(0x45c), "vcmp.f64\td8, d8");
        assert_eq!(at(0x460), "vcmp.f32\ts0, s2");
    }

    #[test]
    fn it_blocks_give_their_conditions() {
        assert_eq!(it_block("it", "eq").unwrap(), ["eq"]);
        assert_eq!(it_block("ite", "hs").unwrap(), ["hs", "lo"]);
        assert_eq!(it_block("itet", "gt").unwrap(), ["gt", "le", "gt"]);
        assert!(it_block("isb", "sy").is_none());
    }
}
