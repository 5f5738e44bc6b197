#!/usr/bin/env bash
# cargo's runner for the board image (`cargo run --release` in firmware/): flashes it with
# probe-rs and shows its defmt logs. Without probe-rs, says what to install instead of
# cargo's bare "No such file or directory".
set -euo pipefail
if ! command -v probe-rs >/dev/null 2>&1; then
    echo "probe-rs is not installed: cargo install probe-rs-tools --locked (0.24 or later)," >&2
    echo "then connect an ST-LINK or another probe to the board and run this again." >&2
    exit 127
fi
exec probe-rs run --chip STM32H743ZITx "$@"
