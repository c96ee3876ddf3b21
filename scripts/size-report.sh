#!/usr/bin/env bash
# Flash and static RAM of the driver on thumbv7em-none-eabihf (release: opt-level "s", LTO),
# and of the firmware programs (boards/stm32f405, the root crate's qemu_demo, benches/mcu).
#
# A transport's share is the difference between two builds that differ only by it
# (benches/mcu/src/bin/): footprint_driver (a static Link with the default queues and its
# CanPort, driven with every kind of call) or footprint_serial (the same for a SerialLink
# and its SerialPort) minus footprint_base (the same skeleton: vector table, panic handler,
# a CAN driver and a UART over volatile registers, memcpy/memmove). Flash counts .vector_table + .text +
# .rodata + .data (initial values live in flash); static RAM counts .data + .bss + .uninit.
#
# Budgets: the goals where tighter than the floors: driver flash <= 6 KiB (the floor: 8 KiB);
# static RAM <= 512 B in all (a floor) and <= 288 B beyond the transmit queue's slots (256 B
# before closed-loop aiming, whose state takes 28 B of it: BENCHMARKS.md). The serial driver
# is held to the same RAM budget, and to 6.25 KiB of flash: the link it shares carries the
# closed loop's hooks (the tracker's hand-over, the attitude's accounting), about 350 B,
# beside its stream parser. The MAVLink bridge
# (footprint_bridge: a Bridge with a camera over footprint_driver's link and port) is measured
# against footprint_driver: flash <= 44 KiB (the camera definition files included, and the
# core's closed-loop aiming, which the bridge links and footprint_driver does not) and
# static RAM <= 4 KiB. Exit status 1 when one is exceeded.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_binutils

FLASH_BUDGET=6144
SERIAL_FLASH_BUDGET=6400
RAM_BUDGET=512
RAM_BEYOND_SLOTS_BUDGET=288
# The default queues' slots: 8 control frames of 8 bytes, 8 text frames of 9 (8 data bytes
# and whether the frame ends its text). src/link/queue.rs checks this size in a test.
TX_SLOTS=136
# The MAVLink bridge, everything beyond the plain CAN driver.
BRIDGE_FLASH_BUDGET=45056
BRIDGE_RAM_BUDGET=4096
# MAVLink 2 signing (the bridge's `signing` feature, a key configured): footprint_bridge
# built with it, less footprint_bridge without. SHA-256 in sha2's compact form
# (.cargo/config.toml), the streams' timestamps.
SIGNING_FLASH_BUDGET=4096
SIGNING_RAM_BUDGET=512

ensure_bench_toolchain
firmware_cargo benches/mcu "+$BENCH_TOOLCHAIN" build --release --locked \
    --bin footprint_base --bin footprint_driver --bin footprint_serial --bin footprint_bridge \
    --bin qemu_bench
firmware_cargo boards/stm32f405 "+$BENCH_TOOLCHAIN" build --release --locked \
    --bin stm32f405 --bin stm32f405_uart --bin stm32f405_mavlink
root_firmware_cargo "+$BENCH_TOOLCHAIN" build --release --locked --example qemu_demo --target "$TARGET"
# Signing, in a target directory of its own (the feature would reach every program of
# benches/mcu in the same one).
SIGNING_TARGET_DIR="$FIRMWARE_TARGET_DIR-signing"
(cd benches/mcu && CARGO_TARGET_DIR="$SIGNING_TARGET_DIR" cargo "+$BENCH_TOOLCHAIN" build --release \
    --locked --features signing --bin footprint_bridge)

# "flash ram" of an ELF, from its section sizes; exit 1 when it has no code to measure.
sizes() {
    arm-none-eabi-size -A "$1" | awk -v elf="$1" '
        $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" { flash += $2 }
        $1 == ".data" { flash += $2; ram += $2 }
        $1 == ".bss" || $1 == ".uninit" { ram += $2 }
        $1 == ".text" { text = 1 }
        END {
            if (!text) { print "size-report: " elf ": no .text to measure" > "/dev/stderr"; exit 1 }
            print flash + 0, ram + 0
        }'
}

# `measure FLASH_VAR RAM_VAR ELF`: the two sizes into the two variables; a missing or
# unreadable ELF ends the report (exit 1), never a budget met on zeros.
measure() {
    local out
    out=$(sizes "$3") || exit 1
    read -r "$1" "$2" <<<"$out"
}

measure base_flash base_ram "$(firmware_elf footprint_base)"
measure drv_flash drv_ram "$(firmware_elf footprint_driver)"
flash=$((drv_flash - base_flash))
ram=$((drv_ram - base_ram))
beyond=$((ram - TX_SLOTS))
measure ser_flash ser_ram "$(firmware_elf footprint_serial)"
serial_flash=$((ser_flash - base_flash))
serial_ram=$((ser_ram - base_ram))
measure br_flash br_ram "$(firmware_elf footprint_bridge)"
bridge_flash=$((br_flash - drv_flash))
bridge_ram=$((br_ram - drv_ram))

echo "Firmware images (release, thumbv7em-none-eabihf):"
printf "  %-18s %8s %8s\n" program "flash B" "RAM B"
for ex in stm32f405 stm32f405_uart stm32f405_mavlink qemu_demo qemu_bench footprint_base footprint_driver footprint_serial footprint_bridge; do
    measure f r "$(firmware_elf "$ex")"
    printf "  %-18s %8d %8d\n" "$ex" "$f" "$r"
done
echo "  (RAM excludes the stack, which cortex-m-rt places at the top of the 128 KiB.)"
echo
echo "Largest symbols of the driver build:"
arm-none-eabi-nm -C --size-sort -S -t d "$(firmware_elf footprint_driver)" | tail -12 |
    awk '{ printf "  %6d  %s %s\n", $2 + 0, $3, substr($0, index($0, $4)) }'
echo

# Verdicts are decided here, not inside $(...): a subshell could not set `status`.
status=0
flash_verdict=ok
ram_verdict=ok
beyond_verdict=ok
if [ "$flash" -gt "$FLASH_BUDGET" ]; then flash_verdict="OVER BUDGET"; status=1; fi
if [ "$ram" -gt "$RAM_BUDGET" ]; then ram_verdict="OVER BUDGET"; status=1; fi
if [ "$beyond" -gt "$RAM_BEYOND_SLOTS_BUDGET" ]; then beyond_verdict="OVER BUDGET"; status=1; fi
measure sig_flash sig_ram "$SIGNING_TARGET_DIR/$TARGET/release/footprint_bridge"
signing_flash=$((sig_flash - br_flash))
signing_ram=$((sig_ram - br_ram))
signing_flash_verdict=ok
signing_ram_verdict=ok
if [ "$signing_flash" -gt "$SIGNING_FLASH_BUDGET" ]; then signing_flash_verdict="OVER BUDGET"; status=1; fi
if [ "$signing_ram" -gt "$SIGNING_RAM_BUDGET" ]; then signing_ram_verdict="OVER BUDGET"; status=1; fi
bridge_flash_verdict=ok
bridge_ram_verdict=ok
if [ "$bridge_flash" -gt "$BRIDGE_FLASH_BUDGET" ]; then bridge_flash_verdict="OVER BUDGET"; status=1; fi
if [ "$bridge_ram" -gt "$BRIDGE_RAM_BUDGET" ]; then bridge_ram_verdict="OVER BUDGET"; status=1; fi
serial_flash_verdict=ok
serial_ram_verdict=ok
if [ "$serial_flash" -gt "$SERIAL_FLASH_BUDGET" ]; then serial_flash_verdict="OVER BUDGET"; status=1; fi
if [ "$serial_ram" -gt "$RAM_BUDGET" ]; then serial_ram_verdict="OVER BUDGET"; status=1; fi
echo "| driver (footprint_driver - footprint_base) | bytes | budget | verdict |"
echo "|---|---:|---:|---|"
echo "| flash | $flash | <= $FLASH_BUDGET | $flash_verdict |"
echo "| static RAM | $ram | <= $RAM_BUDGET | $ram_verdict |"
echo "| static RAM beyond the $TX_SLOTS B of TX slots | $beyond | <= $RAM_BEYOND_SLOTS_BUDGET | $beyond_verdict |"
echo
echo "| serial driver (footprint_serial - footprint_base) | bytes | budget | verdict |"
echo "|---|---:|---:|---|"
echo "| flash | $serial_flash | <= $SERIAL_FLASH_BUDGET | $serial_flash_verdict |"
echo "| static RAM | $serial_ram | <= $RAM_BUDGET | $serial_ram_verdict |"
echo
echo "| MAVLink bridge, beyond the CAN driver (footprint_bridge - footprint_driver) | bytes | budget | verdict |"
echo "|---|---:|---:|---|"
echo "| flash | $bridge_flash | <= $BRIDGE_FLASH_BUDGET | $bridge_flash_verdict |"
echo "| static RAM | $bridge_ram | <= $BRIDGE_RAM_BUDGET | $bridge_ram_verdict |"
echo
echo "| MAVLink 2 signing (footprint_bridge with the signing feature and a key, less without) | bytes | budget | verdict |"
echo "|---|---:|---:|---|"
echo "| flash | $signing_flash | <= $SIGNING_FLASH_BUDGET | $signing_flash_verdict |"
echo "| static RAM | $signing_ram | <= $SIGNING_RAM_BUDGET | $signing_ram_verdict |"
exit "$status"
