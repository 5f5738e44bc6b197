//! The gait loop on QEMU's `mps2-an500` (Cortex-M7, double-precision FPU): plays host-sim's
//! `fig4` and `lateral` scenarios from the scripted footstep source, counts the instructions of
//! every gait call, and prints a machine-readable report over semihosting.
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
//! SYSCLK of that virtual clock: one timer tick = 40 ns = **40 instructions**. A gait call is
//! timed by reading the timer before and after it, so its count has a resolution of 40
//! instructions (±1 tick) and includes the few instructions of the two timer reads. The
//! counts are exact and repeatable run to run (the virtual clock is driven by the
//! instruction count only). The image checks the factor itself (`CALIB`: a delay loop of known
//! instruction count). They are *instructions*, not Cortex-M7 cycles: QEMU models neither the
//! dual-issue pipeline nor the FPU latencies (a `vdiv.f64` or `vsqrt.f64` takes ~16 cycles
//! on the real core) nor flash wait states and caches; the board image measures cycles with
//! DWT.
//!
//! # Output (one record per line, `key=value` fields)
//! * `CALIB loop_instructions=… timer_ticks=… instructions_per_tick=…`
//! * `SIZE gait=…` (bytes of `Gait<f64, 16>`)
//! * `CMD scenario=… tick=… op=… id=… side=… x=… y=… yaw=… result=… instructions=…`
//! * `REPLAN scenario=… tick=… kind=replan|adjust adjust_ticks=… ratio=… plane=…`
//! * `REF scenario=… tick=… kind=… cog_x=… cog_y=… zmp_x=… zmp_y=… cogv_x=… cogv_y=…`
//!   every 20 ticks and at every non-steady tick; floats in Rust's shortest round-trip `{:e}`
//! * `END scenario=… ticks=… digest=…` (FNV-1a 64 over the bits of every tick's x and y
//!   samples, tick 0 included)
//! * `TIMING scenario=…|all kind=… n=… max=… mean=… max_tick=… max_timer=…` (instructions)
//! * `STACK used=… size=…` (bytes; the stack is painted at reset)
//! * `DONE`, then a semihosting exit with code 0 (1 if a command was refused or the gait
//!   could not be created).
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod hw;

use core::fmt::{self, Write};

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hio};
use panic_semihosting as _; // panics print over semihosting and exit with code 1

use gait_loop::{
    new_gait, script, Clock, Command, CommandRecord, CycleRecord, Kind, Player, Scenario, Stats,
    QUEUE,
};
use planner_core::gait::{Gait, GaitParams, Reference, Side};
use planner_core::Sample;

/// Instructions per CMSDK timer tick under `-icount shift=0` (1 ns per instruction, 25 MHz).
const INSTRUCTIONS_PER_TICK: u32 = 1_000_000_000 / hw::TIMER_HZ;
/// Iterations of the calibration loop (two instructions each: `subs`, `bne`).
const CALIB_LOOPS: u32 = 1_000_000;
/// A `REF` line every this many ticks.
const REF_EVERY: u64 = 20;

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

/// FNV-1a 64 over the bits of the samples of every tick.
struct Digest(u64);

impl Digest {
    fn new() -> Self {
        Digest(0xcbf2_9ce4_8422_2325)
    }

    fn add_sample(&mut self, s: &Sample<f64>) {
        for v in [s.cog, s.cog_vel, s.cog_acc, s.zmp, s.zmp_vel] {
            for b in v.to_bits().to_le_bytes() {
                self.0 ^= u64::from(b);
                self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
            }
        }
    }

    fn add(&mut self, r: &Reference<f64>) {
        self.add_sample(&r.x);
        self.add_sample(&r.y);
    }
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

fn print_ref(out: &mut Console, scenario: &str, tick: u64, kind: &str, r: &Reference<f64>) {
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

fn print_command(out: &mut Console, scenario: &str, c: &CommandRecord) {
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
    match c.result {
        Ok(()) => {
            let _ = write!(out, " result=Ok");
        }
        Err(e) => {
            let _ = write!(out, " result={:?}", e);
        }
    }
    line!(out, " instructions={}", instructions(c.units));
}

/// One control cycle, in a frame of its own: the planner's temporaries (windows, the 20×20
/// factorisation) are not kept reserved next to the gait while it is being created.
#[inline(never)]
fn control_cycle(
    player: &mut Player<'_>,
    gait: &mut Gait<f64, QUEUE>,
    timer: &mut hw::Timer0,
    stats: &mut Stats,
    out: &mut Console,
    ok: &mut bool,
) -> CycleRecord {
    let name = player.scenario().name;
    player.cycle(gait, timer, stats, |c| {
        *ok &= c.result.is_ok();
        print_command(out, name, c);
    })
}

/// Plays one scenario with a fresh gait; returns `false` if something was refused or failed.
/// The gait (~38 KB) lives in this function's frame (not inlined: one frame, whatever the
/// number of scenarios).
#[inline(never)]
fn run_scenario(
    out: &mut Console,
    timer: &mut hw::Timer0,
    scenario: &Scenario,
    params: GaitParams<f64>,
    all: &mut Stats,
) -> bool {
    let name = scenario.name;
    let mut stats = Stats::new();
    let t0 = timer.now();
    let mut created = new_gait(params, scenario);
    let new_units = timer.now().wrapping_sub(t0);
    // Borrowed where `new_gait` returned it (see there).
    let gait = match &mut created {
        Ok(g) => g,
        Err(e) => {
            line!(out, "ERROR scenario={} gait_new={:?}", name, e);
            return false;
        }
    };
    stats.record(Kind::New, new_units, 0);

    let mut ok = true;
    let mut digest = Digest::new();
    digest.add(gait.last());
    print_ref(out, name, 0, Kind::Standing.name(), gait.last());

    let mut player = Player::new(scenario);
    while !player.done(gait) {
        let record = control_cycle(&mut player, gait, timer, &mut stats, out, &mut ok);
        digest.add(&record.reference);
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
                instructions(record.tick_units)
            );
        }
        let notable = !matches!(record.kind, Kind::Steady | Kind::Standing);
        if record.tick % REF_EVERY == 0 || notable {
            print_ref(
                out,
                name,
                record.tick,
                record.kind.name(),
                &record.reference,
            );
        }
    }
    line!(
        out,
        "END scenario={} ticks={} digest={:#018x}",
        name,
        gait.ticks(),
        digest.0
    );
    print_timing(out, name, &stats);
    all.merge(&stats);
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
        "SIZE gait={}",
        core::mem::size_of::<Gait<f64, QUEUE>>()
    );

    let params = GaitParams::<f64>::hrp2();
    let mut all = Stats::new();
    let mut ok = true;
    for name in script::NAMES {
        match Scenario::by_name(name) {
            Some(s) => ok &= run_scenario(&mut out, &mut timer, &s, params, &mut all),
            None => ok = false,
        }
    }
    print_timing(&mut out, "all", &all);

    let (used, size) = hw::stack_usage();
    line!(out, "STACK used={} size={}", used, size);
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
