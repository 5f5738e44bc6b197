//! The vertex positions of a COLLADA (`.dae`) document, placed as its scene places them.
//!
//! The scene's nodes are walked from the visual scene the document's `<scene>` instantiates
//! (the first one if it names none): each node's transform elements in document order
//! (`<matrix>`, `<translate>`, `<rotate>`, `<scale>`; a `<lookat>` or `<skew>` is refused),
//! composed down nested `<node>`s and through `<instance_node>` references into
//! `<library_nodes>`; every `<instance_geometry>` adds its mesh's `POSITION` source under the
//! transform of its node. A document without a visual scene gives every geometry's positions
//! unmoved. Then the asset's `<unit meter>` scales the result, and a `Y_UP` (or `X_UP`)
//! document is turned to z up, as the COLLADA specification defines the axes.
//!
//! Instancing multiplies: a node instanced ten times, each instancing another ten times, is a
//! hundred placements, and a few kilobytes can expand beyond any memory. A document is refused
//! when its scene expands to more than [`MAX_NODES`] placed nodes or [`MAX_POSITIONS`] placed
//! vertex positions (a foot mesh has thousands), or nests nodes more than 64 deep.

use std::collections::BTreeMap;

use quick_xml::events::Event;

use crate::robot::model::Vec3;

/// The most nodes a scene may place, counting every instancing \[nodes\].
pub const MAX_NODES: usize = 100_000;
/// The most vertex positions a scene may place, counting every instancing.
pub const MAX_POSITIONS: usize = 5_000_000;

/// An element of the document: its name (without a namespace prefix), attributes, text and
/// children.
#[derive(Debug, Default)]
struct El {
    name: String,
    attrs: Vec<(String, String)>,
    text: String,
    kids: Vec<El>,
}

impl El {
    fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    fn kid(&self, name: &str) -> Option<&El> {
        self.kids.iter().find(|k| k.name == name)
    }

    fn all<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a El> + 'a {
        self.kids.iter().filter(move |k| k.name == name)
    }

    /// Every element named `name` at any depth, in document order.
    fn descendants<'a>(&'a self, name: &str, out: &mut Vec<&'a El>) {
        for k in &self.kids {
            if k.name == name {
                out.push(k);
            }
            k.descendants(name, out);
        }
    }

    fn numbers(&self) -> Result<Vec<f64>, String> {
        self.text
            .split_whitespace()
            .map(|x| {
                x.parse::<f64>()
                    .map_err(|_| format!("<{}>: {x:?} is not a number", self.name))
            })
            .collect()
    }
}

fn local(name: &[u8]) -> String {
    let n = String::from_utf8_lossy(name);
    n.rsplit(':').next().unwrap_or(&n).to_string()
}

fn parse(text: &str) -> Result<El, String> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut stack: Vec<El> = vec![El::default()];
    let open = |e: &quick_xml::events::BytesStart| El {
        name: local(e.name().as_ref()),
        attrs: e
            .attributes()
            .flatten()
            .map(|a| {
                (
                    local(a.key.as_ref()),
                    String::from_utf8_lossy(&a.value).into_owned(),
                )
            })
            .collect(),
        ..El::default()
    };
    loop {
        match reader.read_event() {
            Err(e) => return Err(format!("not well-formed XML: {e}")),
            Ok(Event::Start(e)) => stack.push(open(&e)),
            Ok(Event::Empty(e)) => {
                let el = open(&e);
                if let Some(top) = stack.last_mut() {
                    top.kids.push(el);
                }
            }
            Ok(Event::Text(t)) => {
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&String::from_utf8_lossy(t.as_ref()));
                }
            }
            Ok(Event::End(_)) => {
                let el = stack.pop().ok_or("unbalanced XML")?;
                match stack.last_mut() {
                    Some(top) => top.kids.push(el),
                    None => return Err("unbalanced XML".into()),
                }
            }
            Ok(Event::Eof) => break,
            Ok(_) => {}
        }
    }
    let mut root = stack.pop().ok_or("empty document")?;
    if !stack.is_empty() {
        return Err("the document ends inside an element".into());
    }
    root.kids
        .pop()
        .filter(|r| r.name == "COLLADA")
        .ok_or_else(|| "no <COLLADA> root element".into())
}

/// A 4 × 4 homogeneous transform, row-major.
type Mat4 = [[f64; 4]; 4];

const ID4: Mat4 = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

fn mul4(a: &Mat4, b: &Mat4) -> Mat4 {
    let mut c = [[0.0; 4]; 4];
    for (i, row) in c.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn apply4(m: &Mat4, p: Vec3) -> Vec3 {
    let mut out = [0.0; 3];
    for (i, o) in out.iter_mut().enumerate() {
        *o = m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3];
    }
    out
}

/// The transform of one transform element (`None`: not a transform element).
fn transform(e: &El) -> Result<Option<Mat4>, String> {
    let want = |n: usize| -> Result<Vec<f64>, String> {
        let v = e.numbers()?;
        if v.len() == n {
            Ok(v)
        } else {
            Err(format!("<{}> has {} numbers, not {n}", e.name, v.len()))
        }
    };
    let mut m = ID4;
    match e.name.as_str() {
        "matrix" => {
            let v = want(16)?;
            for (i, row) in m.iter_mut().enumerate() {
                row.copy_from_slice(&v[4 * i..4 * i + 4]);
            }
        }
        "translate" => {
            let v = want(3)?;
            for i in 0..3 {
                m[i][3] = v[i];
            }
        }
        "scale" => {
            let v = want(3)?;
            for i in 0..3 {
                m[i][i] = v[i];
            }
        }
        "rotate" => {
            let v = want(4)?;
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if n == 0.0 {
                return Err("<rotate> about a zero axis".into());
            }
            let (x, y, z) = (v[0] / n, v[1] / n, v[2] / n);
            let (s, c) = v[3].to_radians().sin_cos();
            let t = 1.0 - c;
            m[0][..3].copy_from_slice(&[t * x * x + c, t * x * y - s * z, t * x * z + s * y]);
            m[1][..3].copy_from_slice(&[t * x * y + s * z, t * y * y + c, t * y * z - s * x]);
            m[2][..3].copy_from_slice(&[t * x * z - s * y, t * y * z + s * x, t * z * z + c]);
        }
        "lookat" | "skew" => {
            return Err(format!(
                "a node's <{}> transform is not read (matrix, translate, rotate and scale are)",
                e.name
            ))
        }
        _ => return Ok(None),
    }
    Ok(Some(m))
}

/// The document's geometries: id → vertex positions (in the mesh's own frame).
fn geometries(root: &El) -> Result<BTreeMap<String, Vec<Vec3>>, String> {
    let mut out = BTreeMap::new();
    let mut geoms = Vec::new();
    root.descendants("geometry", &mut geoms);
    for g in geoms {
        let Some(mesh) = g.kid("mesh") else { continue };
        // The source the <vertices> POSITION input names, else one whose id names positions.
        let named = mesh
            .kid("vertices")
            .and_then(|v| {
                v.all("input")
                    .find(|i| i.attr("semantic") == Some("POSITION"))
            })
            .and_then(|i| i.attr("source"))
            .map(|s| s.trim_start_matches('#').to_string());
        let source = mesh.all("source").find(|s| match &named {
            Some(id) => s.attr("id") == Some(id.as_str()),
            None => s
                .attr("id")
                .is_some_and(|id| id.to_lowercase().contains("position")),
        });
        let Some(array) = source.and_then(|s| s.kid("float_array")) else {
            continue;
        };
        let v = array.numbers()?;
        let stride = source
            .and_then(|s| s.kid("technique_common"))
            .and_then(|t| t.kid("accessor"))
            .and_then(|a| a.attr("stride"))
            .and_then(|s| s.parse::<usize>().ok())
            .unwrap_or(3)
            .max(3);
        let points = v.chunks_exact(stride).map(|c| [c[0], c[1], c[2]]).collect();
        out.insert(g.attr("id").unwrap_or_default().to_string(), points);
    }
    Ok(out)
}

/// The element an `url` attribute names (its id).
fn url(e: &El) -> &str {
    e.attr("url").unwrap_or_default().trim_start_matches('#')
}

/// Walks `node` under `parent`, adding its geometries' vertices to `out`.
fn walk(
    node: &El,
    parent: &Mat4,
    lib: &BTreeMap<String, &El>,
    geoms: &BTreeMap<String, Vec<Vec3>>,
    depth: usize,
    placed: &mut usize,
    out: &mut Vec<Vec3>,
) -> Result<(), String> {
    if depth > 64 {
        return Err("nodes nested more than 64 deep (an <instance_node> cycle?)".into());
    }
    *placed += 1;
    if *placed > MAX_NODES {
        return Err(format!(
            "the scene places more than {MAX_NODES} nodes through its <instance_node>s: refused"
        ));
    }
    let mut m = *parent;
    for k in &node.kids {
        if let Some(t) = transform(k)? {
            m = mul4(&m, &t);
        }
    }
    for k in &node.kids {
        match k.name.as_str() {
            "instance_geometry" => {
                let g = geoms.get(url(k)).ok_or_else(|| {
                    format!("<instance_geometry url=\"#{}\">: no such mesh", url(k))
                })?;
                if out.len() + g.len() > MAX_POSITIONS {
                    return Err(format!(
                        "the scene places more than {MAX_POSITIONS} vertex positions through \
                         its <instance_node>s and <instance_geometry>s: refused"
                    ));
                }
                out.extend(g.iter().map(|p| apply4(&m, *p)));
            }
            "instance_node" => {
                let n = lib
                    .get(url(k))
                    .ok_or_else(|| format!("<instance_node url=\"#{}\">: no such node", url(k)))?;
                walk(n, &m, lib, geoms, depth + 1, placed, out)?;
            }
            "node" => walk(k, &m, lib, geoms, depth + 1, placed, out)?,
            _ => {}
        }
    }
    Ok(())
}

/// The vertex positions of the document `text`, in metres, z up (see the module docs).
pub fn vertices(text: &str) -> Result<Vec<Vec3>, String> {
    let root = parse(text)?;
    let asset = root.kid("asset");
    let unit = asset
        .and_then(|a| a.kid("unit"))
        .and_then(|u| u.attr("meter"))
        .map_or(Ok(1.0), |m| {
            m.trim()
                .parse::<f64>()
                .map_err(|_| format!("<unit meter=\"{m}\">: not a number"))
        })?;
    let up = asset
        .and_then(|a| a.kid("up_axis"))
        .map_or("Y_UP", |u| u.text.trim());
    let geoms = geometries(&root)?;
    let mut nodes = Vec::new();
    root.descendants("node", &mut nodes);
    let lib: BTreeMap<String, &El> = nodes
        .iter()
        .filter_map(|n| n.attr("id").map(|id| (id.to_string(), *n)))
        .collect();
    let mut scenes = Vec::new();
    root.descendants("visual_scene", &mut scenes);
    let wanted = root
        .kid("scene")
        .and_then(|s| s.kid("instance_visual_scene"))
        .and_then(|i| i.attr("url"))
        .map(|u| u.trim_start_matches('#').to_string());
    let scene = match &wanted {
        Some(id) => scenes
            .iter()
            .find(|s| s.attr("id") == Some(id.as_str()))
            .or(scenes.first()),
        None => scenes.first(),
    };
    let mut out = Vec::new();
    let mut placed = 0;
    match scene {
        Some(s) => {
            for n in s.all("node") {
                walk(n, &ID4, &lib, &geoms, 0, &mut placed, &mut out)?;
            }
        }
        None => out.extend(geoms.values().flatten().copied()),
    }
    Ok(out
        .into_iter()
        .map(|p| {
            let p = p.map(|v| v * unit);
            match up {
                // The specification's axes (right, up, in): Y_UP (x, y, z), X_UP (−y, x, z),
                // Z_UP (x, z, −y).
                "Y_UP" => [p[0], -p[2], p[1]],
                "X_UP" => [-p[1], -p[2], p[0]],
                _ => p,
            }
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &[Vec3], b: &[Vec3]) -> bool {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(p, q)| (0..3).all(|i| (p[i] - q[i]).abs() < 1e-12))
    }

    #[test]
    fn positions_in_metres_z_up_under_the_node_transforms() {
        let doc = |scene: &str| {
            format!(
                r##"<COLLADA><asset><unit meter="0.1" name="decimetre"/><up_axis>Y_UP</up_axis></asset>
            <library_geometries><geometry id="g"><mesh>
            <source id="a-normals"><float_array id="a-normals-array" count="3">0 0 1</float_array></source>
            <source id="a-pos"><float_array id="a-pos-array" count="6">1 2 3 4 5 6</float_array></source>
            <vertices id="v"><input semantic="POSITION" source="#a-pos"/></vertices>
            </mesh></geometry></library_geometries>
            <library_nodes><node id="lib"><translate>1 0 0</translate><instance_geometry url="#g"/></node></library_nodes>
            <library_visual_scenes><visual_scene id="s">{scene}</visual_scene></library_visual_scenes>
            <scene><instance_visual_scene url="#s"/></scene></COLLADA>"##
            )
        };
        // × 0.1 (unit), y up turned to z up: (x, −z, y); the normals are not positions.
        let plain = vertices(&doc(r##"<node><instance_geometry url="#g"/></node>"##));
        assert!(
            close(
                &plain.clone().expect("read"),
                &[[0.1, -0.3, 0.2], [0.4, -0.6, 0.5]]
            ),
            "{plain:?}"
        );
        // A scale, then a nested node turned 90° about its z, then an instanced node moved
        // along its x: (1, 2, 3) → (2, 2, 3) → (−2, 2, 3) → × 0.5 → (−1, 1, 1.5).
        let nested = vertices(&doc(
            r##"<node><scale>0.5 0.5 0.5</scale><node><rotate>0 0 1 90</rotate>
                <instance_node url="#lib"/></node></node>"##,
        ))
        .expect("read");
        let want = |p: Vec3| [0.1 * p[0], -0.1 * p[2], 0.1 * p[1]];
        assert!(
            close(&nested, &[want([-1.0, 1.0, 1.5]), want([-2.5, 2.5, 3.0])]),
            "{nested:?}"
        );
        // A <matrix> (row-major) composes as the others: here x doubled and moved by 1 along z.
        let m = vertices(&doc(
            r##"<node><matrix>2 0 0 0 0 1 0 0 0 0 1 1 0 0 0 1</matrix><instance_geometry url="#g"/></node>"##,
        ))
        .expect("read");
        assert!(
            close(&m, &[want([2.0, 2.0, 4.0]), want([8.0, 5.0, 7.0])]),
            "{m:?}"
        );
        let e = vertices(&doc(r##"<node><lookat>0 0 1 0 0 0 0 1 0</lookat></node>"##))
            .expect_err("refused");
        assert!(e.contains("<lookat>"), "{e}");
    }

    /// Nine levels of a node instancing the next ten times (10⁹ placements from a document of
    /// a few kilobytes): refused once the scene places more than [`MAX_NODES`] nodes, without
    /// expanding it; a mesh of 100 positions placed 6·10⁴ times (fewer nodes than the cap):
    /// refused by [`MAX_POSITIONS`]; 10⁴ placements of it are read.
    #[test]
    fn instancing_fan_out_is_capped() {
        // n0 places the mesh, e0 nothing; nK and eK instance the level below.
        let mut lib =
            String::from(r##"<node id="n0"><instance_geometry url="#g"/></node><node id="e0"/>"##);
        for k in 1..10 {
            let times = if k == 5 { 6 } else { 10 };
            let below = if k == 5 { 4 } else { k - 1 };
            for n in ["n", "e"] {
                lib += &format!(r##"<node id="{n}{k}">"##);
                for _ in 0..times {
                    lib += &format!(r##"<instance_node url="#{n}{below}"/>"##);
                }
                lib += "</node>";
            }
        }
        let mesh: Vec<String> = (0..300).map(|i| format!("{}", i % 7)).collect();
        let mesh = mesh.join(" ");
        let doc = |top: &str| {
            format!(
                r##"<COLLADA><asset><up_axis>Z_UP</up_axis></asset>
            <library_geometries><geometry id="g"><mesh>
            <source id="p"><float_array id="pa" count="300">{mesh}</float_array></source>
            <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
            </mesh></geometry></library_geometries>
            <library_nodes>{lib}</library_nodes>
            <library_visual_scenes><visual_scene id="s"><node><instance_node url="#{top}"/></node>
            </visual_scene></library_visual_scenes></COLLADA>"##
            )
        };
        let e = vertices(&doc("e9")).expect_err("refused");
        assert!(e.contains("more than 100000 nodes"), "{e}");
        let e = vertices(&doc("n5")).expect_err("refused");
        assert!(e.contains("more than 5000000 vertex positions"), "{e}");
        assert_eq!(vertices(&doc("n4")).expect("read").len(), 1_000_000);
    }
}
