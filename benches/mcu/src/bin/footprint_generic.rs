//! A poll generic over its port is the poll written for the port: `scripts/port-generic.sh`
//! builds this program and checks that each function written for one port
//! (`poll_can`, `poll_serial`) compiles to the same instructions as the generic one
//! (`poll_any`) at that port, or to the same function. Like the footprint builds, it is
//! never run (the runner refuses it); only its code matters.
#![no_std]
#![no_main]

// A module of each program, not a library: see its header.
#[path = "../footprint.rs"]
mod footprint;

use footprint::{input, output, RegCan, RegPort};
use idu_gimbal::{CanPort, Config, Instant, Link, Port, SerialLink, SerialPort};

/// One turn of a main loop, written for the CAN port. Each function is exported, so that
/// the compiler keeps a symbol for it even where it finds two alike (it then makes one an
/// alias of the other: one address, which the script takes as the same code).
#[inline(never)]
#[no_mangle]
fn poll_can(link: &mut Link, port: &mut CanPort<RegCan>, now: Instant) -> u32 {
    let ok = port.poll(link, now).is_ok();
    u32::from(ok) ^ port.next_deadline(link, now).as_millis()
}

/// The same turn, written for the serial port.
#[inline(never)]
#[no_mangle]
fn poll_serial(link: &mut SerialLink, port: &mut SerialPort<RegPort>, now: Instant) -> u32 {
    let ok = port.poll(link, now).is_ok();
    u32::from(ok) ^ port.next_deadline(link, now).as_millis()
}

/// The same turn, generic over the port, at each port (exported below).
#[inline(always)]
fn poll_any<P: Port, const Q: usize, const T: usize>(
    link: &mut Link<Q, T, P::Medium>,
    port: &mut P,
    now: Instant,
) -> u32 {
    let ok = port.poll(link, now).is_ok();
    u32::from(ok) ^ port.next_deadline(link, now).as_millis()
}

/// [`poll_any`] at the CAN port.
#[inline(never)]
#[no_mangle]
fn poll_any_can(link: &mut Link, port: &mut CanPort<RegCan>, now: Instant) -> u32 {
    poll_any(link, port, now)
}

/// [`poll_any`] at the serial port.
#[inline(never)]
#[no_mangle]
fn poll_any_serial(link: &mut SerialLink, port: &mut SerialPort<RegPort>, now: Instant) -> u32 {
    poll_any(link, port, now)
}

#[cortex_m_rt::entry]
fn main() -> ! {
    let Some(can_link) = cortex_m::singleton!(: Link = Link::new(Config::default())) else {
        cortex_m::asm::udf()
    };
    let Some(serial_link) = cortex_m::singleton!(: SerialLink = SerialLink::new(Config::default()))
    else {
        cortex_m::asm::udf()
    };
    let mut can = CanPort::new(RegCan);
    let mut serial = SerialPort::new(RegPort);
    footprint::use_mem_builtins();
    loop {
        let now = Instant::from_millis(input(4));
        let v = match input(5) & 3 {
            0 => poll_can(can_link, &mut can, now),
            1 => poll_any_can(can_link, &mut can, now),
            2 => poll_serial(serial_link, &mut serial, now),
            _ => poll_any_serial(serial_link, &mut serial, now),
        };
        output(v);
    }
}
