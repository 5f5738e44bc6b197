#!/bin/sh
# The runner of `cargo run` in firmware/ (.cargo/config.toml): flashes the board image with
# probe-rs and shows its defmt log. Without probe-rs on PATH it says how to install it, in one
# line, instead of cargo's bare "could not execute process".
if ! command -v probe-rs >/dev/null 2>&1; then
    echo "probe-rs is not installed (it flashes the image just built, $1): install it with" \
        "\`cargo install probe-rs-tools --locked\` or its installer" \
        "(https://probe.rs/docs/getting-started/installation/), then run again" >&2
    exit 127
fi
exec probe-rs run --chip STM32H743ZITx "$@"
