//! planner-core's CAN node on QEMU's `mps2-an500` (Cortex-M7, double-precision FPU): plays
//! host-sim's `fig4` and `lateral` scenarios as CAN frames through an in-memory device, counts
//! the instructions of every `Node::poll` (one 5 ms control cycle, as the board runs it), and
//! prints a machine-readable report over semihosting.
//!
//! Run (from firmware/qemu, after `cargo build --release`):
//!
//! ```text
//! timeout 120 qemu-system-arm -M mps2-an500 -nographic \
//!     -semihosting-config enable=on,target=native -icount shift=0 \
//!     -kernel target/thumbv7em-none-eabihf/release/qemu
//! ```
//!
//! # How the instructions are counted
//! DWT CYCCNT reads 0 under QEMU. With `-icount shift=0` QEMU advances its virtual clock by
//! 2⁰ = 1 ns per executed instruction, and the CMSDK APB timer 0 counts at the board's 25 MHz
//! SYSCLK of that virtual clock: one timer tick = 40 ns = **40 instructions**. A poll is
//! timed by reading the timer before and after it, so its count has a resolution of 40
//! instructions (±1 tick) and includes the few instructions of the two timer reads. The
//! counts are exact and repeatable run to run (the virtual clock is driven by the
//! instruction count only). The image checks the factor itself (`CALIB`: a delay loop of known
//! instruction count). They are *instructions*, not Cortex-M7 cycles: QEMU models neither the
//! dual-issue pipeline nor the FPU latencies (a `vdiv.f64` or `vsqrt.f64` takes ~16 cycles
//! on the real core) nor flash wait states and caches; the board image measures cycles with
//! DWT.
//!
//! # Memory (as on the board)
//! The node (`walk_robot::Node<16>`, ~14 KB: it borrows its preview gains from flash) is a
//! `static` in .bss, placed once by `cortex_m::singleton!` (and built again in place of the
//! first one for the second scenario). Building it takes ~25 KB of stack once (the gait and the
//! node are built by value), the control loop ~20 KB (`STACK ... control=`); `memory.x` puts
//! the stack into a 64 KiB region of its own below the 64 KiB RAM, as `board/stack.x` does on
//! the board (the lower half of its DTCM).
//!
//! # Output (one record per line, `key=value` fields)
//! * `CALIB loop_instructions=… timer_ticks=… instructions_per_tick=…`
//! * `SIZE node=… gait=…` (bytes of `Node<16>` and `Gait<f64, 16>`)
//! * `CMD scenario=… tick=… op=… id=… side=… x=… y=… yaw=… frame=ID#DATA result=… answered=…`
//!   per command sent (footstep fields for push and modify only): the scenario's command, its
//!   frame (hex, candump style), the node's answer (`Ok` or the refusal reason) and the tick of
//!   the cycle that answered
//! * `REPLAN scenario=… tick=… kind=… adjust_ticks=… ratio=… plane=… instructions=…` (kind of
//!   the cycle, instructions of its poll)
//! * `REF scenario=… tick=… kind=… cog_x=… cog_y=… zmp_x=… zmp_y=… cogv_x=… cogv_y=…`
//!   every 20 ticks and at every cycle that is not steady or standing; floats in Rust's
//!   shortest round-trip `{:e}`
//! * `END scenario=… ticks=… digest=… tx_frames=… tx_digest=… heartbeats=… heartbeat_acks=…`
//!   (`digest`: FNV-1a 64 over the bits of every tick's x and y samples, tick 0 included;
//!   `tx_digest`: over the identifier and data of every frame the node transmitted)
//! * `NODE scenario=… refused=… tx_dropped=… bus_errors=… rx_overflow=…` (the node's counters,
//!   the device's lost frames)
//! * `TIMING scenario=…|all kind=… n=… max=… mean=… max_tick=… max_timer=…` (instructions)
//! * `STACK used=… size=… startup=… control=…` (bytes: the high-water mark, of the stack
//!   region's size; `startup`: while building the node, `control`: while running the
//!   scenarios, measured after painting the stack again once the node is built)
//! * `DONE`, then a semihosting exit with code 0 (1 if a command was refused or not answered,
//!   or the node could not be created).
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod hw;
mod machine;

use core::fmt::{self, Write};

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hio};
use panic_semihosting as _; // panics print over semihosting and exit with code 1

use gait_loop::{script, Clock, Command, Fnv, Kind, Runner, Scenario, Sent, Stats, QUEUE};
use machine::{Node, Scalar};
use planner_core::gait::{Gait, GaitError, Reference, Side};
use planner_core::node::NodeConfig;

/// Instructions per CMSDK timer tick under `-icount shift=0` (1 ns per instruction, 25 MHz).
const INSTRUCTIONS_PER_TICK: u32 = 1_000_000_000 / hw::TIMER_HZ;
/// Iterations of the calibration loop (two instructions each: `subs`, `bne`).
const CALIB_LOOPS: u32 = 1_000_000;
/// A `REF` line every this many ticks.
const REF_EVERY: u64 = 20;
/// The board's 5 ms slot in core cycles at 480 MHz: a cycle of more instructions counts as an
/// overrun in the board's bookkeeping.
const BOARD_PERIOD_CYCLES: u32 = 2_400_000;

impl Clock for hw::Timer0 {
    fn now(&mut self) -> u32 {
        self.count()
    }
}

/// Semihosting stdout with a line buffer (one host call per line instead of one per
/// formatted piece).
struct Console {
    host: hio::HostStream,
    buf: heapless::Vec<u8, 256>,
}

impl Console {
    fn flush(&mut self) {
        if !self.buf.is_empty() {
            // Nothing to do about a host that does not take the output.
            let _ = self.host.write_all(&self.buf);
            self.buf.clear();
        }
    }
}

impl Write for Console {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        let mut rest = s.as_bytes();
        while !rest.is_empty() {
            let room = self.buf.capacity() - self.buf.len();
            if room == 0 {
                self.flush();
                continue;
            }
            let (now, later) = rest.split_at(room.min(rest.len()));
            // Fits: `now` is at most `room` long.
            let _ = self.buf.extend_from_slice(now);
            rest = later;
        }
        Ok(())
    }
}

/// Writes one line and hands it to the host.
macro_rules! line {
    ($out:expr, $($arg:tt)*) => {{
        let _ = writeln!($out, $($arg)*);
        $out.flush();
    }};
}

fn side(s: Side) -> &'static str {
    match s {
        Side::Left => "L",
        Side::Right => "R",
    }
}

fn instructions(timer_ticks: u32) -> u64 {
    u64::from(timer_ticks) * u64::from(INSTRUCTIONS_PER_TICK)
}

fn print_ref(out: &mut Console, scenario: &str, tick: u64, kind: &str, r: &Reference<Scalar>) {
    line!(
        out,
        "REF scenario={} tick={} kind={} cog_x={:e} cog_y={:e} zmp_x={:e} zmp_y={:e} cogv_x={:e} cogv_y={:e}",
        scenario,
        tick,
        kind,
        r.x.cog,
        r.y.cog,
        r.x.zmp,
        r.y.zmp,
        r.x.cog_vel,
        r.y.cog_vel
    );
}

fn print_timing(out: &mut Console, scenario: &str, stats: &Stats) {
    for kind in Kind::ALL {
        let s = stats.get(kind);
        if s.n == 0 {
            continue;
        }
        let mean = instructions(1) as f64 * s.sum as f64 / f64::from(s.n);
        line!(
            out,
            "TIMING scenario={} kind={} n={} max={} mean={:.0} max_tick={} max_timer={}",
            scenario,
            kind.name(),
            s.n,
            instructions(s.max),
            mean,
            s.max_tick,
            s.max
        );
    }
}

fn print_command(out: &mut Console, scenario: &str, c: &Sent) {
    let _ = write!(
        out,
        "CMD scenario={} tick={} op={}",
        scenario,
        c.tick,
        c.command.name()
    );
    if let Command::Push(id, f) | Command::Modify(id, f) = c.command {
        let _ = write!(
            out,
            " id={} side={} x={:e} y={:e} yaw={:e}",
            id,
            side(f.side),
            f.x,
            f.y,
            f.yaw
        );
    }
    let _ = write!(out, " frame={:03X}#", c.frame.id);
    for b in c.frame.bytes() {
        let _ = write!(out, "{:02X}", b);
    }
    match c.answer {
        Some(a) => {
            match a.reason {
                None => {
                    let _ = write!(out, " result=Ok");
                }
                Some(r) => {
                    let _ = write!(out, " result={:?}", r);
                }
            }
            line!(out, " answered={}", a.tick);
        }
        None => line!(out, " result=NoAnswer answered=none"),
    }
}

/// The node's `static`: `Node::new`'s result, kept where it was returned.
type Slot = Result<Node<QUEUE>, GaitError>;

/// Builds the node into its `static` (in .bss) with `cortex_m::singleton!`, as the board's
/// `place_node` does, but keeps the `Result` (moving the node out of it would copy its 14 KB
/// through this frame once more). Not inlined: the temporaries of `Node::new` (the gait, the
/// preview-gain computation, the node returned by value) live in this frame only while it runs.
#[inline(never)]
fn place_node(cfg: NodeConfig<Scalar>) -> &'static mut Slot {
    match cortex_m::singleton!(: Slot = Node::with_gains(cfg, machine::gains())) {
        Some(slot) => slot,
        None => panic!("place_node called twice"),
    }
}

/// A fresh node in place of the old one (the next scenario starts from start-up), in a frame
/// of its own like [`place_node`].
#[inline(never)]
fn renew_node(slot: &mut Slot, cfg: NodeConfig<Scalar>) {
    *slot = Node::with_gains(cfg, machine::gains());
}

/// Plays one scenario against `node` (just created); returns `false` if a command was refused
/// or not answered, or a footstep could not be encoded.
#[inline(never)]
fn run_scenario(
    out: &mut Console,
    timer: &mut hw::Timer0,
    scenario: &Scenario,
    node: &mut Node<QUEUE>,
    stats: &mut Stats,
) -> bool {
    let name = scenario.name;
    let mut digest = Fnv::default();
    digest.add_reference(node.gait().last());
    print_ref(out, name, 0, Kind::Standing.name(), node.gait().last());

    let mut runner = Runner::new(scenario);
    // The board's bookkeeping around each poll (board-core's `cycle`), with the instructions
    // as its cycles: overruns told to the node, a summary per 200 cycles.
    let mut board = board_core::cycle::Stats::default();
    let (mut summaries, mut worst_window) = (0u32, 0u32);
    while !runner.done() {
        let record = match runner.cycle(node, timer, stats, |_, _| {}) {
            Ok(r) => r,
            Err(e) => {
                line!(out, "ERROR scenario={} unrepresentable_step={}", name, e.0);
                return false;
            }
        };
        let spent = u32::try_from(instructions(record.units)).unwrap_or(u32::MAX);
        let outcome = board.record(node, &record.report, spent, spent > BOARD_PERIOD_CYCLES);
        if let Some(w) = outcome.summary {
            summaries += 1;
            worst_window = worst_window.max(w.worst);
        }
        let reference = &record.report.reference;
        digest.add_reference(reference);
        if let Some(info) = record.replan {
            line!(
                out,
                "REPLAN scenario={} tick={} kind={} adjust_ticks={} ratio={:e} plane={} instructions={}",
                name,
                record.tick,
                record.kind.name(),
                info.adjust_ticks,
                info.ratio,
                info.plane,
                instructions(record.units)
            );
        }
        let notable = !matches!(record.kind, Kind::Steady | Kind::Standing);
        if record.tick % REF_EVERY == 0 || notable {
            print_ref(out, name, record.tick, record.kind.name(), reference);
        }
    }

    let mut ok = true;
    for c in runner.controller().sent() {
        ok &= matches!(c.answer, Some(a) if a.reason.is_none());
        print_command(out, name, c);
    }
    let (tx_frames, tx_digest) = runner.transmitted();
    let (heartbeats, heartbeat_acks, _) = runner.controller().heartbeats();
    line!(
        out,
        "END scenario={} ticks={} digest={:#018x} tx_frames={} tx_digest={:#018x} heartbeats={} heartbeat_acks={}",
        name,
        node.gait().ticks(),
        digest.0,
        tx_frames,
        tx_digest,
        heartbeats,
        heartbeat_acks
    );
    let c = node.counters();
    line!(
        out,
        "NODE scenario={} refused={} tx_dropped={} bus_errors={} rx_overflow={}",
        name,
        c.refused,
        c.tx_dropped,
        c.bus_errors,
        runner.bus().rx_overflow()
    );
    line!(
        out,
        "BOARD scenario={} summaries={} worst={} overruns={} status_overruns={}",
        name,
        summaries,
        worst_window,
        board.overruns,
        node.counters().overruns
    );
    print_timing(out, name, stats);
    ok
}

#[entry]
fn main() -> ! {
    let Ok(host) = hio::hstdout() else {
        exit(debug::EXIT_FAILURE);
    };
    let mut out = Console {
        host,
        buf: heapless::Vec::new(),
    };
    let Some(mut timer) = hw::Timer0::take() else {
        panic!("timer taken twice");
    };
    timer.start_free_running();

    // The instructions-per-tick factor, checked: CALIB_LOOPS iterations of `subs; bne`.
    let t0 = timer.now();
    cortex_m::asm::delay(CALIB_LOOPS - 1);
    let calib = timer.now().wrapping_sub(t0);
    line!(
        out,
        "CALIB loop_instructions={} timer_ticks={} instructions_per_tick={}",
        2 * CALIB_LOOPS,
        calib,
        INSTRUCTIONS_PER_TICK
    );
    line!(
        out,
        "SIZE node={} gait={}",
        core::mem::size_of::<Node<QUEUE>>(),
        core::mem::size_of::<Gait<Scalar, QUEUE, machine::Gains>>()
    );
    line!(
        out,
        "MACHINE name={} scalar={}",
        machine::NAME,
        core::any::type_name::<Scalar>()
    );

    // The robot file compiled in (walk-robot's build script): host-sim's default robot, whose
    // stance both scenarios start from.
    let cfg = machine::NODE_CONFIG;
    let mut all = Stats::new();
    let mut ok = true;
    let mut placed: Option<&'static mut Slot> = None;
    let (mut startup_stack, mut control_stack) = (0, 0);
    for name in script::NAMES {
        let Some(scenario) = Scenario::by_name(name) else {
            ok = false;
            continue;
        };
        ok &= machine::starts_at(&scenario.feet);
        let t0 = timer.now();
        let slot = match placed.take() {
            None => place_node(cfg),
            Some(slot) => {
                renew_node(slot, cfg);
                slot
            }
        };
        let new_units = timer.now().wrapping_sub(t0);
        // The start-up's high-water mark (building the node), then a fresh paint for the
        // control loop's.
        startup_stack = startup_stack.max(hw::stack_usage().0);
        hw::repaint_stack();
        let node = match slot {
            Ok(n) => n,
            Err(e) => {
                line!(out, "ERROR scenario={} node_new={:?}", name, e);
                exit(debug::EXIT_FAILURE);
            }
        };
        let mut stats = Stats::new();
        stats.record(Kind::New, new_units, 0);
        ok &= run_scenario(&mut out, &mut timer, &scenario, node, &mut stats);
        control_stack = control_stack.max(hw::stack_usage().0);
        all.merge(&stats);
        placed = Some(slot);
    }
    print_timing(&mut out, "all", &all);

    let (_, size) = hw::stack_usage();
    line!(
        out,
        "STACK used={} size={} startup={} control={}",
        startup_stack.max(control_stack),
        size,
        startup_stack,
        control_stack
    );
    line!(out, "DONE");
    exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    })
}

/// Ends the QEMU run with `code` (semihosting `SYS_EXIT`).
fn exit(code: debug::ExitStatus) -> ! {
    debug::exit(code);
    // Not reached under QEMU; on a debugger that ignores the exit request, sleep.
    loop {
        cortex_m::asm::wfi();
    }
}
