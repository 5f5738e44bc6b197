#!/usr/bin/env bash
# Runs every test of the repository on a fresh machine: the one command for a newcomer.
#
#     bash tests/run-all.sh          (from any directory)
#
# 1. installs what rustup can provide and the build needs (the thumbv7em-none-eabihf target,
#    clippy, rustfmt) if it is missing, QEMU (qemu-system-arm, apt-get), and the CAN tools the
#    can.log test reads with (can-utils, apt-get; python-can and cantools, pip), the Python
#    MCAP reader the walk.mcap test reads with (mcap, zstandard, jsonschema; pip), and the
#    physics engine (MuJoCo 3.2.7, pip), the robot descriptions and their oracle
#    (example-robot-data 6.0.0 and pin 4.1.0, pip), the ROS 2 peer of the gateway's tests
#    (cyclonedds 11.0.1, pip), and LAPACK for the comparison bench (liblapack-dev, apt-get);
# 2. the host workspace: unit, integration and bench targets, then the doctests (this includes
#    firmware/board-core, the board's CAN adapter, pacer and reset reason on a mock FDCAN);
# 3. planner-core cross-compiled for the Cortex-M (no_std, no allocator);
# 4. the firmware images: the STM32H743 one (workspace firmware/; its flash and RAM checked
#    against firmware/README.md by firmware/size.sh) and the QEMU one
#    (firmware/qemu; the walk-tests QEMU test in step 2 builds and runs it, which needs
#    qemu-system-arm: step 1 installs it with apt-get), and the M4F one (firmware/qemu with
#    the `m4f` feature: the f32 node on QEMU's mps2-an386, built for the Cortex-M4 into
#    firmware/qemu/target/m4f; tests/tests/qemu_m4.rs in step 2 builds and runs it);
# 5. the book in docs/ (mdBook: built, and its Rust code blocks compiled and run);
# 6. Miri on planner-core (tests/miri.sh: a nightly toolchain with miri, installed if missing;
#    about 4 minutes; WALK_SKIP_MIRI=1 leaves it out).
#
# WALK_LONG=1 makes the long runs for a release: the fault sweep with 10 seeds per row and 40
# per heavier mixed row, 2,048 random programs of the protocol property test (each can also be
# set alone: WALK_FAULT_SEEDS, WALK_FAULT_HEAVY_SEEDS, WALK_PROTOCOL_CASES), and the MuJoCo
# runs of host-sim/tests/physics.rs that take minutes: the full Tables I/II grid (with the full
# and with the weakest stabilizer) and every fault-sweep row in the engine (both walks).
set -euo pipefail

if [ "${WALK_LONG:-0}" = 1 ]; then
    export WALK_FAULT_SEEDS="${WALK_FAULT_SEEDS:-10}"
    export WALK_FAULT_HEAVY_SEEDS="${WALK_FAULT_HEAVY_SEEDS:-40}"
    export WALK_PROTOCOL_CASES="${WALK_PROTOCOL_CASES:-2048}"
fi

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

TARGET=thumbv7em-none-eabihf

# Each section's header says when it starts, counted from the outermost script's start.
export WALK_RUN_START="${WALK_RUN_START:-$(date +%s)}"
section() {
    printf '\n==== %s ==== (at %d s)\n' "$*" "$(($(date +%s) - WALK_RUN_START))"
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

# QEMU (Debian's qemu-system-arm, 7.2 on Debian 12) for the firmware's instruction-counted
# timing checks under mps2-an500 (tests/tests/qemu.rs fails without it unless
# WALK_SKIP_QEMU=1).
if ! command -v qemu-system-arm >/dev/null 2>&1; then
    echo "installing qemu-system-arm"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -q
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q qemu-system-arm
fi
qemu-system-arm --version | head -n 1

# --- host-sim plots: a TrueType font (Debian's fonts-dejavu-core) -------------------------
# host-sim/src/output/plot renders the PNG text with DejaVu Sans read at run time (or the font
# named by HOST_SIM_FONT); the plot tests fail without one.
if [ -z "${HOST_SIM_FONT:-}" ] && [ ! -f /usr/share/fonts/truetype/dejavu/DejaVuSans.ttf ]; then
    echo "installing fonts-dejavu-core"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -q
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q fonts-dejavu-core
fi
# --- end host-sim plots ------------------------------------------------------------------

# --- LAPACK for the comparison bench (planner-core/benches/compare) -----------------------
# Debian's reference LAPACK with its link-time library (liblapack-dev): the bench links
# -llapack, and step 2 builds and runs it in test mode.
if ! dpkg-query -W -f='${Status}' liblapack-dev 2>/dev/null | grep -q "ok installed"; then
    echo "installing liblapack-dev"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -q
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q liblapack-dev
fi
# --- end LAPACK -----------------------------------------------------------------------------

# --- llvm-mca and llvm-objdump for the M7/M4F cycle estimate (tests/tests/cycles.rs) --------
# Debian's llvm (its Cortex-M7 and Cortex-M4 scheduling models); WALK_SKIP_LLVM_MCA=1 skips
# the estimate's test instead.
if [ "${WALK_SKIP_LLVM_MCA:-0}" != 1 ] && ! command -v llvm-mca >/dev/null 2>&1; then
    echo "installing llvm (llvm-mca, llvm-objdump)"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -q
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q llvm
fi
# --- end llvm ---------------------------------------------------------------------------------

# --- the real CAN tools that read host-sim's can.log (host-sim/tests/canlog.rs) -----------
# Debian's can-utils (log2asc, asc2log), python-can and cantools (for the python3 on PATH;
# cantools for the example controller, host-sim/tests/controller.rs). With
# WALK_REQUIRE_CAN_TOOLS=1 the test fails instead of skipping when one is missing.
if ! command -v log2asc >/dev/null 2>&1 || ! command -v asc2log >/dev/null 2>&1; then
    echo "installing can-utils"
    SUDO=""
    if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
    $SUDO apt-get update -q
    $SUDO env DEBIAN_FRONTEND=noninteractive apt-get install -y -q can-utils
fi
if ! python3 -c "import can, cantools" >/dev/null 2>&1; then
    echo "installing python-can and cantools"
    python3 -m pip install -q python-can cantools
fi
export WALK_REQUIRE_CAN_TOOLS=1
# --- end CAN tools --------------------------------------------------------------------------

# --- the Python MCAP reader that reads host-sim's walk.mcap (host-sim/tests/mcap.rs) --------
# PyPI's mcap (with zstandard for the chunks) and jsonschema (each message against its
# channel's schema). With WALK_REQUIRE_MCAP_TOOLS=1 the test fails instead of skipping.
if ! python3 -c "import mcap.reader, zstandard, jsonschema" >/dev/null 2>&1; then
    echo "installing the Python mcap reader and jsonschema"
    python3 -m pip install -q mcap zstandard jsonschema
fi
export WALK_REQUIRE_MCAP_TOOLS=1
# --- end MCAP reader ------------------------------------------------------------------------
# --- MuJoCo, the physics engine of `host-sim physics` (host-sim/tests/physics.rs) ------------
# PyPI's mujoco wheel (it ships libmujoco and numpy comes with it) for the python3 on PATH,
# pinned to the version host-sim/src/physics/bridge.rs is written for. With
# WALK_REQUIRE_MUJOCO=1 the physics tests fail instead of skipping when it is missing.
MUJOCO_VERSION=3.2.7
if [ "$(python3 -c 'import mujoco; print(mujoco.__version__)' 2>/dev/null)" != "$MUJOCO_VERSION" ]; then
    echo "installing mujoco==$MUJOCO_VERSION"
    python3 -m pip install -q "mujoco==$MUJOCO_VERSION"
fi
export WALK_REQUIRE_MUJOCO=1
# --- end MuJoCo -------------------------------------------------------------------------------
# --- robots from their packages (host-sim/tests/import.rs) -----------------------------------
# PyPI's example-robot-data (Talos, Unitree G1 and others: their URDFs, used where pip puts
# them; none of their files is in this repository) and Pinocchio (`pin`), the oracle of the
# imported multi-body models. With WALK_REQUIRE_ROBOT_DATA=1 the import tests fail instead of
# skipping when one is missing.
ROBOT_DATA_VERSION=6.0.0
PIN_VERSION=4.1.0
if [ "$(python3 -c 'import importlib.metadata as m; print(m.version("example-robot-data"))' 2>/dev/null)" != "$ROBOT_DATA_VERSION" ] \
    || [ "$(python3 -c 'import pinocchio; print(pinocchio.__version__)' 2>/dev/null)" != "$PIN_VERSION" ]; then
    echo "installing example-robot-data==$ROBOT_DATA_VERSION pin==$PIN_VERSION"
    python3 -m pip install -q "example-robot-data==$ROBOT_DATA_VERSION" "pin==$PIN_VERSION"
fi
export WALK_REQUIRE_ROBOT_DATA=1
# --- end robots from their packages -----------------------------------------------------------

# --- the ROS 2 peer of the gateway's tests (host-sim/tests/ros2.rs) ---------------------------
# PyPI's cyclonedds (Eclipse Cyclone DDS with its Python binding): the independent ROS 2 peer
# that drives `host-sim ros2`. With WALK_REQUIRE_ROS2=1 the tests fail instead of skipping.
CYCLONEDDS_VERSION=11.0.1
if [ "$(python3 -c 'import importlib.metadata as m; print(m.version("cyclonedds"))' 2>/dev/null)" != "$CYCLONEDDS_VERSION" ]; then
    echo "installing cyclonedds==$CYCLONEDDS_VERSION"
    python3 -m pip install -q "cyclonedds==$CYCLONEDDS_VERSION"
fi
export WALK_REQUIRE_ROS2=1
# --- end ROS 2 peer ---------------------------------------------------------------------------

# --- the live view's test client (host-sim/tests/live.rs) -------------------------------------
# PyPI's websockets (a client of the Foxglove WebSocket protocol) and jsonschema. With
# WALK_REQUIRE_LIVE=1 the tests fail instead of skipping.
if ! python3 -c "import websockets, jsonschema" >/dev/null 2>&1; then
    echo "installing websockets and jsonschema"
    python3 -m pip install -q websockets jsonschema
fi
export WALK_REQUIRE_LIVE=1
# --- end live view ----------------------------------------------------------------------------

LOG="$(mktemp)"
trap 'rm -f "$LOG"' EXIT

section "host workspace: doctests"
cargo test --workspace --doc 2>&1 | tee -a "$LOG"

section "host workspace: cargo test --workspace --all-targets"
cargo test --workspace --all-targets 2>&1 | tee -a "$LOG"

section "protocol model check (stateright, release; WALK_LONG=1: the larger bound)"
cargo test --release -p planner-core --test model_check -- --nocapture 2>&1 | tee -a "$LOG"

section "host-sim with the SocketCAN backend (compile test: no CAN interface here)"
cargo build -p host-sim --features socketcan

section "planner-core for $TARGET (no_std)"
cargo build -p planner-core --target "$TARGET"

section "firmware images (release)"
image_size() {
    if command -v llvm-size >/dev/null 2>&1; then
        llvm-size "$1"
    elif command -v arm-none-eabi-size >/dev/null 2>&1; then
        arm-none-eabi-size "$1"
    else
        ls -l "$1"
    fi
}
# The STM32H743 image (workspace firmware/: app + board) and the QEMU image (its own
# workspace firmware/qemu, built and run by tests/tests/qemu.rs above).
(
    cd firmware
    cargo build --release
    elf="target/$TARGET/release/board"
    test -f "$elf"
    image_size "$elf"
)
# The board image's flash and RAM as firmware/README.md quotes them (fails if they differ). The
# size tool: llvm-size, else rustup's llvm-tools component (installed here if neither is there).
if ! command -v llvm-size >/dev/null 2>&1 && ! command -v arm-none-eabi-size >/dev/null 2>&1 &&
    ! ls "$(rustc --print sysroot)"/lib/rustlib/*/bin/llvm-size >/dev/null 2>&1; then
    echo "installing component llvm-tools"
    rustup component add llvm-tools
fi
bash firmware/size.sh --check
(
    cd firmware/qemu
    cargo build --release
    elf="target/$TARGET/release/qemu"
    test -f "$elf"
    image_size "$elf"
)
# The M4F image (the f32 node; Cortex-M4 rustflags, so a target dir of its own), built and run
# by tests/tests/qemu_m4.rs above.
(
    cd firmware/qemu
    RUSTFLAGS="-C target-cpu=cortex-m4" cargo build --release --features m4f --target-dir target/m4f
    elf="target/m4f/$TARGET/release/qemu"
    test -f "$elf"
    image_size "$elf"
)

section "the book (docs/): mdbook build, and mdbook test of its Rust code against planner-core"
# mdbook from crates.io (installed if missing, without its file watcher, web server and search index). Its
# Rust code blocks are compiled and run against planner-core, built into a target dir of its
# own so that rustdoc finds exactly one planner_core library.
MDBOOK_VERSION=0.5.4
if [ "$(mdbook --version 2>/dev/null)" != "mdbook v$MDBOOK_VERSION" ]; then
    echo "installing mdbook $MDBOOK_VERSION"
    cargo install --locked mdbook --version "$MDBOOK_VERSION" --no-default-features
fi
cargo build -q -p planner-core --target-dir target/book
mdbook build docs --dest-dir "$(mktemp -d)"
mdbook test docs -L target/book/debug/deps 2>&1 | tee -a "$LOG"

section "Miri: planner-core under the interpreter (nightly toolchain, bounded selection)"
# tests/miri.sh installs the nightly toolchain with miri if missing; WALK_SKIP_MIRI=1 skips.
if [ "${WALK_SKIP_MIRI:-0}" = 1 ]; then
    echo "skipped (WALK_SKIP_MIRI=1)"
else
    bash tests/miri.sh 2>&1 | tee -a "$LOG"
fi

section "all tests passed"
# One closing line for the whole run (cargo prints one "test result" line per test binary).
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($i ~ /^passed;?$/) p += $(i-1); if ($i ~ /^failed;?$/) f += $(i-1) } }
     END { printf "%d passed, %d failed\n", p, f }' "$LOG"
