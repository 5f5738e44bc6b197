#!/usr/bin/env bash
# The control cycles of the QEMU logs in estimated core cycles (Cortex-M7 at 480 MHz; with
# --m4f the f32 image on a Cortex-M4F at 168 MHz), not instructions.
#
#   bash firmware/qemu/cycles.sh [--m4f] [--scenario NAME|FILE.toml|fault-KIND-RATE|all]
#                                [--kinds steady,replan,adjust,start,cycle] [--call N] [--top K]
#
# Builds the QEMU image (release, as tests/tests/qemu.rs runs it; --m4f: the M4F image as
# tests/tests/qemu_m4.rs builds it, into target/m4f) and the `qemu-cycles` tool
# (tests/src/bin/qemu-cycles.rs), records host-sim's run of a scenario (fig4 by default;
# `all`: every log the QEMU tests replay, as they replay them: the figures of
# docs/src/timing.md) as the image's replay log, finds each kind's worst poll from the image's
# own report, traces the image up to it under QEMU (`-d in_asm,exec,nochain`, as
# attribute.sh) and weights every executed block by llvm-mca's cycles for it (-mcpu=cortex-m7
# or cortex-m4; low: steady state, high: a cold pass). It prints its method and assumptions
# (no cache misses, no flash wait states, branches predicted, LLVM's model of the FP divider),
# then per kind: instructions, estimated cycles, cycles per instruction and the share of the
# budget (5 % of 5 ms: 120,000 cycles at 480 MHz, 42,000 at 168 MHz). Needs llvm-mca and
# llvm-objdump (Debian's llvm package: apt-get install llvm). fig4 takes a few seconds, `all`
# about half a minute. tests/tests/cycles.rs checks the figures the documents quote.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
for tool in "${LLVM_MCA:-llvm-mca}" "${LLVM_OBJDUMP:-llvm-objdump}"; do
    command -v "$tool" >/dev/null || {
        echo "cycles.sh: $tool not found (Debian: apt-get install llvm)" >&2
        exit 1
    }
done
ELF="$ROOT/firmware/qemu/target/thumbv7em-none-eabihf/release/qemu"
if [[ " $* " == *" --m4f "* ]]; then
    (cd "$ROOT/firmware/qemu" && env -u CARGO_TARGET_DIR RUSTFLAGS="-C target-cpu=cortex-m4" \
        cargo build --release -q --features m4f --target-dir target/m4f)
    ELF="$ROOT/firmware/qemu/target/m4f/thumbv7em-none-eabihf/release/qemu"
else
    (cd "$ROOT/firmware/qemu" && env -u CARGO_TARGET_DIR -u RUSTFLAGS cargo build --release -q)
fi
cargo build --release -q --manifest-path "$ROOT/Cargo.toml" -p walk-tests --bin qemu-cycles
exec "$ROOT/target/release/qemu-cycles" "$@" "$ELF"
