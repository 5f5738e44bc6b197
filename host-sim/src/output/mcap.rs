//! The walk as an MCAP file (`walk.mcap` of `host-sim run`), for robotics viewers such as
//! Foxglove.
//!
//! Every message is JSON (message encoding `json`), every channel has a schema (encoding
//! `jsonschema`, the schema's JSON text as its data). Channels:
//!
//! | topic | schema | one message per |
//! | --- | --- | --- |
//! | `/reference` | `host_sim.Reference` | row of `trajectory.csv`: COG (position, velocity), planned ZMP, phase, both feet |
//! | `/multibody/zmp` | `host_sim.MultibodyZmp` | row with a multi-body ZMP: the ZMP of the multi-body model |
//! | `/feet/left`, `/feet/right` | `foxglove.PoseInFrame` | row: the foot's pose in frame `world` (Foxglove's 3D panel draws it) |
//! | `/can` | `host_sim.CanFrame` | line of `can.log`: identifier, data, the log line's time |
//! | `/scene` | `foxglove.SceneUpdate` | row: entity `walk` in frame `world`: the soles (cubes of the sole's length and width and [`SOLE_THICKNESS`], left blue, right red, lifted with the foot), the COG (blue sphere at the COG height), the planned ZMP (red sphere on the floor), the multi-body ZMP (green) |
//!
//! **Times.** A message's log time (and publish time) is in nanoseconds since the Unix epoch,
//! on the clock of `can.log` ([`crate::sim::bus::LOG_EPOCH_S`] is simulated time 0): a trajectory
//! row at CSV time `t` is logged at `LOG_EPOCH_S + t`, a CAN frame at its `can.log` time
//! (microseconds, as in the log). The messages are written in non-decreasing log time over
//! all channels (ties: trajectory row first, then the frames in log order). The `t` field of
//! the trajectory messages is the CSV time in seconds; `timestamp` of the pose messages is the
//! log time.
//!
//! Chunks are compressed with zstd; the summary (statistics, chunk and message indexes) is
//! written, so a viewer can seek.

use std::collections::BTreeMap;
use std::error::Error;
use std::fs;
use std::io::BufWriter;
use std::path::Path;

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions};
use planner_core::gait::{FootPose, Phase, Reference, Side};
use serde_json::{json, Value};

use crate::eval::multibody::MbSample;
use crate::sim::bus::LOG_EPOCH_S;

/// The topics of the file, in the order of their channel ids.
pub const TOPICS: [&str; 6] = [
    "/reference",
    "/multibody/zmp",
    "/feet/left",
    "/feet/right",
    "/can",
    "/scene",
];

/// The frame id of the pose and scene messages.
pub const WORLD_FRAME: &str = "world";

/// The thickness of the sole cubes of `/scene` \[m\].
pub const SOLE_THICKNESS: f64 = 0.01;
/// Diameter of the COG sphere of `/scene` \[m\].
pub const COG_DIAMETER: f64 = 0.06;
/// Diameter of the ZMP spheres of `/scene` \[m\].
pub const ZMP_DIAMETER: f64 = 0.03;

/// What goes into the file.
#[derive(Clone, Copy, Debug)]
pub struct McapInput<'a> {
    /// One reference per row of `trajectory.csv` (row `j` at `j · dt`).
    pub trajectory: &'a [Reference<f64>],
    /// The tick \[s\].
    pub dt: f64,
    /// The multi-body evaluation of the trajectory (sample `j` belongs to row `j`).
    pub mb: &'a [MbSample],
    /// The lines of `can.log` (`candump -l` format, see [`crate::sim::bus`]).
    pub can_log: &'a [String],
    /// The COG height of the pendulum, where `/scene` draws the COG \[m\].
    pub cog_height: f64,
    /// The sole: length and width \[m\] (the cubes of `/scene`).
    pub sole: [f64; 2],
}

/// A frame of `can.log`: time \[µs since the Unix epoch\], identifier, data.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogFrame {
    /// Microseconds since the Unix epoch.
    pub unix_us: u64,
    /// The 11-bit identifier.
    pub id: u16,
    /// The data bytes (0 … 8).
    pub data: Vec<u8>,
}

/// Parses one `candump -l` line `(SSSSSSSSSS.UUUUUU) IFACE ID#DATA` (standard identifiers,
/// classic frames; [`crate::sim::bus::parse_candump_line`]); the error quotes the line.
pub fn parse_log_line(line: &str) -> Result<LogFrame, String> {
    let e = crate::sim::bus::parse_candump_line(line).ok_or_else(|| {
        format!("can.log line {line:?}: not a candump -l line with a standard identifier")
    })?;
    // MCAP times are nanoseconds.
    if e.unix_us.checked_mul(1000).is_none() {
        return Err(format!("can.log line {line:?}: time out of range"));
    }
    Ok(LogFrame {
        unix_us: e.unix_us,
        id: e.frame.id,
        data: e.frame.bytes().to_vec(),
    })
}

fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Standing => "standing",
        Phase::Double => "double",
        Phase::Single(Side::Left) => "single_left",
        Phase::Single(Side::Right) => "single_right",
    }
}

fn number(description: &str) -> Value {
    json!({ "type": "number", "description": description })
}

fn object(title: &str, description: &str, properties: Value) -> Value {
    let required: Vec<String> = properties
        .as_object()
        .map(|p| p.keys().cloned().collect())
        .unwrap_or_default();
    json!({
        "title": title,
        "description": description,
        "type": "object",
        "properties": properties,
        "required": required,
    })
}

fn foot_schema(which: &str) -> Value {
    object(
        which,
        &format!("The {which} foot (sole centre on the ground; z: sole height)"),
        json!({
            "x": number("[m]"),
            "y": number("[m]"),
            "z": number("[m]"),
            "yaw": number("heading [rad]"),
        }),
    )
}

fn reference_schema() -> Value {
    object(
        "host_sim.Reference",
        "The planner's reference of one control cycle (a row of trajectory.csv)",
        json!({
            "t": number("simulated time, the t column of trajectory.csv [s]"),
            "phase": {
                "type": "string",
                "enum": ["standing", "double", "single_left", "single_right"],
                "description": "support phase",
            },
            "cog": object("cog", "centre of gravity", json!({
                "x": number("[m]"),
                "y": number("[m]"),
                "vx": number("[m/s]"),
                "vy": number("[m/s]"),
            })),
            "zmp": object("zmp", "planned ZMP", json!({
                "x": number("[m]"),
                "y": number("[m]"),
            })),
            "left": foot_schema("left"),
            "right": foot_schema("right"),
        }),
    )
}

fn multibody_schema() -> Value {
    object(
        "host_sim.MultibodyZmp",
        "The ZMP of the multi-body HRP-2 model following the reference",
        json!({
            "t": number("simulated time [s]"),
            "x": number("[m]"),
            "y": number("[m]"),
        }),
    )
}

fn pose_schema() -> Value {
    let xyz = |w: bool| {
        let mut p = json!({ "x": number(""), "y": number(""), "z": number("") });
        if w {
            p["w"] = number("");
        }
        p
    };
    object(
        "foxglove.PoseInFrame",
        "A timestamped pose in a named frame (Foxglove's well-known schema)",
        json!({
            "timestamp": object("timestamp", "log time", json!({
                "sec": { "type": "integer", "minimum": 0 },
                "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 },
            })),
            "frame_id": { "type": "string" },
            "pose": object("pose", "position [m] and orientation (unit quaternion)", json!({
                "position": object("position", "[m]", xyz(false)),
                "orientation": object("orientation", "quaternion", xyz(true)),
            })),
        }),
    )
}

fn can_schema() -> Value {
    object(
        "host_sim.CanFrame",
        "A CAN frame as delivered on the virtual bus (a line of can.log), decoded by name with \
         host-sim/can/walking.dbc",
        json!({
            "id": { "type": "integer", "minimum": 0, "maximum": 2047,
                    "description": "standard identifier" },
            "name": { "type": "string",
                      "description": "the DBC's message name (empty for an identifier it does not name)" },
            "signals": { "type": "object", "additionalProperties": { "type": "number" },
                         "description": "every signal of the message in physical units, by name" },
            "id_hex": { "type": "string", "description": "identifier as in can.log" },
            "dlc": { "type": "integer", "minimum": 0, "maximum": 8 },
            "data": { "type": "array", "items": { "type": "integer", "minimum": 0, "maximum": 255 },
                      "description": "data bytes" },
            "t": number("simulated time (log time minus the log epoch) [s]"),
        }),
    )
}

fn scene_schema() -> Value {
    let xyz = |w: bool| {
        let mut p = json!({ "x": number(""), "y": number(""), "z": number("") });
        if w {
            p["w"] = number("");
        }
        p
    };
    let pose = object(
        "pose",
        "position [m] and orientation (unit quaternion)",
        json!({
            "position": object("position", "[m]", xyz(false)),
            "orientation": object("orientation", "quaternion", xyz(true)),
        }),
    );
    let color = object(
        "color",
        "RGBA, 0 … 1",
        json!({ "r": number(""), "g": number(""), "b": number(""), "a": number("") }),
    );
    let primitive = |title: &str| {
        object(
            title,
            "a box or an ellipsoid",
            json!({
                "pose": pose.clone(),
                "size": object("size", "extent along its axes [m]", xyz(false)),
                "color": color.clone(),
            }),
        )
    };
    let time = object(
        "time",
        "seconds and nanoseconds",
        json!({
            "sec": { "type": "integer", "minimum": 0 },
            "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 },
        }),
    );
    let empty = json!({ "type": "array", "maxItems": 0 });
    let entity = object(
        "entity",
        "one entity of the scene, replaced by the next message with the same id",
        json!({
            "timestamp": time.clone(),
            "frame_id": { "type": "string" },
            "id": { "type": "string" },
            "lifetime": time,
            "frame_locked": { "type": "boolean" },
            "metadata": empty.clone(),
            "arrows": empty.clone(),
            "cubes": { "type": "array", "items": primitive("cube") },
            "spheres": { "type": "array", "items": primitive("sphere") },
            "cylinders": empty.clone(),
            "lines": empty.clone(),
            "triangles": empty.clone(),
            "texts": empty.clone(),
            "models": empty.clone(),
        }),
    );
    object(
        "foxglove.SceneUpdate",
        "Entities of a 3D scene (Foxglove's well-known schema; the parts this file uses)",
        json!({
            "deletions": empty,
            "entities": { "type": "array", "items": entity },
        }),
    )
}

fn quaternion(yaw: f64) -> Value {
    let (s, c) = (0.5 * yaw).sin_cos();
    json!({ "x": 0.0, "y": 0.0, "z": s, "w": c })
}

/// A cube or a sphere: centre, heading, size \[m\], colour (RGBA, 0 … 1).
fn shape(centre: [f64; 3], yaw: f64, size: [f64; 3], rgba: [f64; 4]) -> Value {
    json!({
        "pose": {
            "position": { "x": centre[0], "y": centre[1], "z": centre[2] },
            "orientation": quaternion(yaw),
        },
        "size": { "x": size[0], "y": size[1], "z": size[2] },
        "color": { "r": rgba[0], "g": rgba[1], "b": rgba[2], "a": rgba[3] },
    })
}

fn scene_json(
    log_ns: u64,
    r: &Reference<f64>,
    mb: Option<&MbSample>,
    cog_height: f64,
    sole: [f64; 2],
) -> Value {
    let size = [sole[0], sole[1], SOLE_THICKNESS];
    let colours = [[0.19, 0.19, 0.56, 0.8], [0.56, 0.19, 0.19, 0.8]];
    let cubes: Vec<Value> = r
        .feet
        .iter()
        .zip(colours)
        .map(|(f, c)| shape([f.x, f.y, f.z + 0.5 * SOLE_THICKNESS], f.yaw, size, c))
        .collect();
    let mut spheres = vec![
        shape(
            [r.x.cog, r.y.cog, cog_height],
            0.0,
            [COG_DIAMETER; 3],
            [0.12, 0.37, 0.75, 1.0],
        ),
        shape(
            [r.x.zmp, r.y.zmp, 0.0],
            0.0,
            [ZMP_DIAMETER; 3],
            [0.84, 0.15, 0.16, 1.0],
        ),
    ];
    if let Some(m) = mb {
        spheres.push(shape(
            [m.mb_zmp_x, m.mb_zmp_y, 0.0],
            0.0,
            [ZMP_DIAMETER; 3],
            [0.17, 0.63, 0.17, 1.0],
        ));
    }
    let time = json!({ "sec": log_ns / 1_000_000_000, "nsec": log_ns % 1_000_000_000 });
    json!({
        "deletions": [],
        "entities": [{
            "timestamp": time,
            "frame_id": WORLD_FRAME,
            "id": "walk",
            "lifetime": { "sec": 0, "nsec": 0 },
            "frame_locked": false,
            "metadata": [],
            "arrows": [],
            "cubes": cubes,
            "spheres": spheres,
            "cylinders": [],
            "lines": [],
            "triangles": [],
            "texts": [],
            "models": [],
        }],
    })
}

fn foot_json(f: &FootPose<f64>) -> Value {
    json!({ "x": f.x, "y": f.y, "z": f.z, "yaw": f.yaw })
}

fn pose_json(log_ns: u64, f: &FootPose<f64>) -> Value {
    json!({
        "timestamp": { "sec": log_ns / 1_000_000_000, "nsec": log_ns % 1_000_000_000 },
        "frame_id": WORLD_FRAME,
        "pose": {
            "position": { "x": f.x, "y": f.y, "z": f.z },
            "orientation": quaternion(f.yaw),
        },
    })
}

/// The log time of CSV time `t` \[ns since the Unix epoch\] (saturating).
pub fn log_time_ns(t: f64) -> u64 {
    (LOG_EPOCH_S * 1_000_000_000).saturating_add((t * 1e9).round().max(0.0) as u64)
}

/// Writes the MCAP file at `path` (see the module documentation); the error names the file.
///
/// Errors: a `dt`, a `cog_height` or a sole size that is not positive and finite, a line of `can.log` that does not parse, a
/// multi-body evaluation longer than the trajectory, or an I/O error.
pub fn write_mcap(path: &Path, input: &McapInput<'_>) -> Result<(), Box<dyn Error>> {
    let named = |e: &dyn std::fmt::Display| format!("cannot write {}: {e}", path.display());
    if !(input.dt > 0.0 && input.dt.is_finite()) {
        return Err(format!(
            "write_mcap: dt must be positive and finite, got {}",
            input.dt
        )
        .into());
    }
    if !(input.cog_height > 0.0 && input.cog_height.is_finite()) {
        return Err(format!(
            "write_mcap: cog_height must be positive and finite, got {}",
            input.cog_height
        )
        .into());
    }
    if !input.sole.iter().all(|v| *v > 0.0 && v.is_finite()) {
        return Err(format!(
            "write_mcap: sole size {:?} is not positive and finite",
            input.sole
        )
        .into());
    }
    if input.mb.len() > input.trajectory.len() {
        return Err(format!(
            "write_mcap: {} multi-body samples for {} trajectory rows",
            input.mb.len(),
            input.trajectory.len()
        )
        .into());
    }
    let frames = input
        .can_log
        .iter()
        .filter(|l| !l.trim().is_empty())
        .map(|l| parse_log_line(l))
        .collect::<Result<Vec<_>, _>>()?;
    let file = fs::File::create(path).map_err(|e| named(&e))?;
    let writer = WriteOptions::new()
        .compression(Some(Compression::Zstd))
        .profile("")
        .library(concat!("host-sim ", env!("CARGO_PKG_VERSION")))
        .create(BufWriter::new(file))
        .map_err(|e| named(&e))?;
    let mut out = Out {
        w: writer,
        channels: [0; 6],
        seq: [0; 6],
    };
    for (i, (topic, schema)) in TOPICS.iter().zip(&schemas()).enumerate() {
        let name = schema["title"].as_str().unwrap_or("unnamed");
        let data = serde_json::to_vec(schema)?;
        let sid = out
            .w
            .add_schema(name, "jsonschema", &data)
            .map_err(|e| named(&e))?;
        out.channels[i] = out
            .w
            .add_channel(sid, topic, "json", &BTreeMap::new())
            .map_err(|e| named(&e))?;
    }
    let mut frames = frames.iter().peekable();
    for (k, r) in input.trajectory.iter().enumerate() {
        let t = k as f64 * input.dt;
        let ns = log_time_ns(t);
        while let Some(f) = frames.next_if(|f| f.unix_us * 1000 < ns) {
            out.put(CAN, f.unix_us * 1000, &frame_json(f))
                .map_err(|e| named(&e))?;
        }
        for (ch, v) in sample_messages(t, r, input.mb.get(k), input.cog_height, input.sole) {
            out.put(ch, ns, &v).map_err(|e| named(&e))?;
        }
    }
    for f in frames {
        out.put(CAN, f.unix_us * 1000, &frame_json(f))
            .map_err(|e| named(&e))?;
    }
    out.w.finish().map_err(|e| named(&e))?;
    Ok(())
}

/// The index of `/reference` in [`TOPICS`].
pub const REFERENCE: usize = 0;
/// The index of `/multibody/zmp`.
pub const MULTIBODY: usize = 1;
/// The index of `/feet/left`.
pub const LEFT: usize = 2;
/// The index of `/feet/right`.
pub const RIGHT: usize = 3;
/// The index of `/can`.
pub const CAN: usize = 4;
/// The index of `/scene`.
pub const SCENE: usize = 5;

/// The schema of each of [`TOPICS`] (JSON Schema; its `title` is the schema's name).
pub fn schemas() -> [Value; 6] {
    [
        reference_schema(),
        multibody_schema(),
        pose_schema(),
        pose_schema(),
        can_schema(),
        scene_schema(),
    ]
}

/// The messages of one trajectory row at time `t` \[s\] (log time [`log_time_ns`]`(t)`):
/// `/reference`, `/multibody/zmp` (with `mb`), both feet and `/scene`, by channel index.
pub fn sample_messages(
    t: f64,
    r: &Reference<f64>,
    mb: Option<&MbSample>,
    cog_height: f64,
    sole: [f64; 2],
) -> Vec<(usize, Value)> {
    let ns = log_time_ns(t);
    let mut out = vec![(
        REFERENCE,
        json!({
            "t": t,
            "phase": phase_name(r.phase),
            "cog": { "x": r.x.cog, "y": r.y.cog, "vx": r.x.cog_vel, "vy": r.y.cog_vel },
            "zmp": { "x": r.x.zmp, "y": r.y.zmp },
            "left": foot_json(&r.feet[0]),
            "right": foot_json(&r.feet[1]),
        }),
    )];
    if let Some(m) = mb {
        out.push((
            MULTIBODY,
            json!({ "t": t, "x": m.mb_zmp_x, "y": m.mb_zmp_y }),
        ));
    }
    for (ch, foot) in [(LEFT, &r.feet[0]), (RIGHT, &r.feet[1])] {
        out.push((ch, pose_json(ns, foot)));
    }
    out.push((SCENE, scene_json(ns, r, mb, cog_height, sole)));
    out
}

/// The writer and its channels.
struct Out<W: std::io::Write + std::io::Seek> {
    w: mcap::Writer<W>,
    channels: [u16; 6],
    seq: [u32; 6],
}

impl<W: std::io::Write + std::io::Seek> Out<W> {
    fn put(&mut self, ch: usize, log_ns: u64, v: &Value) -> Result<(), Box<dyn Error>> {
        let data = serde_json::to_vec(v)?;
        let header = MessageHeader {
            channel_id: self.channels[ch],
            sequence: self.seq[ch],
            log_time: log_ns,
            publish_time: log_ns,
        };
        self.seq[ch] = self.seq[ch].wrapping_add(1);
        self.w.write_to_known_channel(&header, &data)?;
        Ok(())
    }
}

pub(crate) fn frame_json(f: &LogFrame) -> Value {
    let ns = f.unix_us * 1000;
    let (name, signals) = super::dbc::decode(f.id, &f.data).unwrap_or_default();
    json!({
        "id": f.id,
        "name": name,
        "signals": signals,
        "id_hex": format!("{:03X}", f.id),
        "dlc": f.data.len(),
        "data": f.data,
        "t": ns.saturating_sub(LOG_EPOCH_S * 1_000_000_000) as f64 * 1e-9,
    })
}
