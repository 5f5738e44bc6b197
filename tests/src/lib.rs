//! End-to-end checks, and what the firmware tests share.

use std::process::Command;

/// A `cargo` command run in `dir` (a firmware workspace) with this test's own build settings
/// removed, so that they do not leak into the firmware's build: its target and rustflags come
/// from `firmware/.cargo/config.toml`.
pub fn firmware_cargo(dir: &std::path::Path) -> Command {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(dir);
    for var in [
        "CARGO_TARGET_DIR",
        "CARGO_BUILD_TARGET",
        "CARGO_BUILD_TARGET_DIR",
        "RUSTFLAGS",
        "CARGO_ENCODED_RUSTFLAGS",
        "CARGO_BUILD_RUSTFLAGS",
    ] {
        cmd.env_remove(var);
    }
    cmd
}

/// The QEMU images' report lines (`KIND key=value …`), as the QEMU tests read them.
pub mod report {
    use std::collections::BTreeMap;

    /// One output line: its keyword and `key=value` fields.
    #[derive(Debug, Clone)]
    pub struct Record {
        /// The first word.
        pub kind: String,
        /// The `key=value` words.
        pub fields: BTreeMap<String, String>,
    }

    impl Record {
        /// The line's record; `None` for an empty line.
        pub fn parse(line: &str) -> Option<Record> {
            let mut words = line.split_whitespace();
            let kind = words.next()?.to_string();
            let fields = words
                .filter_map(|w| w.split_once('='))
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            Some(Record { kind, fields })
        }

        /// Field `key` (panics if missing: the image's report is malformed).
        pub fn get(&self, key: &str) -> &str {
            self.fields
                .get(key)
                .unwrap_or_else(|| panic!("{} line without `{key}`: {:?}", self.kind, self.fields))
        }

        /// Field `key` as a number (panics if it is not one).
        pub fn num<T: std::str::FromStr>(&self, key: &str) -> T {
            let v = self.get(key);
            v.parse()
                .unwrap_or_else(|_| panic!("{} line: `{key}={v}` is not a number", self.kind))
        }
    }

    /// The last `n` lines of `s`.
    pub fn tail(s: &str, n: usize) -> String {
        let lines: Vec<&str> = s.lines().collect();
        lines[lines.len().saturating_sub(n)..].join("\n")
    }
}
