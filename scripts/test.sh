#!/usr/bin/env bash
# The whole test suite: what the README's second command runs and what CI runs.
#
#   scripts/test.sh                  every stage, in order
#   scripts/test.sh STAGE [STAGE...] only those, e.g. `scripts/test.sh fast`
#
# Stages:
#   fast      fmt, clippy (host and thumbv7em), library builds for the MCU, docs, package
#             dry-runs, MSRV builds, `cargo test` of the workspace (with and without the
#             bridge's optional features)
#   firmware  the QEMU sessions (the core's demo, the MAVLink bridge's, embassy's), the
#             STM32F405 release builds, the board crates, the MCU benchmarks' build and lints
#             (benches/mcu)
#   e2e       real third-party clients against gimbalctl: pymavlink as PX4 turning the
#             vehicle (closed-loop aiming), as PX4 and ArduPilot and as a ground station of
#             the camera (FTP, parameters, tracking), MAVSDK's camera plugin, each against
#             both behaviours of the simulated gimbal in lock; a QGroundControl-faithful
#             client for every camera family, MAVProxy's camera module, MAVLink 2 signing
#             with pymavlink's; the host simulation session
#   bench     instruction counts under QEMU -icount (the MAVLink bridge beside the C MAVLink
#             library on the same bytes) and flash/RAM sizes, with the pinned bench
#             toolchain; exits 1 over a budget
#
# Each stage installs what it needs when it is missing, and says what before installing it.
set -euo pipefail
cd "$(dirname "$0")/.."

# The suite builds each thing once: it keeps no incremental caches and no debug info (a
# failing assertion still names its file and line; code generation is the same). Full DWARF
# for every dependency of the host, MSRV, board and bench builds, with the incremental
# caches, filled about 8 GB of target/, more than a CI machine had free; without them it
# ends near 3.5 GB. The environment overrides each.
export CARGO_INCREMENTAL="${CARGO_INCREMENTAL:-0}"
export CARGO_PROFILE_DEV_DEBUG="${CARGO_PROFILE_DEV_DEBUG:-0}"
export CARGO_PROFILE_RELEASE_DEBUG="${CARGO_PROFILE_RELEASE_DEBUG:-0}"

step() { printf '\n=== %s\n' "$*"; }

# apt-get (quiet: one line an install, its output only when it fails) and the firmware
# scripts' helpers.
. scripts/firmware-env.sh
apt_install() {
    echo "installing (apt): $*"
    _apt_install "$@"
}
pip_install() {
    ensure_python
    echo "installing (pip): $*"
    python3 -m pip install --quiet --disable-pip-version-check "$@"
}

stage_fast() {
    step "toolchain: thumbv7em-none-eabihf target, rustfmt, clippy"
    if ! rustup target list --installed | grep -qx thumbv7em-none-eabihf; then
        echo "installing (rustup): the thumbv7em-none-eabihf target"
        rustup target add thumbv7em-none-eabihf >/dev/null
    fi
    if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
        echo "installing (rustup): rustfmt and clippy"
        rustup component add rustfmt clippy >/dev/null
    fi

    step "cargo fmt --check"
    cargo fmt --all -- --check

    step "clippy, host, all targets and features"
    cargo clippy --workspace --all-targets --all-features -- -D warnings

    step "clippy, thumbv7em-none-eabihf, lib and examples"
    cargo clippy --target thumbv7em-none-eabihf --lib --examples -- -D warnings

    step "firmware support library (boards/support): clippy for thumbv7em-none-eabihf, all features"
    # Its QEMU and meter parts build for bare-metal ARM only, so the host clippy above skips them.
    cargo clippy -p idu-firmware-support --target thumbv7em-none-eabihf --all-features -- -D warnings

    step "library builds for thumbv7em-none-eabihf: no features, defmt, mock; the FDCAN adapter"
    cargo build --target thumbv7em-none-eabihf --lib
    cargo build --target thumbv7em-none-eabihf --lib --features defmt
    cargo build --target thumbv7em-none-eabihf --lib --features mock
    cargo clippy -p idu-gimbal-fdcan --target thumbv7em-none-eabihf --lib --features defmt -- -D warnings

    step "MAVLink bridge (idu-gimbal-mavlink): clippy and build for thumbv7em-none-eabihf"
    cargo clippy -p idu-gimbal-mavlink --target thumbv7em-none-eabihf --lib --examples -- -D warnings
    # With MAVLink 2 signing: sha2 without std, as a firmware builds it.
    cargo clippy -p idu-gimbal-mavlink --target thumbv7em-none-eabihf --lib --features signing -- -D warnings
    cargo build -p idu-gimbal-mavlink --target thumbv7em-none-eabihf --lib
    cargo build -p idu-gimbal-mavlink --target thumbv7em-none-eabihf --lib --features roi
    cargo build -p idu-gimbal-mavlink --target thumbv7em-none-eabihf --lib --features defmt

    step "docs, warnings denied"
    RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --all-features
    # docs.rs builds each crate alone, with the features its [package.metadata.docs.rs]
    # lists: each library crate lists every optional feature (so that nothing behind one is
    # missing from its published docs), and its docs build so, warnings denied.
    docs_rs=$(cargo metadata --no-deps --format-version 1 | python3 -c '
import json, sys
bad = 0
for p in json.load(sys.stdin)["packages"]:
    name = p["name"]
    if name not in ("idu-gimbal", "idu-gimbal-mavlink", "idu-gimbal-fdcan"):
        continue
    docs_rs = ((p.get("metadata") or {}).get("docs") or {}).get("rs") or {}
    listed = docs_rs.get("features", [])
    optional = set(p["features"]) - {"default"}
    if set(listed) != optional:
        print(f"{name}: docs.rs features {sorted(listed)}, optional features {sorted(optional)}", file=sys.stderr)
        bad = 1
    print(name, ",".join(listed))
sys.exit(bad)
')
    while read -r crate features; do
        RUSTDOCFLAGS="-D warnings" cargo doc --quiet -p "$crate" --no-deps --features "$features"
    done <<<"$docs_rs"

    step "packages: cargo publish --dry-run of the library crates (idu-gimbal, idu-gimbal-mavlink, idu-gimbal-fdcan)"
    # The bridge depends on the unpublished core: cargo packages the workspace's crates
    # together. --allow-dirty: tests may append to proptest-regressions files; the package's
    # contents are fixed by each crate's `include`. cargo unpacks the packaged crates into
    # its registry cache under a name keyed by the target directory's path and the version,
    # and reuses what it finds there: a copy from an earlier run of an older tree would be
    # built instead of this one. Those copies of these two crates go first, and so do their
    # builds in target/ (where the verification builds): a registry crate is never rebuilt
    # for a change of its content, so the bridge would link an older core's build.
    cargo clean --quiet -p idu-gimbal -p idu-gimbal-mavlink -p idu-gimbal-fdcan
    cargo_home=${CARGO_HOME:-$HOME/.cargo}
    rm -rf "$cargo_home"/registry/src/-*/idu-gimbal-[0-9]* \
        "$cargo_home"/registry/src/-*/idu-gimbal-mavlink-[0-9]* \
        "$cargo_home"/registry/src/-*/idu-gimbal-fdcan-[0-9]* \
        "$cargo_home"/registry/cache/-*/idu-gimbal-[0-9]*.crate \
        "$cargo_home"/registry/cache/-*/idu-gimbal-mavlink-[0-9]*.crate \
        "$cargo_home"/registry/cache/-*/idu-gimbal-fdcan-[0-9]*.crate
    cargo publish --dry-run --workspace --exclude gimbalctl --allow-dirty 2>&1 |
        grep -v '^warning: ignoring \(test\|example\)'

    step "MSRV: the declared rust-version builds each library crate"
    # Read from the manifests (idu-gimbal and idu-gimbal-fdcan 1.87; idu-gimbal-mavlink 1.88, as mavio's code
    # generator pulls icu 2.4), installed with the minimal profile.
    msrv() { sed -n 's/^rust-version = "\(.*\)"$/\1/p' "$1"; }
    core_msrv=$(msrv Cargo.toml)
    bridge_msrv=$(msrv idu-gimbal-mavlink/Cargo.toml)
    for v in "$core_msrv" "$bridge_msrv"; do
        if ! rustup toolchain list | grep -q "^$v-"; then
            echo "installing (rustup): the Rust $v toolchain (minimal profile)"
            rustup toolchain install "$v" --profile minimal >/dev/null 2>&1
        fi
    done
    CARGO_TARGET_DIR=target/msrv cargo "+$core_msrv" check -p idu-gimbal --features std,defmt,mock
    CARGO_TARGET_DIR=target/msrv cargo "+$core_msrv" check -p idu-gimbal-fdcan --features std,defmt
    CARGO_TARGET_DIR=target/msrv cargo "+$bridge_msrv" check -p idu-gimbal-mavlink --features roi,signing
    # Nothing else reads these checks (half a gigabyte).
    rm -rf target/msrv

    step "tmux (gimbalctl control's terminal test)"
    command -v tmux >/dev/null 2>&1 || apt_install tmux
    tmux -V

    step "cargo test --workspace --all-features"
    cargo test --workspace --all-features

    step "MAVLink bridge tests without its optional features (the firmware's build: ROI unsupported)"
    cargo test -p idu-gimbal-mavlink
}

stage_firmware() {
    step "firmware: QEMU sessions, STM32F405 release builds, board crates"
    scripts/firmware-checks.sh
}

stage_e2e() {
    ensure_python
    python3 -c "import pymavlink" 2>/dev/null || pip_install pymavlink==2.4.50
    python3 -c "import mavsdk" 2>/dev/null || pip_install mavsdk==4.1.0
    # MAVProxy without what its metadata pulls in for the GUI and the 3-D map (vtk,
    # matplotlib, opencv-python, quantized-mesh-tile, pynmeagps: hundreds of MB more): its
    # camera module imports numpy and cv2 (lib/camera_projection.py), defusedxml (its
    # definition.py), mavproxy.py pyserial; pymavlink stays the one above. About 350 MB.
    python3 -c "import MAVProxy, cv2, numpy, defusedxml, serial" 2>/dev/null ||
        pip_install --no-deps --no-warn-conflicts mavproxy==1.8.75 pyserial==3.5 defusedxml==0.7.1 \
            numpy==2.4.6 opencv-python-headless==5.0.0.93
    cargo build --quiet -p gimbalctl

    step "MAVLink aiming: pymavlink as PX4, the vehicle turning, against both lock behaviours"
    python3 gimbalctl/tests/mavlink_aiming.py target/debug/gimbalctl

    # Once, outside the lock loop: the camera does not depend on what lock holds.
    step "MAVLink camera: QGroundControl's camera client (from its source) against every camera family"
    python3 gimbalctl/tests/qgc_camera.py target/debug/gimbalctl

    # The document leaves open what the gimbal holds in lock while the vehicle turns: every
    # client runs against the simulated gimbal holding its north heading, then its motor angle.
    for holds in north motor; do
        export GIMBALCTL_SIM_LOCK_HOLDS=$holds
        step "MAVLink end to end: pymavlink as PX4 and ArduPilot against gimbalctl mavlink --sim (lock holds $holds)"
        python3 gimbalctl/tests/mavlink_e2e.py target/debug/gimbalctl

        step "MAVLink camera: FTP, extended parameters, tracking, focus with pymavlink, dual light (lock holds $holds)"
        python3 gimbalctl/tests/mavlink_camera.py target/debug/gimbalctl

        step "MAVLink camera: MAVSDK's Camera plugin as the ground station (lock holds $holds)"
        python3 gimbalctl/tests/mavsdk_camera.py target/debug/gimbalctl
    done
    unset GIMBALCTL_SIM_LOCK_HOLDS

    # Once: the vehicle does not turn in it, so what lock holds changes nothing MAVProxy sees.
    step "MAVLink camera: MAVProxy's camera module as the ground station, through a stand-in ArduPilot (dual light with a field of view, X3)"
    python3 gimbalctl/tests/mavproxy_camera.py target/debug/gimbalctl

    step "MAVLink 2 signing: pymavlink's own signing against gimbalctl mavlink --signing-passphrase and --signing-key-file"
    python3 gimbalctl/tests/mavlink_signing.py target/debug/gimbalctl

    step "host_sim: the link and its port against the simulated gimbal, scripted"
    cargo run --quiet --example host_sim --features mock,std
}

stage_bench() {
    step "bench: instruction counts and sizes against their budgets (pinned toolchain)"
    scripts/bench.sh
}

stages=("$@")
if [ "${#stages[@]}" -eq 0 ]; then
    stages=(fast firmware e2e bench)
fi
for s in "${stages[@]}"; do
    case "$s" in
    fast | firmware | e2e | bench) ;;
    *)
        echo "error: unknown stage '$s' (valid: fast, firmware, e2e, bench)" >&2
        exit 2
        ;;
    esac
done
for s in "${stages[@]}"; do
    "stage_$s"
    # What the stage left on disk, so that a run short of space shows where it went.
    printf '\n%s stage done: target/ %s, %s free\n' "$s" \
        "$(du -sh target 2>/dev/null | cut -f1)" "$(df -h --output=avail . | tail -n 1 | tr -d ' ')"
done
