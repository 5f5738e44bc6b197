//! A figure a test measured is the one the documents quote: `assert_quoted` finds the one
//! line (or table row) of a document that holds an anchor and asserts it holds the measured
//! figure, naming the command that measures it. (walk-tests' `figures` does this for the other
//! crates' tests; planner-core's tests cannot depend on walk-tests.)

/// Asserts that `doc` (relative to the repository root) quotes `expected` in its one line (or
/// table row) that contains `anchor`; `command` is what measures the figure.
pub fn assert_quoted(command: &str, doc: &str, anchor: &str, expected: &str) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(doc);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{doc}: cannot read {}: {e}", path.display()));
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.contains(anchor))
        .collect();
    let [(at, line)] = lines[..] else {
        panic!(
            "{doc}: the anchor `{anchor}` is on {} lines, not one (where `{command}`'s figure \
             `{expected}` is expected)",
            lines.len()
        );
    };
    assert!(
        line.contains(expected),
        "{doc}:{} (the line with `{anchor}`)\n  the document says: {}\n  measured:          \
         {expected}\n  measured by:       `{command}`\n  write `{expected}` there",
        at + 1,
        line.trim()
    );
}
