#!/usr/bin/env bash
# By-hand check: what a real ArduPilot (ArduCopter SITL) reports of a MAVLink gimbal bridge.
#
#   bash tools/ardupilot-sitl/run_check.sh /path/to/gimbalctl [extra args for check_gimbal.py]
#   BRIDGE_ARGS="--sim-lock-holds motor" bash tools/ardupilot-sitl/run_check.sh /path/to/gimbalctl
#
# Starts `gimbalctl mavlink --sim --listen 127.0.0.1:14560 $BRIDGE_ARGS`, ArduCopter SITL (-I0, GCS on
# TCP 5760, SERIAL2 = udpclient to the bridge, home heading $HEADING), then check_gimbal.py
# (pymavlink) sets SERIAL2_PROTOCOL=2, MNT1_TYPE=6 (MAVLink gimbal v2, "Gremsy" in older trees),
# CAM1_TYPE=6 (MAVLinkCamV2), reboots SITL, waits for the gimbal and aims it step by step,
# the last step in flight (arm, take off, a region of interest held while the vehicle turns).
# Bounded (< 5 min) and cleans up what it started. Env overrides: AP_DIR, PY, HEADING, HOME_LLA,
# BRIDGE_ARGS (extra `gimbalctl mavlink` options, split on spaces, e.g. --sim-lock-holds motor,
# which only a bridge that has them accepts), RUNS_DIR (where the run dirs go; default ./runs here).
set -u
if [ $# -lt 1 ] || [ -z "$1" ]; then
    echo "usage: run_check.sh /path/to/gimbalctl [helper args] (GIMBALCTL: the built gimbalctl)" >&2
    exit 2
fi
GIMBALCTL=$1
shift
HERE=$(cd "$(dirname "$0")" && pwd)
AP_DIR=${AP_DIR:-$HERE/ardupilot}
PY=${PY:-python3}
HEADING=${HEADING:-90}
HOME_LLA=${HOME_LLA:--35.363261,149.165230,584}
HOME="$HOME_LLA,$HEADING"
SITL_BIN=$AP_DIR/build/sitl/bin/arducopter
DEFAULTS=$AP_DIR/Tools/autotest/default_params/copter.parm

[ -x "$GIMBALCTL" ] || { echo "not executable: $GIMBALCTL" >&2; exit 1; }
[ -x "$SITL_BIN" ] || { echo "SITL not built: $SITL_BIN (see $HERE/README.md)" >&2; exit 1; }
if ! "$PY" -c 'import pymavlink' 2>/dev/null; then
    echo "pymavlink missing for $PY; installing" >&2
    "$PY" -m pip install -q pymavlink || exit 1
fi
# SITL's GCS port is TCP 5760 (a listener answers a connect); the bridge's is UDP 14560
# (free when it can be bound).
if (exec 3<>/dev/tcp/127.0.0.1/5760) 2>/dev/null; then
    echo "TCP port 5760 already in use (another SITL?)" >&2; exit 1
fi
if ! "$PY" -c 'import socket, sys
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
try:
    s.bind(("127.0.0.1", 14560))
except OSError:
    sys.exit("UDP port 14560 already in use (another bridge?)")' ; then
    exit 1
fi

BRIDGE_ARGS=${BRIDGE_ARGS:-}
RUNS_DIR=${RUNS_DIR:-$HERE/runs}
mkdir -p "$RUNS_DIR" || exit 1
RUN=$(mktemp -d "$RUNS_DIR/run-$(date +%Y%m%d-%H%M%S)-XXXX") || exit 1
BRIDGE_PID= SITL_PID=
cleanup() {
    for pid in $SITL_PID $BRIDGE_PID; do
        kill "$pid" 2>/dev/null
    done
    sleep 0.5
    for pid in $SITL_PID $BRIDGE_PID; do
        kill -9 "$pid" 2>/dev/null
    done
    wait 2>/dev/null
}
trap cleanup EXIT
trap 'exit 130' INT TERM

echo "== run dir: $RUN"
echo "== gimbalctl: $GIMBALCTL ($(stat -c '%y' "$GIMBALCTL" 2>/dev/null))"
# -e: in a git worktree .git is a file.
[ -e "$(dirname "$GIMBALCTL")/../../.git" ] && echo "== bridge repo HEAD: $(git -C "$(dirname "$GIMBALCTL")/../.." log --oneline -1 2>/dev/null)"
echo "== ArduPilot: $(git -C "$AP_DIR" log --oneline -1 2>/dev/null)"
echo "== home: $HOME (heading $HEADING)"

# 1. the bridge under test (hard cap 300 s in case cleanup is skipped)
# shellcheck disable=SC2086 # BRIDGE_ARGS is a list of options, split on purpose
timeout 300 "$GIMBALCTL" mavlink --sim --listen 127.0.0.1:14560 $BRIDGE_ARGS >"$RUN/bridge.out" 2>"$RUN/bridge.err" &
BRIDGE_PID=$!
sleep 0.5
kill -0 $BRIDGE_PID 2>/dev/null || { echo "bridge did not start:"; cat "$RUN/bridge.err"; exit 1; }
echo "== bridge: $(head -1 "$RUN/bridge.out")${BRIDGE_ARGS:+ (extra options: $BRIDGE_ARGS)}"

# 2. ArduCopter SITL, run from the run dir (eeprom.bin, logs there); -w wipes params at the
#    first start only (SITL's reboot re-execs without it).
(cd "$RUN" && exec timeout 300 "$SITL_BIN" -w -I0 --model + --speedup 1 \
    --defaults "$DEFAULTS" --home "$HOME" \
    --serial2 udpclient:127.0.0.1:14560 >"$RUN/sitl.log" 2>&1) &
SITL_PID=$!
echo "== SITL pid $SITL_PID: $SITL_BIN -w -I0 --model + --speedup 1 --defaults $DEFAULTS --home $HOME --serial2 udpclient:127.0.0.1:14560"

# 3. the GCS-side helper (bounded)
timeout 290 "$PY" "$HERE/check_gimbal.py" --ap tcp:127.0.0.1:5760 --bridge 127.0.0.1:14560 \
    --bridge-stderr "$RUN/bridge.err" --home="$HOME" --deadline 280 "$@"
RC=$?
echo "== helper exit code $RC"
echo "== bridge stderr (last 20 lines of $RUN/bridge.err):"
tail -20 "$RUN/bridge.err" | sed 's/^/    | /'
echo "== SITL log tail ($RUN/sitl.log):"
tail -8 "$RUN/sitl.log" | sed 's/^/    | /'
exit $RC
