#!/usr/bin/env bash
# Deterministic cost benchmarks on an emulated STM32F405: guest instructions counted under
# QEMU `-icount shift=0` (benches/mcu: qemu_bench, qemu_bench_mavlink, the latter beside the
# C MAVLink library on the same bytes, and qemu_bench_signing, what MAVLink 2 signing costs
# a frame), then the flash cost of each CRC variant (nm) and the
# driver's flash and static RAM (scripts/size-report.sh), and that no panic path of the
# libraries is left in these programs (scripts/panic-paths.py). Built with the pinned toolchain
# BENCH_TOOLCHAIN (scripts/firmware-env.sh), the one the budgets are measured with.
#
# Exit status 1 if a budget is exceeded or a panic path is found. Installs the bench
# toolchain, the target, qemu-system-arm, the ARM binutils, pyelftools and, for the C MAVLink
# library, gcc-arm-none-eabi, newlib and a pinned pymavlink (its mavgen) when missing. QEMU is
# bounded by QEMU_TIMEOUT seconds (default 120).
#
#   scripts/bench.sh                 this tree's numbers
#   scripts/bench.sh --compare REV   the same for REV (built in a scratch worktree, removed
#                                    afterwards) and for this tree, side by side: one row per
#                                    measurement, a column per revision. Exit status: this
#                                    tree's budgets. Bad usage exits 2.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() {
    echo "usage: scripts/bench.sh [--compare REV]" >&2
    exit 2
}

if [ "$#" -gt 0 ]; then
    case "$1" in
    --compare)
        if [ "$#" -lt 2 ] || [ -z "$2" ]; then
            echo "error: --compare needs a revision (e.g. --compare main)" >&2
            usage
        fi
        if [ "$#" -gt 2 ]; then
            echo "error: unexpected argument '$3'" >&2
            usage
        fi
        rev=$2
        if ! commit=$(git rev-parse --verify --quiet "$rev^{commit}"); then
            echo "error: --compare: '$rev' is not a revision of this repository" >&2
            exit 2
        fi
        scratch=$(mktemp -d)
        cleanup() {
            git worktree remove --force "$scratch/tree" >/dev/null 2>&1 || true
            rm -rf "$scratch"
        }
        trap cleanup EXIT
        git worktree add --detach "$scratch/tree" "$commit" >/dev/null
        # The other revision builds in a target directory kept between comparisons (its
        # dependencies then build once), inside this tree's target/, so it never mixes with
        # this tree's artifacts.
        mkdir -p target/bench-compare
        ln -s "$PWD/target/bench-compare" "$scratch/tree/target"
        echo "== $rev ($(git rev-parse --short "$commit")) ==" >&2
        (cd "$scratch/tree" && scripts/bench.sh) >"$scratch/other.txt" 2>&1 || true
        echo "== this tree ($(git rev-parse --short HEAD)$(git diff --quiet HEAD -- . 2>/dev/null || echo ', modified')) ==" >&2
        status=0
        scripts/bench.sh >"$scratch/this.txt" 2>&1 || status=$?
        python3 scripts/bench-compare.py "$scratch/other.txt" "$scratch/this.txt" \
            "$rev ($(git rev-parse --short "$commit"))" "this tree"
        exit "$status"
        ;;
    *)
        echo "error: unknown argument '$1'" >&2
        usage
        ;;
    esac
fi

. scripts/firmware-env.sh

ensure_target
ensure_bench_toolchain
ensure_qemu
ensure_binutils
ensure_pyelftools
ensure_mavlink_c

echo "bench toolchain: $(rustc "+$BENCH_TOOLCHAIN" --version)"
status=0
firmware_cargo benches/mcu "+$BENCH_TOOLCHAIN" run --release --locked --bin qemu_bench || status=$?
echo
firmware_cargo benches/mcu "+$BENCH_TOOLCHAIN" run --release --locked --bin qemu_bench_mavlink || status=$?
echo
# Signing, in the target directory scripts/size-report.sh builds it in (the feature would
# reach every program of benches/mcu in the shared one).
(cd benches/mcu && CARGO_TARGET_DIR="$FIRMWARE_TARGET_DIR-signing" cargo "+$BENCH_TOOLCHAIN" run \
    --release --locked --features signing --bin qemu_bench_signing) || status=$?

echo
echo "Flash cost of the CRC variants (bytes; arm-none-eabi-nm --size-sort, qemu_bench build):"
elf=$(firmware_elf qemu_bench)
arm-none-eabi-nm -C --size-sort -S -t d "$elf" |
    awk '/crcs::bench_crc|crcs::NIBBLE|crcs::CRC_CRATE|wire::crc::TABLE|wire::crc::checksum|wire::crc::update/ {
        printf "  %6d  %s %s\n", $2 + 0, $3, substr($0, index($0, $4)) }'
echo "  (bench_crc_crate_table256 is a call into idu_gimbal::wire::crc::checksum, listed separately)"

echo
scripts/size-report.sh || status=$?

echo
echo "A poll generic over its port against the poll written for the port (footprint_generic):"
scripts/port-generic.sh || status=$?

echo
echo "No panic path of the libraries in the benchmark programs (scripts/panic-paths.py):"
python3 scripts/panic-paths.py "$PWD" "$(firmware_elf qemu_bench)" "$(firmware_elf qemu_bench_mavlink)" \
    "$FIRMWARE_TARGET_DIR-signing/$TARGET/release/qemu_bench_signing" || status=$?
exit "$status"
