//! The front page and the book hold together: every relative link of `README.md` and of the
//! book's chapters names a file that exists, every chapter is in the book's `SUMMARY.md` and
//! every `SUMMARY.md` entry is a chapter, every chapter has one title, the front page stays a
//! front page (at most 200 lines, exactly the two set-up commands in its first code block),
//! and every headline figure of the front page names the command that measures it; and
//! neither speaks of work history (issue numbers, reviews, what was fixed or how the code was
//! before).

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

/// The level-1 headings (`# …`) of the markdown `text`, outside code blocks.
fn titles(text: &str) -> Vec<&str> {
    let mut in_code = false;
    let mut out = vec![];
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        } else if !in_code && line.starts_with("# ") {
            out.push(line);
        }
    }
    out
}

/// Every chapter has one title: a second `# …` heading is a second chapter, to be a file of
/// its own in `SUMMARY.md`.
#[test]
fn every_chapter_has_one_title() {
    for c in chapters() {
        let text = std::fs::read_to_string(&c).expect("readable");
        let t = titles(&text);
        assert_eq!(t.len(), 1, "{}: titles {t:?}", c.display());
    }
    assert_eq!(
        titles("# A\n```sh\n# a comment\n```\ntext\n# B\n"),
        ["# A", "# B"]
    );
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

/// Phrases of work history rather than of the product (lower case): an issue or a review, a
/// defect "now fixed", what the code did "before the change". Product text says what the
/// product is and does; its history is in git.
const HISTORY_PHRASES: [&str; 11] = [
    "next issue",
    "review item",
    "now fixed",
    "fixed now",
    "(refused now)",
    "before the change",
    "history:",
    "git history",
    "the former ",
    "formerly",
    "previously",
];

/// The places in `text` that speak of work history: an `issue` followed by a number (`issue
/// 12`, `issue #12`, `Issue 12's`) or one of [`HISTORY_PHRASES`], each with its line number.
fn history_words(text: &str) -> Vec<String> {
    let mut found = vec![];
    for (n, line) in text.lines().enumerate() {
        let lower = line.to_lowercase();
        let mut rest = lower.as_str();
        while let Some(i) = rest.find("issue") {
            let before_ok = rest[..i]
                .chars()
                .next_back()
                .is_none_or(|c| !c.is_alphanumeric());
            let after = rest[i + "issue".len()..].trim_start_matches([' ', '#']);
            let spaced = rest[i + "issue".len()..].starts_with([' ', '#']);
            if before_ok && spaced && after.starts_with(|c: char| c.is_ascii_digit()) {
                found.push(format!("line {}: {}", n + 1, line.trim()));
            }
            rest = &rest[i + "issue".len()..];
        }
        for phrase in HISTORY_PHRASES {
            if lower.contains(phrase) {
                found.push(format!("line {} ({phrase:?}): {}", n + 1, line.trim()));
            }
        }
    }
    found
}

/// The front page and every chapter of the book describe the product: no issue numbers,
/// reviews, defects "now fixed" or what the code did before (firmware/README.md is not
/// checked here).
#[test]
fn product_text_has_no_work_history() {
    let mut files = vec![root().join("README.md")];
    files.extend(chapters());
    let mut stale = vec![];
    for f in &files {
        let text = std::fs::read_to_string(f).expect("readable");
        for w in history_words(&text) {
            stale.push(format!("{}: {w}", f.display()));
        }
    }
    assert!(
        stale.is_empty(),
        "work history in product text (say what the product does, not how it came to):\n{}",
        stale.join("\n")
    );
}

/// The check above finds issue numbers and history phrases, and leaves product words alone.
#[test]
fn history_words_are_found() {
    let text = "the gait (next issue)\nIssue 12's target\nsee issue #4\nthe reissue 3\n\
        it issues two instructions\nboth now fixed\nthe former box\nHistory: none\n\
        an issue of timing 5 ms\nbefore the change above\nthe step before it";
    let lines: Vec<String> = history_words(text)
        .iter()
        .map(|w| w.split([' ', ':']).nth(1).unwrap_or("").to_string())
        .collect();
    assert_eq!(
        lines,
        ["1", "2", "3", "6", "7", "8", "10"],
        "{:#?}",
        history_words(text)
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

/// The repository file paths the front page's shell commands name (a `.toml`, `.urdf`, `.log`
/// or `.sh` argument that is not an output: not after `--out`, not under `out/`) exist.
#[test]
fn the_front_pages_commands_name_files_that_exist() {
    let text = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let mut missing = vec![];
    let mut checked = 0;
    for (i, block) in text.split("```").enumerate() {
        if i % 2 == 0 || !block.starts_with("sh\n") {
            continue;
        }
        for line in block.lines() {
            let code = line.split(" #").next().unwrap_or(line);
            let words: Vec<&str> = code.split_whitespace().collect();
            for (j, w) in words.iter().enumerate() {
                let file = [".toml", ".urdf", ".log", ".sh"]
                    .iter()
                    .any(|x| w.ends_with(x));
                let output = j > 0 && words[j - 1] == "--out" || w.starts_with("out/");
                if file && !output {
                    checked += 1;
                    if !root().join(w).is_file() {
                        missing.push(format!("{w} (in `{}`)", line.trim()));
                    }
                }
            }
        }
    }
    assert!(
        checked >= 2,
        "no file argument found in README.md's commands"
    );
    assert!(
        missing.is_empty(),
        "README.md names missing files: {missing:?}"
    );
}

/// The front page installs mdbook as `tests/run-all.sh` does (its version, without the
/// default features), and says how to get probe-rs for flashing.
#[test]
fn the_front_page_states_the_installs_the_test_command_uses() {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let run_all = std::fs::read_to_string(root().join("tests/run-all.sh")).expect("run-all.sh");
    let version = run_all
        .lines()
        .find_map(|l| l.strip_prefix("MDBOOK_VERSION="))
        .expect("run-all.sh's MDBOOK_VERSION");
    assert!(
        run_all.contains(
            "cargo install --locked mdbook --version \"$MDBOOK_VERSION\" --no-default-features"
        ),
        "run-all.sh's mdbook install changed: update this test and the front page"
    );
    let install =
        format!("cargo install --locked mdbook --version {version} --no-default-features");
    let flat = readme.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(
        flat.contains(&install),
        "README.md does not say `{install}`"
    );
    for doc in ["README.md", "firmware/README.md"] {
        let text = std::fs::read_to_string(root().join(doc)).expect(doc);
        let flat = text.split_whitespace().collect::<Vec<_>>().join(" ");
        assert!(
            flat.contains("cargo install probe-rs-tools --locked"),
            "{doc} does not say how to install probe-rs"
        );
    }
}

/// `cargo run` in firmware/ runs `firmware/probe-run.sh` (the runner of
/// `firmware/.cargo/config.toml`), which without probe-rs on PATH says how to install it in
/// one line, exit status 127.
#[test]
fn the_flashing_runner_says_how_to_install_probe_rs() {
    let config =
        std::fs::read_to_string(root().join("firmware/.cargo/config.toml")).expect("config");
    assert!(
        config
            .lines()
            .any(|l| l.trim() == "runner = \"./probe-run.sh\""),
        "{config}"
    );
    let empty = std::env::temp_dir().join(format!("walk-no-probe-rs-{}", std::process::id()));
    std::fs::create_dir_all(&empty).expect("a directory");
    let o = std::process::Command::new("/bin/sh")
        .arg(root().join("firmware/probe-run.sh"))
        .arg("target/board.elf")
        .env("PATH", &empty)
        .output()
        .expect("sh runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(127), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("cargo install probe-rs-tools --locked"),
        "{err}"
    );
    let _ = std::fs::remove_dir(&empty);
}
