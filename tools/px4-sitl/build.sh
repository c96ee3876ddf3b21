#!/usr/bin/env bash
# Fetch and build PX4 SITL (px4_sitl, SIH simulator, no Gazebo) for run_check.sh.
#
#   bash tools/px4-sitl/build.sh [WORK_DIR]        # default ~/px4-sitl
#
# Leaves WORK_DIR/PX4-Autopilot (the source tree, build/px4_sitl_sihmin in it) and
# WORK_DIR/venv (Python with the build's generators and pymavlink). Only the three submodules
# the build needs are checked out; the board label `sihmin` (created here) disables what needs
# the others. Sources are cloned from the URLs below; without access to GitHub point them at
# local mirrors (bare repositories), e.g.
#   PX4_URL=/srv/mirror/PX4-Autopilot.git MAVLINK_URL=/srv/mirror/mavlink.git \
#   PYMAVLINK_URL=/srv/mirror/pymavlink.git LIBEVENTS_URL=/srv/mirror/libevents.git \
#   HEATSHRINK_URL=/srv/mirror/heatshrink.git bash tools/px4-sitl/build.sh
# Env: PX4_COMMIT (default below), JOBS (2), NO_APT=1 to skip apt-get.
set -euo pipefail
WORK=${1:-$HOME/px4-sitl}
# The newest commit of PX4's main in the snapshot used whose submodules all exist in theirs
# (its child a1be954 moves mavlink to a commit the mavlink snapshot lacks, which the next
# commit needs for AVAILABLE_MODES.seq). The fork dakejahl/PX4-Autopilot holds the same tree.
PX4_COMMIT=${PX4_COMMIT:-0d4ae424d3faa57759fdee25a3ecd6ba2250ab30}
PX4_URL=${PX4_URL:-https://github.com/PX4/PX4-Autopilot.git}
MAVLINK_URL=${MAVLINK_URL:-https://github.com/mavlink/mavlink.git}
PYMAVLINK_URL=${PYMAVLINK_URL:-https://github.com/ArduPilot/pymavlink.git}
LIBEVENTS_URL=${LIBEVENTS_URL:-https://github.com/mavlink/libevents.git}
HEATSHRINK_URL=${HEATSHRINK_URL:-https://github.com/PX4/heatshrink.git}
JOBS=${JOBS:-2}
SRC=$WORK/PX4-Autopilot
LABEL=sihmin

if [ -z "${NO_APT:-}" ]; then
    SUDO=
    [ "$(id -u)" -eq 0 ] || SUDO=sudo
    $SUDO apt-get update -qq
    $SUDO apt-get install -y --no-install-recommends cmake ninja-build g++ gcc make git python3-venv >/dev/null
fi
mkdir -p "$WORK"
if [ ! -x "$WORK/venv/bin/python" ]; then
    python3 -m venv "$WORK/venv"
fi
"$WORK/venv/bin/pip" install -q empy==3.3.4 jinja2 pyyaml jsonschema kconfiglib pyros-genmsg packaging \
    future lxml numpy pymavlink

# A clone at a commit; a few large files (docs, gyro_fft's CMSIS tables) may be missing from a
# mirror: the checkout then reports them and goes on.
clone_at() {  # url dir commit
    local url=$1 dir=$2 want=$3
    if [ -z "$want" ]; then
        echo "error: no commit recorded for $dir in its parent tree" >&2
        exit 1
    fi
    if [ ! -e "$dir/.git" ]; then
        rm -rf "$dir"
        git clone -q --no-checkout "$url" "$dir"
    fi
    if ! git -C "$dir" cat-file -e "$want^{commit}" 2>/dev/null; then
        local head
        head=$(git -C "$dir" rev-parse HEAD 2>/dev/null || git -C "$dir" rev-parse FETCH_HEAD)
        echo "WARNING: $want is not in $url; using its HEAD $head instead" >&2
        want=$head
    fi
    # Missing files are reported and passed over; a checkout that moved nowhere is an error.
    git -C "$dir" checkout -q -f "$want" ||
        echo "WARNING: the checkout of $want in $dir reported missing files; going on" >&2
    if [ "$(git -C "$dir" rev-parse HEAD)" != "$(git -C "$dir" rev-parse "$want^{commit}")" ]; then
        echo "error: $dir is not at $want after the checkout" >&2
        exit 1
    fi
    echo "$dir at $want"
}
sub_commit() { git -C "$1" ls-tree HEAD "$2" | awk '{print $3}'; }

clone_at "$PX4_URL" "$SRC" "$PX4_COMMIT"
clone_at "$MAVLINK_URL" "$SRC/src/modules/mavlink/mavlink" "$(sub_commit "$SRC" src/modules/mavlink/mavlink)"
clone_at "$PYMAVLINK_URL" "$SRC/src/modules/mavlink/mavlink/pymavlink" \
    "$(sub_commit "$SRC/src/modules/mavlink/mavlink" pymavlink)"
clone_at "$LIBEVENTS_URL" "$SRC/src/lib/events/libevents" "$(sub_commit "$SRC" src/lib/events/libevents)"
clone_at "$HEATSHRINK_URL" "$SRC/src/lib/heatshrink/heatshrink" "$(sub_commit "$SRC" src/lib/heatshrink/heatshrink)"

# The board label: px4_sitl's default.px4board plus these (non-default labels are merged over
# default.px4board, cmake/kconfig.cmake). Gazebo off as in the sih label; gyro_fft (CMSIS
# tables), uxrce_dds_client (Micro-XRCE-DDS-Client) and the GPS drivers (PX4-GPSDrivers; the
# Septentrio driver and SPARTN with them) need submodules not checked out. SIH's own simulated
# GPS (sensor_gps_sim) is kept.
cat >"$SRC/boards/px4/sitl/$LABEL.px4board" <<'EOF'
CONFIG_MODULES_SIMULATION_GZ_BRIDGE=n
CONFIG_MODULES_SIMULATION_GZ_MSGS=n
CONFIG_MODULES_SIMULATION_GZ_PLUGINS=n
CONFIG_MODULES_GYRO_FFT=n
CONFIG_MODULES_UXRCE_DDS_CLIENT=n
CONFIG_DRIVERS_GPS=n
CONFIG_GPS_SPARTN=n
CONFIG_DRIVERS_GNSS_SEPTENTRIO=n
EOF

cd "$SRC"
export PATH="$WORK/venv/bin:$PATH"
export GIT_SUBMODULES_ARE_EVIL=1  # Tools/check_submodules.sh would try to update every submodule
start=$(date +%s)
nice -n 10 cmake -S . -B "build/px4_sitl_$LABEL" -G Ninja -DCONFIG="px4_sitl_$LABEL" \
    -DPython3_EXECUTABLE="$WORK/venv/bin/python" -DPYTHON_EXECUTABLE="$WORK/venv/bin/python"
nice -n 10 cmake --build "build/px4_sitl_$LABEL" -- -j"$JOBS"
end=$(date +%s)
echo "built $SRC/build/px4_sitl_$LABEL/bin/px4 in $((end - start)) s"
