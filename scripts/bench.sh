#!/usr/bin/env bash
# Deterministic cost benchmarks on an emulated STM32F405: guest instructions counted under
# QEMU `-icount shift=0` (examples/qemu_bench.rs), then the flash cost of each CRC variant
# (nm) and the driver's flash and static RAM (scripts/size-report.sh).
#
# Exit status 1 if a budget of issue 4 is exceeded. Installs the target, qemu-system-arm and
# the ARM binutils when missing. QEMU is bounded by QEMU_TIMEOUT seconds (default 120).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_qemu
ensure_binutils

status=0
cargo run --release --target "$TARGET" --example qemu_bench || status=$?
echo
cargo run --release --target "$TARGET" -p idu-gimbal-mavlink --example qemu_bench_mavlink || status=$?

echo
echo "Flash cost of the CRC variants (bytes; arm-none-eabi-nm --size-sort, qemu_bench build):"
elf=$(example_elf qemu_bench)
arm-none-eabi-nm -C --size-sort -S -t d "$elf" |
    awk '/crcs::bench_crc|crcs::NIBBLE|crcs::CRC_CRATE|wire::crc::TABLE|wire::crc::update/ {
        printf "  %6d  %s %s\n", $2 + 0, $3, substr($0, index($0, $4)) }'
echo "  (bench_crc_crate_table256 is a call into idu_gimbal::wire::crc::update, listed separately)"

echo
scripts/size-report.sh || status=$?
exit "$status"
