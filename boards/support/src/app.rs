//! The main loop of every CAN firmware, whatever its HAL: `boards/stm32f405` (`stm32f405`),
//! `boards/rp2040_mcp2515`, `boards/esp32c3_twai` and `boards/stm32h743_fdcan` (the stand-in
//! vehicle data is [`crate::vehicle`]). A board sets up its clocks, its CAN controller and
//! its tick, builds a [`Link`] and a [`CanPort`], then calls [`App::step`] forever with the
//! time and what it does with each [`Report`] (defmt, a serial console, nothing).
//!
//! What it does each turn: pushes the vehicle's estimates at 10 Hz (the link sends each
//! at its own rate while fresh), polls the port (busy polling: a postback is four
//! back-to-back frames, ~0.5 ms at 1 Mbit/s, more than some receive FIFOs hold), and hands
//! out the first CAN driver error of each poll (the port counts every one), each event
//! with the newest postback, and the counters every 10 s.

use embedded_can::nb::Can;
use idu_gimbal::link::LinkStats;
use idu_gimbal::port::{CanPort, CanPortStats, DriverError, Port};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::{Event, Instant, Link};

use crate::vehicle::Vehicle;

/// What a turn of the loop has to tell.
pub enum Report {
    /// The CAN driver reported an error during the poll (counted in the stats too).
    Driver(DriverError),
    /// An event, with the newest postback (for [`Event::Postback`]).
    Event(Event, Option<Postback>),
    /// The counters, every 10 s: the link's and the port's.
    Stats(LinkStats, CanPortStats),
}

/// The loop's schedule: the next vehicle push and the next counters line.
pub struct App {
    next_vehicle: Instant,
    next_stats: Instant,
}

impl App {
    /// A loop starting at `now`: vehicle data at once, the first counters in 10 s.
    pub fn new(now: Instant) -> Self {
        App {
            next_vehicle: now,
            next_stats: now.add_millis(10_000),
        }
    }

    /// One turn at `now`: vehicle data from `vehicle` when due, a poll, and every report.
    pub fn step<C: Can, const Q: usize, const T: usize>(
        &mut self,
        link: &mut Link<Q, T>,
        port: &mut CanPort<C>,
        now: Instant,
        vehicle: impl FnOnce(Instant) -> Option<Vehicle>,
        mut report: impl FnMut(Report),
    ) {
        if now.is_at_or_after(self.next_vehicle) {
            self.next_vehicle = now.add_millis(100);
            if let Some(v) = vehicle(now) {
                v.push(link);
            }
        }
        if let Err(e) = port.poll(link, now) {
            report(Report::Driver(e));
        }
        while let Some(event) = link.next_event() {
            report(Report::Event(
                event,
                link.latest_postback(now).map(|(p, _)| p),
            ));
        }
        if now.is_at_or_after(self.next_stats) {
            self.next_stats = now.add_millis(10_000);
            report(Report::Stats(link.stats(), port.stats()));
        }
    }
}
