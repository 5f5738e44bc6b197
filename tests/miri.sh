#!/usr/bin/env bash
# planner-core under Miri (the MIR interpreter: undefined behaviour, out-of-bounds and
# uninitialised reads, invalid arithmetic on pointers, leaks), bounded for CI.
#
#     bash tests/miri.sh              (from any directory; about 3 minutes on 2 cores)
#     MIRI_ALL=1 bash tests/miri.sh   every test of planner-core (far beyond an hour: local only)
#
# 1. installs the nightly toolchain with the miri and rust-src components if missing
#    (`rustup toolchain install nightly --profile minimal -c miri,rust-src`; an existing
#    nightly only gets the missing components: it is not updated);
# 2. `cargo +nightly miri setup` (builds the Miri sysroot once, cached in ~/.cache/miri);
# 3. `cargo +nightly miri test -p planner-core` on the selection below, with Miri's default
#    (strict) flags: isolation on, Stacked Borrows, leak check. MIRIFLAGS from the environment
#    is passed through (e.g. MIRIFLAGS=-Zmiri-tree-borrows).
#
# Target directory: target/miri (MIRI_TARGET_DIR overrides), so that the stable build cache in
# target/ is left alone.
#
# libm: libm 0.2.16 computes sqrt/sqrtf with inline assembly (`sqrtsd`/`sqrtss`, its default
# "arch" feature) on x86_64, which Miri cannot interpret ("unsupported operation: inline
# assembly is not supported"; first hit in real::tests::f32_and_f64_agree_on_the_functions_used
# and tests/precision.rs). Not undefined behaviour. This script therefore builds with
# `--features libm/force-soft-floats` (its own feature set, in target/miri only): libm's
# portable sqrt, which is correctly rounded like the instruction, so the results are the same.
# Nothing else changes (planner-core has `#![deny(unsafe_code)]`; what Miri checks here is the
# dependencies it uses: nalgebra, heapless, libm, and the std/core code they reach).
#
# Selection. Miri is ~10^3-10^4 times slower than native code; most planner-core tests are
# numerical (dense oracles, proptest, long walks) and take minutes to hours under it. Their
# counts are fixed in the test files (`cases: 256` / `cases: 64` in explicit ProptestConfigs,
# so PROPTEST_CASES has no effect), so a test either runs whole or is skipped.
# Measured on this machine (2 cores, nightly 2026-05-19 miri, while other builds kept the load
# average at 7-8: an unloaded CI runner should be faster); one `cargo miri test --exact <name>`
# each, wall time including ~4-5 s of cargo/Miri start-up, timeout 60 s; the oracle times are
# per-test times from one run of the whole binary:
#
#   --lib (16 tests)
#     lipm::tests::a_and_big_a_are_inverse                              6.5 s   run
#     lipm::tests::both_particular_regimes_satisfy_the_pendulum_equation 11.0 s  run
#     lipm::tests::hermite_meets_its_ends                               8.0 s   run
#     lipm::tests::sample_satisfies_the_pendulum_equation               8.7 s   run
#     lipm::tests::vw_and_big_a_give_the_paper_form                     7.3 s   run
#     real::tests::f32_and_f64_agree_on_the_functions_used              6.8 s   run
#     window::tests::bad_timing_is_an_error                             9.1 s   run
#     window::tests::banded_lu_solves_a_dense_check                    11.0 s   run
#     window::tests::z_is_banded_as_documented                          8.7 s   run
#     wire::tests::acks_status_and_stream_round_trip                    5.0 s   run
#     wire::tests::bad_frames_are_rejected_with_a_reason                5.2 s   run
#     wire::tests::crc8_matches_the_autosar_check_value                 5.2 s   run
#     wire::tests::steps_round_trip_at_wire_precision                   7.1 s   run
#     timing::tests::eq17_matches_brute_force_for_zero_end_velocities   > 60 s  skipped
#     timing::tests::general_quartics_match_brute_force                 > 60 s  skipped
#     wire::tests::every_one_two_and_three_bit_error_is_caught          > 60 s  skipped
#   --test precision (1 test)
#     f32_planner_stays_within_a_tenth_of_a_millimetre                  > 60 s  skipped (binary not built)
#   --test oracle (6 tests)
#     bad_durations_are_rejected_with_their_index                       7.0 s   run
#     boundary_conditions_hold                                         17.5 s   run
#     non_finite_boundaries_are_rejected_and_leave_the_plan_untouched   1.5 s   run
#     oracle_detects_a_perturbed_boundary                  99.6 s (38 s at load 2)   run
#     planner_matches_the_general_44_unknown_formulation              > 175 s  skipped
#     rk4_integration_matches_the_closed_form_cog                       > 60 s  skipped
#   --test props (2 proptests, 256 cases each)
#     f32_solver_is_within_a_tenth_of_a_millimetre_of_f64              > 300 s  skipped (binary not built)
#     random_windows_are_c1_and_meet_their_conditions                   > 60 s  skipped
#   --test gait (7 tests)
#     walking_in_place_when_no_step_is_given_then_stopping             40.2 s   run
#     a_refused_modification_changes_nothing                          205.2 s   skipped
#     straight_walk_starts_walks_and_stops_at_rest_between_the_feet     50.0 s  skipped (CI time)
#     the_modification_rule                                             > 75 s  skipped
#     turning_walk_follows_the_yawed_feet                               41.9 s  skipped (CI time)
#     random_walks::random_walks_stay_continuous (proptest, 64 walks)   > 60 s  skipped
#     a_reused_prediction_is_the_plan_itself (new)                    > 540 s  skipped
#   --test node (5 tests)                                                      binary not built
#     a_silent_controller_stops_the_robot                             > 180 s  skipped
#     every_reason_code_is_answered_and_changes_nothing                 > 60 s  skipped
#     one_planning_command_per_cycle                                    > 60 s  skipped
#     repeats_are_duplicates_whatever_happened_since                    > 60 s  skipped
#     the_stream_carries_the_gaits_reference                            > 60 s  skipped
#   --test shaping (8 tests: each builds preview gains / dense batch references)  binary not built
#     every test (a_..., b_..., c_..., d_..., e_..., errors_are_reported_not_panicked) > 60 s  skipped
#
# So the CI run covers the LIPM closed forms, the banded LU of the window solver
# (window::tests), the CAN codec (wire::tests), the plan's error paths and boundary conditions
# (oracle) and a whole gait from rest to rest (walking in place): about a minute measured. Whole binaries whose every test
# is too slow (precision, props, node, shaping) are not built at all, which also saves their
# Miri start-up.
#
# The `--skip` filters are substrings matched against every test name of every selected binary;
# the names are unique in planner-core. A test added later runs by default: if it is too slow
# under Miri, add it to SKIP below with its measured time.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

TOOLCHAIN=nightly

# Each section's header says when it starts, counted from the outermost script's start.
export WALK_RUN_START="${WALK_RUN_START:-$(date +%s)}"
section() {
    printf '\n==== %s ==== (at %d s)\n' "$*" "$(($(date +%s) - WALK_RUN_START))"
}

section "miri toolchain"
if ! command -v rustup >/dev/null 2>&1; then
    echo "rustup not found: install Rust with rustup (https://rustup.rs) first" >&2
    exit 1
fi
if ! rustup toolchain list | grep -q "^${TOOLCHAIN}-"; then
    echo "installing toolchain $TOOLCHAIN with miri and rust-src"
    rustup toolchain install "$TOOLCHAIN" --profile minimal -c miri,rust-src
fi
installed_components="$(rustup +"$TOOLCHAIN" component list --installed)"
for component in miri rust-src; do
    if ! grep -q "^${component}" <<<"$installed_components"; then
        echo "installing component $component ($TOOLCHAIN)"
        rustup component add --toolchain "$TOOLCHAIN" "$component"
    fi
done
cargo +"$TOOLCHAIN" miri --version

export CARGO_TARGET_DIR="${MIRI_TARGET_DIR:-$ROOT/target/miri}"
export CARGO_TERM_COLOR="${CARGO_TERM_COLOR:-never}"

section "cargo miri setup"
cargo +"$TOOLCHAIN" miri setup

# Binaries and tests left out (measured times above).
TARGETS=(--lib --test oracle --test gait)
SKIP=(
    # --lib
    timing::tests::eq17_matches_brute_force_for_zero_end_velocities
    timing::tests::general_quartics_match_brute_force
    wire::tests::every_one_two_and_three_bit_error_is_caught
    # 65,790 footstep frames decoded (every queued number and every alias 256·k older): run by
    # `cargo test`
    wire::tests::step_numbers_alias_never_by_their_high_byte
    # 2,000 random frames × 256 keys × 2 identifiers of CRC-8 (over 2 min under Miri): run by
    # `cargo test`
    wire::tests::exactly_one_step_key_matches_any_footstep_frame
    # added with the structured solver and the encoding (thousands of cases each; not measured under
    # Miri, > 60 s by their host times): run by `cargo test`
    timing::tests::random_quartics_match_brute_force
    window::tests::structured_elimination_agrees_with_banded_lu_over_many_timings
    wire::tests::round_to_i32_is_libm_round_saturated
    # the f32 path of the same (400,000 cases; not measured under Miri): run by `cargo test`
    wire::tests::round_to_i32_of_f32_is_libm_roundf_saturated
    # a million f32 values; 300 window solves into a reused buffer (not measured under Miri):
    # run by `cargo test`
    trig::tests::single_precision_sine_and_cosine_are_accurate
    # the f64 sine and cosine against libm's (12.4 million arguments; not measured under Miri):
    # run by `cargo test`
    trig::tests::double_precision_sine_and_cosine_are_libms_within_an_ulp
    window::tests::a_reused_plan_buffer_gives_the_fresh_plan
    # the root search's step count over 2,000 quartics against a grid (not measured under Miri):
    # run by `cargo test`
    timing::tests::the_search_takes_few_steps
    # 2,000 random batches of frames ordered both ways (not measured under Miri; pure
    # integer code on fixed arrays): run by `cargo test`
    node::cycle::tests::the_acting_order_is_the_scanned_one
    # the timing's table and the particular solutions over 6-8 interval lengths each, compared
    # with their series (minutes under Miri together): run by `cargo test`
    window::rhs::tests
    # 200 random windows planned whole and sampled interval by interval (not measured under
    # Miri; the rhs tests beside it run the same table and particulars): run by `cargo test`
    window::tests::a_sample_without_a_plan_is_the_plan_s
    # footsteps from a velocity: plain arithmetic over the reach check, which the gait's walk
    # below runs too: run by `cargo test`
    velocity::tests
    # --test oracle
    planner_matches_the_general_44_unknown_formulation
    rk4_integration_matches_the_closed_form_cog
    # the same solves as boundary_conditions_hold, perturbed (38-100 s under Miri): run by
    # `cargo test`
    oracle_detects_a_perturbed_boundary
    # --test gait
    a_refused_modification_changes_nothing
    the_modification_rule
    random_walks_stay_continuous
    a_reused_prediction_is_the_plan_itself   # > 9 min
    # two more whole walks (50 s and 42 s): walking in place keeps a gait from rest to rest
    straight_walk_starts_walks_and_stops_at_rest_between_the_feet
    turning_walk_follows_the_yawed_feet
    # six walks of 24 steps with lookups checked along (not measured under Miri; a walk of a few
    # steps takes ~40 s there): run by `cargo test`
    lookups_by_id_match_a_search_of_the_queue
)

if [ "${MIRI_ALL:-0}" = 1 ]; then
    TARGETS=(--lib --tests)
    SKIP=()
fi

skip_args=()
for name in "${SKIP[@]}"; do
    skip_args+=(--skip "$name")
done

section "cargo miri test -p planner-core (${#SKIP[@]} --skip filters)"
start=$SECONDS
cargo +"$TOOLCHAIN" miri test -p planner-core --features libm/force-soft-floats "${TARGETS[@]}" \
    -- "${skip_args[@]}"
echo "miri: $((SECONDS - start)) s"
