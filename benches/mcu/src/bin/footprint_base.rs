//! Footprint baseline: the skeleton of `footprint_driver` without the driver. See
//! `src/footprint.rs` and `scripts/size-report.sh`.
#![no_std]
#![no_main]

// A module of each program, not a library: see its header.
#[path = "../footprint.rs"]
mod footprint;

#[cortex_m_rt::entry]
fn main() -> ! {
    footprint::use_mem_builtins();
    loop {
        footprint::can_skeleton();
        footprint::port_skeleton();
    }
}
