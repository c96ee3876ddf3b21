# Sourced by the firmware scripts (demo.sh, bench.sh, size-report.sh, firmware-checks.sh,
# boards.sh). Installs what they need when it is missing: the thumbv7em-none-eabihf Rust
# target, qemu-system-arm and the ARM binutils (Debian packages, through apt-get; sudo only
# when not root). Nothing is downloaded when everything is already there.

TARGET=thumbv7em-none-eabihf
# Every firmware crate (boards/*, benches/mcu) is a workspace of its own; they all build in
# this one target directory, so the dependencies they share build once.
FIRMWARE_TARGET_DIR="${FIRMWARE_TARGET_DIR:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/target/boards}"
# Every QEMU run is bounded (seconds); the cargo runner (.cargo/qemu-run.sh) applies it.
export QEMU_TIMEOUT="${QEMU_TIMEOUT:-120}"

_as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

_apt_updated=
_apt_install() {
    if ! command -v apt-get >/dev/null 2>&1; then
        echo "error: $* missing and apt-get unavailable: install it with your package manager" >&2
        return 1
    fi
    if [ -z "$_apt_updated" ]; then
        _as_root apt-get update -qq
        _apt_updated=1
    fi
    _as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$@"
}

ensure_target() {
    if ! rustc --print target-list >/dev/null 2>&1; then
        echo "error: no Rust toolchain (rustc) found" >&2
        return 1
    fi
    if command -v rustup >/dev/null 2>&1; then
        if ! rustup target list --installed 2>/dev/null | grep -qx "$TARGET"; then
            echo "installing the $TARGET Rust target" >&2
            rustup target add "$TARGET"
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
        rustup toolchain install "$BENCH_TOOLCHAIN" --profile minimal
    fi
    if ! rustup target list --installed --toolchain "$BENCH_TOOLCHAIN" | grep -qx "$TARGET"; then
        echo "installing the $TARGET target for Rust $BENCH_TOOLCHAIN" >&2
        rustup target add --toolchain "$BENCH_TOOLCHAIN" "$TARGET"
    fi
}

# `firmware_cargo DIR [+TOOLCHAIN] ARGS…`: cargo in the firmware crate DIR (so that its
# .cargo/config.toml, which names its target, applies), in the shared target directory.
firmware_cargo() {
    local dir=$1
    shift
    (cd "$dir" && CARGO_TARGET_DIR="$FIRMWARE_TARGET_DIR" cargo "$@")
}

# The path of a release firmware ELF (a program of any firmware crate) for the target.
firmware_elf() {
    echo "$FIRMWARE_TARGET_DIR/$TARGET/release/$1"
}
