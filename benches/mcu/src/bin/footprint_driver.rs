//! Footprint of the CAN path: `footprint_base` plus a `Link` (default queues, in a static)
//! and its `CanPort`, that a firmware drives with every kind of call: commands, a rate hold, text, vehicle data,
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
    use idu_gimbal::{CanPort, Config, Link};

    // Both in one static, as a firmware holds them for its lifetime.
    let Some((link, port)) = cortex_m::singleton!(
        : (Link, CanPort<RegCan>) = (Link::new(Config::default()), CanPort::new(RegCan))
    ) else {
        cortex_m::asm::udf()
    };
    footprint::use_mem_builtins();
    loop {
        footprint::port_skeleton();
        footprint::drive(link, port);
    }
}
