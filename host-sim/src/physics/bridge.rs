//! The bridge to MuJoCo: a Python process that only steps the engine.
//!
//! # Why a bridge and not FFI
//!
//! The engine comes from PyPI's `mujoco` wheel, pinned to [`MUJOCO_VERSION`] (installed by
//! `tests/run-all.sh` with `pip install mujoco==3.2.7`). The wheel ships `libmujoco`, but a
//! Rust FFI would have to declare `mjModel` and `mjData` by hand to read `qpos`,
//! `sensordata` or the contacts: those are large C structs whose layouts change between
//! releases without an ABI promise, and a mismatch is silent memory corruption, not an error.
//! The wheel's Python binding is generated from the very headers of its library, so it is
//! always consistent with it; the price is a pipe round trip per control tick (a 10 s walk,
//! 12,000 ticks, takes about 3 s in a debug build). So `bridge.py` (embedded in the binary, run with `python3
//! -c`) loads the MJCF, sets the servo targets, calls `mj_step` and sends back the sensor
//! data; the stabilizer, the fall detector and the evaluation are all Rust.
//!
//! # Protocol (stdin/stdout, little-endian)
//!
//! The host sends `u32 n` and the MJCF (n bytes); the bridge answers one line, `OK <version>
//! <nq> <nu> <nsensordata>` or `ERR <message>`. Then frames: `I` + nq × f64 (reset to this
//! `qpos`, at rest), `S` + `u32 k` + nu × f64 servo targets + 6 × f64 external wrench on the
//! trunk (world frame; for push tests) and k engine steps, `Q` to quit. `I` and `S` answer an
//! [`Observation`].

use std::io::{BufRead, BufReader, Read, Write};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use super::model::sensor;

/// The MuJoCo release the model and the bridge are written for (PyPI's `mujoco`).
pub const MUJOCO_VERSION: &str = "3.2.7";

/// The bridge script.
const SCRIPT: &str = include_str!("bridge.py");

/// The Python interpreter the bridge runs on: `HOST_SIM_PYTHON`, or `python3`.
pub fn python() -> String {
    std::env::var("HOST_SIM_PYTHON").unwrap_or_else(|_| "python3".into())
}

/// The version of the MuJoCo that `python` imports, or why there is none (the message names
/// what to install).
pub fn installed_version(python: &str) -> Result<String, String> {
    let out = Command::new(python)
        .args(["-c", "import mujoco; print(mujoco.__version__)"])
        .stdin(Stdio::null())
        .output()
        .map_err(|e| {
            format!("cannot run {python} ({e}): install Python 3 and python3 -m pip install mujoco=={MUJOCO_VERSION}")
        })?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).trim().to_string())
    } else {
        Err(format!(
            "{python} cannot import mujoco: install it with python3 -m pip install \
             mujoco=={MUJOCO_VERSION}"
        ))
    }
}

/// What the engine reports after a step.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Observation {
    /// Simulated time \[s\].
    pub time: f64,
    /// The sensors (layout: [`sensor`]); the only input of the stabilizer.
    pub sensors: Vec<f64>,
    /// Ground truth for the evaluation: the waist (base) position \[m\].
    pub base_pos: [f64; 3],
    /// Ground truth: the waist orientation quaternion (w, x, y, z).
    pub base_quat: [f64; 4],
    /// Ground truth: centre of pressure of all floor contacts (x, y) \[m\]; NaN if airborne.
    pub cop: [f64; 2],
    /// Ground truth: total normal floor force \[N\].
    pub normal_force: f64,
    /// Ground truth: a geom other than the two soles touches the floor.
    pub other_contact: bool,
    /// Ground truth: the floor's normal force on the left and the right sole \[N\].
    pub sole_force: [f64; 2],
}

/// A running MuJoCo engine behind the bridge.
pub struct Engine {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    /// The engine's version string.
    pub version: String,
    nq: usize,
    nu: usize,
    nsensor: usize,
}

fn io_err(e: std::io::Error) -> String {
    format!("MuJoCo bridge: {e}")
}

impl Engine {
    /// Starts the bridge (`python3`, or the interpreter named by `HOST_SIM_PYTHON`) with the
    /// MJCF `xml`. Fails with a message naming what to install when Python or MuJoCo is
    /// missing, or the engine's own message when it rejects the model.
    pub fn start(xml: &str) -> Result<Self, String> {
        Self::start_with(&python(), xml)
    }

    /// [`Engine::start`] with the Python interpreter `python`.
    pub fn start_with(python: &str, xml: &str) -> Result<Self, String> {
        let mut child = Command::new(python)
            .arg("-c")
            .arg(SCRIPT)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| {
                format!(
                    "cannot start {python} for the MuJoCo bridge ({e}): install Python 3 and \
                     MuJoCo (python3 -m pip install mujoco=={MUJOCO_VERSION}), or set \
                     HOST_SIM_PYTHON"
                )
            })?;
        let mut stdin = child.stdin.take().ok_or("MuJoCo bridge: no stdin")?;
        let mut stdout = BufReader::new(child.stdout.take().ok_or("MuJoCo bridge: no stdout")?);
        // A bridge that ended at once (no Python, no MuJoCo) closes its pipes: the write or
        // the read fails, and the answer is empty.
        let not_started = |what: String| {
            format!(
                "the MuJoCo bridge did not start ({what}): install MuJoCo with python3 -m pip \
                 install mujoco=={MUJOCO_VERSION}"
            )
        };
        let sent = stdin
            .write_all(&(xml.len() as u32).to_le_bytes())
            .and_then(|_| stdin.write_all(xml.as_bytes()))
            .and_then(|_| stdin.flush());
        let mut line = String::new();
        let read = stdout.read_line(&mut line);
        if let Err(e) = sent.and(read.map(|_| ())) {
            let _ = child.kill();
            let _ = child.wait();
            return Err(not_started(e.to_string()));
        }
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first() {
            Some(&"OK") if words.len() == 5 => {}
            Some(&"ERR") => {
                let _ = child.wait();
                return Err(format!(
                    "MuJoCo: {} (the physics command needs python3 -m pip install \
                     mujoco=={MUJOCO_VERSION})",
                    line.trim_start_matches("ERR").trim()
                ));
            }
            _ => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(not_started(format!("answer {:?}", line.trim())));
            }
        }
        let num = |i: usize| -> Result<usize, String> {
            words[i]
                .parse()
                .map_err(|_| format!("MuJoCo bridge: bad answer {line:?}"))
        };
        let (nq, nu, nsensor) = (num(2)?, num(3)?, num(4)?);
        if nsensor != sensor::LEN {
            return Err(format!(
                "MuJoCo model has {nsensor} sensor values, {} expected",
                sensor::LEN
            ));
        }
        Ok(Self {
            version: words[1].to_string(),
            child,
            stdin,
            stdout,
            nq,
            nu,
            nsensor,
        })
    }

    /// Number of position coordinates (7 of the free joint + the joints).
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// Number of actuators.
    pub fn nu(&self) -> usize {
        self.nu
    }

    fn observe(&mut self) -> Result<Observation, String> {
        let n = 1 + self.nsensor + 13;
        let mut buf = vec![0u8; 8 * n];
        self.stdout.read_exact(&mut buf).map_err(|e| {
            format!("MuJoCo bridge ended: {e} (see the Python error above, if any)")
        })?;
        let v: Vec<f64> = buf
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])))
            .collect();
        let t = &v[1 + self.nsensor..];
        Ok(Observation {
            time: v[0],
            sensors: v[1..1 + self.nsensor].to_vec(),
            base_pos: [t[0], t[1], t[2]],
            base_quat: [t[3], t[4], t[5], t[6]],
            cop: [t[7], t[8]],
            normal_force: t[9],
            other_contact: t[10] != 0.0,
            sole_force: [t[11], t[12]],
        })
    }

    fn send(&mut self, bytes: &[u8]) -> Result<(), String> {
        self.stdin
            .write_all(bytes)
            .and_then(|_| self.stdin.flush())
            .map_err(io_err)
    }

    /// Resets the engine to `qpos` at rest.
    pub fn reset(&mut self, qpos: &[f64]) -> Result<Observation, String> {
        if qpos.len() != self.nq {
            return Err(format!(
                "qpos of {} values, {} expected",
                qpos.len(),
                self.nq
            ));
        }
        let mut b = vec![b'I'];
        for v in qpos {
            b.extend_from_slice(&v.to_le_bytes());
        }
        self.send(&b)?;
        self.observe()
    }

    /// Sets the servo targets and the external wrench on the trunk, steps `k` times.
    pub fn step(&mut self, k: u32, ctrl: &[f64], wrench: [f64; 6]) -> Result<Observation, String> {
        if ctrl.len() != self.nu {
            return Err(format!(
                "{} servo targets, {} expected",
                ctrl.len(),
                self.nu
            ));
        }
        let mut b = vec![b'S'];
        b.extend_from_slice(&k.to_le_bytes());
        for v in ctrl.iter().chain(wrench.iter()) {
            b.extend_from_slice(&v.to_le_bytes());
        }
        self.send(&b)?;
        self.observe()
    }

    /// Sets the floating base's horizontal linear velocity (world frame) \[m/s\], everything
    /// else of the state unchanged: a velocity push.
    pub fn set_base_velocity(&mut self, v: [f64; 2]) -> Result<Observation, String> {
        let mut b = vec![b'V'];
        for x in v {
            b.extend_from_slice(&x.to_le_bytes());
        }
        self.send(&b)?;
        self.observe()
    }
}

impl Drop for Engine {
    fn drop(&mut self) {
        let _ = self.stdin.write_all(b"Q");
        let _ = self.stdin.flush();
        let _ = self.child.wait();
    }
}
