//! planner-core's CAN node on QEMU's `mps2-an500` (Cortex-M7, double-precision FPU): replays
//! CAN logs recorded on the host into the node through the board's own control cycle
//! (board-core's `ControlLoop`) and link adapter (board-core's `Link` over an in-memory FDCAN),
//! counts the instructions of every `Node::poll` and of every whole cycle, and prints a
//! machine-readable report over semihosting.
//!
//! The logs are read from the file `replay.wlog` in QEMU's working directory (semihosting
//! `SYS_OPEN`, `SYS_FLEN`, `SYS_READ`: `semihost.rs`), in the compact binary format of
//! `gait_loop::binlog` (one or more logs, each its name, control period, start feet and the
//! frames to replay with their times; host-sim writes it, `host_sim::replay::binary_log`). Each
//! log is played by `gait_loop::Player` (`planner_core::playback`'s rule, as `host-sim replay`
//! plays a candump log) into a node built afresh from the robot's compiled-in configuration
//! (`walk_robot::NODE_CONFIG`, as on the board; a log must start on that stance and be for
//! its control period: see `restart_node`; a log whose name ends in `-measured` with
//! `AdjustConfig::from_measured` on, `machine::NODE_CONFIG_MEASURED`).
//! `tests/tests/qemu.rs` records host-sim runs, writes their logs into one such file and runs
//! the image once on it.
//!
//! With the `m4f` feature the same code is the M4F image: the `f32` node
//! (`walk_robot::NodeF32`) on QEMU's `mps2-an386` (Cortex-M4F), replaying the same logs
//! (`machine.rs` says what differs; `tests/tests/qemu_m4.rs` runs it).
//!
//! Run (from firmware/qemu, after `cargo build --release`, in a directory holding a
//! `replay.wlog`):
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
//! dual-issue pipeline nor the FPU latencies (a `vdiv.f64` or `vsqrt.f64` takes 30 cycles in
//! the cycle estimate's model of the core, `docs/src/timing.md`) nor flash wait states and
//! caches; the board image measures cycles with
//! DWT. Reading the log (semihosting traps, decoding) happens outside the timed poll.
//!
//! # Memory (as on the board)
//! The node (`walk_robot::Node<16>`, ~14 KB: it borrows its preview gains from flash) is a
//! `static` in .bss, parked (`ParkedNode`: every byte zero) and configured in place for the
//! first log (`ParkedNode::start`, as the board at start-up) and by `Node::restart` for every
//! further one: nothing of the node is built on the stack (`STACK ... startup=` is the first
//! log's start-up, `control=` the loops').
//! `memory.x` puts the stack into a 64 KiB region of its own below the 64 KiB RAM, as
//! `board/stack.x` does on the board (the lower half of its DTCM).
//!
//! # Output (one record per line, `key=value` fields)
//! * `CALIB loop_instructions=… timer_ticks=… instructions_per_tick=…`
//! * `SIZE node=… gait=…` (bytes of `Node<16>` and `Gait<f64, 16>`)
//! * `LOG file=replay.wlog bytes=…`
//! * per log, `scenario` being its name:
//!   * `RUN scenario=… index=… frames=… period_us=…`
//!   * `REPLAN scenario=… tick=… kind=… adjust_ticks=… ratio=… plane=… instructions=…` (kind of
//!     the cycle, instructions of its poll)
//!   * `CHECK scenario=… cycle=… tx_frames=… tx_digest=… ref_digest=…` after every
//!     500th cycle (the digests so far, to locate a difference)
//!   * `END scenario=… cycles=… ticks=… fed=… cut=… tx_frames=… tx_digest=… ref_digest=…`
//!     (`tx_digest`: FNV-1a 64 over every frame the node sent, each as its cycle (8 bytes),
//!     identifier (2 bytes) and data, `gait_loop::Fnv::add_sent`; `ref_digest`: over the bits
//!     of every cycle's x and y reference samples, the start-up one included; `cut`: 1 if
//!     the replay ended at its longest rather than standing and idle)
//!   * `NODE scenario=… refused=… tx_dropped=… bus_errors=… rx_overflow=…` (the node's
//!     counters, the device's lost frames)
//!   * `BOARD scenario=… summaries=… worst=… overruns=… status_overruns=… feeds=…
//!     busy_pulses=… busy_high=… missed_slots=… log_missed=… log_overruns=… log_refused=…
//!     link_frames=… link_digest=… rx_lost=… replaced=… rx_foreign=… wire_lost=…` (the board's
//!     cycle, board-core's `ControlLoop`, run around every poll: `board.rs`; `LINK` frames
//!     are digested apart from `tx_digest`)
//!   * `TIMING scenario=… kind=… n=… max=… mean=… max_tick=… max_timer=…` (instructions of
//!     the poll), and `WHOLE …` the same for the board's whole cycle (slot start to feed)
//! * `TIMING scenario=all …`, `WHOLE scenario=all …`: over every log
//! * `STACK used=… size=… startup=… control=…` (bytes: the high-water mark, of the stack
//!   region's size; `startup`: while building the node, `control`: while replaying,
//!   measured after painting the stack again once the node is built)
//! * `RUNS count=…`, `DONE`, then a semihosting exit with code 0 (1 if the file is missing or
//!   refused, a log is not for the robot's control period or stance, or a node could not be
//!   created; an `ERROR` line says which).
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod board;
mod hw;
mod machine;
mod semihost;

use core::fmt::{self, Write};

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hio};
use panic_semihosting as _; // panics print over semihosting and exit with code 1

use board_core::control::{ControlLoop, Io, MicrosClock};
use board_core::{Pacer, ResetReason};
use gait_loop::binlog::{Bytes, Frames, Header};
use gait_loop::{Device, Fnv, Kind, Pending, Player, ReplayFdcan, ReplayLink, Stats, QUEUE};
use machine::{Node, ParkedNode, Scalar};
use planner_core::gait::{Gait, GaitError};
use planner_core::playback::{self, LogClock};
use static_cell::ConstStaticCell;

use semihost::HostFile;

/// Instructions per CMSDK timer tick under `-icount shift=0` (1 ns per instruction, 25 MHz).
const INSTRUCTIONS_PER_TICK: u32 = board::INSTRUCTIONS_PER_TICK;
/// Iterations of the calibration loop (two instructions each: `subs`, `bne`).
const CALIB_LOOPS: u32 = 1_000_000;
/// A `CHECK` line every this many cycles.
const CHECK_EVERY: u64 = 500;
/// The board's 5 ms slot in core cycles at 480 MHz: a cycle of more instructions counts as an
/// overrun in the board's bookkeeping.
const BOARD_PERIOD_CYCLES: u32 = 2_400_000;
/// The logs to replay, in QEMU's working directory (NUL-terminated for `SYS_OPEN`).
const LOG_FILE: &[u8] = b"replay.wlog\0";

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

fn instructions(timer_ticks: u32) -> u64 {
    u64::from(timer_ticks) * u64::from(INSTRUCTIONS_PER_TICK)
}

/// `what` lines (`TIMING`: the poll; `WHOLE`: the board's whole cycle) of `stats`.
fn print_timing(out: &mut Console, what: &str, scenario: &str, stats: &Stats) {
    for kind in Kind::ALL {
        let s = stats.get(kind);
        if s.n == 0 {
            continue;
        }
        let mean = instructions(1) as f64 * s.sum as f64 / f64::from(s.n);
        line!(
            out,
            "{} scenario={} kind={} n={} max={} mean={:.0} max_tick={} max_timer={}",
            what,
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

/// The node's `static`: parked ([`ParkedNode`]: every byte zero, so it is in .bss and costs
/// no flash), configured in place for the first log ([`start_node`]) and restarted in place
/// for every further one ([`restart_node`]).
static NODE: ConstStaticCell<ParkedNode<QUEUE>> =
    ConstStaticCell::new(ParkedNode::new(machine::gains()));

/// Configures the parked node in place, as the board does at start-up: from the constant
/// `machine::NODE_CONFIG` (`walk_robot::NODE_CONFIG`, or `NODE_CONFIG_F32` for the M4F).
/// Nothing of the node's 14 KB is built on the stack. Not inlined: its frame is the start-up's
/// stack, measured apart from the control loop's. (The image replays only logs that start on
/// the robot's stance, the one the board starts on.)
/// `measured`: with `machine::NODE_CONFIG_MEASURED` instead.
#[inline(never)]
fn start_node(
    parked: &'static mut ParkedNode<QUEUE>,
    measured: bool,
) -> Result<&'static mut Node<QUEUE>, GaitError> {
    if measured {
        parked.start(machine::NODE_CONFIG_MEASURED)
    } else {
        parked.start(machine::NODE_CONFIG)
    }
}

/// The node afresh, in place (the next log starts from start-up): `Node::restart`
/// (`measured`: with `machine::NODE_CONFIG_MEASURED`).
#[inline(never)]
fn restart_node(node: &mut Node<QUEUE>, measured: bool) -> Result<(), GaitError> {
    if measured {
        node.restart(machine::NODE_CONFIG_MEASURED)
    } else {
        node.restart(machine::NODE_CONFIG)
    }
}

/// The board's control loop over the image's hardware (`board.rs`).
type Board<'a> = ControlLoop<
    board::ReplayClock<'a>,
    board::Instructions<'a>,
    board::CountingWatchdog,
    board::CountingBusy,
    board::CountingLog,
>;

/// Replays one log (its header read, its frames next in `frames`) into `node` (just created)
/// through the board's control cycle (board-core's `ControlLoop`: a board started afresh with
/// the node) and link adapter (over the in-memory FDCAN); returns `false` if the log's frames
/// were refused or ended early, or the cycle's slots left the log's grid.
#[inline(never)]
fn replay<B: Bytes>(
    out: &mut Console,
    timer: &hw::Timer0,
    header: &Header,
    frames: &mut Frames<'_, B>,
    node: &mut Node<QUEUE>,
    stats: &mut Stats,
    whole: &mut Stats,
) -> bool {
    let name = header.name();
    let period_us = header.period_us;
    let clock = match LogClock::new(header.first_us, u64::from(period_us)) {
        // The slots' `now_ms` are the log's poll times (`playback::poll_ms`, linear for a
        // whole number of milliseconds).
        Some(clock) if period_us % 1000 == 0 => clock,
        _ => {
            line!(out, "ERROR scenario={} period_us={}", name, period_us);
            return false;
        }
    };
    let mut player = Player::with_device(
        clock,
        header.count,
        header.last_us,
        ReplayLink::new(ReplayFdcan::new()),
    );
    let mut ref_digest = Fnv::default();
    ref_digest.add_reference(node.gait().last());
    // The board's cycle around each poll, on the log's grid: slot k at `poll_ms(k)`.
    let mut micros = board::ReplayClock::new(timer);
    let first = micros.now_us().wrapping_add(period_us);
    let pacer = Pacer::new(first, period_us, period_us / 1000)
        .with_first_ms(playback::poll_ms(0, u64::from(period_us)));
    let mut ctl: Board<'_> = ControlLoop::new(
        Io {
            clock: micros,
            counter: board::Instructions(timer),
            watchdog: board::CountingWatchdog::default(),
            busy: board::CountingBusy::default(),
            log: board::CountingLog::default(),
        },
        pacer,
        BOARD_PERIOD_CYCLES,
        ResetReason::Unknown,
    );
    while !player.done() {
        let cycle = player.next_cycle();
        let step = player.cycle(
            node,
            frames,
            |n, ms, link| {
                let pending = Pending::before(n, link);
                let run = ctl.step(n, link);
                let on_grid = run.slot.now_ms == ms && u64::from(run.slot.index) == cycle;
                let spent = run.spent / board::INSTRUCTIONS_PER_TICK;
                (pending.after(n, link, spent, run.report), run, on_grid)
            },
            |_, _| {},
        );
        let (record, run) = match step {
            Ok((record, run, true)) => (record, run),
            Ok((_, run, false)) => {
                line!(
                    out,
                    "ERROR scenario={} cycle={} slot={} now_ms={}",
                    name,
                    cycle,
                    run.slot.index,
                    run.slot.now_ms
                );
                return false;
            }
            Err(_) => {
                line!(
                    out,
                    "ERROR scenario={} cycle={} log={:?}",
                    name,
                    cycle,
                    frames.error()
                );
                return false;
            }
        };
        stats.record(record.kind, record.units, record.tick);
        stats.record(Kind::Cycle, record.units, record.tick);
        let whole_units = run.whole / board::INSTRUCTIONS_PER_TICK;
        whole.record(record.kind, whole_units, record.tick);
        whole.record(Kind::Cycle, whole_units, record.tick);
        ref_digest.add_reference(&record.report.reference);
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
        if (cycle + 1) % CHECK_EVERY == 0 {
            let (tx_frames, tx_digest) = player.transmitted();
            line!(
                out,
                "CHECK scenario={} cycle={} tx_frames={} tx_digest={:#018x} ref_digest={:#018x}",
                name,
                cycle,
                tx_frames,
                tx_digest,
                ref_digest.0
            );
        }
    }

    let (tx_frames, tx_digest) = player.transmitted();
    line!(
        out,
        "END scenario={} cycles={} ticks={} fed={} cut={} tx_frames={} tx_digest={:#018x} ref_digest={:#018x}",
        name,
        player.next_cycle(),
        node.gait().ticks(),
        player.fed(),
        u8::from(player.cut()),
        tx_frames,
        tx_digest,
        ref_digest.0
    );
    let c = node.counters();
    let link = player.bus();
    line!(
        out,
        "NODE scenario={} refused={} tx_dropped={} bus_errors={} rx_overflow={}",
        name,
        c.refused,
        c.tx_dropped,
        c.bus_errors,
        link.rx_overflow()
    );
    let io = &ctl.io;
    let (link_frames, link_digest) = player.link();
    let h = link.health();
    line!(
        out,
        "BOARD scenario={} summaries={} worst={} overruns={} status_overruns={} feeds={} busy_pulses={} busy_high={} missed_slots={} log_missed={} log_overruns={} log_refused={} link_frames={} link_digest={:#018x} rx_lost={} replaced={} rx_foreign={} wire_lost={}",
        name,
        io.log.summaries,
        io.log.worst,
        ctl.stats().overruns,
        node.counters().overruns,
        io.watchdog.feeds,
        io.busy.pulses,
        u8::from(io.busy.high),
        ctl.pacer().missed(),
        io.log.missed,
        io.log.overruns,
        io.log.refused,
        link_frames,
        link_digest,
        h.rx_lost,
        h.replaced,
        h.rx_foreign,
        link.peripheral().wire_lost()
    );
    print_timing(out, "TIMING", name, stats);
    print_timing(out, "WHOLE", name, whole);
    true
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
    // Nothing accessible below the stack, as on the board: an overflow faults.
    if !hw::guard_below_stack() {
        line!(out, "ERROR stack_guard=0");
        exit(debug::EXIT_FAILURE);
    }
    if semihost::cmdline_has("overflow") {
        // The fault entry's test (`tests/tests/qemu.rs`): run the stack below its region.
        line!(out, "OVERFLOW stack_bytes={}", hw::stack_usage().1);
        let depth = overflow(0);
        // Not reached: the fault handler ends the run.
        line!(out, "ERROR overflow_returned={}", depth);
        exit(debug::EXIT_FAILURE);
    }
    let Some(mut timer) = hw::Timer0::take() else {
        panic!("timer taken twice");
    };
    timer.start_free_running();

    // The instructions-per-tick factor, checked: CALIB_LOOPS iterations of `subs; bne`.
    let t0 = timer.count();
    cortex_m::asm::delay(CALIB_LOOPS - 1);
    let calib = timer.count().wrapping_sub(t0);
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

    let Some(mut file) = HostFile::open(LOG_FILE) else {
        line!(out, "ERROR file=replay.wlog cannot_open=1");
        exit(debug::EXIT_FAILURE);
    };
    line!(out, "LOG file=replay.wlog bytes={}", file.len());

    // The robot file compiled in (walk-robot's build script): host-sim's default robot. Each
    // log's control period and start feet must be the robot's (see `restart_node`).
    let cfg = walk_robot::NODE_CONFIG;
    let period_us = (cfg.params.dt * 1e6 + 0.5) as u32;
    let mut all = Stats::new();
    let mut all_whole = Stats::new();
    let mut ok = true;
    let Some(parked) = NODE.try_take() else {
        line!(out, "ERROR node_taken_twice=1");
        exit(debug::EXIT_FAILURE);
    };
    let mut parked = Some(parked);
    let mut started: Option<&'static mut Node<QUEUE>> = None;
    let (mut startup_stack, mut control_stack) = (0, 0);
    let mut runs = 0u32;
    loop {
        let header = match Header::read(&mut file) {
            Ok(Some(h)) => h,
            Ok(None) => break,
            Err(e) => {
                line!(out, "ERROR index={} header={:?}", runs, e);
                ok = false;
                break;
            }
        };
        let name = header.name();
        line!(
            out,
            "RUN scenario={} index={} frames={} period_us={}",
            name,
            runs,
            header.count,
            header.period_us
        );
        if header.period_us != period_us {
            line!(
                out,
                "ERROR scenario={} period_us={} robot_period_us={}",
                name,
                header.period_us,
                period_us
            );
            ok = false;
            break;
        }
        if !machine::starts_at(&header.feet) {
            line!(out, "ERROR scenario={} feet_not_the_robots_stance=1", name);
            ok = false;
            break;
        }
        let measured = name.ends_with(machine::MEASURED_SUFFIX);
        let t0 = timer.count();
        let configured = match (started.take(), parked.take()) {
            (Some(node), _) => restart_node(node, measured).map(|()| node),
            (None, Some(p)) => start_node(p, measured),
            (None, None) => {
                line!(out, "ERROR scenario={} no_node=1", name);
                exit(debug::EXIT_FAILURE);
            }
        };
        let new_units = timer.count().wrapping_sub(t0);
        // The start-up's high-water mark (configuring the node; the first log's: later ones
        // include the control loop before them), then a fresh paint for the control loop's.
        if runs == 0 {
            startup_stack = hw::stack_usage().0;
        }
        hw::repaint_stack();
        let node = match configured {
            Ok(n) => n,
            Err(e) => {
                line!(out, "ERROR scenario={} node_new={:?}", name, e);
                exit(debug::EXIT_FAILURE);
            }
        };
        let mut stats = Stats::new();
        stats.record(Kind::New, new_units, 0);
        let mut whole = Stats::new();
        let mut frames = Frames::new(&header, &mut file);
        if !replay(
            &mut out,
            &timer,
            &header,
            &mut frames,
            node,
            &mut stats,
            &mut whole,
        ) {
            // The log was refused (its ERROR line says why): where the next one would begin
            // is unknown.
            ok = false;
            break;
        }
        // A replay cut at its longest leaves frames unread: skip to the next header.
        if let Err(e) = frames.skip_rest() {
            line!(out, "ERROR scenario={} log={:?}", name, e);
            ok = false;
            break;
        }
        control_stack = control_stack.max(hw::stack_usage().0);
        all.merge(&stats);
        all_whole.merge(&whole);
        started = Some(node);
        runs += 1;
    }
    if file.failed() {
        line!(out, "ERROR file=replay.wlog read_failed=1");
        ok = false;
    }
    print_timing(&mut out, "TIMING", "all", &all);
    print_timing(&mut out, "WHOLE", "all", &all_whole);

    let (_, size) = hw::stack_usage();
    line!(
        out,
        "STACK used={} size={} startup={} control={}",
        startup_stack.max(control_stack),
        size,
        startup_stack,
        control_stack
    );
    line!(out, "RUNS count={}", runs);
    line!(out, "DONE");
    exit(if ok && runs > 0 {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    })
}

/// Recurses with a 256-byte frame until the stack runs out (`-append overflow`): the stack
/// overflow the fault entry must survive. Each level also computes in floating point, so the
/// fault finds the FPU's context active and its lazy save pending (which the entry drops).
#[inline(never)]
fn overflow(depth: u32) -> u32 {
    let frame = core::hint::black_box([depth; 64]);
    let scaled = core::hint::black_box(f64::from(depth) * 1.5);
    if core::hint::black_box(depth) == u32::MAX {
        return depth;
    }
    overflow(depth + 1)
        .wrapping_add(frame[(depth % 64) as usize])
        .wrapping_add(scaled as u32)
}

/// Ends the QEMU run with `code` (semihosting `SYS_EXIT`).
fn exit(code: debug::ExitStatus) -> ! {
    debug::exit(code);
    // Not reached under QEMU; on a debugger that ignores the exit request, sleep.
    loop {
        cortex_m::asm::wfi();
    }
}
