#!/usr/bin/env bash
# Host decode benchmark: `gimbalctl decode` against
# `python3 -m cantools decode` (cantools 45, benches/host/gimbal.dbc) on the same generated
# `candump -L` log, in the same run.
#
#   bash benches/host/compare.sh
#
# Goals: gimbalctl >= 1.7M lines/s and >= 50x cantools' lines/s; exit 1 if either is missed.
# Also reports gimbalctl's peak RSS on a 1M-line and a 10M-line log (streaming: it should
# not grow with the log).
#
# Method: both tools read the log from stdin (`< log`) and write to /dev/null, with their
# default output (cantools' multi-line form, gimbalctl's JSON lines). gimbalctl: RUNS runs
# over the whole LINES-line log, the median is the figure (min and max are shown).
# cantools: one run over the first CANTOOLS_LINES lines of the same log (the whole log by
# default, ~20-30 s), its interpreter start-up included. lines/s = lines / wall time.
#
# Environment: LINES (1000000), BIG_LINES (10000000), CANTOOLS_LINES (LINES), RUNS (5),
# SEED (7), WORK (target/hostbench: logs and the cantools venv).
set -euo pipefail
cd "$(dirname "$0")/../.."

LINES=${LINES:-1000000}
BIG_LINES=${BIG_LINES:-10000000}
CANTOOLS_LINES=${CANTOOLS_LINES:-$LINES}
RUNS=${RUNS:-5}
SEED=${SEED:-7}
WORK=${WORK:-target/hostbench}
MIN_LPS=1700000
MIN_RATIO=50
GEN=benches/host/gen_log.py
DBC=benches/host/gimbal.dbc
BIN=target/release/gimbalctl

mkdir -p "$WORK"

# --- tools ---------------------------------------------------------------------------
have_cantools() {
    "$1" -c 'import sys, cantools; sys.exit(0 if cantools.__version__.startswith("45.") else 1)' \
        2>/dev/null
}
PY=$WORK/venv/bin/python
if ! have_cantools "$PY"; then
    # A venv of its own, so that the pinned cantools never meets the system's packages;
    # Debian keeps venv's pip bootstrap in python3-venv (scripts/firmware-env.sh's apt-get).
    if ! python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then
        . scripts/firmware-env.sh
        echo "compare: installing python3-venv" >&2
        _apt_install python3-venv
    fi
    python3 -m venv "$WORK/venv"
    "$PY" -m pip install -q 'cantools==45.*'
fi
have_cantools "$PY" || { echo "compare: cannot install cantools 45" >&2; exit 1; }
CANTOOLS_VERSION=$("$PY" -c 'import cantools; print(cantools.__version__)')

if [ ! -x /usr/bin/time ]; then
    echo "compare: installing GNU time" >&2
    if [ "$(id -u)" = 0 ]; then
        (apt-get install -y -qq time >/dev/null 2>&1 || { apt-get update -qq && apt-get install -y -qq time; }) >&2
    else
        (sudo apt-get install -y -qq time || { sudo apt-get update -qq && sudo apt-get install -y -qq time; }) >&2
    fi
fi

cargo build --release -q -p gimbalctl

# --- logs ----------------------------------------------------------------------------
# Regenerated when missing or older than the generator.
gen() { # gen LINES FILE
    if [ ! -s "$2" ] || [ "$GEN" -nt "$2" ]; then
        python3 "$GEN" "$1" --seed "$SEED" > "$2.tmp" && mv "$2.tmp" "$2"
    fi
}
LOG=$WORK/log-$LINES-seed$SEED.log
BIG=$WORK/log-$BIG_LINES-seed$SEED.log
CT_LOG=$WORK/cantools-$CANTOOLS_LINES-of-$LINES-seed$SEED.log
gen "$LINES" "$LOG"
gen "$BIG_LINES" "$BIG"
if [ "$CANTOOLS_LINES" = "$LINES" ]; then
    CT_LOG=$LOG
elif [ ! -s "$CT_LOG" ] || [ "$LOG" -nt "$CT_LOG" ]; then
    head -n "$CANTOOLS_LINES" "$LOG" > "$CT_LOG"
fi

# --- the inputs are what they should be ----------------------------------------------
# Control frames match `gimbalctl encode`, and every generated line is one message.
python3 "$GEN" --verify "$BIN" --seed "$SEED"
# gimbalctl decodes every line of the benchmark log, none malformed or foreign.
stats=$("$BIN" decode --stats < "$LOG" | tail -n 1)
want="{\"type\":\"stats\",\"lines\":$LINES,\"frames\":$LINES,\"messages\":$LINES,\"crc_errors\":0,\"incomplete\":0,\"malformed_lines\":0,\"foreign_frames\":0}"
[ "$stats" = "$want" ] || { echo "compare: gimbalctl on $LOG: $stats" >&2; exit 1; }
# cantools decodes every line of a sample with the DBC (a decoded frame's header line ends
# in ` ::`; an unknown or undecodable one has its error after the `::`).
head -n 20000 "$LOG" > "$WORK/sample.log"
ok=$("$PY" -m cantools decode "$DBC" < "$WORK/sample.log" | grep -c ' ::$' || true)
[ "$ok" = 20000 ] || { echo "compare: cantools decoded $ok of 20000 sample lines" >&2; exit 1; }

# --- timing --------------------------------------------------------------------------
now_ns() { date +%s%N; }
seconds() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.6f", (b - a) / 1e9 }'; }

t0=$(now_ns)
"$PY" -m cantools decode "$DBC" < "$CT_LOG" > /dev/null
t1=$(now_ns)
ct_s=$(seconds "$t0" "$t1")

times=()
for _ in $(seq "$RUNS"); do
    t0=$(now_ns)
    "$BIN" decode < "$LOG" > /dev/null
    t1=$(now_ns)
    times+=("$(seconds "$t0" "$t1")")
done
read -r g_min g_med g_max < <(printf '%s\n' "${times[@]}" | sort -g |
    awk '{ t[NR] = $1 } END { print t[1], t[int((NR + 1) / 2)], t[NR] }')

# --- peak RSS ------------------------------------------------------------------------
rss_kib() { # rss_kib FILE -> peak RSS in KiB of `gimbalctl decode < FILE`
    /usr/bin/time -f '%M' -o "$WORK/time.out" "$BIN" decode < "$1" > /dev/null
    tail -n 1 "$WORK/time.out"
}
rss_1m=$(rss_kib "$LOG")
t0=$(now_ns)
rss_10m=$(rss_kib "$BIG")
t1=$(now_ns)
big_s=$(seconds "$t0" "$t1")

# --- report --------------------------------------------------------------------------
ct_lps=$(awk -v n="$CANTOOLS_LINES" -v s="$ct_s" 'BEGIN { printf "%.0f", n / s }')
g_lps=$(awk -v n="$LINES" -v s="$g_med" 'BEGIN { printf "%.0f", n / s }')
g_best=$(awk -v n="$LINES" -v s="$g_min" 'BEGIN { printf "%.0f", n / s }')
g_worst=$(awk -v n="$LINES" -v s="$g_max" 'BEGIN { printf "%.0f", n / s }')
big_lps=$(awk -v n="$BIG_LINES" -v s="$big_s" 'BEGIN { printf "%.0f", n / s }')
ratio=$(awk -v a="$g_lps" -v b="$ct_lps" 'BEGIN { printf "%.1f", a / b }')

cat <<EOF
host decode benchmark: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')
log: $LINES lines of candump -L (seed $SEED): attitude/GPS/altitude/control frames, all valid
cantools $CANTOOLS_VERSION decode ($CANTOOLS_LINES lines, 1 run):   $(printf '%9s' "$ct_lps") lines/s  (${ct_s} s)
gimbalctl decode ($LINES lines, median of $RUNS): $(printf '%9s' "$g_lps") lines/s  (${g_med} s; best $g_best, worst $g_worst lines/s)
ratio gimbalctl/cantools:                  ${ratio}x
gimbalctl peak RSS:  $rss_1m KiB at $LINES lines,  $rss_10m KiB at $BIG_LINES lines  ($big_lps lines/s on the $BIG_LINES-line log)
EOF

fail=0
if [ "$g_lps" -lt "$MIN_LPS" ]; then
    echo "FAIL: gimbalctl $g_lps lines/s < $MIN_LPS"
    fail=1
fi
if awk -v r="$ratio" -v m="$MIN_RATIO" 'BEGIN { exit !(r < m) }'; then
    echo "FAIL: ratio ${ratio}x < ${MIN_RATIO}x"
    fail=1
fi
[ "$fail" = 0 ] && echo "PASS: >= $MIN_LPS lines/s and >= ${MIN_RATIO}x cantools"
exit "$fail"
