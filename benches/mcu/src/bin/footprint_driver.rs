//! Footprint of the driver: `footprint_base` plus a `Gimbal` (default queues, in a static)
//! that a firmware drives with every kind of call: commands, a rate hold, text, vehicle data,
//! polling, events and counters. See `src/footprint.rs` and
//! `scripts/size-report.sh`.
#![no_std]
#![no_main]

// A module of each program, not a library: see its header.
#[path = "../footprint.rs"]
mod footprint;

#[cortex_m_rt::entry]
fn main() -> ! {
    use footprint::RegCan;
    use idu_gimbal::{Config, Gimbal};

    let Some(gimbal) =
        cortex_m::singleton!(: Gimbal<RegCan> = Gimbal::new(RegCan, Config::default()))
    else {
        cortex_m::asm::udf()
    };
    footprint::use_mem_builtins();
    loop {
        footprint::port_skeleton();
        footprint::drive(gimbal);
    }
}
