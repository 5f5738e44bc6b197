//! The board's link set-up: the top-level `memory.x` and `board/stack.x` copied into OUT_DIR
//! (on this package's linker search path), linked with cortex-m-rt's `link.x` and defmt's
//! `defmt.x`, as `board/build.rs` does. The image is laid out like the board's.

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let memory_x = manifest.join("..").join("..").join("memory.x");
    let stack_x = manifest.join("..").join("board").join("stack.x");
    for (from, name) in [(&memory_x, "memory.x"), (&stack_x, "stack.x")] {
        let text = fs::read(from).unwrap_or_else(|e| panic!("cannot read {}: {e}", from.display()));
        fs::write(out.join(name), text)
            .unwrap_or_else(|e| panic!("cannot write {name} into OUT_DIR: {e}"));
        println!("cargo:rerun-if-changed={}", from.display());
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    println!("cargo:rustc-link-arg-bins=-Tstack.x");
    println!("cargo:rerun-if-changed=build.rs");
}
