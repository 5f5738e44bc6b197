//! The source tree keeps its rooms: no `.rs` file under `planner-core/src` or `host-sim/src`
//! is longer than [`MAX_LINES`] lines, and no two sibling modules of `planner-core/src`,
//! `host-sim/src` or `firmware/board-core/src` import each other, directly or around a longer
//! circle (`a` uses `b`, `b` uses `c`, `c` uses `a`).
//!
//! "Imports" are the paths the code names, `use` or not: `crate::a::b`, `super::x`,
//! `super::super::y` and the groups `crate::{a, b::{c, d}}`, read from the source with the
//! comments, strings and character literals left out. A path counts for the file's module
//! (an inline `mod tests { use super::… }` resolves `super` from where it stands, and what it
//! names counts for the file's module). A path from module `p::a` (or anything inside it) to
//! `p::b` (or anything inside it) is an edge `a → b` among the children of `p`; a module using
//! its own parent or child is no edge. A circle is a strongly connected component of more
//! than one module in the graph of one parent's children.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The longest a source file of planner-core or host-sim may be.
const MAX_LINES: usize = 800;

/// The crates whose files are held to [`MAX_LINES`].
const SIZED: [&str; 2] = ["planner-core/src", "host-sim/src"];

/// The crates whose sibling modules must not import each other.
const ROOMS: [&str; 3] = [
    "planner-core/src",
    "host-sim/src",
    "firmware/board-core/src",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every `.rs` file under `dir`, as (its path relative to `dir` with `/`, its text), sorted.
fn sources(dir: &Path) -> Vec<(String, String)> {
    fn walk(base: &Path, dir: &Path, out: &mut Vec<(String, String)>) {
        for e in std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let p = e.expect("a directory entry").path();
            if p.is_dir() {
                walk(base, &p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p.strip_prefix(base).expect("under the base");
                let rel: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                let text = std::fs::read_to_string(&p).expect("a readable source file");
                out.push((rel.join("/"), text));
            }
        }
    }
    let mut out = vec![];
    walk(dir, dir, &mut out);
    out.sort();
    out
}

/// The module a file is: `a/b.rs` and `a/b/mod.rs` are `a::b`, `lib.rs` and `main.rs` the
/// crate's root (an empty path).
fn module_of(rel: &str) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .trim_end_matches(".rs")
        .split('/')
        .map(str::to_string)
        .collect();
    if (parts.len() == 1 && (parts[0] == "lib" || parts[0] == "main")) || parts[0] == "bin" {
        return vec![];
    }
    if parts.last().is_some_and(|l| l == "mod") {
        parts.pop();
    }
    parts
}

/// A token of Rust source, as far as paths need: an identifier (or keyword), `::`, or one
/// character of punctuation.
#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Ident(String),
    PathSep,
    Punct(char),
}

/// The tokens of `src` with comments, string literals and character literals left out.
fn tokens(src: &str) -> Vec<Tok> {
    let c: Vec<char> = src.chars().collect();
    let mut out = vec![];
    let mut i = 0;
    while i < c.len() {
        let ch = c[i];
        let next = c.get(i + 1).copied();
        if ch == '/' && next == Some('/') {
            while i < c.len() && c[i] != '\n' {
                i += 1;
            }
        } else if ch == '/' && next == Some('*') {
            let mut depth = 0;
            while i < c.len() {
                if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if ch == '"' {
            i += 1;
            while i < c.len() && c[i] != '"' {
                i += if c[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
        } else if (ch == 'r' || ch == 'b')
            && !c[..i]
                .last()
                .is_some_and(|p| p.is_alphanumeric() || *p == '_')
            && raw_string_len(&c[i..]).is_some()
        {
            i += raw_string_len(&c[i..]).unwrap_or(1);
        } else if ch == '\'' {
            // A character literal ('x', '\n', '\u{7f}'), or a lifetime ('a).
            if next == Some('\\') {
                i += 2;
                while i < c.len() && c[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if c.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
            }
        } else if ch.is_alphabetic() || ch == '_' {
            let start = i;
            while i < c.len() && (c[i].is_alphanumeric() || c[i] == '_') {
                i += 1;
            }
            out.push(Tok::Ident(c[start..i].iter().collect()));
        } else if ch == ':' && next == Some(':') {
            out.push(Tok::PathSep);
            i += 2;
        } else {
            if !ch.is_whitespace() {
                out.push(Tok::Punct(ch));
            }
            i += 1;
        }
    }
    out
}

/// The length of the raw (or byte, or raw byte) string literal `c` starts with, if it starts
/// with one: `r"…"`, `r#"…"#`, `br"…"`, `b"…"`.
fn raw_string_len(c: &[char]) -> Option<usize> {
    let mut i = 0;
    if c.get(i) == Some(&'b') {
        i += 1;
    }
    let raw = c.get(i) == Some(&'r');
    if raw {
        i += 1;
    }
    if i == 0 {
        return None;
    }
    let mut hashes = 0;
    while raw && c.get(i) == Some(&'#') {
        hashes += 1;
        i += 1;
    }
    if c.get(i) != Some(&'"') {
        return None;
    }
    i += 1;
    while i < c.len() {
        if !raw && c[i] == '\\' {
            i += 2;
            continue;
        }
        if c[i] == '"' && (0..hashes).all(|h| c.get(i + 1 + h) == Some(&'#')) {
            return Some(i + 1 + hashes);
        }
        i += 1;
    }
    Some(c.len())
}

/// The paths of the path expression at `t[i..]` (segments, a `{…}` group expanded into one
/// path per item), and the index after it.
fn paths_at(t: &[Tok], mut i: usize) -> (Vec<Vec<String>>, usize) {
    let mut prefix = vec![];
    loop {
        match t.get(i) {
            Some(Tok::Ident(s)) => {
                prefix.push(s.clone());
                i += 1;
            }
            Some(Tok::Punct('{')) => {
                let mut out = vec![];
                i += 1;
                loop {
                    match t.get(i) {
                        Some(Tok::Punct('}')) | None => return (out, i + 1),
                        Some(Tok::Punct(',')) => i += 1,
                        // `X as Y`: the rename is no path.
                        Some(Tok::Ident(s)) if s == "as" => i += 2,
                        Some(Tok::Ident(_)) | Some(Tok::Punct('{')) => {
                            let (items, j) = paths_at(t, i);
                            for item in items {
                                let mut p = prefix.clone();
                                // `{self, …}` names the prefix itself.
                                p.extend(item.into_iter().filter(|s| s != "self"));
                                out.push(p);
                            }
                            i = j;
                        }
                        // `*`, `as`-renames' tails and the like.
                        Some(_) => i += 1,
                    }
                }
            }
            _ => return (vec![prefix], i),
        }
        if t.get(i) == Some(&Tok::PathSep) {
            i += 1;
        } else {
            return (vec![prefix], i);
        }
    }
}

/// The modules (absolute paths from the crate's root) that the file of module `module` names
/// with `crate::…` and `super::…` paths (`super` resolved from the inline module it stands in).
fn named_paths(module: &[String], src: &str) -> Vec<Vec<String>> {
    let t = tokens(src);
    let mut out = vec![];
    // The inline modules (`mod name {`) around the current token; `None` for other blocks.
    let mut blocks: Vec<Option<String>> = vec![];
    let mut i = 0;
    while i < t.len() {
        match &t[i] {
            Tok::Punct('{') => {
                let before = |n: usize| i.checked_sub(n).and_then(|k| t.get(k));
                let inline = match (before(2), before(1)) {
                    (Some(Tok::Ident(m)), Some(Tok::Ident(name))) if m == "mod" => {
                        Some(name.clone())
                    }
                    _ => None,
                };
                blocks.push(inline);
                i += 1;
            }
            Tok::Punct('}') => {
                blocks.pop();
                i += 1;
            }
            Tok::Ident(s)
                if (s == "crate" || s == "super")
                    && t.get(i + 1) == Some(&Tok::PathSep)
                    && (i == 0 || t[i - 1] != Tok::PathSep) =>
            {
                let (paths, j) = paths_at(&t, i);
                let mut here: Vec<String> = module.to_vec();
                here.extend(blocks.iter().flatten().cloned());
                for p in paths {
                    let mut segs = p.into_iter().peekable();
                    let mut base = if segs.peek().is_some_and(|s| s == "crate") {
                        segs.next();
                        vec![]
                    } else {
                        here.clone()
                    };
                    while segs.peek().is_some_and(|s| s == "super") {
                        segs.next();
                        base.pop();
                    }
                    base.extend(segs);
                    out.push(base);
                }
                i = j.max(i + 1);
            }
            _ => i += 1,
        }
    }
    out
}

/// The edges `a → b` among sibling modules (each the full path of the module) of the crate
/// whose files are `files` (relative path, text).
fn sibling_edges(files: &[(String, String)]) -> BTreeSet<(Vec<String>, Vec<String>)> {
    let modules: BTreeSet<Vec<String>> = files.iter().map(|(p, _)| module_of(p)).collect();
    let mut edges = BTreeSet::new();
    for (path, src) in files {
        let from = module_of(path);
        for named in named_paths(&from, src) {
            // The module the path names: its longest prefix that is a module of a file.
            let Some(to) = (0..=named.len())
                .rev()
                .map(|n| named[..n].to_vec())
                .find(|p| modules.contains(p))
            else {
                continue;
            };
            let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
            if common < from.len() && common < to.len() {
                edges.insert((from[..=common].to_vec(), to[..=common].to_vec()));
            }
        }
    }
    edges
}

/// The circles of `edges`: its strongly connected components of more than one module, each
/// sorted, in order.
fn circles(edges: &BTreeSet<(Vec<String>, Vec<String>)>) -> Vec<Vec<Vec<String>>> {
    let mut next: BTreeMap<&Vec<String>, Vec<&Vec<String>>> = BTreeMap::new();
    for (a, b) in edges {
        next.entry(a).or_default().push(b);
        next.entry(b).or_default();
    }
    let reach = |from: &Vec<String>| -> BTreeSet<Vec<String>> {
        let mut seen = BTreeSet::new();
        let mut stack = vec![from];
        while let Some(m) = stack.pop() {
            for n in &next[m] {
                if seen.insert((*n).clone()) {
                    stack.push(n);
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&Vec<String>, BTreeSet<Vec<String>>> =
        next.keys().map(|m| (*m, reach(m))).collect();
    let mut out: Vec<Vec<Vec<String>>> = vec![];
    let mut placed = BTreeSet::new();
    for (m, r) in &reached {
        if placed.contains(*m) || !r.contains(*m) {
            continue;
        }
        let component: Vec<Vec<String>> = r
            .iter()
            .filter(|n| reached[n].contains(*m))
            .cloned()
            .collect();
        placed.extend(component.iter().cloned());
        out.push(component);
    }
    out
}

/// The circles of the crate whose files are `files`, in words: `a → b → a`.
fn circles_in(files: &[(String, String)]) -> Vec<String> {
    circles(&sibling_edges(files))
        .iter()
        .map(|c| {
            c.iter()
                .map(|m| m.join("::"))
                .collect::<Vec<_>>()
                .join(", ")
        })
        .collect()
}

#[test]
fn no_source_file_is_longer_than_the_limit() {
    let mut long = vec![];
    let mut seen = 0;
    for dir in SIZED {
        for (path, text) in sources(&root().join(dir)) {
            seen += 1;
            let n = text.lines().count();
            if n > MAX_LINES {
                long.push(format!("{dir}/{path}: {n} lines"));
            }
        }
    }
    assert!(seen > 40, "only {seen} files found: the walk is broken");
    assert!(
        long.is_empty(),
        "source files over {MAX_LINES} lines (split them into rooms by role):\n{}",
        long.join("\n")
    );
}

#[test]
fn no_sibling_modules_import_each_other() {
    let mut found = vec![];
    for dir in ROOMS {
        let files = sources(&root().join(dir));
        let edges = sibling_edges(&files);
        assert!(
            edges.len() >= 3,
            "{dir}: only {} edges between sibling modules: the scanner is broken",
            edges.len()
        );
        for c in circles(&edges) {
            let inside: Vec<String> = edges
                .iter()
                .filter(|(a, b)| c.contains(a) && c.contains(b))
                .map(|(a, b)| format!("{} → {}", a.join("::"), b.join("::")))
                .collect();
            let names: Vec<String> = c.iter().map(|m| m.join("::")).collect();
            found.push(format!(
                "{dir}: {} ({})",
                names.join(", "),
                inside.join(", ")
            ));
        }
    }
    assert!(
        found.is_empty(),
        "sibling modules that import each other (directly or around a circle; move what both \
         need into one of them or below both):\n{}",
        found.join("\n")
    );
}

/// `(path, text)` pairs from string literals.
fn crate_of(files: &[(&str, &str)]) -> Vec<(String, String)> {
    files
        .iter()
        .map(|(p, t)| (p.to_string(), t.to_string()))
        .collect()
}

#[test]
fn two_modules_importing_each_other_are_a_circle() {
    let files = crate_of(&[
        ("lib.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
        ("a.rs", "use crate::b::Thing;\n"),
        ("b.rs", "pub fn f() { super::a::g(); }\n"),
        ("c.rs", "use crate::a;\n"),
    ]);
    assert_eq!(circles_in(&files), ["a, b"]);
}

#[test]
fn a_longer_circle_is_found_through_groups_and_submodules() {
    let files = crate_of(&[
        ("lib.rs", "pub mod a;\npub mod b;\npub mod c;\npub mod d;\n"),
        // a::inner names b through a group; b's child names c; c names a and d.
        ("a/mod.rs", "pub mod inner;\n"),
        ("a/inner.rs", "use crate::{b::{self, x}, d};\n"),
        ("b/mod.rs", "pub mod deep;\n"),
        ("b/deep.rs", "fn f() { super::super::c::g() }\n"),
        ("c.rs", "use crate::{a::inner::X as Y, d::*};\n"),
        ("d.rs", "\n"),
    ]);
    assert_eq!(circles_in(&files), ["a, b, c"]);
}

#[test]
fn what_is_not_an_import_makes_no_circle() {
    let files = crate_of(&[
        ("lib.rs", "pub mod a;\npub mod b;\n"),
        // b names a in code; a names b only in comments, strings, char literals, a child's
        // own tests and a parent's items.
        ("b.rs", "use crate::a::X;\n"),
        (
            "a/mod.rs",
            "pub mod t;\n// crate::b::f\n/* crate::b::g */\nconst S: &str = \"crate::b::h\";\n\
             const R: &str = r#\"super::b\"#;\nconst C: char = '{';\n\
             fn f<'a>(x: &'a u8) {}\nuse super::*;\n",
        ),
        (
            "a/t.rs",
            "mod tests {\n    use super::super::X;\n    use super::helper;\n}\n\
             fn helper() { crate::a::t::inner(); }\n",
        ),
    ]);
    let edges = sibling_edges(&files);
    let names: Vec<String> = edges
        .iter()
        .map(|(a, b)| format!("{} -> {}", a.join("::"), b.join("::")))
        .collect();
    assert_eq!(names, ["b -> a"]);
    assert!(circles_in(&files).is_empty());
}
