//! In MuJoCo under the stabilizer, the built-in `velocity` scenario (forward, a step change to
//! sideways, a turn and its reversal, zero), drawn in Talos's proportions, walks without a
//! fall by the engine's verdict on Talos imported from example-robot-data's URDF
//! (`host-sim robot import`). Slow (a 25 s engine run of a 90 kg robot): under `WALK_LONG=1`.
//! `WALK_LONG=1 cargo test -p host-sim --test velocity_talos -- --nocapture` prints the
//! figures `docs/src/velocity.md` quotes.

#[allow(dead_code)]
mod engine;
mod urdf;

#[test]
fn the_velocity_scenario_walks_on_imported_talos_in_mujoco() {
    use host_sim::physics::{run, PhysicsConfig};
    use host_sim::robot::import::import;
    use host_sim::sim::scenario_trajectory;
    let test = "the_velocity_scenario_walks_on_imported_talos_in_mujoco";
    if std::env::var("WALK_LONG").is_err() {
        println!("{test} runs with WALK_LONG=1");
        return;
    }
    let Some(file) = urdf::robot_file(urdf::TALOS, test) else {
        return;
    };
    if !engine::engine_here(test) {
        return;
    }
    let robot = import(&file, None).expect("Talos imports").robot;
    let (_, trajectory, dt) = scenario_trajectory("velocity", &robot).expect("scenario");
    let cfg = PhysicsConfig::for_robot(&robot);
    let r = run(&trajectory, dt, &cfg).expect("engine run").report;
    let figures = format!(
        "max tilt {:.2} deg; CoP mean {:.1} mm, worst {:.1} mm; landing error {:.1} mm over {} \
         landings",
        r.max_tilt_deg,
        r.cop_err_mean_m * 1e3,
        r.cop_err_max_m * 1e3,
        r.gait.landing_err_max_m * 1e3,
        r.gait.landings
    );
    println!("talos velocity: fell {}, {figures}", r.fell);
    assert!(!r.fell, "fell at {:?} s", r.fall_time_s);
    assert!(r.walked(), "a gait measure beyond its bound: {:?}", r.gait);
    assert!(r.max_tilt_deg < 2.0, "tilt {} deg", r.max_tilt_deg);
    // The book quotes these figures (its line breaks aside).
    let book = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../docs/src/velocity.md"
    ))
    .expect("docs/src/velocity.md");
    let flat = |t: &str| t.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat(&book).contains(&flat(&figures)),
        "docs/src/velocity.md does not quote Talos's figures ({figures})"
    );
}
