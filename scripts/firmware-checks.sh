#!/usr/bin/env bash
# The firmware stage of the test suite (`scripts/test.sh firmware`):
#   1. the QEMU demo sessions must pass (exit 0): the core's, and the MAVLink bridge's;
#   2. the STM32F405 firmware, CAN, UART and MAVLink bridge, builds in release mode (sizes
#      printed);
#   3. every board crate under boards/ (RP2040, ESP32-C3, STM32H743, embassy, …) builds in
#      release mode and is clippy-clean (scripts/boards.sh; sizes printed);
#   4. the embassy firmware's scripted session passes on QEMU (boards/embassy_qemu/run.sh).
#
# The budgets (instruction counts, sizes) are the bench stage's: scripts/bench.sh. Every
# QEMU run is bounded by QEMU_TIMEOUT seconds (default 120).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_qemu
ensure_binutils

echo "--- firmware: QEMU demo session"
scripts/demo.sh

echo "--- firmware: the MAVLink bridge's QEMU session (scripted autopilot, bridge, CAN, simulated gimbal)"
cargo run --release --target "$TARGET" -p idu-gimbal-mavlink --example qemu_mavlink

echo "--- firmware: STM32F405 release builds (CAN, UART, MAVLink bridge)"
cargo build --release --target "$TARGET" --example stm32f405 --example stm32f405_uart
cargo build --release --target "$TARGET" -p idu-gimbal-mavlink --example stm32f405_mavlink
arm-none-eabi-size "$(example_elf stm32f405)" "$(example_elf stm32f405_uart)" "$(example_elf stm32f405_mavlink)"

echo "--- firmware: board crates (boards/*: release builds, clippy, sizes)"
scripts/boards.sh

echo "--- firmware: embassy on QEMU (boards/embassy_qemu: the async link task, the scripted session)"
CARGO_TARGET_DIR="$PWD/target/boards" boards/embassy_qemu/run.sh
