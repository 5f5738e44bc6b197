//! End-to-end checks, and what the firmware tests share.

use std::process::Command;

pub use doc_figures as figures;
pub mod logs;
pub mod trace;

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
        "WALK_ROBOT",
    ] {
        cmd.env_remove(var);
    }
    cmd
}

/// The QEMU images' report lines (`KIND key=value …`), as the QEMU tests read them.
pub mod report {
    use std::collections::BTreeMap;
    use std::path::Path;
    use std::process::Command;

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

    /// What one QEMU run printed.
    pub struct QemuRun {
        /// Everything it printed.
        pub stdout: String,
        /// Its lines' records.
        pub records: Vec<Record>,
    }

    impl QemuRun {
        /// The records of `kind`.
        pub fn all<'a>(&'a self, kind: &'a str) -> impl Iterator<Item = &'a Record> + 'a {
            self.records.iter().filter(move |r| r.kind == kind)
        }

        /// The records of `kind` for log `scenario`.
        pub fn of<'a>(
            &'a self,
            kind: &'a str,
            scenario: &'a str,
        ) -> impl Iterator<Item = &'a Record> + 'a {
            self.all(kind)
                .filter(move |r| r.get("scenario") == scenario)
        }

        /// The one record of `kind` (panics unless there is exactly one).
        pub fn one<'a>(&'a self, kind: &'a str) -> &'a Record {
            let mut it = self.all(kind);
            let r = it
                .next()
                .unwrap_or_else(|| panic!("no {kind} line in the QEMU output"));
            assert!(it.next().is_none(), "more than one {kind} line");
            r
        }

        /// The one record of `kind` for log `scenario` (panics unless there is exactly one).
        pub fn one_of<'a>(&'a self, kind: &'a str, scenario: &'a str) -> &'a Record {
            let mut it = self.of(kind, scenario);
            let r = it
                .next()
                .unwrap_or_else(|| panic!("no {kind} line for {scenario}"));
            assert!(
                it.next().is_none(),
                "more than one {kind} line for {scenario}"
            );
            r
        }

        /// The `TIMING` record of `kind` for `scenario` (`all`: over every log).
        pub fn timing<'a>(&'a self, scenario: &'a str, kind: &'a str) -> Option<&'a Record> {
            self.of("TIMING", scenario).find(|r| r.get("kind") == kind)
        }
    }

    /// Runs a QEMU image (`elf`, on QEMU machine `machine`, counting instructions with
    /// `-icount shift=0`, semihosting on) in `dir`, which holds its input files; its exit code
    /// and output (the run is stopped after 300 s: exit code 124).
    pub fn qemu(machine: &str, elf: &Path, dir: &Path) -> std::process::Output {
        qemu_with(machine, elf, dir, &[])
    }

    /// [`qemu`] with further arguments for QEMU (e.g. `-append overflow`, the image's
    /// semihosting command line).
    pub fn qemu_with(machine: &str, elf: &Path, dir: &Path, args: &[&str]) -> std::process::Output {
        Command::new("timeout")
            .arg("300")
            .args(["qemu-system-arm", "-M", machine, "-nographic"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .args(["-icount", "shift=0"])
            .arg("-kernel")
            .arg(elf)
            .args(args)
            .current_dir(dir)
            .output()
            .expect("cannot run timeout/qemu-system-arm")
    }

    /// [`qemu`], which must succeed and print a `DONE` line; its report.
    pub fn run_qemu(machine: &str, elf: &Path, dir: &Path) -> QemuRun {
        let out = qemu(machine, elf, dir);
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "QEMU exited with {:?} (124: timed out)\nstdout (tail):\n{}\nstderr:\n{}",
            out.status.code(),
            tail(&stdout, 20),
            String::from_utf8_lossy(&out.stderr)
        );
        let records = stdout.lines().filter_map(Record::parse).collect();
        let run = QemuRun { stdout, records };
        assert!(run.all("DONE").next().is_some(), "no DONE line");
        run
    }

    /// The last `n` lines of `s`.
    pub fn tail(s: &str, n: usize) -> String {
        let lines: Vec<&str> = s.lines().collect();
        lines[lines.len().saturating_sub(n)..].join("\n")
    }
}

/// `false` when `qemu-system-arm` is missing and `WALK_SKIP_QEMU=1`; panics when it is missing
/// otherwise.
pub fn qemu_available() -> bool {
    let found = Command::new("qemu-system-arm")
        .arg("--version")
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if found {
        return true;
    }
    if std::env::var("WALK_SKIP_QEMU").as_deref() == Ok("1") {
        eprintln!("qemu-system-arm not found: QEMU checks skipped (WALK_SKIP_QEMU=1)");
        return false;
    }
    panic!(
        "qemu-system-arm not found: run tests/run-all.sh (it installs Debian's qemu-system-arm), \
         or `apt-get install qemu-system-arm`; set WALK_SKIP_QEMU=1 to skip the QEMU checks"
    );
}

/// `cargo build --release` in `firmware/<dir>` (a workspace with its own target dir); the ELF
/// `target/thumbv7em-none-eabihf/release/<bin>`.
pub fn build_firmware(dir: &str, bin: &str) -> std::path::PathBuf {
    build_firmware_with(dir, bin, None, &[], "target")
}

/// [`build_firmware`] with `RUSTFLAGS` (e.g. another `target-cpu`), further arguments (e.g.
/// `--features`) and a target dir of its own (relative to `firmware/<dir>`, so that builds with
/// other flags do not replace each other's); the ELF
/// `<target_dir>/thumbv7em-none-eabihf/release/<bin>`.
pub fn build_firmware_with(
    dir: &str,
    bin: &str,
    rustflags: Option<&str>,
    args: &[&str],
    target_dir: &str,
) -> std::path::PathBuf {
    build_firmware_env(dir, bin, rustflags, args, target_dir, &[])
}

/// [`build_firmware_with`] with environment variables for the build (e.g. `WALK_ROBOT`, the
/// robot file `firmware/robot` compiles in).
pub fn build_firmware_env(
    dir: &str,
    bin: &str,
    rustflags: Option<&str>,
    args: &[&str],
    target_dir: &str,
    envs: &[(&str, &std::ffi::OsStr)],
) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("firmware")
        .join(dir);
    let mut cmd = firmware_cargo(&dir);
    for (k, v) in envs {
        cmd.env(k, v);
    }
    if let Some(flags) = rustflags {
        cmd.env("RUSTFLAGS", flags);
    }
    let out = cmd
        .args(["build", "--release", "--target-dir", target_dir])
        .args(args)
        .output()
        .expect("cannot run cargo");
    assert!(
        out.status.success(),
        "building {} failed:\n{}",
        dir.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let elf = dir
        .join(target_dir)
        .join("thumbv7em-none-eabihf/release")
        .join(bin);
    assert!(elf.is_file(), "no image at {}", elf.display());
    elf
}

/// The size of section `name` of the 32-bit little-endian ELF file `elf` (the firmware
/// images), from its section headers; `None` if the file is not such an ELF or has no such
/// section.
pub fn elf32_section_size(elf: &std::path::Path, name: &str) -> Option<u32> {
    let b = std::fs::read(elf).ok()?;
    let u16_at = |o: usize| Some(u16::from_le_bytes(b.get(o..o + 2)?.try_into().ok()?));
    let u32_at = |o: usize| Some(u32::from_le_bytes(b.get(o..o + 4)?.try_into().ok()?));
    // ELFCLASS32, little-endian.
    if b.get(0..6)? != [0x7F, b'E', b'L', b'F', 1, 1] {
        return None;
    }
    let shoff = u32_at(0x20)? as usize;
    let shentsize = usize::from(u16_at(0x2E)?);
    let shnum = usize::from(u16_at(0x30)?);
    let shstrndx = usize::from(u16_at(0x32)?);
    let header = |i: usize| shoff + i * shentsize;
    let strtab = u32_at(header(shstrndx) + 16)? as usize;
    (0..shnum).find_map(|i| {
        let h = header(i);
        let name_at = strtab + u32_at(h)? as usize;
        let end = name_at + b.get(name_at..)?.iter().position(|&c| c == 0)?;
        (b.get(name_at..end)? == name.as_bytes())
            .then(|| u32_at(h + 20))
            .flatten()
    })
}

/// Asserts that the firmware image `elf` keeps its parked node in .bss: .data at most 1 KiB (a
/// non-zero byte in `ParkedNode::new`'s value would move the node's kilobytes there, and so into
/// flash) and .bss at least `min_bss` bytes (the node is there).
pub fn assert_parked_node_in_bss(elf: &std::path::Path, min_bss: u32) {
    let data = elf32_section_size(elf, ".data").unwrap_or(0);
    let bss = elf32_section_size(elf, ".bss").expect("no .bss");
    assert!(
        data <= 1024,
        ".data is {data} B: the parked node is not all zero bytes"
    );
    assert!(bss >= min_bss, ".bss is {bss} B: where is the node?");
}
