//! Puts this package's `memory.x` (QEMU mps2-an500 layout; `memory-m4f.x`, the mps2-an386
//! one, with the `m4f` feature) where cortex-m-rt's `link.x` can `INCLUDE` it (a copy named
//! `memory.x` in OUT_DIR, and OUT_DIR on this package's linker search path), and links with
//! cortex-m-rt's linker script.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let layout_file = if env::var_os("CARGO_FEATURE_M4F").is_some() {
        "memory-m4f.x"
    } else {
        "memory.x"
    };
    let memory_x = manifest.join(layout_file);

    let layout =
        fs::read(&memory_x).unwrap_or_else(|e| panic!("cannot read {}: {e}", memory_x.display()));
    fs::write(out.join("memory.x"), layout).expect("cannot write memory.x into OUT_DIR");

    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!(
        "cargo:rerun-if-changed={}",
        manifest.join("memory.x").display()
    );
    println!(
        "cargo:rerun-if-changed={}",
        manifest.join("memory-m4f.x").display()
    );
    println!("cargo:rerun-if-changed=build.rs");
}
