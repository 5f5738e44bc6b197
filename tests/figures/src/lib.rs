//! Figures quoted in the documents, checked by the tests that measure them (used by the tests
//! of planner-core, host-sim and walk-tests; `walk_tests::figures` re-exports it).
//!
//! A test that measures a figure the front page or the book quotes formats it exactly as the
//! document writes it (thousands separators, the same rounding: [`thousands`], [`sci`]) and
//! asserts that the document says so, at the line or table row named by an anchor text:
//!
//! ```no_run
//! use doc_figures::{thousands, Quotes};
//!
//! let worst: u64 = 38_360; // measured
//! Quotes::new("cargo test --release -p walk-tests --test qemu -- --nocapture")
//!     .cell("README.md", "worst control cycle on the Cortex-M7", "figure",
//!           &format!("{} instructions", thousands(worst)))
//!     .line("docs/src/timing.md", "(QEMU high-water marks)", "2,844 B of stack")
//!     .assert();
//! ```
//!
//! A figure that is no longer quoted fails the test with what the document says there, what
//! was measured and the command that measures it, so that the maintainer knows what to write.
//! Every figure of a [`Quotes`] is checked before it fails: one run reports every stale one.
//!
//! The anchor must be on exactly one line of the document; the expected text must occur in
//! that line (or in the named cell of that table row) as a whole figure: `3,240` is not found
//! in `13,240` nor in `3,2405`, `0.32` not in `0.325`.

use std::path::{Path, PathBuf};

/// The repository's root (documents are named relative to it).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("..")
        .canonicalize()
        .expect("the repository root")
}

/// `n` with a comma every three digits, as the documents write counts: `38,360`, `120,000`,
/// `18`.
pub fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `x` in scientific notation with `digits` significant digits and a signed exponent, as the
/// documents write small errors: `sci(1.96e-11, 2)` is `2.0e-11`.
pub fn sci(x: f64, digits: usize) -> String {
    format!("{:.*e}", digits.saturating_sub(1), x)
}

/// The figures one command measures, checked against the documents that quote them; every
/// mismatch is collected and [`Quotes::assert`] reports them all.
#[must_use = "call `assert` to check the figures"]
pub struct Quotes {
    command: String,
    checked: usize,
    failures: Vec<String>,
    /// How far every number of the figures checked next may be from the measured one
    /// ([`Quotes::within`], [`Quotes::within_units`], [`Quotes::exact`]).
    tolerance: Tolerance,
}

impl Quotes {
    /// Figures measured by `command` (named in the failure message: it is the command a
    /// maintainer runs to see the measured figure).
    pub fn new(command: &str) -> Self {
        Quotes {
            command: command.to_string(),
            checked: 0,
            failures: vec![],
            tolerance: Tolerance::EXACT,
        }
    }

    /// Figures that are estimates whose last digits move with things the test does not hold
    /// fixed (the image's layout, say): every number of the quoted text may differ from the
    /// measured one by `relative` of it, plus half a unit of its last quoted digit; the words
    /// between the numbers must be the same. It holds for the figures checked after it.
    pub fn within(mut self, relative: f64) -> Self {
        self.tolerance = Tolerance {
            relative,
            absolute: 0.0,
        };
        self
    }

    /// Figures that are counts read off a clock with a coarser tick than the count (QEMU's
    /// instruction counts through a 25 MHz timer: 40 instructions a tick, whose phase moves
    /// with the emulator's version): every number of the quoted text may differ from the
    /// measured one by `units` of it, plus half a unit of its last quoted digit; the words
    /// between the numbers must be the same. It holds for the figures checked after it.
    pub fn within_units(mut self, units: f64) -> Self {
        self.tolerance = Tolerance {
            relative: 0.0,
            absolute: units,
        };
        self
    }

    /// The figures checked after it must be quoted exactly as measured (the default).
    pub fn exact(mut self) -> Self {
        self.tolerance = Tolerance::EXACT;
        self
    }

    /// `doc` (relative to the repository root) quotes `expected` in its line (or table row)
    /// that contains `anchor`.
    pub fn line(mut self, doc: &str, anchor: &str, expected: &str) -> Self {
        self.checked += 1;
        if let Err(e) = check_near(doc, anchor, None, expected, &self.command, self.tolerance) {
            self.failures.push(e);
        }
        self
    }

    /// `doc` (relative to the repository root) quotes `expected` in the cell of column
    /// `column` (the text of its header cell, trimmed) of its table row that contains `anchor`.
    pub fn cell(mut self, doc: &str, anchor: &str, column: &str, expected: &str) -> Self {
        self.checked += 1;
        if let Err(e) = check_near(
            doc,
            anchor,
            Some(column),
            expected,
            &self.command,
            self.tolerance,
        ) {
            self.failures.push(e);
        }
        self
    }

    /// [`Quotes::cell`] for a figure that may be spelt any of `spellings` (a value within a
    /// rounding tolerance of a rounding boundary: the engine may land on either side of it on
    /// another CPU); the failure names the first.
    pub fn cell_any(mut self, doc: &str, anchor: &str, column: &str, spellings: &[String]) -> Self {
        self.checked += 1;
        let mut first = None;
        for s in spellings {
            match check_near(doc, anchor, Some(column), s, &self.command, self.tolerance) {
                Ok(()) => return self,
                Err(e) => {
                    first.get_or_insert(e);
                }
            }
        }
        if let Some(e) = first {
            self.failures.push(e);
        }
        self
    }

    /// Panics, listing every figure that is not quoted as measured; prints how many were
    /// checked otherwise.
    pub fn assert(self) {
        assert!(
            self.failures.is_empty(),
            "{} of {} quoted figures differ from the measured ones (update the documents):\n\n{}",
            self.failures.len(),
            self.checked,
            self.failures.join("\n\n")
        );
        println!(
            "{} figures measured by `{}` quoted as measured",
            self.checked, self.command
        );
    }
}

/// Asserts that `doc` (relative to the repository root) quotes `expected` in its line (or
/// table row) that contains `anchor`; the failure names `command`, which measures it.
pub fn assert_quoted(doc: &str, anchor: &str, expected: &str, command: &str) {
    Quotes::new(command).line(doc, anchor, expected).assert();
}

/// [`assert_quoted`] in the cell of column `column` of the table row that contains `anchor`.
pub fn assert_quoted_in(doc: &str, anchor: &str, column: &str, expected: &str, command: &str) {
    Quotes::new(command)
        .cell(doc, anchor, column, expected)
        .assert();
}

/// Whether `doc` quotes `expected` at `anchor` (in `column`'s cell, if given); the failure
/// message otherwise.
pub fn check(
    doc: &str,
    anchor: &str,
    column: Option<&str>,
    expected: &str,
    command: &str,
) -> Result<(), String> {
    check_near(doc, anchor, column, expected, command, Tolerance::EXACT)
}

/// [`check`] with every number within `tolerance` ([`Quotes::within`]; 0: exact text).
fn check_near(
    doc: &str,
    anchor: &str,
    column: Option<&str>,
    expected: &str,
    command: &str,
    tolerance: Tolerance,
) -> Result<(), String> {
    let path = repo_root().join(doc);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| format!("{doc}: cannot read {}: {e}", path.display()))?;
    check_text_near(doc, &text, anchor, column, expected, command, tolerance)
}

/// [`check`] on the document's text `text` (`doc` names it in the message).
pub fn check_text(
    doc: &str,
    text: &str,
    anchor: &str,
    column: Option<&str>,
    expected: &str,
    command: &str,
) -> Result<(), String> {
    check_text_near(
        doc,
        text,
        anchor,
        column,
        expected,
        command,
        Tolerance::EXACT,
    )
}

/// [`check_text`] with every number within `tolerance` ([`Quotes::within`]).
fn check_text_near(
    doc: &str,
    text: &str,
    anchor: &str,
    column: Option<&str>,
    expected: &str,
    command: &str,
    tolerance: Tolerance,
) -> Result<(), String> {
    let lines: Vec<&str> = text.lines().collect();
    let found: Vec<usize> = (0..lines.len())
        .filter(|&i| lines[i].contains(anchor))
        .collect();
    let at = match found[..] {
        [i] => i,
        [] => {
            return Err(format!(
                "{doc}: no line contains the anchor `{anchor}`, where `{command}`'s measured \
                 figure `{expected}` is expected: restore the line or move the test's anchor"
            ))
        }
        _ => {
            let nums: Vec<String> = found.iter().map(|i| (i + 1).to_string()).collect();
            return Err(format!(
                "{doc}: the anchor `{anchor}` is on lines {}: make it name one line",
                nums.join(", ")
            ));
        }
    };
    let line = lines[at];
    let (place, says) = match column {
        None => (format!("{doc}:{}", at + 1), line.trim().to_string()),
        Some(col) => {
            let cell = table_cell(&lines, at, col)
                .map_err(|e| format!("{doc}:{}: the row with `{anchor}`: {e}", at + 1))?;
            (
                format!("{doc}:{}, column `{col}`", at + 1),
                cell.to_string(),
            )
        }
    };
    let quoted = if tolerance != Tolerance::EXACT {
        contains_near(&says, expected, tolerance)
    } else {
        contains_figure(&says, expected)
    };
    if quoted {
        return Ok(());
    }
    Err(format!(
        "{place} (the line with `{anchor}`)\n  the document says: {says}\n  measured:          \
         {expected}\n  measured by:       `{command}`\n  write `{expected}` there (and check \
         the prose around it)"
    ))
}

/// The cell of column `column` of the table row `lines[row]`: the header is the first line of
/// the block of table lines (`|…`) the row is in.
fn table_cell<'a>(lines: &[&'a str], row: usize, column: &str) -> Result<&'a str, String> {
    let is_row = |l: &str| l.trim_start().starts_with('|');
    if !is_row(lines[row]) {
        return Err("not a table row".into());
    }
    let mut head = row;
    while head > 0 && is_row(lines[head - 1]) {
        head -= 1;
    }
    if head == row {
        return Err("the anchor is in the table's header row".into());
    }
    let header = cells(lines[head]);
    let index = header
        .iter()
        .position(|h| *h == column)
        .ok_or_else(|| format!("the table has no column `{column}` (its columns: {header:?})"))?;
    cells(lines[row])
        .get(index)
        .copied()
        .ok_or_else(|| format!("the row has no cell for column `{column}`"))
}

/// The trimmed cells of the table row `line` (`| a | b |`).
pub fn cells(line: &str) -> Vec<&str> {
    let t = line.trim();
    let t = t.strip_prefix('|').unwrap_or(t);
    let t = t.strip_suffix('|').unwrap_or(t);
    t.split('|').map(str::trim).collect()
}

/// Whether `figure` occurs in `text` as a whole: not inside a longer number or word (`3,240`
/// is not in `13,240` nor in `3,2405`; `0.32` not in `0.325`).
fn contains_figure(text: &str, figure: &str) -> bool {
    if figure.is_empty() {
        return true;
    }
    let part_of = |c: Option<char>, beyond: Option<char>| match c {
        Some(c) if c.is_alphanumeric() => true,
        // A separator joining the figure to more digits: `3,2405`, `1.0.32`.
        Some('.' | ',') => beyond.is_some_and(|b| b.is_ascii_digit()),
        _ => false,
    };
    text.match_indices(figure).any(|(i, _)| {
        let mut before = text[..i].chars().rev();
        let mut after = text[i + figure.len()..].chars();
        let (b, bb) = (before.next(), before.next());
        let (a, aa) = (after.next(), after.next());
        let first = figure.chars().next();
        let last = figure.chars().last();
        // The neighbours only matter where the figure itself begins or ends with a word
        // character (`9.2 M + ` may be followed by anything).
        let clean_start = !first.is_some_and(|c| c.is_alphanumeric()) || !part_of(b, bb);
        let clean_end = !last.is_some_and(|c| c.is_alphanumeric()) || !part_of(a, aa);
        clean_start && clean_end
    })
}

/// A number of a figure at the start of `s` (digits with `,` groups and one `.`): its value,
/// the unit of its last digit and its length in bytes.
fn number_at(s: &str) -> Option<(f64, f64, usize)> {
    let b = s.as_bytes();
    let mut end = 0;
    let mut decimals = None;
    while end < b.len() {
        let c = b[end];
        let next_digit = b.get(end + 1).is_some_and(u8::is_ascii_digit);
        if c.is_ascii_digit() {
            decimals = decimals.map(|d: i32| d + 1);
        } else if c == b',' && decimals.is_none() && next_digit && end > 0 {
        } else if c == b'.' && decimals.is_none() && next_digit && end > 0 {
            decimals = Some(0);
        } else {
            break;
        }
        end += 1;
    }
    if end == 0 || !b[0].is_ascii_digit() {
        return None;
    }
    let value: f64 = s[..end].replace(',', "").parse().ok()?;
    Some((value, 10f64.powi(-decimals.unwrap_or(0)), end))
}

/// How far a quoted number may be from the measured one: `relative` of it plus `absolute`
/// (plus half a unit of its last quoted digit, when not exact).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Tolerance {
    relative: f64,
    absolute: f64,
}

impl Tolerance {
    /// The quoted text is the measured one.
    const EXACT: Tolerance = Tolerance {
        relative: 0.0,
        absolute: 0.0,
    };
}

/// Whether `text` holds `figure` with its words as written and each of its numbers within
/// `tolerance` of it (plus half a unit of the number's last quoted digit).
fn contains_near(text: &str, figure: &str, tolerance: Tolerance) -> bool {
    let matches_at = |mut t: &str| {
        let mut f = figure;
        while !f.is_empty() {
            match number_at(f) {
                Some((want, _, flen)) => {
                    let Some((got, unit, tlen)) = number_at(t) else {
                        return false;
                    };
                    let allowed = tolerance.relative * want.abs() + tolerance.absolute;
                    if (got - want).abs() > allowed + 0.5 * unit + 1e-12 {
                        return false;
                    }
                    f = &f[flen..];
                    t = &t[tlen..];
                }
                None => {
                    let c = f.chars().next().unwrap_or(' ');
                    if !t.starts_with(c) {
                        return false;
                    }
                    f = &f[c.len_utf8()..];
                    t = &t[c.len_utf8()..];
                }
            }
        }
        true
    };
    text.char_indices().any(|(i, _)| {
        // A number of the figure must not start inside a number of the text.
        let inside = text[..i].chars().last().is_some_and(|c| c.is_ascii_digit());
        !(inside && figure.starts_with(|c: char| c.is_ascii_digit())) && matches_at(&text[i..])
    })
}

#[cfg(test)]
mod tests {
    #[test]
    fn estimates_match_within_their_tolerance() {
        let rel = super::Tolerance {
            relative: 0.01,
            absolute: 0.0,
        };
        let cell = "**61.8–69.1 k** (0.52–0.58 of the 120,000 budget)";
        assert!(super::contains_near(cell, "**61.8–69.0 k**", rel));
        assert!(super::contains_near(cell, "0.51–0.58 of the 120,000", rel));
        assert!(!super::contains_near(cell, "**60.0–69.0 k**", rel));
        assert!(!super::contains_near(cell, "**61.8–69.0 M**", rel));
        assert!(!super::contains_near("161.8 k", "61.8 k", rel));
    }

    #[test]
    fn tick_counts_match_within_a_tick() {
        let tick = super::Tolerance {
            relative: 0.0,
            absolute: 40.0,
        };
        let cell = "**38,400** instructions";
        assert!(super::contains_near(cell, "**38,440** instructions", tick));
        assert!(super::contains_near(cell, "**38,360** instructions", tick));
        assert!(!super::contains_near(cell, "**38,480** instructions", tick));
        assert!(!super::contains_near(cell, "**38,440** cycles", tick));
        assert!(!super::contains_near("138,400", "38,400", tick));
    }

    use super::*;

    const DOC: &str = "# T\n\nThe figures are the worst over those 18 logs.\n\n\
        | kind | worst | mean |\n|---|---|---|\n| steady cycle | 3,240 (ceiling 3,300) | 2,387 |\n\
        | the board's whole cycle | **38,520** | 2,568 |\n";

    #[test]
    fn numbers_are_written_as_the_documents_write_them() {
        assert_eq!(thousands(0), "0");
        assert_eq!(thousands(18), "18");
        assert_eq!(thousands(999), "999");
        assert_eq!(thousands(1_000), "1,000");
        assert_eq!(thousands(38_360), "38,360");
        assert_eq!(thousands(120_000), "120,000");
        assert_eq!(thousands(9_216_000), "9,216,000");
        assert_eq!(sci(1.96e-11, 2), "2.0e-11");
        assert_eq!(sci(5.27e-11, 2), "5.3e-11");
        assert_eq!(sci(1e-9, 1), "1e-9");
    }

    #[test]
    fn a_figure_is_found_in_its_row_and_cell() {
        let ok = |anchor, column, expected| check_text("T", DOC, anchor, column, expected, "c");
        assert!(ok("worst over those", None, "18 logs").is_ok());
        assert!(ok("steady cycle", Some("worst"), "3,240").is_ok());
        assert!(ok("steady cycle", Some("mean"), "2,387").is_ok());
        assert!(ok("whole cycle", Some("worst"), "38,520").is_ok());
        // In the row, not in that cell.
        assert!(ok("steady cycle", None, "2,387").is_ok());
        let e = ok("steady cycle", Some("worst"), "2,387").unwrap_err();
        assert!(e.contains("says: 3,240 (ceiling 3,300)"), "{e}");
        assert!(e.contains("measured:          2,387"), "{e}");
        assert!(e.contains("`c`"), "{e}");
    }

    #[test]
    fn a_figure_inside_a_longer_one_is_not_found() {
        let ok = |anchor, expected| check_text("T", DOC, anchor, None, expected, "c");
        assert!(ok("steady cycle", "240").is_err());
        assert!(ok("steady cycle", "3,24").is_err());
        assert!(ok("steady cycle", "3,2").is_err());
        assert!(ok("steady cycle", "2,38").is_err());
        assert!(ok("worst over", "8 logs").is_err());
        assert!(contains_figure("0.32 of", "0.32"));
        assert!(!contains_figure("0.325 of", "0.32"));
        assert!(contains_figure("9.2 M + 9.2 M states", "9.2 M + "));
        assert!(contains_figure("9.2 M + 9.2 M states", "+ 9.2 M states"));
        assert!(!contains_figure("19.2 M + 9.2 M states", "9.2 M + "));
        assert!(contains_figure("COG 2.0e-11 m, ZMP", "COG 2.0e-11 m"));
    }

    #[test]
    fn an_anchor_names_one_line() {
        let e = check_text("T", DOC, "cycle", None, "3,240", "c").unwrap_err();
        assert!(e.contains("is on lines 7, 8"), "{e}");
        let e = check_text("T", DOC, "no such row", None, "3,240", "c").unwrap_err();
        assert!(e.contains("no line contains"), "{e}");
        let e = check_text("T", DOC, "steady", Some("best"), "3,240", "c").unwrap_err();
        assert!(e.contains("no column `best`"), "{e}");
    }
}
