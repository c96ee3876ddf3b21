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

#[cfg(test)]
#[cfg(feature = "session")]
mod tests {
    use super::*;
    use crate::session::{CanRig, DemoBus, Rig};
    use crate::vehicle::vehicle_stand_in;
    use idu_gimbal::mock::Faults;
    use idu_gimbal::Config;

    /// What a run of the loop reported.
    #[derive(Default)]
    struct Seen {
        link_up: u32,
        postbacks: u32,
        postbacks_without_one: u32,
        driver_errors: u32,
        /// When the counters came, their postbacks, and the postbacks reported by then.
        stats: heapless::Vec<(u32, u32, u32), 4>,
    }

    /// The loop against the simulated gimbal on `bus`, a turn a millisecond for `ms`.
    fn run(bus: &DemoBus, ms: u32) -> (Seen, u32) {
        let mut rig = CanRig::new(bus, Instant::from_millis(0)).unwrap();
        let mut link: Link<8, 8> = Link::new(Config::default());
        let mut app = App::new(Instant::from_millis(0));
        let mut seen = Seen::default();
        for t in 0..ms {
            let now = Instant::from_millis(t);
            app.step(&mut link, rig.port(), now, vehicle_stand_in, |r| match r {
                Report::Driver(_) => seen.driver_errors += 1,
                Report::Event(Event::LinkUp, _) => seen.link_up += 1,
                Report::Event(Event::Postback, Some(_)) => seen.postbacks += 1,
                Report::Event(Event::Postback, None) => seen.postbacks_without_one += 1,
                Report::Event(..) => {}
                Report::Stats(s, _) => {
                    let _ = seen.stats.push((t, s.postbacks, seen.postbacks));
                }
            });
            rig.run_gimbal(now);
        }
        (seen, rig.sim_stats().vehicle_frames)
    }

    /// 25 s of the loop: the link comes up once, each postback (every 500 ms) is reported
    /// with the postback itself, the vehicle's frames reach the gimbal, and the counters
    /// are reported at 10 s and 20 s.
    #[test]
    fn the_loop_reports_the_gimbal_and_feeds_it_the_vehicle() {
        let (seen, vehicle_frames) = run(&DemoBus::new(1), 25_000);
        assert_eq!(seen.link_up, 1);
        // The simulated gimbal's postbacks every 500 ms from 500 ms: 500, 1000, …, 24 500.
        assert_eq!(seen.postbacks, 49);
        assert_eq!(seen.postbacks_without_one, 0);
        assert_eq!(seen.driver_errors, 0);
        // Fresh from 0 ms (pushed every 100 ms), each sent at its own period: the attitude
        // every 100 ms (250 in 25 s), the GPS and the altitude every 200 ms (125 each).
        assert_eq!(vehicle_frames, 250 + 125 + 125);
        let at: heapless::Vec<u32, 4> = seen.stats.iter().map(|s| s.0).collect();
        assert_eq!(at, [10_000, 20_000]);
        // The counters agree with the events: every postback counted was reported.
        for &(_, counted, reported) in &seen.stats {
            assert_eq!(counted, reported);
        }
    }

    /// A bus that refuses every frame: each poll's driver error is reported, the link
    /// never comes up.
    #[test]
    fn the_loop_reports_driver_errors() {
        let bus = DemoBus::new(1).with_faults(Faults {
            tx_error: 1.0,
            ..Faults::NONE
        });
        let (seen, vehicle_frames) = run(&bus, 1_000);
        assert!(seen.driver_errors > 0);
        assert_eq!(seen.link_up, 0);
        assert_eq!(vehicle_frames, 0);
    }
}
