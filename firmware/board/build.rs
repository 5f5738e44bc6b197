//! Puts the top-level `memory.x` (STM32H743 layout) where cortex-m-rt's `link.x` can `INCLUDE`
//! it (a copy in OUT_DIR, and OUT_DIR on this package's linker search path), and links with
//! cortex-m-rt's and defmt's linker scripts and with `stack.x` (this package's: the stack in
//! the lower 64 KiB of the DTCM, below .data and .bss, see that file).

use std::env;
use std::fs;
use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR"));
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let memory_x = manifest.join("..").join("..").join("memory.x");

    let layout =
        fs::read(&memory_x).unwrap_or_else(|e| panic!("cannot read {}: {e}", memory_x.display()));
    fs::write(out.join("memory.x"), layout).expect("cannot write memory.x into OUT_DIR");
    let stack_x = manifest.join("stack.x");
    let stack =
        fs::read(&stack_x).unwrap_or_else(|e| panic!("cannot read {}: {e}", stack_x.display()));
    fs::write(out.join("stack.x"), stack).expect("cannot write stack.x into OUT_DIR");

    println!("cargo:rustc-link-search={}", out.display());
    // cortex-m-rt's linker script (it INCLUDEs memory.x) and defmt's (interned strings).
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
    println!("cargo:rustc-link-arg-bins=-Tstack.x");
    println!("cargo:rerun-if-changed={}", memory_x.display());
    println!("cargo:rerun-if-changed={}", stack_x.display());
    println!("cargo:rerun-if-changed=build.rs");
}
