#!/usr/bin/env bash
# Flash and static RAM of the driver on thumbv7em-none-eabihf (release: opt-level "s", LTO),
# and of the firmware examples.
#
# The driver's share is the difference between two builds that differ only by the driver:
# examples/footprint_driver.rs (a static Gimbal with the default queues, driven with every
# kind of call) minus examples/footprint_base.rs (the same skeleton: vector table, panic
# handler, a CAN driver over volatile registers, memcpy/memmove). Flash counts
# .vector_table + .text + .rodata + .data (initial values live in flash); static RAM counts
# .data + .bss + .uninit.
#
# Budgets (issue 4): driver <= 8 KiB flash, <= 512 B static RAM. Exit status 1 when exceeded.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_binutils

FLASH_BUDGET=8192
RAM_BUDGET=512

cargo build --release --target "$TARGET" \
    --example footprint_base --example footprint_driver \
    --example stm32f405 --example qemu_demo --example qemu_bench

# "flash ram" of an ELF, from its section sizes.
sizes() {
    arm-none-eabi-size -A "$1" | awk '
        $1 == ".vector_table" || $1 == ".text" || $1 == ".rodata" { flash += $2 }
        $1 == ".data" { flash += $2; ram += $2 }
        $1 == ".bss" || $1 == ".uninit" { ram += $2 }
        END { print flash + 0, ram + 0 }'
}

read -r base_flash base_ram < <(sizes "$(example_elf footprint_base)")
read -r drv_flash drv_ram < <(sizes "$(example_elf footprint_driver)")
flash=$((drv_flash - base_flash))
ram=$((drv_ram - base_ram))

echo "Firmware images (release, thumbv7em-none-eabihf):"
printf "  %-18s %8s %8s\n" example "flash B" "RAM B"
for ex in stm32f405 qemu_demo qemu_bench footprint_base footprint_driver; do
    read -r f r < <(sizes "$(example_elf "$ex")")
    printf "  %-18s %8d %8d\n" "$ex" "$f" "$r"
done
echo "  (RAM excludes the stack, which cortex-m-rt places at the top of the 128 KiB.)"
echo
echo "Largest symbols of the driver build:"
arm-none-eabi-nm -C --size-sort -S -t d "$(example_elf footprint_driver)" | tail -12 |
    awk '{ printf "  %6d  %s %s\n", $2 + 0, $3, substr($0, index($0, $4)) }'
echo

# Verdicts are decided here, not inside $(...): a subshell could not set `status`.
status=0
flash_verdict=ok
ram_verdict=ok
if [ "$flash" -gt "$FLASH_BUDGET" ]; then flash_verdict="OVER BUDGET"; status=1; fi
if [ "$ram" -gt "$RAM_BUDGET" ]; then ram_verdict="OVER BUDGET"; status=1; fi
echo "| driver (footprint_driver - footprint_base) | bytes | budget | verdict |"
echo "|---|---:|---:|---|"
echo "| flash | $flash | <= $FLASH_BUDGET | $flash_verdict |"
echo "| static RAM | $ram | <= $RAM_BUDGET | $ram_verdict |"
exit "$status"
