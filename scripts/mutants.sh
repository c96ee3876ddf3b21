#!/usr/bin/env bash
# Mutation testing of the core's codecs, link and drivers with cargo-mutants: every mutant
# (an operator flipped, a function body replaced by a default, a condition forced) should
# make some test fail. Exit status 1 when fewer than 95 % of the viable mutants are caught.
#
#   scripts/mutants.sh [--file GLOB]... [other cargo-mutants arguments]
#
# Scope: package idu-gimbal, files src/wire/**, src/link/** (tests.rs excluded: it is the
# tests) and src/driver/** (and src/driver.rs, the layout before the serial transport), or
# the --file globs given. Installs cargo-mutants (`cargo install --locked`) when missing.
#
# Settings (environment): MUTANTS_JOBS (default 1: each job builds its own copy of the tree,
# and the machine has 2 cores), MUTANTS_TIMEOUT (seconds per mutant's tests, default 300),
# PROPTEST_CASES (default 32: the proptests still run, on fewer cases, which keeps a mutant's
# test run near 30 s; a mutant only a rare case would catch is then reported as missed, which
# errs on the safe side). Timeouts count as caught (a mutant that makes the tests hang is
# detected) and are listed.
#
# Cost: about 1,000 mutants in the full scope; at 30 to 60 s each (an incremental build and
# the test suite) that is 8 to 16 hours on one job: run it on a quiet machine, or scope it
# with --file. Not part of CI. Results: target/mutants/mutants.out/ (outcomes.json,
# missed.txt, caught.txt, timeout.txt, unviable.txt).
set -euo pipefail
cd "$(dirname "$0")/.."

if ! cargo mutants --version >/dev/null 2>&1; then
    echo "installing cargo-mutants" >&2
    cargo install --locked cargo-mutants
fi

files=()
for arg in "$@"; do
    [ "$arg" = "--file" ] && files=(override)
done
if [ "${#files[@]}" -eq 0 ]; then
    set -- --file 'src/wire/**' --file 'src/link/**' --file 'src/driver/**' --file src/driver.rs \
        --exclude src/link/tests.rs "$@"
fi

export PROPTEST_CASES="${PROPTEST_CASES:-32}"
out=target/mutants
mkdir -p "$out"
status=0
cargo mutants --package idu-gimbal --all-features \
    --jobs "${MUTANTS_JOBS:-1}" --timeout "${MUTANTS_TIMEOUT:-300}" \
    --output "$out" "$@" || status=$?
# cargo-mutants exits 2 when mutants were missed, 3 on timeouts: the score decides here.
case "$status" in 0 | 2 | 3) ;; *) exit "$status" ;; esac

results="$out/mutants.out"
count() { [ -f "$results/$1.txt" ] && grep -c . "$results/$1.txt" || echo 0; }
caught=$(count caught)
missed=$(count missed)
timeout=$(count timeout)
unviable=$(count unviable)
viable=$((caught + missed + timeout))
echo
echo "mutants: $viable viable ($caught caught, $timeout timed out, $missed missed), $unviable unviable"
if [ "$viable" -eq 0 ]; then
    echo "mutants: nothing viable was tested" >&2
    exit 1
fi
score=$(( (caught + timeout) * 1000 / viable ))
echo "mutants: score $((score / 10)).$((score % 10)) % (caught and timed out over viable; goal 95 %)"
if [ "$missed" -gt 0 ]; then
    echo "missed:"
    sed 's/^/  /' "$results/missed.txt"
fi
[ "$score" -ge 950 ]
