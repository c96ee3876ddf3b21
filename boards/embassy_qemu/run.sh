#!/usr/bin/env bash
# embassy on an emulated STM32F405 (QEMU netduinoplus2) driving the simulated gimbal: builds
# the firmware (release) and runs its scripted session. Exit status: the session's (0 only if
# every check passed; 1 on a failed check, a panic or a HardFault; 124 if QEMU ran longer than
# QEMU_TIMEOUT seconds, default 120).
#
# Works on a fresh machine with Rust: installs the thumbv7em-none-eabihf target and
# qemu-system-arm when missing (scripts/firmware-env.sh).
set -euo pipefail
cd "$(dirname "$0")"
. ../../scripts/firmware-env.sh

ensure_target
ensure_qemu
cargo build --release --locked
# CARGO_TARGET_DIR, when set, is honoured (scripts/firmware-checks.sh passes the board crates'
# shared target/boards, where scripts/boards.sh has just built this).
elf="${CARGO_TARGET_DIR:-target}/$TARGET/release/embassy-qemu"

# The runner of .cargo/config.toml (`cargo run --release` here), with QEMU_TIMEOUT as the
# bound. -icount shift=3,sleep=off: virtual time is 8 ns per guest instruction, and idle WFI
# jumps to the next timer event, so the output is the same on every run and every host.
exec timeout --foreground "$QEMU_TIMEOUT" qemu-system-arm \
    -cpu cortex-m4 -machine netduinoplus2 -nographic \
    -semihosting-config enable=on,target=native \
    -icount shift=3,sleep=off \
    -kernel "$elf"
