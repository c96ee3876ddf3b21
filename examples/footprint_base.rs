//! Footprint baseline: the skeleton of `footprint_driver` without the driver. See
//! `examples/common/footprint.rs` and `scripts/size-report.sh`.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/footprint.rs"]
mod footprint;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    footprint::use_mem_builtins();
    loop {
        footprint::can_skeleton();
        footprint::port_skeleton();
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
