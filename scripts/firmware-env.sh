# Sourced by the firmware scripts (demo.sh, bench.sh, size-report.sh, firmware-checks.sh,
# boards.sh) and test.sh. Installs what they need when it is missing: the thumbv7em-none-eabihf
# Rust target, qemu-system-arm and the ARM binutils (Debian packages, through apt-get; sudo
# only when not root), a Python pip may install into (ensure_python), and for the bench
# the C MAVLink library's generator and compiler.
# Nothing is downloaded when everything is already there.

TARGET=thumbv7em-none-eabihf
# Every firmware crate (boards/*, benches/mcu) is a workspace of its own; they all build in
# this one target directory, so the dependencies they share build once.
FIRMWARE_TARGET_DIR="${FIRMWARE_TARGET_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/target/boards}"
# Every QEMU run is bounded (seconds); the cargo runner (.cargo/qemu-run.sh) applies it.
export QEMU_TIMEOUT="${QEMU_TIMEOUT:-120}"

_as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

# `_quiet CMD…`: runs CMD with its output kept aside, shown only when it fails (an install
# is a line of its own, said by the caller, not dpkg's log).
_quiet() {
    local log rc=0
    log=$(mktemp)
    "$@" >"$log" 2>&1 || rc=$?
    if [ "$rc" -ne 0 ]; then
        cat "$log" >&2
        echo "error: '$*' failed (exit $rc)" >&2
    fi
    rm -f "$log"
    return "$rc"
}

_apt_updated=
_apt_install() {
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "error: $* missing and apt-get unavailable: install it with your package manager" >&2
        return 1
    fi
    if [ -z "$_apt_updated" ]; then
        _quiet _as_root apt-get update -qq
        _apt_updated=1
    fi
    _quiet _as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@"
}

ensure_target() {
    if ! rustc --print target-list >/dev/null 2>&1; then
        echo "error: no Rust toolchain (rustc) found" >&2
        return 1
    fi
    if command -v rustup >/dev/null 2>&1; then
        if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
            echo "installing the $TARGET Rust target" >&2
            _quiet rustup target add "$TARGET"
        fi
    fi
}

ensure_qemu() {
    if ! command -v qemu-system-arm >/dev/null 2>&1; then
        echo "installing qemu-system-arm" >&2
        _apt_install qemu-system-arm
    fi
}

ensure_binutils() {
    if ! command -v arm-none-eabi-size >/dev/null 2>&1 || ! command -v arm-none-eabi-nm >/dev/null 2>&1; then
        echo "installing binutils-arm-none-eabi (arm-none-eabi-size, arm-none-eabi-nm)" >&2
        _apt_install binutils-arm-none-eabi
    fi
}

# The toolchain the instruction-count and size budgets are measured and enforced with
# (BENCHMARKS.md, "Method"). A new stable rustc can move a count by an instruction or two, so
# the budgets are checked with this one, not with whatever stable is; moving it is a change
# of its own that re-measures every table. The library's MSRV builds are checked apart.
BENCH_TOOLCHAIN="${BENCH_TOOLCHAIN:-1.95.0}"

ensure_bench_toolchain() {
    if ! command -v rustup >/dev/null 2>&1; then
        echo "error: rustup is needed to install the bench toolchain $BENCH_TOOLCHAIN" >&2
        return 1
    fi
    if ! rustup toolchain list | grep -q "^$BENCH_TOOLCHAIN-"; then
        echo "installing the Rust $BENCH_TOOLCHAIN toolchain (minimal profile) for the budgets" >&2
        _quiet rustup toolchain install "$BENCH_TOOLCHAIN" --profile minimal
    fi
    if ! rustup target list --installed --toolchain "$BENCH_TOOLCHAIN" | grep -qx "$TARGET"; then
        echo "installing the $TARGET target for Rust $BENCH_TOOLCHAIN" >&2
        _quiet rustup target add --toolchain "$BENCH_TOOLCHAIN" "$TARGET"
    fi
}

# The Python the scripts install into and run: `python3` as found when pip may install
# into it; otherwise (no pip, or a distribution's Python marked externally managed, as
# Debian 12's is) a virtual environment under target/py, created once and put first on
# PATH for this script and everything it runs. PY_VENV overrides the place.
PY_VENV="${PY_VENV:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/target/py}"
_python_ready=
ensure_python() {
    [ -z "$_python_ready" ] || return 0
    _python_ready=1
    if [ -x "$PY_VENV/bin/python3" ]; then
        export PATH="$PY_VENV/bin:$PATH"
        return 0
    fi
    if ! command -v python3 >/dev/null 2>&1; then
        echo "installing python3" >&2
        _apt_install python3
    fi
    if python3 -m pip --version >/dev/null 2>&1 && ! _externally_managed; then
        return 0
    fi
    # Debian keeps venv's pip bootstrap (ensurepip) in python3-venv.
    if ! python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then
        echo "installing python3-venv" >&2
        _apt_install python3-venv
    fi
    echo "creating a Python environment for the scripts' packages: $PY_VENV" >&2
    python3 -m venv "$PY_VENV"
    export PATH="$PY_VENV/bin:$PATH"
}

# Whether pip would refuse to install into `python3` (PEP 668): outside a virtual
# environment, with the marker beside its standard library.
_externally_managed() {
    python3 -c 'import os, sys, sysconfig
marker = os.path.join(sysconfig.get_path("stdlib"), "EXTERNALLY-MANAGED")
sys.exit(0 if sys.prefix == sys.base_prefix and os.path.exists(marker) else 1)'
}

# `_pip_pinned NAME VERSION WHY`: NAME==VERSION installed with pip unless that version is.
_pip_pinned() {
    ensure_python
    local have
    have=$(python3 -c "import importlib.metadata as m; print(m.version('$1'))" 2>/dev/null || true)
    if [ "$have" != "$2" ]; then
        echo "installing (pip): $1==$2 ($3)" >&2
        python3 -m pip install --quiet --disable-pip-version-check "$1==$2"
    fi
}

# pyelftools, pinned, for scripts/panic-paths.py (the panic locations an ELF keeps).
PYELFTOOLS="${PYELFTOOLS:-0.33}"
ensure_pyelftools() {
    _pip_pinned pyelftools "$PYELFTOOLS" scripts/panic-paths.py
}

# The C MAVLink library qemu_bench_mavlink measures beside the bridge: generated by
# pymavlink's mavgen (C, MAVLink 2, the common dialect its package carries) with this
# pinned pymavlink, compiled by benches/mcu/build.rs with arm-none-eabi-gcc (newlib for its
# headers). Exports IDU_MAVLINK_C_INCLUDE, the generated headers' directory.
MAVLINK_C_PYMAVLINK="${MAVLINK_C_PYMAVLINK:-2.4.50}"
ensure_mavlink_c() {
    if ! command -v arm-none-eabi-gcc >/dev/null 2>&1 \
        || [ "$(arm-none-eabi-gcc -print-file-name=nano.specs)" = nano.specs ]; then
        echo "installing gcc-arm-none-eabi and libnewlib-arm-none-eabi (the C MAVLink library's build)" >&2
        _apt_install gcc-arm-none-eabi libnewlib-arm-none-eabi
    fi
    _pip_pinned pymavlink "$MAVLINK_C_PYMAVLINK" mavgen
    local out
    out="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/target/mavlink-c/pymavlink-$MAVLINK_C_PYMAVLINK"
    if [ ! -f "$out/common/mavlink.h" ]; then
        local xml
        xml=$(python3 -c "import os, pymavlink; print(os.path.join(os.path.dirname(pymavlink.__file__), 'dialects', 'v20', 'common.xml'))")
        rm -rf "$out"
        python3 -m pymavlink.tools.mavgen --lang=C --wire-protocol=2.0 --output="$out" "$xml" >/dev/null
    fi
    export IDU_MAVLINK_C_INCLUDE="$out"
}

# `firmware_cargo DIR [+TOOLCHAIN] ARGS…`: cargo in the firmware crate DIR (so that its
# .cargo/config.toml, which names its target, applies), in the shared target directory.
firmware_cargo() {
    local dir=$1
    shift
    (cd "$dir" && CARGO_TARGET_DIR="$FIRMWARE_TARGET_DIR" cargo "$@")
}

# `root_firmware_cargo ARGS…`: cargo for the root crate's firmware examples (qemu_demo),
# built for the target in the shared target directory, from the repository's root (where
# `memory.x` and `.cargo/config.toml` are).
root_firmware_cargo() {
    (cd "$(dirname "${BASH_SOURCE[0]}")/.." && CARGO_TARGET_DIR="$FIRMWARE_TARGET_DIR" cargo "$@")
}

# The path of a release firmware ELF (a program of any firmware crate, or the root crate's
# example qemu_demo) for the target.
firmware_elf() {
    case "$1" in
        qemu_demo) echo "$FIRMWARE_TARGET_DIR/$TARGET/release/examples/$1" ;;
        *) echo "$FIRMWARE_TARGET_DIR/$TARGET/release/$1" ;;
    esac
}
