//! The front page and the book hold together: every relative link of `README.md` and of the
//! book's chapters names a file that exists, every chapter is in the book's `SUMMARY.md` and
//! every `SUMMARY.md` entry is a chapter, the front page stays a front page (at most 200
//! lines, exactly the two set-up commands in its first code block), and every headline figure
//! of the front page names the command that measures it.

use std::path::{Path, PathBuf};

use walk_tests::figures::cells;

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

/// The programs a headline figure's command may run.
const PROGRAMS: [&str; 4] = ["cargo", "bash", "sh", "python3"];

/// The rows of the "Headline figures" table of the front page `text` that name no command in
/// backticks in their `command` column, each with why (panics if there is no such table).
fn headline_rows_without_command(text: &str) -> Vec<String> {
    let section = text
        .split("\n## ")
        .find(|s| s.starts_with("Headline figures"))
        .expect("README.md has no `## Headline figures` section");
    let rows: Vec<&str> = section
        .lines()
        .filter(|l| l.trim_start().starts_with('|'))
        .collect();
    assert!(
        rows.len() >= 3,
        "the Headline figures section has no table with a row: {rows:?}"
    );
    let header = cells(rows[0]);
    let column = header
        .iter()
        .position(|h| *h == "command")
        .unwrap_or_else(|| {
            panic!("the Headline figures table has no `command` column: {header:?}")
        });
    assert!(
        cells(rows[1])
            .iter()
            .all(|c| c.chars().all(|ch| "-: ".contains(ch))),
        "the table's second line is not its separator: {}",
        rows[1]
    );
    let mut missing = vec![];
    for row in &rows[2..] {
        let row_cells = cells(row);
        let command = row_cells.get(column).copied().unwrap_or("");
        // A span in backticks (the odd pieces between them) that runs a program.
        let closed = command.matches('`').count() % 2 == 0;
        let named = closed
            && command.split('`').skip(1).step_by(2).any(|span| {
                span.split_whitespace()
                    .next()
                    .is_some_and(|program| PROGRAMS.contains(&program) || program.ends_with(".sh"))
            });
        if !named {
            missing.push(format!(
                "the row `{}` names no command in backticks in its command column (it has \
                 `{command}`): write the command that measures the figure (one that starts \
                 with one of {PROGRAMS:?} or a `.sh` script)",
                row_cells.first().copied().unwrap_or("")
            ));
        }
    }
    missing
}

/// The front page's "Headline figures" table: every row names, in backticks in its `command`
/// column, the command that measures its figure (a figure without its command cannot be
/// checked, nor kept up to date).
#[test]
fn every_headline_figure_names_its_command() {
    let text = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let missing = headline_rows_without_command(&text);
    assert!(
        missing.is_empty(),
        "README.md, Headline figures:\n{}",
        missing.join("\n")
    );
}

/// The check above finds a figure without its command.
#[test]
fn a_headline_figure_without_its_command_is_found() {
    let text = "# W\n\n## Headline figures\n\n| what | figure | command |\n|---|---|---|\n\
        | a | 1 | `cargo test -p a` |\n| b | 2 | |\n| c | 3 | see the book |\n\
        | d | 4 | `Node::poll` |\n| e | 5 | `bash firmware/size.sh` |\n| f | 6 | `cargo |\n\n\
        ## Next\n\n| x | y | command |\n|---|---|---|\n| g | 7 | |\n";
    let missing = headline_rows_without_command(text);
    let rows: Vec<&str> = missing
        .iter()
        .map(|m| m.split('`').nth(1).unwrap_or(""))
        .collect();
    assert_eq!(rows, ["b", "c", "d", "f"], "{missing:#?}");
}
