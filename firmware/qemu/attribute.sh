#!/usr/bin/env bash
# Where one control cycle's instructions go, per function, on the emulated Cortex-M7.
#
#   bash firmware/qemu/attribute.sh [qemu-attribute options]
#
# Builds the QEMU image (release, as tests/tests/qemu.rs runs it) and the `qemu-attribute`
# tool (tests/src/bin/qemu-attribute.rs), records host-sim's run of a scenario as the image's
# replay log (`--scenario NAME|FILE.toml|fault-KIND-RATE|worst-PATH` (worst-start, worst-adjusting, worst-report, worst-reach, worst-measured, worst-velocity, worst-velocity-start, worst-goal-start, worst-goal, worst-resume), fig4 by default; the fault
# rows and the worst admissible cycles are the QEMU test's), runs the image on it under QEMU's
# instruction trace and prints, for the `Node::poll` that ran the most instructions (or `--call N`, 0-based; poll N
# is the cycle of tick N+1), its instructions per function: inclusive on the call stack and
# self per source function (inlined included; `--lines` adds source lines). Other options:
# `--stop-after N` (calls), `--top K`, `--function SUBSTR`, `--counts FILE` (every poll's count),
# `--stdout FILE` (the image's own report). A whole run traces in about 20 s.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
(cd "$ROOT/firmware/qemu" && env -u CARGO_TARGET_DIR -u RUSTFLAGS cargo build --release -q)
cargo build --release -q --manifest-path "$ROOT/Cargo.toml" -p walk-tests --bin qemu-attribute
exec "$ROOT/target/release/qemu-attribute" "$@" \
    "$ROOT/firmware/qemu/target/thumbv7em-none-eabihf/release/qemu"
