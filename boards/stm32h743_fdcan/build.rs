//! Puts memory.x where the linker finds it, and passes the linker scripts unless the
//! rustflags already do (see .cargo/config.toml: the repository's config passes them for
//! this target).
use std::{env, fs, path::PathBuf};

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR is set by cargo"));
    fs::copy("memory.x", out.join("memory.x")).expect("memory.x is readable");
    println!("cargo:rustc-link-search={}", out.display());

    // The effective rustflags, separated by 0x1f: "-C", "link-arg=-Tlink.x", ...
    let flags = env::var("CARGO_ENCODED_RUSTFLAGS").unwrap_or_default();
    let given = |arg: &str| {
        flags
            .split('\x1f')
            .any(|f| f.strip_prefix("-C").unwrap_or(f) == format!("link-arg={arg}"))
    };
    for arg in ["-Tlink.x", "-Tdefmt.x", "--nmagic"] {
        if !given(arg) {
            println!("cargo:rustc-link-arg-bins={arg}");
        }
    }
    println!("cargo:rerun-if-env-changed=CARGO_ENCODED_RUSTFLAGS");
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
}
