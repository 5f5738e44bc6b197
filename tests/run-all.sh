#!/usr/bin/env bash
# Runs every test of the repository on a fresh machine: the one command for a newcomer.
#
#     bash tests/run-all.sh          (from any directory)
#
# 1. installs what rustup can provide and the build needs (the thumbv7em-none-eabihf target,
#    clippy, rustfmt) if it is missing;
# 2. the host workspace: unit, integration and bench targets, then the doctests;
# 3. planner-core cross-compiled for the Cortex-M (no_std, no allocator);
# 4. the firmware image (its own workspace in firmware/).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

TARGET=thumbv7em-none-eabihf

section() {
    printf '\n==== %s ====\n' "$*"
}

section "toolchain"
if ! command -v rustup >/dev/null 2>&1; then
    echo "rustup not found: install Rust with rustup (https://rustup.rs) first" >&2
    exit 1
fi
# rustup acts on the toolchain selected for this directory (a rust-toolchain file, if any).
if ! grep -qx "$TARGET" <<<"$(rustup target list --installed)"; then
    echo "installing target $TARGET"
    rustup target add "$TARGET"
fi
installed_components="$(rustup component list --installed)"
for component in clippy rustfmt; do
    if ! grep -q "^${component}" <<<"$installed_components"; then
        echo "installing component $component"
        rustup component add "$component"
    fi
done
rustc --version
cargo --version

LOG="$(mktemp)"
trap 'rm -f "$LOG"' EXIT

section "host workspace: doctests"
cargo test --workspace --doc 2>&1 | tee -a "$LOG"

section "host workspace: cargo test --workspace --all-targets"
cargo test --workspace --all-targets 2>&1 | tee -a "$LOG"

section "planner-core for $TARGET (no_std)"
cargo build -p planner-core --target "$TARGET"

section "firmware (release image)"
(
    cd firmware
    cargo build --release
    elf="target/$TARGET/release/firmware"
    test -f "$elf"
    if command -v llvm-size >/dev/null 2>&1; then
        llvm-size "$elf"
    elif command -v arm-none-eabi-size >/dev/null 2>&1; then
        arm-none-eabi-size "$elf"
    else
        ls -l "$elf"
    fi
)

section "all tests passed"
# One closing line for the whole run (cargo prints one "test result" line per test binary).
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($i ~ /^passed;?$/) p += $(i-1); if ($i ~ /^failed;?$/) f += $(i-1) } }
     END { printf "%d passed, %d failed\n", p, f }' "$LOG"
