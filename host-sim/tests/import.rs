//! `host-sim robot import`: robot files from URDFs. Talos and Unitree G1 from PyPI's
//! `example-robot-data` (used where pip installed them), their multi-body COM and ZMP against
//! Pinocchio, every built-in scenario walked in MuJoCo; and the refusals, each naming the URDF
//! element, on small descriptions written here.

mod engine;
mod urdf;

use std::path::{Path, PathBuf};
use std::process::Command;

use doc_figures::Quotes;
use engine::engine_here;
use host_sim::eval::multibody::evaluate;
use host_sim::robot::import::import;
use host_sim::robot::Robot;
use host_sim::scenario::BUILT_IN;
use host_sim::sim::scenario_trajectory;
use urdf::{pinocchio_here, pinocchio_script, robot_file, temp_dir, G1, TALOS};

/// The command that measures the figures the book and the front page quote from here.
const COMMAND: &str = "cargo test --release -p host-sim --test import -- --nocapture";
/// The book's page.
const BOOK: &str = "docs/src/robot.md";

/// `f(v)`, and `f` of `v` moved by `±d`: a value on a rounding boundary may round either way
/// on another CPU.
fn spellings(f: &dyn Fn(f64) -> String, v: f64, d: f64) -> Vec<String> {
    let mut out: Vec<String> = [v, v - d, v + d].iter().map(|&x| f(x)).collect();
    out.dedup();
    out
}

/// The sum of every `<mass value="…">` of a URDF, read from its text (not through the
/// importer's parser).
fn urdf_mass(path: &Path) -> f64 {
    let text = std::fs::read_to_string(path).expect("URDF");
    text.split("<mass")
        .skip(1)
        .map(|m| {
            let v = m.split("value=\"").nth(1).expect("value");
            v[..v.find('"').expect("quote")]
                .parse::<f64>()
                .expect("mass")
        })
        .sum()
}

#[test]
fn talos_imports_with_its_masses_limits_and_soles() {
    let Some(urdf) = robot_file(TALOS, "talos_imports_with_its_masses_limits_and_soles") else {
        return;
    };
    let imported = import(&urdf, None).expect("Talos imports");
    let r = &imported.robot;
    let m = &r.model;
    // Every link's mass, nothing dropped or counted twice.
    assert!(
        (m.total_mass() - urdf_mass(&urdf)).abs() < 1e-9,
        "{}",
        m.total_mass()
    );
    // The legs: the URDF's joints, hip to ankle, with their limits.
    for (leg, side) in m.legs.iter().zip(["left", "right"]) {
        let names: Vec<&str> = leg.links.iter().map(|l| l.joint.name.as_str()).collect();
        let want: Vec<String> = (1..=6).map(|i| format!("leg_{side}_{i}_joint")).collect();
        assert_eq!(names, want);
        let knee = &leg.links[3].joint;
        assert_eq!(knee.range, Some([0.0, 2.618]));
        assert_eq!(knee.effort, Some(300.0));
        assert_eq!(knee.velocity, Some(7.0));
        // The sole: the URDF's sole frame, 0.107 m below the ankle.
        assert_eq!(leg.sole.p, [0.0, 0.0, -0.107]);
    }
    // The written file is the robot: read back, the same model.
    let back = Robot::from_toml(&imported.toml).expect("the written file reads");
    assert_eq!(&back, r);
    // The pendulum height is the stance COG (to the rounding to 1 mm).
    let z = m
        .stance_cog_height(r.planner.params.step_width)
        .expect("stance");
    assert!((z - r.planner.params.cog_height).abs() <= 0.0005, "{z}");
    assert!(m.closed_form.is_none());
}

/// One imported robot's walk through the node and its multi-body model, against Pinocchio
/// on the full URDF: COM to 1e-9 m, ZMP to 0.1 mm (the second differences of the model and
/// the manifold differences of the oracle agree to O(dt²)).
fn against_pinocchio(tail: &str, test: &str) -> Option<f64> {
    let urdf = robot_file(tail, test)?;
    if !pinocchio_here(test) {
        return None;
    }
    let robot = import(&urdf, None).expect("imports").robot;
    let (_, trajectory, dt) = scenario_trajectory("straight", &robot).expect("walk");
    let n = trajectory.len().min(900);
    let mb = evaluate(&robot.model, &trajectory[..n], dt).expect("multi-body model");
    let ticks: Vec<serde_json::Value> = mb
        .iter()
        .map(|s| {
            let mut q = serde_json::Map::new();
            for (leg, angles) in robot.model.legs.iter().zip(&s.q) {
                for (l, a) in leg.links.iter().zip(angles) {
                    q.insert(l.joint.name.clone(), (*a).into());
                }
            }
            serde_json::json!({
                "base": [s.waist[0], s.waist[1], s.waist[2], s.waist_yaw],
                "q": q,
            })
        })
        .collect();
    let job = serde_json::json!({
        "urdf": urdf,
        "gravity": robot.model.gravity,
        "dt": dt,
        "ticks": ticks,
    });
    let mut child = Command::new(host_sim::physics::bridge::python())
        .arg(pinocchio_script())
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("python3 runs");
    {
        use std::io::Write;
        let mut stdin = child.stdin.take().expect("stdin");
        stdin
            .write_all(job.to_string().as_bytes())
            .expect("job written");
    }
    let out = child.wait_with_output().expect("oracle ends");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let oracle: Vec<serde_json::Value> = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(oracle.len(), n - 2);
    let (mut com, mut zmp) = (0.0f64, 0.0f64);
    for (k, o) in oracle.iter().enumerate() {
        let s = &mb[k + 1];
        let v = |key: &str, i: usize| o[key][i].as_f64().expect("number");
        for i in 0..3 {
            com = com.max((s.mb_cog[i] - v("com", i)).abs());
        }
        zmp = zmp.max((s.mb_zmp_x - v("zmp", 0)).abs());
        zmp = zmp.max((s.mb_zmp_y - v("zmp", 1)).abs());
    }
    println!(
        "{test}: {} ticks, COM within {com:.2e} m, ZMP within {zmp:.2e} m",
        n - 2
    );
    assert!(com < 1e-9, "COM differs by {com:.3e} m");
    assert!(zmp < 1e-4, "ZMP differs by {zmp:.3e} m");
    Some(zmp)
}

#[test]
fn multibody_zmp_matches_pinocchio() {
    let test = "multibody_zmp_matches_pinocchio";
    let (Some(talos), Some(g1)) = (against_pinocchio(TALOS, test), against_pinocchio(G1, test))
    else {
        return;
    };
    let um = |x: f64| format!("{:.1} µm", x * 1e6);
    Quotes::new(COMMAND)
        .cell_any(
            BOOK,
            "| Talos |",
            "ZMP against Pinocchio",
            &spellings(&um, talos, 2e-9),
        )
        .cell_any(
            BOOK,
            "| Unitree G1 |",
            "ZMP against Pinocchio",
            &spellings(&um, g1, 2e-9),
        )
        .cell_any(
            "README.md",
            "robots imported from their URDFs",
            "figure",
            &spellings(
                &|x| format!("multi-body ZMP within {}", um(x)),
                talos.max(g1),
                2e-9,
            ),
        )
        .assert();
}

/// `host-sim robot import URDF --out FILE`, then every built-in scenario in MuJoCo with
/// `--robot FILE`: no fall (two engine runs at a time).
fn walks_every_built_in(tail: &str, name: &str) {
    let test = format!("{name}_walks_every_built_in_scenario");
    let Some(urdf) = robot_file(tail, &test) else {
        return;
    };
    if !engine_here(&test) {
        return;
    }
    let dir = temp_dir(name);
    let file = dir.join(format!("{name}.toml"));
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["robot", "import"])
        .arg(&urdf)
        .arg("--out")
        .arg(&file)
        .output()
        .expect("host-sim runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let run = |scenario: &str| -> serde_json::Value {
        let d: PathBuf = dir.join(scenario);
        let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(["physics", scenario, "--robot"])
            .arg(&file)
            .arg("--out")
            .arg(&d)
            .output()
            .expect("host-sim runs");
        assert!(
            out.status.success(),
            "{scenario}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&std::fs::read(d.join("physics.json")).expect("physics.json"))
            .expect("JSON")
    };
    let results: Vec<(&str, serde_json::Value)> = std::thread::scope(|s| {
        let halves: Vec<_> = BUILT_IN
            .chunks(BUILT_IN.len().div_ceil(2))
            .map(|chunk| s.spawn(move || chunk.iter().map(|n| (*n, run(n))).collect::<Vec<_>>()))
            .collect();
        halves
            .into_iter()
            .flat_map(|h| h.join().expect("worker"))
            .collect()
    });
    assert_eq!(results.len(), BUILT_IN.len());
    let mut q = Quotes::new(COMMAND);
    for (scenario, j) in &results {
        assert_eq!(j["fell"], false, "{name} {scenario}: {j}");
        assert!(j["simulated_s"].as_f64().expect("s") > 5.0, "{j}");
        let num = |k: &str| j[k].as_f64().unwrap_or(f64::NAN);
        let row = format!("| {name} | {scenario} |");
        let around = |v: f64| [v, v - 2e-6, v + 2e-6];
        let mut pairs = Vec::new();
        for a in around(num("cop_err_mean_m")) {
            for b in around(num("cop_err_max_m")) {
                let p = format!("{:.1} / {:.1} mm", a * 1e3, b * 1e3);
                if !pairs.contains(&p) {
                    pairs.push(p);
                }
            }
        }
        q = q
            .cell_any(
                BOOK,
                &row,
                "max tilt",
                &spellings(&|x| format!("{x:.2}°"), num("max_tilt_deg"), 2e-4),
            )
            .cell_any(BOOK, &row, "CoP error mean / worst", &pairs);
        println!(
            "{name} {scenario}: tilt {:.2}°, CoP error mean {:.1} mm, worst {:.1} mm",
            j["max_tilt_deg"].as_f64().unwrap_or(f64::NAN),
            1e3 * j["cop_err_mean_m"].as_f64().unwrap_or(f64::NAN),
            1e3 * j["cop_err_max_m"].as_f64().unwrap_or(f64::NAN)
        );
    }
    q.assert();
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn talos_walks_every_built_in_scenario() {
    walks_every_built_in(TALOS, "talos");
}

#[test]
fn g1_walks_every_built_in_scenario() {
    walks_every_built_in(G1, "g1");
}

// --- small descriptions written here -------------------------------------------------------

/// A link with a box inertial (and a box collision if `collide`).
fn link(name: &str, mass: f64, collide: Option<&str>) -> String {
    let inertial = if mass > 0.0 {
        format!(
            "<inertial><origin xyz=\"0 0 -0.05\"/><mass value=\"{mass}\"/>\
             <inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.005\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial>"
        )
    } else {
        String::new()
    };
    let collision = collide
        .map(|g| {
            format!("<collision><origin xyz=\"0.03 0 -0.05\"/><geometry>{g}</geometry></collision>")
        })
        .unwrap_or_default();
    format!("<link name=\"{name}\">{inertial}{collision}</link>\n")
}

fn joint(name: &str, kind: &str, parent: &str, child: &str, xyz: &str, axis: &str) -> String {
    format!(
        "<joint name=\"{name}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
         <origin xyz=\"{xyz}\"/><axis xyz=\"{axis}\"/>\
         <limit lower=\"-2\" upper=\"2\" effort=\"200\" velocity=\"5\"/></joint>\n"
    )
}

/// A 40 kg biped: hips yaw, roll, pitch, knee, ankle pitch, roll; legs 0.25 + 0.25 m; feet
/// 0.2 × 0.1 m boxes, 3 cm ahead of the ankle. `edit` changes its text.
fn biped(edit: impl Fn(String) -> String) -> String {
    let mut s = String::from("<robot name=\"biped\">\n");
    s += &link("pelvis", 10.0, None);
    s += &link("torso", 14.0, None);
    s += &joint("waist", "fixed", "pelvis", "torso", "0 0 0.1", "1 0 0");
    let axes = ["0 0 1", "1 0 0", "0 1 0", "0 1 0", "0 1 0", "1 0 0"];
    let offsets = [
        "0 Y -0.05",
        "0 0 0",
        "0 0 0",
        "0 0 -0.25",
        "0 0 -0.25",
        "0 0 0",
    ];
    for (side, y) in [("l", "0.08"), ("r", "-0.08")] {
        let mut parent = "pelvis".to_string();
        for i in 0..6 {
            let child = format!("{side}_link{i}");
            let foot = (i == 5).then_some("<box size=\"0.2 0.1 0.05\"/>");
            s += &link(&child, if i == 0 { 0.5 } else { 1.5 }, foot);
            s += &joint(
                &format!("{side}_j{i}"),
                "revolute",
                &parent,
                &child,
                &offsets[i].replace('Y', y),
                axes[i],
            );
            parent = child;
        }
    }
    s += "</robot>\n";
    edit(s)
}

fn import_text(name: &str, text: &str) -> Result<host_sim::robot::import::Imported, String> {
    import_with(name, text, &[], None)
}

/// Imports `text` as `robot.urdf` with `files` (name, text) beside it, and `--sole soles`.
fn import_with(
    name: &str,
    text: &str,
    files: &[(&str, &str)],
    soles: Option<[&str; 2]>,
) -> Result<host_sim::robot::import::Imported, String> {
    let dir = temp_dir(name);
    let path = dir.join("robot.urdf");
    std::fs::write(&path, text).expect("written");
    for (f, t) in files {
        std::fs::write(dir.join(f), t).expect("written");
    }
    let r = import(&path, soles).map_err(|e| e.to_string());
    let _ = std::fs::remove_dir_all(&dir);
    r
}

/// The collision box of [`biped`]'s feet, as written there.
const FOOT_BOX: &str = "<collision><origin xyz=\"0.03 0 -0.05\"/><geometry><box size=\"0.2 0.1 0.05\"/></geometry></collision>";

/// The foot mesh written here (`tests/urdf/foot_cm.dae`): the biped's foot box in centimetres,
/// placed by its scene's node transforms.
fn foot_cm() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/urdf/foot_cm.dae"))
        .expect("the fixture")
}

/// Sole length, width and the two sole centres in the ankle frames.
fn soles_of(r: &Robot) -> ([f64; 2], [[f64; 3]; 2]) {
    let p = &r.planner.params;
    (
        [2.0 * p.sole_half_length, 2.0 * p.sole_half_width],
        [r.model.legs[0].sole.p, r.model.legs[1].sole.p],
    )
}

fn near(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn collada_node_transforms_and_mesh_scale_place_the_sole() {
    let boxed = import_text("box-feet", &biped(|s| s))
        .expect("imports")
        .robot;
    let (size, centres) = soles_of(&boxed);
    // The same feet as a COLLADA mesh in centimetres, under a node <matrix> (cm to m, 3 cm
    // forward, 5 cm down), an instanced library node and a <rotate>: the same soles.
    let mesh = |attrs: &str| {
        biped(move |s| {
            s.replace(
                FOOT_BOX,
                &format!("<collision><geometry><mesh filename=\"foot_cm.dae\"{attrs}/></geometry></collision>"),
            )
        })
    };
    let dae = foot_cm();
    let r = import_with("dae-feet", &mesh(""), &[("foot_cm.dae", &dae)], None)
        .expect("imports")
        .robot;
    let (s, c) = soles_of(&r);
    assert!(near(&s, &size, 1e-9), "{s:?} against {size:?}");
    for k in 0..2 {
        assert!(near(&c[k], &centres[k], 1e-9), "{c:?} against {centres:?}");
    }
    // The URDF's mesh scale on top: 1.5 along x makes the sole 0.3 m long, centred 4.5 cm ahead.
    let r = import_with(
        "dae-scaled",
        &mesh(" scale=\"1.5 1 1\""),
        &[("foot_cm.dae", &dae)],
        None,
    )
    .expect("imports")
    .robot;
    let (s, c) = soles_of(&r);
    assert!(near(&s, &[0.3, 0.1], 1e-9), "{s:?}");
    assert!(near(&c[0], &[0.045, 0.0, -0.075], 1e-9), "{c:?}");
    // Without the node's matrix the mesh is read in centimetres as metres: refused, naming
    // the mesh, its link and its placement.
    let unscaled = dae.replace(
        "0.01 0 0 0.03 0 0.01 0 0 0 0 0.01 -0.05 0 0 0 1",
        "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1",
    );
    assert_ne!(unscaled, dae);
    for soles in [None, Some(["l_link5", "r_link5"])] {
        let e = import_with("dae-cm", &mesh(""), &[("foot_cm.dae", &unscaled)], soles)
            .err()
            .expect("refused");
        assert!(
            e.contains("<mesh filename=\"foot_cm.dae\">")
                && e.contains("<link name=\"l_link5\">")
                && e.contains("placed at")
                && e.contains("COLLADA node transforms"),
            "{soles:?}: {e}"
        );
    }
}

#[test]
fn a_massless_frame_is_never_the_sole_without_the_geometry_below_it() {
    // A massless sensor frame at each ankle joint, the lowest leaf link of each leg.
    let frames = |s: String| {
        let mut out = s.replace("</robot>", "");
        for side in ["l", "r"] {
            out += &format!(
                "<link name=\"{side}_ft_frame\"/><joint name=\"{side}_ft\" type=\"fixed\">\
                 <parent link=\"{side}_link5\"/><child link=\"{side}_ft_frame\"/>\
                 <origin xyz=\"0 0 0\"/></joint>\n"
            );
        }
        out + "</robot>\n"
    };
    let want = [0.03, 0.0, -0.075];
    let r = import_text("ft-frame", &biped(frames)).expect("imports");
    let (size, c) = soles_of(&r.robot);
    assert!(near(&size, &[0.2, 0.1], 1e-9), "{size:?}");
    assert!(
        near(&c[0], &want, 1e-12) && near(&c[1], &want, 1e-12),
        "{c:?}"
    );
    assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    // Named as the soles: the soles stay on the geometry, and the import says why.
    let r = import_with(
        "ft-frame-named",
        &biped(frames),
        &[],
        Some(["l_ft_frame", "r_ft_frame"]),
    )
    .expect("imports");
    let (_, c) = soles_of(&r.robot);
    assert!(near(&c[0], &want, 1e-12), "{c:?}");
    assert_eq!(r.warnings.len(), 2, "{:?}", r.warnings);
    assert!(
        r.warnings[0].contains("<link name=\"l_ft_frame\"> (at (0.0000, 0.0000, 0.0000)")
            && r.warnings[0].contains("lies 0.0750 m above the foot's lowest point"),
        "{}",
        r.warnings[0]
    );
    // A sole frame on the geometry's sole plane is the sole centre (here 2 cm behind the
    // middle: the sole is the largest rectangle centred on it).
    let soles = |s: String| {
        frames(s).replace("_ft_frame", "_sole").replace(
            "<origin xyz=\"0 0 0\"/></joint>",
            "<origin xyz=\"0.01 0 -0.075\"/></joint>",
        )
    };
    let r = import_text("sole-frame", &biped(soles)).expect("imports");
    let (size, c) = soles_of(&r.robot);
    assert!(near(&c[0], &[0.01, 0.0, -0.075], 1e-12), "{c:?}");
    assert!(near(&size, &[0.16, 0.1], 1e-9), "{size:?}");
    assert!(r
        .toml
        .contains("# from: <link name=\"l_sole\">; <link name=\"r_sole\">"));
}

#[test]
fn a_small_biped_imports_with_its_box_soles() {
    let r = import_text("biped", &biped(|s| s)).expect("imports").robot;
    let p = &r.planner.params;
    assert!((r.model.total_mass() - 40.0).abs() < 1e-9);
    // The feet's boxes: 0.2 × 0.1 m, their bottom 0.075 m below the ankle, centred 3 cm ahead.
    assert!((2.0 * p.sole_half_length - 0.2).abs() < 1e-9, "{p:?}");
    assert!((2.0 * p.sole_half_width - 0.1).abs() < 1e-9, "{p:?}");
    for leg in &r.model.legs {
        let s = leg.sole.p;
        assert!((s[0] - 0.03).abs() < 1e-12 && s[1].abs() < 1e-12 && (s[2] + 0.075).abs() < 1e-12);
    }
    assert!((p.step_width - 0.16).abs() < 1e-12);
}

#[test]
fn refusals_name_the_urdf_element() {
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "two roots",
            biped(|s| s.replace("</robot>", "<link name=\"loose\"/></robot>")),
            "no floating-base candidate: 2 root links",
        ),
        (
            "five joints",
            biped(|s| {
                s.replace(
                    "type=\"revolute\"><parent link=\"l_link1\"",
                    "type=\"fixed\"><parent link=\"l_link1\"",
                )
            }),
            "has 5 revolute joints",
        ),
        (
            "prismatic knee",
            biped(|s| s.replace("\"l_j3\" type=\"revolute\"", "\"l_j3\" type=\"prismatic\"")),
            "<joint name=\"l_j3\" type=\"prismatic\">",
        ),
        (
            "massless shank",
            biped(|s| {
                s.replace(
                    "<link name=\"r_link3\"><inertial><origin xyz=\"0 0 -0.05\"/><mass value=\"1.5\"/>",
                    "<link name=\"r_link3\"><inertial><origin xyz=\"0 0 -0.05\"/><mass value=\"0\"/>",
                )
            }),
            "<link name=\"r_link3\"> (moved by <joint name=\"r_j3\">) has no <inertial>",
        ),
        (
            "no feet geometry",
            biped(|s| {
                s.replace(
                    "<geometry><box size=\"0.2 0.1 0.05\"/></geometry>",
                    "<geometry><sphere radius=\"0\"/></geometry>",
                )
            }),
            "its collision geometry gives a sole",
        ),
        (
            "no collision",
            biped(|s| {
                s.replace(
                    "<collision><origin xyz=\"0.03 0 -0.05\"/><geometry><box size=\"0.2 0.1 0.05\"/></geometry></collision>",
                    "",
                )
            }),
            "(<link name=\"l_link5\">) has no <collision> or <visual> geometry",
        ),
        (
            "a mesh sole",
            biped(|s| {
                s.replace(
                    "<box size=\"0.2 0.1 0.05\"/>",
                    "<mesh filename=\"foot.ply\"/>",
                )
            }),
            "<mesh filename=\"foot.ply\">: the soles are read from STL, COLLADA",
        ),
        (
            "a mesh sole and a hand",
            biped(|s| {
                s.replace(
                    "<box size=\"0.2 0.1 0.05\"/>",
                    "<mesh filename=\"foot.ply\"/>",
                )
                .replace(
                    "</robot>",
                    &format!(
                        "{}{}</robot>",
                        link("hand", 1.0, Some("<box size=\"0.1 0.1 0.1\"/>")),
                        joint("wrist", "revolute", "torso", "hand", "0 0.2 0", "1 0 0")
                    ),
                )
            }),
            "<mesh filename=\"foot.ply\">: the soles are read from STL, COLLADA",
        ),
    ];
    for (name, text, want) in cases {
        let e = match import_text(&name.replace(' ', "-"), &text) {
            Ok(_) => panic!("{name}: imported"),
            Err(e) => e,
        };
        assert!(e.contains(want), "{name}: {e}");
    }
    // A file cut short, an element closed out of order, an empty file: the file and the line.
    let text = biped(|s| s);
    let cut = &text[..=text[..text.len() / 2].rfind('\n').expect("lines")];
    let e = import_text("cut-short", cut).err().expect("refused");
    assert!(e.contains("robot.urdf: not a readable URDF"), "{e}");
    let ends = format!("the file ends at line {} inside <", cut.lines().count());
    assert!(e.contains(&ends) && e.contains("opened on line"), "{e}");
    let e = import_text("nesting", &text.replacen("</inertial>", "", 1))
        .err()
        .expect("refused");
    let line = 1 + text[..text.find("</inertial>").expect("inertial")]
        .matches('\n')
        .count();
    assert!(
        e.contains(&format!("line {line}")) || e.contains(&format!("line {}", line + 1)),
        "{e}"
    );
    let e = import_text("empty", "").err().expect("refused");
    assert!(e.contains("no XML element"), "{e}");
    // The command line: exit status 2 and the message.
    let dir = temp_dir("cli");
    let path = dir.join("robot.urdf");
    std::fs::write(
        &path,
        biped(|s| s.replace("</robot>", "<link name=\"loose\"/></robot>")),
    )
    .expect("written");
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(["robot", "import"])
        .arg(&path)
        .arg("--out")
        .arg(dir.join("r.toml"))
        .output()
        .expect("host-sim runs");
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no floating-base candidate"));
    assert!(!dir.join("r.toml").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The push-recovery map of Talos (`WALK_LONG=1`; 576 engine runs, about 9 minutes of a
/// release build on 2 cores), against its summary in the book (`docs/src/adjust.md`).
#[test]
fn talos_push_map_is_the_books() {
    if std::env::var("WALK_LONG").as_deref() != Ok("1") {
        eprintln!("import: Talos's push map runs with WALK_LONG=1");
        return;
    }
    let test = "talos_push_map_is_the_books";
    let Some(urdf) = robot_file(TALOS, test) else {
        return;
    };
    if !engine_here(test) {
        return;
    }
    use host_sim::physics::push_map::{map, MapSpec};
    use host_sim::physics::PhysicsConfig;
    let robot = import(&urdf, None).expect("imports").robot;
    let cfg = PhysicsConfig::for_robot(&robot);
    let spec = MapSpec::new(false);
    let cells = map(&robot.node_config(), &cfg, &spec);
    engine::map_summary_is_the_books(&spec, &cells);
}

/// `key = value` of a robot file's text, its first occurrence.
fn value_of(toml: &str, key: &str) -> f64 {
    toml.lines()
        .find_map(|l| l.strip_prefix(&format!("{key} = ")))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse().ok())
        .expect("a number")
}

/// A robot that falls before its first step (its soles written 0.1 m above its ankles, where
/// its shanks reach the floor): `physics` writes its files and exits non-zero naming the fall;
/// the commands of many runs stop before the first.
#[test]
fn a_run_that_cannot_start_exits_non_zero_naming_why() {
    let test = "a_run_that_cannot_start_exits_non_zero_naming_why";
    if !engine_here(test) {
        return;
    }
    let good = import_text("cannot-start", &biped(|s| s)).expect("imports");
    let sole_z = good.robot.model.legs[0].sole.p[2];
    let up = 0.1 - sole_z;
    let mut text = good.toml.replace(
        &format!("left = [0.03, 0.0, {sole_z}]"),
        "left = [0.03, 0.0, 0.1]",
    );
    text = text.replace(
        &format!("right = [0.03, 0.0, {sole_z}]"),
        "right = [0.03, 0.0, 0.1]",
    );
    for key in ["waist_height", "cog_height"] {
        let v = value_of(&good.toml, key);
        text = text.replacen(
            &format!("{key} = {v}"),
            &format!("{key} = {:.4}", v - up),
            1,
        );
    }
    assert_eq!(text.matches("0.0, 0.1]").count(), 2, "{text}");
    let dir = temp_dir("cannot-start");
    let file = dir.join("robot.toml");
    std::fs::write(&file, &text).expect("written");
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(args)
            .arg("--robot")
            .arg(&file)
            .arg("--out")
            .arg(dir.join(args[0]))
            .output()
            .expect("host-sim runs")
    };
    let out = run(&["physics", "straight"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("biped cannot start the walk: it fell")
            && err.contains("during the engine's settle (non-sole contact), and walked 0 s"),
        "{err}"
    );
    let j: serde_json::Value = serde_json::from_slice(
        &std::fs::read(dir.join("physics/physics.json")).expect("physics.json written"),
    )
    .expect("JSON");
    assert_eq!(j["fell"], true);
    assert!(j["fall_time_s"].as_f64().expect("a time") < 0.0, "{j}");
    let out = run(&["physics-sequence"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("biped cannot start the walk: standing on its soles in MuJoCo"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
