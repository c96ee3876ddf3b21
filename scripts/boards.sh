#!/usr/bin/env bash
# Builds every board crate under boards/*/ (each a standalone crate with its own workspace,
# Cargo.lock, .cargo/config.toml naming its target, and linker setup): a release build
# (the ELF is linked), rustfmt --check and clippy with -D warnings (the root's `cargo fmt
# --all` and clippy do not reach them: they are outside its workspace), and the ELF's size
# (text, data, bss).
#
# Generic: a new boards/<name>/ is picked up with nothing to add here. The Rust target of
# each crate comes from `target = "…"` under [build] in its .cargo/config.toml and is
# installed with rustup when missing. A crate without a `[workspace]` of its own belongs to the
# root workspace (boards/support, the library the boards share) and is checked with it, by the
# fast stage of scripts/test.sh. All crates share one target directory (target/boards,
# scripts/firmware-env.sh; BOARDS_TARGET_DIR overrides it), so dependencies they have in
# common build once per target.
#
# Exits non-zero when any crate fails to build, rustfmt or clippy, or when its lock file is out
# of date (--locked); every crate is still tried and the failures are listed at the end.
#
#   scripts/boards.sh              all boards
#   scripts/boards.sh rp2040_mcp2515 esp32c3_twai     only these (an unknown name: exit 2,
#                                                     the valid names on stderr)
set -uo pipefail
cd "$(dirname "$0")/.."
. scripts/firmware-env.sh

export CARGO_TARGET_DIR="${BOARDS_TARGET_DIR:-$FIRMWARE_TARGET_DIR}"
start=$SECONDS

# The size tool: llvm-size reads every target's ELF (Debian package `llvm`); failing that,
# the GNU binutils for ARM (binutils-arm-none-eabi), which reads ARM ELFs only.
size_tool() {
    if command -v llvm-size >/dev/null 2>&1; then
        echo llvm-size
        return
    fi
    echo "installing llvm (llvm-size reads ARM and RISC-V ELFs)" >&2
    if _apt_install llvm >&2 && command -v llvm-size >/dev/null 2>&1; then
        echo llvm-size
    elif command -v arm-none-eabi-size >/dev/null 2>&1; then
        echo arm-none-eabi-size
    fi
}

# The [build] target of a crate's .cargo/config.toml.
board_target() {
    sed -n 's/^[[:space:]]*target[[:space:]]*=[[:space:]]*"\([^"]*\)".*/\1/p' "$1/.cargo/config.toml" | head -n 1
}

ensure_rust_target() {
    if command -v rustup >/dev/null 2>&1 && ! rustup target list --installed 2>/dev/null | grep -qx "$1"; then
        echo "installing the $1 Rust target" >&2
        _quiet rustup target add "$1"
    fi
}

selected=("$@")
all=()
for dir in boards/*/; do
    dir=${dir%/}
    [ -f "$dir/Cargo.toml" ] || continue
    grep -q '^\[workspace\]' "$dir/Cargo.toml" || continue
    all+=("$dir")
done
if [ ${#all[@]} -eq 0 ]; then
    echo "boards: no board crate found under boards/" >&2
    exit 1
fi
boards=()
if [ ${#selected[@]} -eq 0 ]; then
    boards=("${all[@]}")
else
    for name in "${selected[@]}"; do
        if [ -z "$name" ] || [ ! -d "boards/$name" ] || ! printf '%s\n' "${all[@]}" | grep -qxF "boards/$name"; then
            valid=$(printf '%s\n' "${all[@]}" | sed 's|^boards/||' | paste -sd' ')
            echo "boards: unknown board '$name' (valid: $valid)" >&2
            exit 2
        fi
        boards+=("boards/$name")
    done
fi

SIZE=$(size_tool)
failures=()
elfs=()
for dir in "${boards[@]}"; do
    name=$(basename "$dir")
    target=$(board_target "$dir")
    if [ -z "$target" ]; then
        echo "boards: $dir/.cargo/config.toml names no [build] target" >&2
        failures+=("$name: no target")
        continue
    fi
    ensure_rust_target "$target" || { failures+=("$name: rustup target add $target"); continue; }

    echo "--- boards: $name ($target): release build"
    t0=$SECONDS
    # The executables cargo linked, from its JSON messages (diagnostics still rendered).
    if out=$(cd "$dir" && cargo build --release --locked --message-format=json-render-diagnostics); then
        mapfile -t built < <(printf '%s\n' "$out" | grep -o '"executable":"[^"]*"' | sed 's/"executable":"\(.*\)"/\1/')
        if [ ${#built[@]} -eq 0 ]; then
            failures+=("$name: no executable linked")
        fi
        elfs+=("${built[@]}")
        echo "boards: $name built in $((SECONDS - t0)) s"
    else
        failures+=("$name: build")
    fi

    echo "--- boards: $name ($target): rustfmt --check, clippy -D warnings"
    if ! (cd "$dir" && cargo fmt --check); then
        failures+=("$name: rustfmt")
    fi
    if ! (cd "$dir" && cargo clippy --release --locked -- -D warnings); then
        failures+=("$name: clippy")
    fi
done

echo "--- boards: sizes (bytes; text = flash code and constants, data = initialised RAM also stored in flash, bss = zeroed RAM)"
# Berkeley format counts every allocated read-only section as text, reserved regions too: on
# the ESP32-C3 that is esp-hal's .stack (all free RAM) and its *_dummy address-space padding.
# `llvm-size -A <elf>` lists the sections.
if [ ${#elfs[@]} -gt 0 ]; then
    if [ -n "$SIZE" ]; then
        "$SIZE" "${elfs[@]}" || failures+=("size")
    else
        echo "boards: no size tool (llvm-size or arm-none-eabi-size) available" >&2
        failures+=("size: no tool")
    fi
fi

echo "boards: ${#boards[@]} crate(s) in $((SECONDS - start)) s"
if [ ${#failures[@]} -gt 0 ]; then
    printf 'boards: FAILED: %s\n' "${failures[@]}" >&2
    exit 1
fi
echo "boards: all built, formatted and clippy-clean"
