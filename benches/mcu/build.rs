//! The C MAVLink library beside the bridge in `qemu_bench_mavlink`: when
//! `IDU_MAVLINK_C_INCLUDE` names the headers pymavlink's `mavgen` generated (C, MAVLink 2,
//! the common dialect; `scripts/bench.sh` generates them with a pinned pymavlink), this
//! compiles `c/mavlink_c.c` against them with arm-none-eabi-gcc at -O2 for the Cortex-M4F,
//! the flags of the C reference receive path (`benches/c`), and sets `cfg(mavlink_c)`.
//! Without it the benchmark measures the bridge alone and says so.

fn main() {
    println!("cargo:rerun-if-env-changed=IDU_MAVLINK_C_INCLUDE");
    println!("cargo:rerun-if-changed=c/mavlink_c.c");
    println!("cargo:rerun-if-changed=c/mavlink_c.h");
    println!("cargo:rustc-check-cfg=cfg(mavlink_c)");
    let Some(include) = std::env::var_os("IDU_MAVLINK_C_INCLUDE") else {
        return;
    };
    if std::env::var("TARGET").as_deref() != Ok("thumbv7em-none-eabihf") {
        return;
    }
    cc::Build::new()
        .compiler("arm-none-eabi-gcc")
        .file("c/mavlink_c.c")
        .include(&include)
        .include("c")
        // -O2 whatever the Rust profile's opt-level, as the C library's users build it.
        .opt_level(2)
        // No debug info whatever the Rust profile's: with it cc adds -fno-omit-frame-pointer,
        // which changes the code measured (about 5 instructions a message).
        .debug(false)
        .flag("-mcpu=cortex-m4")
        .flag("-mthumb")
        .flag("-mfloat-abi=hard")
        .flag("-mfpu=fpv4-sp-d16")
        .flag("-Wno-address-of-packed-member")
        .compile("mavlink_c");
    println!("cargo:rustc-cfg=mavlink_c");
}
