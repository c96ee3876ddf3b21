//! Footprint of the serial driver: `footprint_base` plus a `SerialGimbal` (default queue, in
//! a static) that a firmware drives with every kind of call the serial path offers:
//! commands, a rate hold, vehicle data observed for point-at, polling, events and counters.
//! See `src/footprint.rs` and `scripts/size-report.sh`.
#![no_std]
#![no_main]

// A module of each program, not a library: see its header.
#[path = "../footprint.rs"]
mod footprint;

#[cortex_m_rt::entry]
fn main() -> ! {
    use footprint::{input, output, RegPort};
    use idu_gimbal::{Config, Instant, SerialGimbal};

    let Some(gimbal) = cortex_m::singleton!(
        : SerialGimbal<RegPort> = SerialGimbal::new(RegPort, Config::default())
    ) else {
        cortex_m::asm::udf()
    };
    footprint::use_mem_builtins();
    loop {
        footprint::can_skeleton();
        let now = Instant::from_millis(input(4));
        // The serial path carries no text.
        footprint::command_surface(gimbal, now, |_| false);
        output(u32::from(gimbal.poll(now).is_ok()));
        footprint::events(gimbal, now);
        output(gimbal.stats().link.postbacks);
    }
}
