#!/usr/bin/env bash
# The board image's flash and static RAM, from the build: the line firmware/README.md quotes.
#
#     bash firmware/size.sh           builds the board image (release) and prints the line
#     bash firmware/size.sh --check   ... and fails if firmware/README.md, the front page's headline row or the
#                                     timing chapter (docs/src/timing.md) does not quote it
#                                     (tests/run-all.sh runs this, so the figures cannot go stale)
#
# Either fails when the image is over its targets (flash 136 KB, static RAM 32 KB) or
# when .data holds more than 1 KiB (the parked node must stay all zero bytes, in .bss).
#
# Needs an `llvm-size` (LLVM on PATH, or rustup's llvm-tools component: `rustup component add
# llvm-tools`) or `arm-none-eabi-size`; all print the same `-A` table.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")"

size_tool() {
    if command -v llvm-size >/dev/null 2>&1; then
        echo llvm-size
        return
    fi
    local sysroot
    sysroot="$(rustc --print sysroot)"
    for t in "$sysroot"/lib/rustlib/*/bin/llvm-size; do
        if [ -x "$t" ]; then
            echo "$t"
            return
        fi
    done
    if command -v arm-none-eabi-size >/dev/null 2>&1; then
        echo arm-none-eabi-size
        return
    fi
    echo "no llvm-size: install LLVM or run \`rustup component add llvm-tools\`" >&2
    exit 1
}

cargo build --release -p firmware-board >&2
elf=target/thumbv7em-none-eabihf/release/board
table="$("$(size_tool)" -A "$elf")"
section() {
    awk -v s="$1" '$1 == s { print $2; found = 1 } END { if (!found) print 0 }' <<<"$table"
}
vt=$(section .vector_table)
text=$(section .text)
rodata=$(section .rodata)
data=$(section .data)
bss=$(section .bss)
uninit=$(section .uninit)
flash=$((vt + text + rodata + data))
ram=$((data + bss + uninit))
line="board image: flash ${flash} B (.vector_table ${vt}, .text ${text}, .rodata ${rodata}, .data ${data}); static RAM ${ram} B (.data ${data}, .bss ${bss}, .uninit ${uninit})"
echo "$line"
# The board image's targets: flash <= 136 KB, static RAM <= 32 KB (1 KB = 1000 B, as the
# READMEs quote sizes). 136 KB: room above the ~112 KB that the fault path, the TX FIFO, the
# bus-off back-off, the message RAM failure recovery, the run-time clock plan, the bounded
# HSE start, the node's step adjustment from the measured state, its ranked receive take,
# the bus-off path's bus monitoring, the per-cycle work budget, the reach checks' kept frames
# and the pair solves of the two planes, with the node's velocity and goal walking (~13 KB: the
# step generator, the re-plan of the queued steps) (of the STM32H743's 2 MB).
if [ "$flash" -gt 136000 ] || [ "$ram" -gt 32000 ]; then
    echo "the board image is over its targets (flash <= 136000 B, static RAM <= 32000 B)" >&2
    exit 1
fi
# The node's `static` is parked (`Node::parked`: every byte zero) so that it lives in .bss; a
# value with a non-zero byte would put its 14 KB into .data, i.e. into flash as well.
if [ "$data" -gt 1024 ]; then
    echo ".data is ${data} B: a large static has a non-zero initializer (is the node's parked" >&2
    echo "value still all zero bytes? see planner_core::node::Node::parked)" >&2
    exit 1
fi
if [ "${1:-}" = "--check" ]; then
    if ! grep -qF -- "$line" README.md; then
        echo "firmware/README.md does not quote the board image's sizes; expected the line:" >&2
        echo "    $line" >&2
        exit 1
    fi
    echo "firmware/README.md quotes these sizes"
    # The front page's headline row, with thousands separators.
    sep() { echo "$1" | sed -e ':a' -e 's/\B[0-9]\{3\}\>/,&/' -e 'ta'; }
    headline="flash $(sep "$flash") B, static RAM $(sep "$ram") B"
    if ! grep -F -- "| board image (STM32H743) |" ../README.md | grep -qF -- "$headline"; then
        echo "README.md's board image row does not say: $headline" >&2
        exit 1
    fi
    echo "README.md's headline row quotes them"
    # The book's timing chapter, in KB to one decimal.
    kb() { awk -v b="$1" 'BEGIN { printf "%.1f KB", b / 1000 }'; }
    book="is $(kb "$flash") of flash (the target 136 KB"
    if ! grep -qF -- "$book" ../docs/src/timing.md; then
        echo "docs/src/timing.md does not say: $book" >&2
        exit 1
    fi
    book="and $(kb "$ram") of static RAM"
    if ! grep -qF -- "$book" ../docs/src/timing.md; then
        echo "docs/src/timing.md does not say: $book" >&2
        exit 1
    fi
    book="Of the flash, $(sep "$rodata") B are"
    if ! grep -qF -- "$book" ../docs/src/timing.md; then
        echo "docs/src/timing.md does not say: $book" >&2
        exit 1
    fi
    echo "docs/src/timing.md quotes the flash, its read-only data and the static RAM"
fi
