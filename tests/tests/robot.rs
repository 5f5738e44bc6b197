//! The firmware and the simulator are configured from one robot file: the node configuration
//! the firmware's build script compiles in (`firmware/robot`, from `host-sim/robots/hrp2.toml`)
//! is, float by float, the one host-sim reads from that file at run time.

use host_sim::robot::Robot;

#[test]
fn the_firmware_node_is_configured_as_the_simulated_one() {
    let host = Robot::hrp2();
    assert_eq!(walk_robot::NAME, host.name());
    assert_eq!(walk_robot::NODE_CONFIG, host.node_config());
    // PartialEq on f64 would let 0.0 equal -0.0: compare the bits of every float too.
    let bits = |c: &planner_core::node::NodeConfig| format!("{c:?}");
    assert_eq!(bits(&walk_robot::NODE_CONFIG), bits(&host.node_config()));
}

#[test]
fn the_generated_source_is_the_configuration_it_was_made_from() {
    // The generator the build script calls, on a second robot: its constant expression
    // evaluates (here, by parsing the bits back) to the configuration.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../host-sim/tests/robots/small.toml"
    ))
    .unwrap();
    let cfg = Robot::from_toml(&text).unwrap().node_config();
    let src = planner_core::robot::node_config_source(&cfg);
    let floats: Vec<f64> = src
        .match_indices("f64::from_bits(")
        .map(|(i, _)| {
            let hex = &src[i + 15..i + 15 + 18];
            f64::from_bits(u64::from_str_radix(hex.trim_start_matches("0x"), 16).unwrap())
        })
        .collect();
    let p = cfg.params;
    let r = cfg.reach;
    let want = [
        p.omega,
        p.dt,
        p.step_width,
        p.sole_half_length,
        p.sole_half_width,
        p.step_height,
        p.cog_height,
        p.gravity,
        p.preview_qe,
        p.preview_r,
        cfg.left.x,
        cfg.left.y,
        cfg.left.yaw,
        cfg.right.x,
        cfg.right.y,
        cfg.right.yaw,
        r.max_forward,
        r.max_backward,
        r.min_width,
        r.max_width,
        r.max_yaw,
        r.max_feet_distance,
        r.yaw_cost,
        r.max_stride,
        r.max_growth,
        r.sole_gap,
        cfg.adjust.margin,
        cfg.adjust.min_change,
        cfg.adjust.max_shift,
        cfg.adjust.max_deviation,
    ];
    assert_eq!(floats, want);
    for int in [
        format!("single_ticks: {},", p.single_ticks),
        format!("adjust_min_ticks: {},", p.adjust_min_ticks),
        format!("heartbeat_timeout_ms: {},", cfg.heartbeat_timeout_ms),
        format!("max_age: {},", cfg.adjust.max_age),
    ] {
        assert!(src.contains(&int), "{int}");
    }
}

#[test]
fn the_compiled_in_gains_are_the_ones_the_node_computes() {
    use planner_core::node::{Node, NodeConfig};
    let cfg = Robot::hrp2().node_config();
    let computed: Node<16> = Node::new(cfg).unwrap();
    let copied: Node<16, &_> = Node::with_gains(cfg, &walk_robot::GAINS).unwrap();
    assert!(copied.same_state(&computed));
    // Every table entry, bit for bit (the build script computed them on the build machine).
    let config = cfg.params.preview_config();
    let gains = planner_core::shaping::PreviewGains::<f64, { planner_core::gait::PREVIEW }>::new(
        &config,
        planner_core::shaping::Law::FromRest,
    )
    .unwrap();
    assert!(gains == walk_robot::GAINS);
    // Gains made for another robot are refused.
    let mut other = NodeConfig::hrp2();
    other.params.preview_r *= 2.0;
    assert!(Node::<16, &_>::with_gains(other, &walk_robot::GAINS).is_err());
    other = NodeConfig::hrp2();
    other.params.cog_height = 0.8;
    assert!(Node::<16, &_>::with_gains(other, &walk_robot::GAINS).is_err());
}
