//! The standing height an import chooses within the legs' torque limits and joint ranges
//! (`host_sim::robot::import::posture`), on a small biped written here: HRP-2's knee bend
//! where the knees are strong enough, a straighter stance where they are not, a refusal naming
//! the knee where no height passes. No engine: the static check alone.

use host_sim::robot::import::posture::{single_support, TORQUE_SHARE};
use host_sim::robot::import::{import, Imported, KNEE_DROP};
use planner_core::gait::Side;

/// A 40 kg biped (legs 0.25 + 0.25 m, box feet 0.05 m high) whose knees' effort limit is
/// `knee` N m (the other joints 200).
fn biped(knee: f64) -> String {
    let link = |name: &str, mass: f64, foot: bool| {
        let collision = if foot {
            "<collision><origin xyz=\"0.03 0 -0.05\"/><geometry><box size=\"0.2 0.1 0.05\"/>\
             </geometry></collision>"
        } else {
            ""
        };
        format!(
            "<link name=\"{name}\"><inertial><origin xyz=\"0 0 -0.05\"/><mass value=\"{mass}\"/>\
             <inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.005\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/>\
             </inertial>{collision}</link>\n"
        )
    };
    let mut s = String::from("<robot name=\"biped\">\n");
    s += &link("pelvis", 24.0, false);
    let axes = ["0 0 1", "1 0 0", "0 1 0", "0 1 0", "0 1 0", "1 0 0"];
    let z = ["0", "0", "0", "-0.25", "-0.25", "0"];
    for (side, y) in [("l", 0.08), ("r", -0.08)] {
        let mut parent = "pelvis".to_string();
        for i in 0..6 {
            let child = format!("{side}_link{i}");
            s += &link(&child, if i == 0 { 0.5 } else { 1.5 }, i == 5);
            let at = if i == 0 { y } else { 0.0 };
            let effort = if i == 3 { knee } else { 200.0 };
            s += &format!(
                "<joint name=\"{side}_j{i}\" type=\"revolute\"><parent link=\"{parent}\"/>\
                 <child link=\"{child}\"/><origin xyz=\"0 {at} {}\"/><axis xyz=\"{}\"/>\
                 <limit lower=\"-2\" upper=\"2\" effort=\"{effort}\" velocity=\"5\"/></joint>\n",
                if i == 0 { "-0.05" } else { z[i] },
                axes[i]
            );
            parent = child;
        }
    }
    s + "</robot>\n"
}

fn import_biped(name: &str, knee: f64) -> Result<Imported, String> {
    let dir = std::env::temp_dir().join(format!("host-sim-height-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary directory");
    let path = dir.join("robot.urdf");
    std::fs::write(&path, biped(knee)).expect("written");
    let r = import(&path, None).map_err(|e| e.to_string());
    let _ = std::fs::remove_dir_all(&dir);
    r
}

/// The knee's static single-support torque of an imported robot \[N m\].
fn knee_torque(i: &Imported) -> f64 {
    let m = &i.robot.model;
    let (_, tau) =
        single_support(m, i.robot.planner.params.step_width, Side::Left).expect("single support");
    tau[3]
}

#[test]
fn the_standing_height_keeps_the_knees_within_their_torque_limits() {
    // Strong knees: HRP-2's bend (the waist 8.8 % of the 0.5 m leg below straight: 0.575 m
    // from the hip joints to the soles, minus 0.044 m).
    let strong = import_biped("strong", 200.0).expect("imports");
    let h0 = strong.robot.model.waist_height;
    assert!(
        (h0 - (0.05 + 0.5 + 0.075 - KNEE_DROP * 0.5)).abs() < 1e-4,
        "{h0}"
    );
    let tau0 = knee_torque(&strong);
    assert!(tau0 > 1.0, "{tau0}");
    // Knees a little too weak for that bend: a straighter stance whose knee torque fits.
    let effort = 0.9 * tau0 / TORQUE_SHARE;
    let weak = import_biped("weak", effort).expect("imports");
    let h1 = weak.robot.model.waist_height;
    let tau1 = knee_torque(&weak);
    assert!(h1 > h0 + 1e-3, "{h1} vs {h0}");
    assert!(tau1 <= TORQUE_SHARE * effort, "{tau1} N m, limit {effort}");
    assert!(weak.toml.contains(&format!("waist_height = {h1}")));
    // Knees too weak for any height tried: refused, the knee and its limit named.
    let Err(e) = import_biped("feeble", 0.05 * tau0) else {
        panic!("imported with knees of {} N m", 0.05 * tau0)
    };
    assert!(
        e.contains("_j3\">: single support needs") && e.contains("effort limit"),
        "{e}"
    );
}
