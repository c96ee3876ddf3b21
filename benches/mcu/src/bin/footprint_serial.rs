//! Footprint of the serial path: `footprint_base` plus a `SerialLink` (default queue) and its
//! `SerialPort`, in statics, that a firmware drives with every kind of call the serial path offers:
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
    use idu_gimbal::{Config, Instant, Port, SerialLink, SerialPort};

    let Some(link) = cortex_m::singleton!(: SerialLink = SerialLink::new(Config::default())) else {
        cortex_m::asm::udf()
    };
    let Some(port) = cortex_m::singleton!(: SerialPort<RegPort> = SerialPort::new(RegPort)) else {
        cortex_m::asm::udf()
    };
    footprint::use_mem_builtins();
    loop {
        footprint::can_skeleton();
        let now = Instant::from_millis(input(4));
        // The serial path carries no text.
        footprint::command_surface(link, now, |_| false);
        output(u32::from(port.poll(link, now).is_ok()));
        footprint::events(link, now);
        output(link.stats().postbacks);
    }
}
