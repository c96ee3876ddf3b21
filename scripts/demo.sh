#!/usr/bin/env bash
# The firmware on an emulated STM32F405 (QEMU netduinoplus2; `qemu_demo` of
# boards/stm32f405_qemu) driving a simulated gimbal over an in-memory CAN bus: a scripted session with telemetry. Exit status 0 only if every step's
# effect was seen in the postbacks.
#
# Works on a fresh machine with Rust: installs the thumbv7em-none-eabihf target and
# qemu-system-arm when missing. QEMU is bounded by QEMU_TIMEOUT seconds (default 120).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_qemu
echo "building the firmware (boards/stm32f405_qemu, release), then running it on QEMU" >&2
firmware_cargo boards/stm32f405_qemu run --quiet --release --locked --bin qemu_demo
