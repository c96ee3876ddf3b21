#!/usr/bin/env bash
# A poll generic over its port compiles to the poll written for the port: builds
# benches/mcu's footprint_generic (release, thumbv7em-none-eabihf, the bench toolchain) and
# compares, instruction by instruction, each function written for one port (poll_can,
# poll_serial) with the generic function at that port (poll_any_can, poll_any_serial).
# Addresses are taken relative to each function; calls must reach the same functions. Two
# names at one address (the compiler made one an alias of the other) are the same code.
# Exit status 1 when a pair differs.
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

ensure_target
ensure_bench_toolchain
ensure_binutils

firmware_cargo benches/mcu "+$BENCH_TOOLCHAIN" build --release --locked --bin footprint_generic
elf=$(firmware_elf footprint_generic)

# The instructions of function $1: mnemonic and operands, its own name and branch targets
# made relative, comments dropped.
body() {
    arm-none-eabi-objdump -d --no-show-raw-insn --disassemble="$1" "$elf" |
        awk -v f="$1" '
            /^ *[0-9a-f]+:\t/ {
                sub(/^ *[0-9a-f]+:\t/, "")
                sub(/[ \t]*@.*/, "")
                gsub("<" f "\\+", "<SELF+")
                gsub(/[0-9a-f]+ </, "<")
                print
            }'
}

address() {
    arm-none-eabi-nm "$elf" | awk -v f="$1" '$3 == f { print $1 }'
}

status=0
for pair in "poll_can poll_any_can" "poll_serial poll_any_serial"; do
    set -- $pair
    a=$(address "$1") b=$(address "$2")
    if [ -z "$a" ] || [ -z "$b" ]; then
        echo "port-generic: $1 or $2 missing from the build" >&2
        status=1
        continue
    fi
    if [ "$a" = "$b" ]; then
        echo "  $2 = $1: one function (the same address)"
        continue
    fi
    # Read here, not in a process substitution, so that a failed disassembly stops the
    # check (set -e) instead of comparing two empty bodies.
    one=$(body "$1")
    other=$(body "$2")
    if [ -z "$one" ] || [ -z "$other" ]; then
        echo "port-generic: no instructions disassembled for $1 or $2" >&2
        status=1
    elif [ "$one" = "$other" ]; then
        echo "  $2 = $1: the same $(printf '%s\n' "$one" | wc -l) instructions"
    else
        echo "port-generic: $2 differs from $1:" >&2
        diff <(printf '%s\n' "$one") <(printf '%s\n' "$other") >&2 || true
        status=1
    fi
done
exit "$status"
