#!/usr/bin/env bash
# Mutation testing: runs cargo-mutants over the protocol code of `idu-gimbal`
# (src/wire, src/link, src/port), or with `bridge` first over the whole of
# `idu-gimbal-mavlink`'s library, or with `geometry` first over the core's geodesy and
# trigonometry (src/geo.rs, src/math.rs), and fails when fewer than 95% of the viable
# mutants are caught. Not part of CI: too slow. Results and the survivor triage are in TESTING.md,
# "Mutation testing".
#
# Usage: scripts/mutants.sh [bridge|geometry] [extra cargo-mutants args, e.g. --shard 0/16 --sharding round-robin]
#   scripts/mutants.sh bridge --re 'src/framing/'   # the bridge's framing only
#   MUTANTS_JOBS=2 scripts/mutants.sh    # parallel jobs (default 1: the machine has 2 cores)
#   MUTANTS_TIMEOUT=60                   # per-mutant test timeout, seconds (default 30)
#   PROPTEST_CASES=256                   # proptest cases per property (default 32 here)
#
# How long: the core's scope is about 1,260 mutants, the bridge's about 1,570, the
# geometry's 312. Without debug info (CARGO_PROFILE_DEV_DEBUG=0, set here) a core mutant
# costs a few seconds' incremental rebuild and about 6 s of tests; with it the rebuild was
# ~12 s. See TESTING.md for the measured wall time of each scope.
# Narrow a run with `--shard k/n`, `--re REGEX` or `--exclude GLOB` to get an answer sooner
# (an extra `--file` widens the scope: cargo-mutants ORs them).
#
# Choices:
# - Tests run: the library's unit tests, tests/driver_sim.rs and tests/point_at.rs (the
#   integration tests that drive a link and its CAN port over the mock bus), tests/driver_errors.rs
#   and tests/defmt_format.rs (the driver errors' counters and defmt encoding),
#   tests/serial.rs (the serial link and port over the mock pipe) and tests/bounds.rs
#   (the parsers and the link under floods), tests/blocking_adapter.rs (the Blocking
#   adapter's classifier), tests/next_deadline.rs (the ports' next_deadline),
#   tests/api_contracts.rs (the public API's documented contracts) and tests/aiming/ (the
#   closed-loop aim against the simulator). Left out: tests/no_panic.rs (fixed 2000 cases
#   per property, about a minute a run, and it only checks panic-freedom, which the unit
#   tests' proptests also exercise), tests/fuzz_corpus.rs (the same, over the fuzz
#   corpora), tests/geo.rs (src/geo.rs is the `geometry` scope's) and doctests (examples,
#   not checks). The `geometry` scope runs the unit tests, tests/geo.rs and the two that
#   aim through it (tests/point_at.rs, tests/aiming/).
# - PROPTEST_CASES=32 instead of 256: the proptests dominate the test time; 32 cases still
#   cover each property, and the hand-written vectors do the exact checking.
# - --all-features: the port tests need the `mock` bus.
# - Score = caught / (caught + missed); unviable mutants (do not build) are left out.
#   Timeouts count as caught: the timeout (30 s) is over four times the unmutated test
#   time (about 6 s for the core's tests, less for the bridge's), so a mutant that hits it
#   has made the suite hang (e.g. a loop that never ends), which is a detected change of
#   behaviour. They are listed separately in the summary.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! cargo mutants --version >/dev/null 2>&1; then
    cargo install --locked cargo-mutants
fi

jobs="${MUTANTS_JOBS:-1}"
timeout="${MUTANTS_TIMEOUT:-30}"
export PROPTEST_CASES="${PROPTEST_CASES:-32}"
# Debug info makes each mutant's rebuild ~5x slower and is not needed to run tests.
export CARGO_PROFILE_DEV_DEBUG="${CARGO_PROFILE_DEV_DEBUG:-0}"

echo "$(cargo mutants --version), jobs $jobs, timeout ${timeout}s, PROPTEST_CASES $PROPTEST_CASES"
start=$(date +%s)
rc=0
# cargo-mutants with the options every scope shares; the scope's own (package, files,
# excludes), the caller's extra arguments and, after `--`, its tests follow.
mutants() {
    cargo mutants \
        --all-features \
        --timeout "$timeout" \
        --build-timeout 600 \
        --jobs "$jobs" \
        --output . \
        "$@"
}
if [ "${1:-}" = bridge ]; then
    shift
    # The bridge: every test but tests/no_panic.rs (its proptests only check panic-freedom,
    # which the fuzz corpus replayed by tests/fuzz_corpus.rs also covers) and
    # tests/defmt_format.rs (the defmt encoding of types whose logic the others test).
    mutants \
        --package idu-gimbal-mavlink \
        --file 'idu-gimbal-mavlink/src/**' \
        "$@" \
        -- --lib --test aiming --test bridge --test burst --test camera --test camera_control \
        --test camera_fov --test camera_settings --test codec --test commands --test framing \
        --test fuzz_corpus --test signing || rc=$?
elif [ "${1:-}" = geometry ]; then
    shift
    mutants \
        --package idu-gimbal \
        --file src/geo.rs \
        --file src/math.rs \
        "$@" \
        -- --lib --test geo --test point_at --test aiming || rc=$?
else
    # #[cfg(test)] modules are skipped by cargo-mutants; src/link/tests.rs is one by path.
    mutants \
        --package idu-gimbal \
        --file 'src/wire/**' \
        --file 'src/link/**' \
        --file 'src/port/**' \
        --exclude src/link/tests.rs \
        --exclude src/link/deadline_tests.rs \
        --exclude src/port/idle_tests.rs \
        "$@" \
        -- --lib --test driver_sim --test point_at --test driver_errors --test defmt_format \
        --test serial --test bounds --test api_contracts --test blocking_adapter \
        --test next_deadline --test aiming || rc=$?
fi
echo "wall time: $(($(date +%s) - start)) s"

# cargo-mutants exits 2 for missed mutants and 3 for timeouts: the score decides here.
# Any other non-zero code (1 usage, 4 baseline failed) is an error of the run itself.
case "$rc" in
    0 | 2 | 3) ;;
    *)
        echo "cargo mutants failed (exit $rc)" >&2
        exit "$rc"
        ;;
esac

count() { if [ -f "mutants.out/$1.txt" ]; then grep -c . "mutants.out/$1.txt" || true; else echo 0; fi; }
caught=$(count caught)
missed=$(count missed)
timeouts=$(count timeout)
unviable=$(count unviable)
detected=$((caught + timeouts))
viable=$((detected + missed))
echo "caught $caught, missed $missed, timeout $timeouts, unviable $unviable"
if [ "$viable" -eq 0 ]; then
    echo "no viable mutants in scope"
    exit 0
fi
# Score in tenths of a percent, integer arithmetic only.
score=$((detected * 1000 / viable))
echo "score: $detected / $viable = $((score / 10)).$((score % 10))% (goal 95%)"
if [ "$missed" -gt 0 ]; then
    echo "missed:"
    sed 's/^/  /' mutants.out/missed.txt
fi
if [ "$score" -lt 950 ]; then
    exit 1
fi
