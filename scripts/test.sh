#!/usr/bin/env bash
# The whole test suite: what the README's second command runs and what CI runs.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n=== %s\n' "$*"; }

step "toolchain: thumbv7em-none-eabihf target, rustfmt, clippy"
rustup target add thumbv7em-none-eabihf >/dev/null
rustup component add rustfmt clippy >/dev/null 2>&1 || true

step "cargo fmt --check"
cargo fmt --all -- --check

step "clippy, host, all targets and features"
cargo clippy --workspace --all-targets --all-features -- -D warnings

step "clippy, thumbv7em-none-eabihf, lib and examples"
cargo clippy --target thumbv7em-none-eabihf --lib --examples -- -D warnings

step "library builds for thumbv7em-none-eabihf: no features, defmt, mock, fdcan"
cargo build --target thumbv7em-none-eabihf --lib
cargo build --target thumbv7em-none-eabihf --lib --features defmt
cargo build --target thumbv7em-none-eabihf --lib --features mock
cargo build --target thumbv7em-none-eabihf --lib --features fdcan

step "MAVLink bridge (idu-gimbal-mavlink): clippy and build for thumbv7em-none-eabihf"
cargo clippy -p idu-gimbal-mavlink --target thumbv7em-none-eabihf --lib --examples -- -D warnings
cargo build -p idu-gimbal-mavlink --target thumbv7em-none-eabihf --lib

step "docs, warnings denied"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --all-features

step "packages: cargo publish --dry-run of the library crates (idu-gimbal, idu-gimbal-mavlink)"
# The bridge depends on the unpublished core: cargo packages the workspace's crates
# together. --allow-dirty: tests may append to proptest-regressions files; the package's
# contents are fixed by each crate's `include`.
cargo publish --dry-run --workspace --exclude gimbalctl --allow-dirty 2>&1 |
    grep -v '^warning: ignoring \(test\|example\)'

step "MSRV: the declared rust-version builds each library crate"
# Read from the manifests (idu-gimbal 1.87; idu-gimbal-mavlink 1.88, as mavio's code
# generator pulls icu 2.4), installed with the minimal profile.
msrv() { sed -n 's/^rust-version = "\(.*\)"$/\1/p' "$1"; }
core_msrv=$(msrv Cargo.toml)
bridge_msrv=$(msrv idu-gimbal-mavlink/Cargo.toml)
for v in "$core_msrv" "$bridge_msrv"; do
    rustup toolchain install "$v" --profile minimal >/dev/null 2>&1
done
CARGO_TARGET_DIR=target/msrv cargo "+$core_msrv" check -p idu-gimbal --features std,defmt,mock,fdcan
CARGO_TARGET_DIR=target/msrv cargo "+$bridge_msrv" check -p idu-gimbal-mavlink

# Firmware steps (QEMU demo, benchmarks, STM32F405 release build) run when present.
if [ -x scripts/firmware-checks.sh ]; then
  step "firmware"
  scripts/firmware-checks.sh
fi

step "tmux (gimbalctl control's terminal test)"
if ! command -v tmux >/dev/null 2>&1; then
  as_root() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
  as_root apt-get update -qq
  as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends tmux
fi
tmux -V

step "cargo test --workspace --all-features"
cargo test --workspace --all-features

step "MAVLink bridge tests without its optional features (the firmware's build: ROI unsupported)"
cargo test -p idu-gimbal-mavlink

step "MAVLink end to end: pymavlink as the autopilot against gimbalctl mavlink --sim"
if ! python3 -c "import pymavlink" 2>/dev/null; then
    python3 -m pip install --quiet --disable-pip-version-check pymavlink==2.4.50
fi
cargo build --quiet -p gimbalctl
python3 gimbalctl/tests/mavlink_e2e.py target/debug/gimbalctl

step "MAVLink camera: MAVSDK's Camera plugin as the ground station against gimbalctl mavlink --sim"
if ! python3 -c "import mavsdk" 2>/dev/null; then
    python3 -m pip install --quiet --disable-pip-version-check mavsdk==4.1.0
fi
python3 gimbalctl/tests/mavsdk_camera.py target/debug/gimbalctl

step "host_sim: the driver against the simulated gimbal, scripted"
cargo run --quiet --example host_sim --features mock,std
