#!/bin/sh
# Cargo runner for thumbv7em-none-eabihf (see .cargo/config.toml): `cargo run --example
# qemu_demo` at the root, `cargo run --bin NAME` in boards/stm32f405_qemu or benches/mcu (or
# an alias from the root) ends up here with the ELF as "$1".
#
#   qemu_demo   QEMU netduinoplus2 (STM32F405), semihosting on; QEMU's exit code is the
#               firmware's (semihosting SYS_EXIT: 0 on success, 1 on failure).
#   qemu_bench  the same with -icount shift=0: the virtual clock advances exactly 1 ns per
#               guest instruction, so SysTick readings count instructions deterministically.
#   stm32f405   a real board: probe-rs run (flash, then stream defmt-rtt logs).
#
# QEMU_TIMEOUT (seconds, default 120) bounds every QEMU run.
set -eu
elf="$1"
shift
name=$(basename "$elf")
timeout_s="${QEMU_TIMEOUT:-120}"

qemu() {
    if ! command -v qemu-system-arm >/dev/null 2>&1; then
        echo "qemu-system-arm not found: run scripts/demo.sh (installs it) or apt-get install qemu-system-arm" >&2
        exit 127
    fi
    exec timeout --foreground "$timeout_s" qemu-system-arm \
        -cpu cortex-m4 -machine netduinoplus2 -nographic \
        -semihosting-config enable=on,target=native \
        "$@" -kernel "$elf"
}

case "$name" in
    qemu_bench*) qemu -icount shift=0 ;;
    qemu_*) qemu ;;
    stm32f405*)
        if ! command -v probe-rs >/dev/null 2>&1; then
            # Single-quoted: in double quotes the backticks would run the install.
            echo 'probe-rs not found: run `cargo install probe-rs-tools` to flash a board; built ELF:' "$elf" >&2
            exit 127
        fi
        exec probe-rs run --chip STM32F405RGTx "$elf" "$@"
        ;;
    footprint_*)
        echo "$name is a size-measurement build, not meant to run: see scripts/size-report.sh" >&2
        exit 2
        ;;
    *)
        echo "qemu-run.sh: no runner for '$name' (expected qemu_* or stm32f405)" >&2
        exit 2
        ;;
esac
