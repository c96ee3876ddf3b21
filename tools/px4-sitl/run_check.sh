#!/usr/bin/env bash
# By-hand check: what a real PX4 (SITL, SIH quadrotor, no Gazebo) reports of a MAVLink gimbal bridge.
#
#   bash tools/px4-sitl/run_check.sh /path/to/gimbalctl [extra args for check_gimbal.py]
#
# Starts `gimbalctl mavlink --sim --listen 127.0.0.1:$BRIDGE_PORT`, then PX4 SITL
# (PX4_SIM_MODEL=sihsim_quadx PX4_SIMULATOR=sihsim, daemon mode, a fresh working directory);
# check_gimbal.py --phase setup sets MNT_MODE_IN 4, MNT_MODE_OUT 2, MAV_1_MODE 0, MAV_1_FORWARD 1
# (SITL refuses MAVLink's reboot command), PX4 is stopped from its shell (param save, shutdown)
# and started again in the same directory (the parameters persist there), and the link to the
# bridge is started from the PX4 shell client:
#   mavlink start -u $LINK_PORT -o $RELAY_PORT -t 127.0.0.1 -m p:MAV_1_MODE -r $LINK_RATE -f -x
# and check_gimbal.py --phase check relays that link to the bridge (decoding both directions),
# flies and runs the cases. Bounded (< 6 min) and cleans up what it started.
#
# Env overrides: PX4_DIR (source tree), PX4_BUILD (build dir), PY (python with pymavlink),
# BRIDGE_ARGS (extra `gimbalctl mavlink` options, split on spaces, e.g. --sim-lock-holds motor),
# BRIDGE_PORT (14560), RELAY_PORT (14561), LINK_PORT (14562), LINK_RATE (46080; empty: no -r),
# LINK (normal: the link above; sitl-gimbal: no link of our own, the bridge behind SITL's own
# gimbal link, mode Gimbal, which sends to UDP 13280), RUN_ROOT (where run directories go).
set -u
if [ $# -lt 1 ] || [ -z "$1" ]; then
    echo "usage: run_check.sh /path/to/gimbalctl [helper args] (GIMBALCTL: the built gimbalctl)" >&2
    exit 2
fi
GIMBALCTL=$1
shift
HERE=$(cd "$(dirname "$0")" && pwd)
PX4_DIR=${PX4_DIR:-$HOME/px4-sitl/PX4-Autopilot}
PX4_BUILD=${PX4_BUILD:-$PX4_DIR/build/px4_sitl_sihmin}
if [ -z "${PY:-}" ]; then
    PY=python3
    [ -x "$(dirname "$PX4_DIR")/venv/bin/python" ] && PY=$(dirname "$PX4_DIR")/venv/bin/python
fi
BRIDGE_PORT=${BRIDGE_PORT:-14560}
RELAY_PORT=${RELAY_PORT:-14561}
LINK_PORT=${LINK_PORT:-14562}
LINK_RATE=${LINK_RATE-46080}
LINK=${LINK:-normal}
BRIDGE_ARGS=${BRIDGE_ARGS:-}
GCS_PORT=18570        # SITL's GCS link (px4-rc.mavlink, instance 0)
SITL_GIMBAL_PORT=13280 # where SITL's own gimbal link (mode Gimbal) sends
RUN_ROOT=${RUN_ROOT:-${TMPDIR:-/tmp}/px4-sitl-runs}
PX4_BIN=$PX4_BUILD/bin/px4

[ -x "$GIMBALCTL" ] || { echo "not executable: $GIMBALCTL" >&2; exit 1; }
[ -x "$PX4_BIN" ] || { echo "PX4 SITL not built: $PX4_BIN (see $HERE/README.md, build.sh)" >&2; exit 1; }
if ! "$PY" -c 'import pymavlink' 2>/dev/null; then
    echo "pymavlink missing for $PY; installing" >&2
    "$PY" -m pip install -q pymavlink || exit 1
fi
case "$LINK" in
    normal) RELAY_LISTEN=$RELAY_PORT ;;
    sitl-gimbal) RELAY_LISTEN=$SITL_GIMBAL_PORT ;;
    *) echo "LINK must be normal or sitl-gimbal" >&2; exit 2 ;;
esac
# PX4's own ports (instance 0) and ours must be free; a running SITL holds 18570.
if ! "$PY" - "$BRIDGE_PORT" "$RELAY_LISTEN" "$LINK_PORT" "$GCS_PORT" 14580 14280 13030 19450 <<'EOF'
import socket, sys
busy = []
for p in sys.argv[1:]:
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        s.bind(("127.0.0.1", int(p)))
    except OSError:
        try:
            s.close(); s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); s.bind(("0.0.0.0", int(p)))
        except OSError:
            busy.append(p)
    s.close()
if busy:
    print("UDP port(s) already in use (another SITL or bridge?): " + " ".join(busy), file=sys.stderr)
    sys.exit(1)
EOF
then exit 1; fi

mkdir -p "$RUN_ROOT"
RUN=$(mktemp -d "$RUN_ROOT/run-XXXXXX")
mkdir -p "$RUN/px4"
BRIDGE_PID= PX4_PID=
stop_px4() {
    [ -n "$PX4_PID" ] || return 0
    kill "$PX4_PID" 2>/dev/null
    for _ in 1 2 3 4 5 6 7 8 9 10; do kill -0 "$PX4_PID" 2>/dev/null || break; sleep 0.2; done
    kill -9 "$PX4_PID" 2>/dev/null
    wait "$PX4_PID" 2>/dev/null
    PX4_PID=
}
cleanup() {
    stop_px4
    if [ -n "$BRIDGE_PID" ]; then
        kill "$BRIDGE_PID" 2>/dev/null; sleep 0.3; kill -9 "$BRIDGE_PID" 2>/dev/null
        wait "$BRIDGE_PID" 2>/dev/null
    fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM

start_px4() {
    # As `make px4_sitl sihsim_quadx` runs it (simulator_sih/CMakeLists.txt), but in daemon mode
    # (-d, no interactive shell) and in a working directory of our own; the data path is the
    # build's etc/ (the ROMFS), linked into the working directory by px4 itself. The output of
    # commands given through the px4-<module> clients goes to this process's stdout: line
    # buffered, so that it reaches the log at once.
    (cd "$RUN/px4" && PX4_SIM_MODEL=sihsim_quadx PX4_SIMULATOR=sihsim \
        exec timeout 400 stdbuf -oL -eL "$PX4_BIN" -d -w "$RUN/px4" "$PX4_BUILD/etc" >"$PX4_LOG" 2>&1) &
    PX4_PID=$!
}
wait_px4_boot() {  # until rcS has run (the shell client answers and mavlink is up)
    local n=0
    while [ $n -lt 100 ]; do
        grep -q "Startup script returned successfully" "$PX4_LOG" 2>/dev/null && return 0
        kill -0 "$PX4_PID" 2>/dev/null || return 1
        sleep 0.2; n=$((n + 1))
    done
    return 1
}
px4_cmd() {  # a PX4 shell command through the px4-<module> client; its output goes to PX4's log
    local before rc
    before=$(wc -l <"$PX4_LOG")
    (cd "$RUN/px4" && "$PX4_BUILD/bin/px4-$1" "${@:2}") >/dev/null 2>&1
    rc=$?
    sleep "${PX4_CMD_WAIT:-0.5}"
    tail -n +$((before + 1)) "$PX4_LOG"
    return $rc
}
link_status() {  # the `mavlink status` block of the instance on UDP port $1
    PX4_CMD_WAIT=1.5 px4_cmd mavlink status | awk -v pat="($1, remote port" '
        /^instance #/ { if (index(blk, pat)) printf "%s", blk; blk = "" }
        { blk = blk $0 "\n" }
        END { if (index(blk, pat)) printf "%s", blk }' \
        | grep -E "instance|mode:|Forwarding|tx:|tx rate max|rx:|transport" | sed 's/^/    | /'
}

echo "== run dir: $RUN"
echo "== gimbalctl: $GIMBALCTL ($(stat -c '%y' "$GIMBALCTL" 2>/dev/null))"
# -e: in a git worktree .git is a file.
[ -e "$(dirname "$GIMBALCTL")/../../.git" ] && echo "== bridge repo HEAD: $(git -C "$(dirname "$GIMBALCTL")/../.." log --oneline -1 2>/dev/null)"
echo "== PX4: $(git -C "$PX4_DIR" log -1 --format='%H %cd %s' --date=short 2>/dev/null), build $PX4_BUILD"
echo "== link: $LINK, bridge UDP $BRIDGE_PORT, relay $RELAY_LISTEN, PX4 link port $LINK_PORT, rate ${LINK_RATE:-(no -r)}"

# 1. the bridge under test (hard cap in case cleanup is skipped)
# shellcheck disable=SC2086 # BRIDGE_ARGS is a list of options, split on purpose
timeout 380 "$GIMBALCTL" mavlink --sim --listen "127.0.0.1:$BRIDGE_PORT" $BRIDGE_ARGS >"$RUN/bridge.out" 2>"$RUN/bridge.err" &
BRIDGE_PID=$!
sleep 0.5
kill -0 $BRIDGE_PID 2>/dev/null || { echo "bridge did not start:"; cat "$RUN/bridge.err"; exit 1; }
echo "== bridge: $(head -1 "$RUN/bridge.out")${BRIDGE_ARGS:+ (extra options: $BRIDGE_ARGS)}"

# 2. PX4, first boot: the parameters
PX4_LOG=$RUN/px4-boot1.log
start_px4
echo "== PX4 pid $PX4_PID: PX4_SIM_MODEL=sihsim_quadx PX4_SIMULATOR=sihsim $PX4_BIN -d -w $RUN/px4 $PX4_BUILD/etc"
wait_px4_boot || { echo "PX4 did not boot:"; tail -30 "$PX4_LOG"; exit 1; }
timeout 60 "$PY" "$HERE/check_gimbal.py" --phase setup --px4 "udpout:127.0.0.1:$GCS_PORT" --deadline 55 "$@" \
    || { echo "setup phase failed"; tail -30 "$PX4_LOG"; exit 1; }
# MNT_MODE_IN/OUT take effect at boot (rcS starts `gimbal` only when MNT_MODE_IN > -1).
echo "== px4-param save; px4-shutdown"
px4_cmd param save | sed 's/^/    | /'
px4_cmd shutdown | grep -v "^$" | tail -3 | sed 's/^/    | /'
for _ in $(seq 1 50); do kill -0 "$PX4_PID" 2>/dev/null || break; sleep 0.2; done
kill -0 "$PX4_PID" 2>/dev/null && echo "== PX4 did not exit on shutdown; stopping it"
stop_px4
echo "== PX4 stopped; parameters kept in $RUN/px4/parameters.bson"

# 3. PX4, second boot, and the link to the bridge
PX4_LOG=$RUN/px4-boot2.log
start_px4
echo "== PX4 restarted, pid $PX4_PID"
wait_px4_boot || { echo "PX4 did not boot again:"; tail -30 "$PX4_LOG"; exit 1; }
grep -E "gimbal|Gimbal|MNT" "$PX4_LOG" | tail -3 | sed 's/^/    | /'
CHECK_ARGS=()
if [ "$LINK" = normal ]; then
    # Pitfall: there is no mode named "normal" (mavlink_main.cpp: Normal is the default, or 0).
    echo "== px4-mavlink start ... -m normal (expected to be refused):"
    PX4_CMD_WAIT=1.5 px4_cmd mavlink start -u $((LINK_PORT + 10)) -o $((RELAY_PORT + 10)) -t 127.0.0.1 -m normal \
        | grep -iE "invalid|error|values:" | head -3 | sed 's/^/    | /'
    RATE_ARGS=()
    [ -n "$LINK_RATE" ] && RATE_ARGS=(-r "$LINK_RATE")
    echo "== px4-mavlink start -u $LINK_PORT -o $RELAY_PORT -t 127.0.0.1 -m p:MAV_1_MODE ${RATE_ARGS[*]} -f -x"
    px4_cmd mavlink start -u "$LINK_PORT" -o "$RELAY_PORT" -t 127.0.0.1 -m p:MAV_1_MODE "${RATE_ARGS[@]}" -f -x \
        | grep -E "mavlink|ERROR" | sed 's/^/    | /'
    CHECK_ARGS=(--relay "$RELAY_PORT:$BRIDGE_PORT")
else
    echo "== no link of our own: the bridge is behind SITL's gimbal link (mode Gimbal, UDP 13030 -> $SITL_GIMBAL_PORT)"
    CHECK_ARGS=(--relay "$SITL_GIMBAL_PORT:$BRIDGE_PORT")
fi
# 4. the ground-station side (bounded)
timeout 330 "$PY" "$HERE/check_gimbal.py" --phase check --px4 "udpout:127.0.0.1:$GCS_PORT" \
    "${CHECK_ARGS[@]}" --bridge-stderr "$RUN/bridge.err" --deadline 320 "$@"
RC=$?
echo "== helper exit code $RC"
echo "== mavlink status of the link to the bridge (PX4 side, after the check):"
link_status "$([ "$LINK" = normal ] && echo "$LINK_PORT" || echo 13030)"
echo "== bridge stderr (last 15 lines of $RUN/bridge.err):"
tail -15 "$RUN/bridge.err" | sed 's/^/    | /'
echo "== PX4 log of the second boot, gimbal and mavlink lines ($PX4_LOG):"
grep -iE "^(INFO|WARN|ERROR).*(gimbal|mavlink|primary|denied|Ignore command|invalid)" "$PX4_LOG" | tail -15 \
    | sed 's/^/    | /'
exit $RC
