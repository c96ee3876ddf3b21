#!/usr/bin/env bash
# Runs every test binary of the workspace many times and reports each binary's failures:
# a test that fails one run in a few hundred shows up here before it turns CI red.
#
#   scripts/flake-hunt.sh [N] [N_SLOW]     (defaults: 200 and 30)
#
# Each binary is built once (`cargo test --workspace --all-features --no-run`), timed on one
# run, then run N times (N_SLOW times when one run takes longer than FLAKE_SLOW_SECONDS,
# default 2) from its package's directory, as cargo test runs it. Proptests draw fresh
# random seeds on every run (no PROPTEST_RNG_SEED is set; the proptest-regressions files
# replay past failures first). Doctests are not test binaries and are not repeated here.
#
# The output of every failing run is kept under target/flake-hunt/. Prints a table (binary,
# runs, failures, seconds per run) and exits 1 when any run failed.
#
# FLAKE_ONLY=REGEX hunts only the binaries whose file name (e.g. `serial-<hash>`,
# `idu_gimbal-<hash>` for the core's unit tests) matches REGEX: a re-run over what a
# change touched.
#
# FLAKE_LOAD=K keeps K busy loops running beside the tests (default 0): a test that races a
# child process or a reader thread fails far more often on a loaded machine, as CI's is.
set -euo pipefail
cd "$(dirname "$0")/.."

N="${1:-200}"
N_SLOW="${2:-30}"
SLOW_SECONDS="${FLAKE_SLOW_SECONDS:-2}"
LOAD="${FLAKE_LOAD:-0}"
case "$N$N_SLOW" in
    *[!0-9]*) echo "flake-hunt: N and N_SLOW must be whole numbers (got '$N', '$N_SLOW')" >&2; exit 2 ;;
esac
case "$LOAD" in
    '' | *[!0-9]*) echo "flake-hunt: FLAKE_LOAD must be a whole number of busy loops (got '$LOAD')" >&2; exit 2 ;;
esac
unset PROPTEST_RNG_SEED PROPTEST_CASES || true

out="$PWD/target/flake-hunt"
rm -rf "$out"
mkdir -p "$out"

# "executable<TAB>package directory" of every test binary. A build that fails ends the
# hunt (exit 1) with the compiler's errors, which the JSON carries.
build=0
cargo test --workspace --all-features --no-run --message-format=json >"$out/build.json" \
    2>"$out/build.log" || build=$?
python3 - "$out/build.json" "$build" >"$out/all.tsv" <<'PY'
import json, os, sys
failed = sys.argv[2] != "0"
binaries = set()
with open(sys.argv[1]) as f:
    for line in f:
        try:
            m = json.loads(line)
        except ValueError:
            continue
        if m.get("reason") == "compiler-artifact" and m.get("profile", {}).get("test") and m.get("executable"):
            binaries.add(m["executable"] + "\t" + os.path.dirname(m["manifest_path"]))
        elif failed and m.get("reason") == "compiler-message" and m["message"].get("level") == "error":
            sys.stderr.write(m["message"].get("rendered") or m["message"].get("message", "") + "\n")
if binaries:
    print("\n".join(sorted(binaries)))
PY
if [ "$build" -ne 0 ]; then
    echo "flake-hunt: the test binaries did not build (exit $build; cargo's log: $out/build.log)" >&2
    exit 1
fi
if [ -n "${FLAKE_ONLY:-}" ]; then
    awk -F'\t' -v re="$FLAKE_ONLY" '{ n = $1; sub(/.*\//, "", n); if (n ~ re) print }' "$out/all.tsv" > "$out/binaries.tsv"
else
    cp "$out/all.tsv" "$out/binaries.tsv"
fi

count=$(wc -l < "$out/binaries.tsv")
echo "flake-hunt: $count test binaries; N=$N, N_SLOW=$N_SLOW (slow: over ${SLOW_SECONDS}s a run), $LOAD busy loop(s) beside"
load_pids=()
stop_load() { [ "${#load_pids[@]}" -eq 0 ] || kill "${load_pids[@]}" 2>/dev/null || true; }
trap stop_load EXIT
for _ in $(seq 1 "$LOAD"); do
    sh -c 'while :; do :; done' &
    load_pids+=("$!")
done
start_all=$(date +%s)
total_failures=0
printf '| binary | runs | failures | seconds a run |\n|---|---:|---:|---:|\n' > "$out/summary.md"
while IFS=$'\t' read -r exe dir; do
    name=$(basename "$exe")
    t0=$(date +%s.%N)
    if ! (cd "$dir" && "$exe" -q > "$out/$name.first.log" 2>&1); then
        first_failed=1
    else
        first_failed=0
    fi
    t1=$(date +%s.%N)
    per_run=$(python3 -c "print(f'{$t1 - $t0:.2f}')")
    runs=$N
    if python3 -c "import sys; sys.exit(0 if $t1 - $t0 > $SLOW_SECONDS else 1)"; then
        runs=$N_SLOW
    fi
    failures=$first_failed
    [ "$first_failed" = 1 ] && cp "$out/$name.first.log" "$out/$name.fail-0.log"
    for i in $(seq 2 "$runs"); do
        if ! (cd "$dir" && "$exe" -q > "$out/$name.log" 2>&1); then
            failures=$((failures + 1))
            cp "$out/$name.log" "$out/$name.fail-$i.log"
        fi
    done
    total_failures=$((total_failures + failures))
    printf '| %s | %d | %d | %s |\n' "$name" "$runs" "$failures" "$per_run" | tee -a "$out/summary.md"
done < "$out/binaries.tsv"
end_all=$(date +%s)
echo
cat "$out/summary.md"
echo
echo "flake-hunt: $total_failures failure(s) in $((end_all - start_all)) s; failing runs' output in $out/"
[ "$total_failures" -eq 0 ]
