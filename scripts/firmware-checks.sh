#!/usr/bin/env bash
# The firmware stage of the test suite (`scripts/test.sh firmware`):
#   1. the QEMU demo sessions must pass (exit 0): the core's (the root crate's example
#      qemu_demo), and the MAVLink bridge's (boards/stm32f405_qemu);
#   2. the STM32F405 firmware, CAN, UART and MAVLink bridge (boards/stm32f405), builds in
#      release mode (sizes printed);
#   3. every board crate under boards/ (STM32F405, RP2040, ESP32-C3, STM32H743, embassy, …)
#      builds in release mode and is rustfmt- and clippy-clean (scripts/boards.sh; sizes
#      printed), and so are the MCU benchmarks (benches/mcu);
#   4. no panic path of the libraries is left in that firmware (scripts/panic-paths.py: the
#      panic locations the images keep);
#   5. the embassy firmware's scripted session passes on QEMU (boards/embassy_qemu/run.sh).
#
# The budgets (instruction counts, sizes) are the bench stage's: scripts/bench.sh. Every
# QEMU run is bounded by QEMU_TIMEOUT seconds (default 120).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_qemu
ensure_binutils
ensure_pyelftools

echo "--- firmware: QEMU demo session"
scripts/demo.sh

echo "--- firmware: the MAVLink bridge's QEMU session (scripted autopilot, bridge, CAN, simulated gimbal)"
firmware_cargo boards/stm32f405_qemu run --release --locked --bin qemu_mavlink

echo "--- firmware: STM32F405 release builds (CAN, UART, MAVLink bridge)"
firmware_cargo boards/stm32f405 build --release --locked
arm-none-eabi-size "$(firmware_elf stm32f405)" "$(firmware_elf stm32f405_uart)" "$(firmware_elf stm32f405_mavlink)"

echo "--- firmware: board crates (boards/*: release builds, clippy, sizes)"
scripts/boards.sh

echo "--- firmware: the MCU benchmarks (benches/mcu: release build, rustfmt, clippy; run by the bench stage)"
firmware_cargo benches/mcu build --release --locked
firmware_cargo benches/mcu fmt --check
firmware_cargo benches/mcu clippy --release --locked -- -D warnings
# The signing bench, in the signing build's own target directory (scripts/size-report.sh).
(cd benches/mcu && CARGO_TARGET_DIR="$FIRMWARE_TARGET_DIR-signing" cargo clippy --release --locked \
    --features signing --bin qemu_bench_signing -- -D warnings)

echo "--- firmware: no panic path of the libraries in the boards' firmware (scripts/panic-paths.py)"
# The search itself first, on made-up bytes; then the images. The RP2040's panic-halt
# drops every location: nothing to look at there.
python3 scripts/panic-paths.py --self-test
python3 scripts/panic-paths.py "$PWD" \
    "$(firmware_elf stm32f405)" "$(firmware_elf stm32f405_uart)" "$(firmware_elf stm32f405_mavlink)" \
    "$(firmware_elf qemu_mavlink)" "$(firmware_elf board-stm32h743-fdcan)" \
    "$(firmware_elf embassy-stm32f405)" "$(firmware_elf embassy-qemu)" \
    "$FIRMWARE_TARGET_DIR/riscv32imc-unknown-none-elf/release/board-esp32c3-twai"

echo "--- firmware: embassy on QEMU (boards/embassy_qemu: the async link task, the scripted session)"
CARGO_TARGET_DIR="$FIRMWARE_TARGET_DIR" boards/embassy_qemu/run.sh
