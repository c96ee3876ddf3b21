#!/usr/bin/env bash
# By-hand check: gimbalctl's `--can` on a real SocketCAN interface, which CI's kernel cannot
# give (no vcan module in its containers). can-utils' `cansend` and `candump` are the other
# end of the bus.
#
#   sudo bash tools/socketcan/run_check.sh /path/to/gimbalctl
#
# Brings up IFACE (default vcan0: `modprobe vcan`, `ip link add … type vcan`, up) when it is
# not, installs can-utils when missing (apt-get), then checks:
#   - `send --can IFACE pitch -45` puts the frame `encode` prints on the bus;
#   - `monitor --can IFACE --count 1` prints another controller's command and a postback
#     written with `cansend`, exactly.
# Exit 0 when both hold, 1 when one does not (what differs is printed), 2 bad usage.
set -euo pipefail

if [ $# -ne 1 ] || [ ! -x "$1" ]; then
    echo "usage: run_check.sh /path/to/gimbalctl (GIMBALCTL: an executable gimbalctl)" >&2
    exit 2
fi
GIMBALCTL=$1
IFACE=${IFACE:-vcan0}

if ! command -v cansend >/dev/null 2>&1 || ! command -v candump >/dev/null 2>&1; then
    apt-get update -qq && apt-get install -y -qq --no-install-recommends can-utils >/dev/null
fi
if ! ip link show "$IFACE" >/dev/null 2>&1; then
    modprobe vcan
    ip link add dev "$IFACE" type vcan
fi
ip link set up "$IFACE"

work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$work"' EXIT
status=0

# send: the frame `encode` prints, on the bus (candump's log form, one frame of that ID).
want=$("$GIMBALCTL" encode pitch -45)
timeout 5 candump -L -n 1 "$IFACE,00000F01:1FFFFFFF" >"$work/dump" &
dump=$!
sleep 0.3
"$GIMBALCTL" send --can "$IFACE" pitch -45
wait "$dump" || true
got=$(awk '{ print $3 }' "$work/dump")
if [ "$got" != "$want" ]; then
    echo "FAIL send: on the bus '$got', encode prints '$want'"
    status=1
else
    echo "ok   send: $got"
fi

# monitor: another controller's command, then a postback (X30, lock, pitch -30, heading 180,
# motor -1.5; its CRC checked by `gimbalctl decode`), until the monitor has its postback.
timeout 10 "$GIMBALCTL" monitor --can "$IFACE" --count 1 >"$work/monitor" &
mon=$!
while kill -0 "$mon" 2>/dev/null; do
    cansend "$IFACE" 00000F01#0F07000000000000
    for f in EB900C0000000000 0000000021FE0F01 01000348F450466A FF26870000000000; do
        cansend "$IFACE" "030F0001#$f"
    done
    sleep 0.2
done
wait "$mon" || { echo "FAIL monitor: no postback within 10 s"; status=1; }
expected='pitch -30.00 deg  heading 180.00 deg  motor -1.50 deg  mode lock  tracking no  gimbal 1 (X30/X30GT)'
if [ "$(tail -1 "$work/monitor")" != "$expected" ] ||
    grep -v -x -F -e "$expected" -e 'control  00000F01  look-down' "$work/monitor" >/dev/null; then
    echo "FAIL monitor printed:"
    sed 's/^/    | /' "$work/monitor"
    status=1
else
    echo "ok   monitor: $(tail -1 "$work/monitor")"
fi
exit "$status"
