#!/usr/bin/env bash
# The firmware on an emulated STM32F405 (QEMU netduinoplus2; the root crate's example
# `qemu_demo`, linked with the root's memory.x) driving a simulated gimbal over an in-memory
# CAN bus, then over the serial line: a scripted session with telemetry. Exit status 0 only if
# every step's effect was seen in the postbacks.
#
# Works on a fresh machine with Rust: installs the thumbv7em-none-eabihf target and
# qemu-system-arm when missing. QEMU is bounded by QEMU_TIMEOUT seconds (default 120).
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_qemu
echo "building the firmware (examples/qemu_demo.rs, release), then running it on QEMU" >&2
root_firmware_cargo run --quiet --release --locked --example qemu_demo --target "$TARGET"
