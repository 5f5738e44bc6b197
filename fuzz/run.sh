#!/usr/bin/env bash
# Bounded fuzzing of the CAN codec, the node, the QEMU image's log decoder and the host's text
# decoders (cargo-fuzz / libFuzzer), on the stable toolchain.
#
#   bash fuzz/run.sh                 # every target, FUZZ_SECONDS (30) each
#   FUZZ_SECONDS=600 bash fuzz/run.sh node
#   FUZZ_SANITIZER=address bash fuzz/run.sh   # ASan: needs -Zsanitizer, so RUSTC_BOOTSTRAP=1
#
# libFuzzer per target, starting from corpus/<target>/ and writing what it finds to a scratch
# directory (the committed seeds stay as they are). The deterministic replay of the committed
# corpus plus pseudo-random inputs is a test of the root workspace (`cargo test -p walk-fuzz`,
# no libFuzzer; the crate is a workspace member, linted and formatted with the others). A crash
# fails the script; its input is in fuzz/artifacts/<target>/ (replay: cargo fuzz run <target>
# --features libfuzzer -s none <file>).
#
# The default sanitizer is none: planner-core and this crate have no `unsafe` code, so coverage
# guidance and the assertions are what matters, and `-s none` needs no nightly flags.
set -euo pipefail

FUZZ_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$FUZZ_DIR"

SECONDS_PER_TARGET="${FUZZ_SECONDS:-30}"
SANITIZER="${FUZZ_SANITIZER:-none}"
CARGO_FUZZ_VERSION="0.13.2"
TARGETS=("$@")
if [ "${#TARGETS[@]}" -eq 0 ]; then
    TARGETS=(decode node text wlog)
fi

if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "installing cargo-fuzz $CARGO_FUZZ_VERSION"
    cargo install --locked cargo-fuzz --version "$CARGO_FUZZ_VERSION"
fi
if [ "$SANITIZER" != "none" ]; then
    export RUSTC_BOOTSTRAP=1 # -Zsanitizer on the stable toolchain
fi

scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT
for target in "${TARGETS[@]}"; do
    echo "== cargo fuzz run $target (${SECONDS_PER_TARGET} s, sanitizer $SANITIZER)"
    mkdir -p "$scratch/$target"
    log="$scratch/$target.log"
    status=0
    cargo fuzz run "$target" --features libfuzzer -s "$SANITIZER" \
        "$scratch/$target" "corpus/$target" -- \
        -max_total_time="$SECONDS_PER_TARGET" -print_final_stats=1 >"$log" 2>&1 || status=$?
    grep -E '^(Done|stat::number_of_executed_units|stat::peak_rss_mb)|#[0-9]+ +DONE' "$log" || true
    if [ "$status" -ne 0 ]; then
        tail -n 60 "$log"
        echo "fuzz target $target failed (exit $status); inputs in $FUZZ_DIR/artifacts/$target/" >&2
        exit "$status"
    fi
    echo "$target: new corpus entries: $(find "$scratch/$target" -type f | wc -l), crashes: 0"
done
