//! The verdict "walked" (no fall, and slip, flight, the CoP outside the support polygon and
//! the landing error within their bounds: `host_sim::physics::gait`) and the stabilizer
//! designed for a stated loop delay (`Gains::for_delay`, `--design-delay-ms`).
//!
//! * Default run: HRP-2's `straight` with 5 ms of loop delay and the gains tuned for none stays
//!   up but slides its feet: not walked (the verdict of a fall alone said "no fall"); with the
//!   gains designed for the delay, and with no delay, it walks.
//! * `WALK_LONG=1`: the book's delay sweep (0, 2, 5, 10 ms; HRP-2 and the imported robots
//!   where `example-robot-data` is installed) and the realistic sensors over several seeds,
//!   printed as the book's table rows and checked against `docs/src/physics.md`.

mod engine;
mod urdf;

use doc_figures::Quotes;
use engine::engine_here;
use host_sim::physics::probe::ProbeArgs;
use host_sim::physics::sensors::SensorModel;
use host_sim::physics::{run, PhysicsConfig, PhysicsReport};
use host_sim::robot::Robot;
use host_sim::scenario::BUILT_IN;
use host_sim::sim::scenario_trajectory;

/// The command that measures the book's delay sweep.
const COMMAND: &str = "WALK_LONG=1 cargo test --release -p host-sim --test delay -- --nocapture";
/// The book's page.
const BOOK: &str = "docs/src/physics.md";
/// The delays of the sweep [ms].
const DELAYS_MS: [usize; 4] = [0, 2, 5, 10];
/// The seeds of the realistic-sensor runs.
const SEEDS: [u64; 5] = [1, 2, 3, 4, 5];

/// The configuration of `robot` with `sensors` `latency_ms` late (seed `seed`), the gains
/// designed for `design_ms` (`None`: for the latency).
fn config(
    robot: &Robot,
    sensors: SensorModel,
    latency_ms: usize,
    design_ms: Option<f64>,
    seed: u64,
) -> PhysicsConfig {
    ProbeArgs {
        sensors,
        latency_ms: Some(latency_ms),
        design_delay_ms: design_ms,
        noise_seed: Some(seed),
        ..ProbeArgs::default()
    }
    .resolve(robot)
    .expect("the configuration")
    .cfg
}

fn walk(robot: &Robot, scenario: &str, cfg: &PhysicsConfig) -> PhysicsReport {
    let (_, trajectory, dt) = scenario_trajectory(scenario, robot).expect("scenario");
    run(&trajectory, dt, cfg).expect("engine run").report
}

fn mm(m: f64) -> String {
    format!("{:.1} mm", m * 1e3)
}

fn ms(s: f64) -> String {
    format!("{:.0} ms", s * 1e3)
}

/// The verdict of a fall alone ("no fall") hid a walk that slid its feet: HRP-2's `straight`
/// with 5 ms of loop delay under the gains tuned for none. The new verdict says it did not
/// walk, and why.
#[test]
fn a_slide_at_5_ms_is_not_a_walk() {
    if !engine_here("a_slide_at_5_ms_is_not_a_walk") {
        return;
    }
    let hrp2 = Robot::hrp2();
    let r = walk(
        &hrp2,
        "straight",
        &config(&hrp2, SensorModel::IDEAL, 5, Some(0.0), 1),
    );
    println!(
        "straight, 5 ms late, gains for no delay: {}; slip {}, flight {} (longest {}), CoP \
         outside {} (longest {}), landing error {}",
        r.verdict_words(),
        mm(r.gait.slip_max_m),
        ms(r.gait.flight_s),
        ms(r.gait.flight_max_s),
        ms(r.gait.cop_outside_s),
        ms(r.gait.cop_outside_max_s),
        mm(r.gait.landing_err_max_m)
    );
    assert!(!r.fell, "{r:?}");
    assert!(!r.walked(), "{r:?}");
    assert!(r.gait.violations().contains(&"slip"), "{r:?}");
    assert!(r.verdict_words().starts_with("did not walk"), "{r:?}");
}

/// With the gains designed for the loop delay, HRP-2 walks `straight` with 0 and with 5 ms
/// of it by the new verdict.
#[test]
fn hrp2_walks_with_0_and_5_ms_of_loop_delay() {
    if !engine_here("hrp2_walks_with_0_and_5_ms_of_loop_delay") {
        return;
    }
    let hrp2 = Robot::hrp2();
    for delay in [0, 5] {
        let r = walk(
            &hrp2,
            "straight",
            &config(&hrp2, SensorModel::IDEAL, delay, None, 1),
        );
        println!(
            "straight, {delay} ms late, gains for the delay: {}; slip {}",
            r.verdict_words(),
            mm(r.gait.slip_max_m)
        );
        assert!(r.walked(), "{delay} ms: {}: {r:?}", r.verdict_words());
        assert!(r.gait.landings >= 8, "{r:?}");
    }
}

/// The robots of the sweep: HRP-2, and Talos and G1 where `example-robot-data` is installed.
fn robots(test: &str) -> Vec<(&'static str, Robot)> {
    let mut v = vec![("HRP-2", Robot::hrp2())];
    for (name, tail) in [("Talos", urdf::TALOS), ("G1", urdf::G1)] {
        if let Some(path) = urdf::robot_file(tail, test) {
            let imported = host_sim::robot::import::import(&path, None).expect("import");
            v.push((name, imported.robot));
        }
    }
    v
}

fn long(test: &str) -> bool {
    let on = std::env::var("WALK_LONG").is_ok_and(|v| v == "1");
    if !on {
        eprintln!("delay: SKIPPED {test} (WALK_LONG=1 runs it)");
    }
    on && engine_here(test)
}

/// The worst of every gait measure and of the CoP error over runs, and how many walked.
#[derive(Default)]
struct Worst {
    walked: usize,
    runs: usize,
    slip: f64,
    flight: f64,
    outside: f64,
    landing: f64,
    cop_max: f64,
    cop_mean_sum: f64,
    fell: Vec<String>,
}

impl Worst {
    /// The book's row `anchor` of these runs (printed, and quoted against the book):
    /// `straight` in the first column, `slip` in the slip column.
    fn book_row(&self, q: Quotes, anchor: &str, straight: String, slip: String) -> Quotes {
        let cells = [
            ("gains for no delay: `straight`", straight),
            (
                "gains for the delay: walked",
                format!("{} of {}", self.walked, self.runs),
            ),
            ("slip", slip),
            ("flight", ms(self.flight)),
            ("CoP outside", ms(self.outside)),
            ("landing error", mm(self.landing)),
            (
                "CoP error mean / worst",
                format!(
                    "{:.1} / {:.1} mm",
                    1e3 * self.cop_mean_sum / self.runs as f64,
                    1e3 * self.cop_max
                ),
            ),
        ];
        println!(
            "{anchor} {} | not walked: {:?}",
            cells
                .iter()
                .map(|c| c.1.as_str())
                .collect::<Vec<_>>()
                .join(" | "),
            self.fell
        );
        cells
            .iter()
            .fold(q, |q, (column, value)| q.cell(BOOK, anchor, column, value))
    }

    fn add(&mut self, name: &str, r: &PhysicsReport) {
        self.runs += 1;
        self.walked += usize::from(r.walked());
        if !r.walked() {
            self.fell.push(format!("{name}: {}", r.verdict_words()));
        }
        self.slip = self.slip.max(r.gait.slip_max_m);
        self.flight = self.flight.max(r.gait.flight_max_s);
        self.outside = self.outside.max(r.gait.cop_outside_max_s);
        self.landing = self.landing.max(r.gait.landing_err_max_m);
        self.cop_max = self.cop_max.max(r.cop_err_max_m);
        self.cop_mean_sum += r.cop_err_mean_m;
    }
}

/// The book's delay sweep: per robot and delay, `straight` under the gains tuned for no delay,
/// and every built-in scenario under the gains designed for the delay: how many walked and
/// the worst of each measure.
#[test]
fn delay_sweep_as_the_book_says() {
    if !long("delay_sweep_as_the_book_says") {
        return;
    }
    let mut q = Quotes::new(COMMAND);
    let mut hrp2_walked = Vec::new();
    for (name, robot) in robots("delay_sweep_as_the_book_says") {
        for delay in DELAYS_MS {
            let old = walk(
                &robot,
                "straight",
                &config(&robot, SensorModel::IDEAL, delay, Some(0.0), 1),
            );
            let mut w = Worst::default();
            for scenario in BUILT_IN {
                let r = walk(
                    &robot,
                    scenario,
                    &config(&robot, SensorModel::IDEAL, delay, None, 1),
                );
                w.add(scenario, &r);
            }
            let anchor = format!("| {name} | {delay} ms |");
            q = w.book_row(q, &anchor, old.walked_text(), mm(w.slip));
            if name == "HRP-2" {
                hrp2_walked.push((delay, w.walked == w.runs));
            }
        }
    }
    // HRP-2 walks every built-in scenario at every delay of the sweep with the gains designed
    // for it.
    assert!(hrp2_walked.iter().all(|w| w.1), "{hrp2_walked:?}");
    q.assert();
}

/// The realistic sensors over several seeds: per robot, every built-in scenario with each seed
/// (the gains designed for the sensors' 2 ms): how many walked, the mean and the worst.
#[test]
fn realistic_sensors_over_seeds_as_the_book_says() {
    if !long("realistic_sensors_over_seeds_as_the_book_says") {
        return;
    }
    let mut q = Quotes::new(COMMAND);
    for (name, robot) in robots("realistic_sensors_over_seeds_as_the_book_says") {
        let mut w = Worst::default();
        let mut slips = Vec::new();
        for seed in SEEDS {
            for scenario in BUILT_IN {
                let cfg = config(&robot, SensorModel::REALISTIC, 2, None, seed);
                let r = walk(&robot, scenario, &cfg);
                slips.push(r.gait.slip_max_m);
                w.add(&format!("{scenario} seed {seed}"), &r);
            }
        }
        let anchor = format!("| {name} | realistic, seeds 1–{} |", SEEDS.len());
        let slip_mean = slips.iter().sum::<f64>() / slips.len() as f64;
        let slip = format!("{:.1} / {}", 1e3 * slip_mean, mm(w.slip));
        q = w.book_row(q, &anchor, "–".to_string(), slip);
    }
    q.assert();
}
