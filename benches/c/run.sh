#!/bin/bash
# The C reference receive path: builds postback_rx.c + the harness with arm-none-eabi-gcc 12.2 and
# measures it on QEMU netduinoplus2 with -icount shift=0 (see README.md). Prints a Markdown
# table; exit 0 when the build, the run and every correctness check succeed.
#
#   bash benches/c/run.sh            (from anywhere; builds into benches/c/build/)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build="$here/build"

# Tools: install only what is missing (apt-get update first; sudo only when not root).
missing=()
command -v arm-none-eabi-gcc >/dev/null 2>&1 || missing+=(gcc-arm-none-eabi)
# newlib-nano (memcpy etc.); the spec file is how the package shows up.
if ! command -v arm-none-eabi-gcc >/dev/null 2>&1 \
    || [ ! -e "$(arm-none-eabi-gcc -print-file-name=nano.specs)" ] \
    || [ "$(arm-none-eabi-gcc -print-file-name=nano.specs)" = nano.specs ]; then
    missing+=(libnewlib-arm-none-eabi)
fi
command -v qemu-system-arm >/dev/null 2>&1 || missing+=(qemu-system-arm)
if [ ${#missing[@]} -gt 0 ]; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "installing: ${missing[*]}" >&2
    $sudo apt-get update >&2
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y --no-install-recommends "${missing[@]}" >&2
fi

CC=arm-none-eabi-gcc
echo "$($CC --version | head -1); $(qemu-system-arm --version | head -1)" >&2
case "$($CC -dumpversion)" in
    12.2*) ;;
    *) echo "warning: the reference figures were measured with arm-none-eabi-gcc 12.2, this is $($CC -dumpversion)" >&2 ;;
esac

# postback_rx.c, the code under test, gets exactly the reference figures' flags (the warning flags change
# no code). The harness and startup code add -ffreestanding. Not for postback_rx.c: it implies
# -fno-builtin, which would turn its fixed-size memcpy into a call to newlib-nano's byte loop.
ANCHOR_FLAGS=(-O2 -mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16)
WARN=(-Wall -Wextra -Werror)
HARNESS_FLAGS=("${ANCHOR_FLAGS[@]}" -ffreestanding "${WARN[@]}")
LDFLAGS=(-nostartfiles --specs=nano.specs -T "$here/link.ld" -Wl,--gc-sections)

rm -rf "$build"
mkdir -p "$build"
$CC "${ANCHOR_FLAGS[@]}" "${WARN[@]}" -c "$here/postback_rx.c" -o "$build/postback_rx.o"
$CC "${ANCHOR_FLAGS[@]}" -S "$here/postback_rx.c" -o "$build/postback_rx.s" # for reading
for src in harness startup; do
    $CC "${HARNESS_FLAGS[@]}" -c "$here/$src.c" -o "$build/$src.o"
done
$CC "${HARNESS_FLAGS[@]}" "${LDFLAGS[@]}" "$build"/postback_rx.o "$build"/harness.o \
    "$build"/startup.o -o "$build/c_bench.elf" -lgcc

# QEMU writes semihosting output to its stderr: merge it so the table lands on stdout.
status=0
timeout 60 qemu-system-arm -cpu cortex-m4 -machine netduinoplus2 -nographic \
    -icount shift=0 -semihosting-config enable=on,target=native \
    -kernel "$build/c_bench.elf" </dev/null 2>&1 || status=$?

# Flash of the receive path: on_frame + crc_fly16 + the nibble table, from the symbol sizes.
# The document declares the table without const, so it lives in .data (32 B of RAM, plus its
# 32 B initial image in flash); it is counted once, as flash.
sym_size() {
    local hex
    hex=$(arm-none-eabi-nm -S "$build/c_bench.elf" | awk -v s="$1" '$4 == s { print $2 }')
    [ -n "$hex" ] || { echo "symbol $1 not found" >&2; exit 1; }
    echo $((16#$hex))
}
on_frame=$(sym_size on_frame)
crc=$(sym_size crc_fly16)
table=$(sym_size wCRC_Table)
ram=$(( $(sym_size rx_buf) + $(sym_size rx_frame) + $(sym_size gimbal_status) + table ))
callees=$(arm-none-eabi-objdump -d "$build/postback_rx.o" | grep -oE 'bl[[:space:]]+[0-9a-f]+ <[^>]+>' | sort -u || true)
echo "| flash: \`on_frame\` + \`crc_fly16\` + \`wCRC_Table\` (bytes) | $((on_frame + crc + table)) = $on_frame + $crc + $table | |"
echo "| static RAM: \`rx_buf\`, \`rx_frame\`, \`gimbal_status\`, \`wCRC_Table\` (bytes) | $ram | |"
[ -z "$callees" ] || echo "calls made by postback_rx.o: $callees" >&2
echo
arm-none-eabi-size "$build/c_bench.elf"

if [ "$status" -ne 0 ]; then
    echo "c_bench: FAILED (QEMU exit status $status)" >&2
    exit 1
fi
