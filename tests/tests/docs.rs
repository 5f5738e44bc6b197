//! The front page and the book hold together: every relative link of `README.md` and of the
//! book's chapters names a file that exists, every chapter is in the book's `SUMMARY.md` and
//! every `SUMMARY.md` entry is a chapter, and the front page stays a front page (at most 200
//! lines, exactly the two set-up commands in its first code block).

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The targets of the markdown links `](target)` of `text` that are not web addresses or
/// anchors, without their anchors.
fn relative_links(text: &str) -> Vec<String> {
    let mut out = vec![];
    let mut rest = text;
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        let Some(j) = rest.find(')') else { break };
        let target = &rest[..j];
        if !target.starts_with("http") && !target.starts_with('#') && !target.is_empty() {
            out.push(target.split('#').next().unwrap_or(target).to_string());
        }
    }
    out
}

fn chapters() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(root().join("docs/src"))
        .expect("docs/src")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .filter(|p| p.file_name().is_some_and(|n| n != "SUMMARY.md"))
        .collect();
    v.sort();
    v
}

#[test]
fn every_relative_link_resolves() {
    let mut files = vec![root().join("README.md")];
    files.extend(chapters());
    let mut checked = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).expect("readable");
        let dir = f.parent().expect("a directory");
        for link in relative_links(&text) {
            assert!(
                dir.join(&link).exists(),
                "{}: the link {link} names no file",
                f.display()
            );
            checked += 1;
        }
    }
    assert!(
        checked >= 8,
        "only {checked} links found: the parser is broken"
    );
}

#[test]
fn the_summary_lists_every_chapter() {
    let summary = std::fs::read_to_string(root().join("docs/src/SUMMARY.md")).expect("SUMMARY");
    let listed: Vec<String> = relative_links(&summary);
    for c in chapters() {
        let name = c.file_name().and_then(|n| n.to_str()).expect("name");
        assert!(
            listed.iter().any(|l| l == name),
            "{name} is not in SUMMARY.md"
        );
    }
    for l in &listed {
        assert!(
            root().join("docs/src").join(l).exists(),
            "SUMMARY.md lists {l}, which does not exist"
        );
    }
}

#[test]
fn the_front_page_is_short_and_names_the_two_commands() {
    let text = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let lines = text.lines().count();
    assert!(lines <= 200, "README.md has {lines} lines");
    let block: Vec<&str> = text
        .split("```")
        .nth(1)
        .expect("a code block")
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty())
        .collect();
    assert_eq!(block.len(), 2, "the first code block: {block:?}");
    assert!(block[0].starts_with("cargo run --release -p host-sim"));
    assert!(block[1].starts_with("bash tests/run-all.sh"));
    assert!(
        !text.to_lowercase().contains("issue "),
        "the front page speaks of the product, not of work items"
    );
}
