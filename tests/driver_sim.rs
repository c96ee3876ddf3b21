//! The driver against the simulated gimbal over the in-memory bus.

#![cfg(feature = "mock")]

mod common;

use common::Host;

use core::num::{NonZeroU16, NonZeroU32};

use embedded_can::{nb::Can, Frame as _};
use idu_gimbal::link::Config;
use idu_gimbal::mock::{Bus, Endpoint, Faults, MockFrame};
use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::wire::control::{GimbalCommand, Heading, Pitch, Rate, ZoomRatio};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::wire::{ids, Frame};
use idu_gimbal::{CanPort, Link, Port};
use idu_gimbal::{Event, Instant};

const E: usize = 3;
const RXQ: usize = 256;
type TestBus = Bus<E, RXQ>;

/// Driver on endpoint 0, simulator on endpoint 1, a sniffer on endpoint 2 that sees every
/// frame either side sends.
struct Bench<'a> {
    host: Host<CanPort<Endpoint<'a, E, RXQ>>, 8, 4>,
    sim: Simulator,
    sim_can: Endpoint<'a, E, RXQ>,
    sniffer: Endpoint<'a, E, RXQ>,
    /// Frames the sniffer saw: (time, id, data).
    seen: Vec<(u32, u32, Vec<u8>)>,
    /// Postbacks the simulator emitted, and those the driver delivered.
    sent_postbacks: Vec<Postback>,
    sim_pending: Vec<Frame>,
    sim_received: u32,
    sniffed: u32,
    /// Driver errors on the simulator's and the sniffer's endpoints.
    sim_errors: u32,
}

impl<'a> Bench<'a> {
    fn new(bus: &'a TestBus, config: Config, sim_config: SimConfig, start: u32) -> Self {
        let now = Instant::from_millis(start);
        Bench {
            host: Host::new(
                Link::new(config),
                CanPort::new(bus.endpoint(0).unwrap()),
                start,
            ),
            sim: Simulator::new(sim_config, now),
            sim_can: bus.endpoint(1).unwrap(),
            sniffer: bus.endpoint(2).unwrap(),
            seen: Vec::new(),
            sent_postbacks: Vec::new(),
            sim_pending: Vec::new(),
            sim_received: 0,
            sniffed: 0,
            sim_errors: 0,
        }
    }

    /// One millisecond of both sides.
    fn tick(&mut self) {
        self.host.poll();
        let now = self.host.instant();
        loop {
            match Can::receive(&mut self.sim_can) {
                Ok(f) => {
                    self.sim_received += 1;
                    if let embedded_can::Id::Extended(id) = f.id() {
                        let _ = self.sim.receive(id.as_raw(), f.data(), now);
                    }
                }
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => self.sim_errors += 1,
            }
        }
        if let Some(p) = self.sim.poll(now) {
            self.sent_postbacks.push(p);
        }
        while let Some(f) = self.sim.pop_frame() {
            self.sim_pending.push(f);
        }
        while let Some(f) = self.sim_pending.first().copied() {
            let frame = MockFrame::extended(f.id, &f.data).unwrap();
            match Can::transmit(&mut self.sim_can, &frame) {
                Ok(_) => {
                    self.sim_pending.remove(0);
                }
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => {
                    self.sim_errors += 1;
                    break;
                }
            }
        }
        loop {
            match Can::receive(&mut self.sniffer) {
                Ok(f) => {
                    self.sniffed += 1;
                    self.seen
                        .push((self.host.now, f.raw_id(), f.data().to_vec()));
                }
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => self.sim_errors += 1,
            }
        }
        self.host.now = self.host.now.wrapping_add(1);
    }

    /// Empties every receive FIFO without letting the simulator send more: the driver
    /// polls once more (its events taken as every poll's are), then the simulator and the
    /// sniffer take what reached them.
    fn settle(&mut self) {
        self.host.poll();
        let now = self.host.instant();
        while let Ok(f) = Can::receive(&mut self.sim_can) {
            self.sim_received += 1;
            let _ = self.sim.receive(f.raw_id(), f.data(), now);
        }
        while Can::receive(&mut self.sniffer).is_ok() {
            self.sniffed += 1;
        }
    }

    fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    fn latest(&self) -> Postback {
        self.host.latest()
    }

    fn count(&self, id: u32, from: u32, to: u32) -> usize {
        self.seen
            .iter()
            .filter(|(t, i, _)| *i == id && t.wrapping_sub(from) < to.wrapping_sub(from))
            .count()
    }
}

fn push_vehicle(b: &mut Bench) {
    let now = b.host.instant();
    b.host
        .link
        .set_attitude(Attitude::new(0.0, 0.0, 30.0).unwrap(), now);
    b.host.link.set_gps(Gps::new(47.0, 8.0).unwrap(), now);
    b.host.link.set_altitude(Altitude::new(450.0).unwrap(), now);
}

#[test]
fn angle_commands_reach_the_gimbal_and_postbacks_report_them() {
    let bus = TestBus::new(1);
    let mut b = Bench::new(&bus, Config::default(), SimConfig::default(), 10_000);
    b.run(600);
    assert!(b.host.link.is_link_up());
    b.host
        .send(GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()));
    b.host
        .send(GimbalCommand::Heading(Heading::new(90.0).unwrap()));
    b.host
        .send(GimbalCommand::ZoomRatio(ZoomRatio::new(10.0).unwrap()));
    // 90° at 60°/s takes 1.5 s; the next postback after that reports it.
    b.run(2100);
    let p = b.latest();
    assert_eq!((p.pitch, p.heading), (-4500, 9000), "{p:?}");
    assert_eq!(b.sim.state().zoom_ratio, 10.0);
    assert_eq!(b.host.events.first().map(|e| e.1), Some(Event::LinkUp));
}

#[test]
fn rate_hold_turns_the_gimbal_and_the_dead_man_stops_it() {
    let bus = TestBus::new(2);
    let mut b = Bench::new(&bus, Config::default(), SimConfig::default(), 0);
    b.run(100);
    let rate = Rate::new(20.0, 0.0).unwrap();
    // The application refreshes the hold every 30 ms for one second, then stops.
    for _ in 0..34 {
        let now = b.host.instant();
        b.host.link.set_rate(rate, now).unwrap();
        b.run(30);
    }
    let last_refresh = b.host.now - 30;
    let yaw_turned = b.sim.state().motor_yaw_deg;
    // 20°/s from the first command's arrival, 1 ms after it left at 100 ms, to 1,120 ms:
    // 1,019 ms, 20.38° (the simulator integrates exactly; `f32` sums keep 3e-4 of it). A
    // hold refreshed too seldom for the simulator's 200 ms rate timeout would fall short.
    assert!(
        (yaw_turned - 20.38).abs() < 0.01,
        "turned {yaw_turned}° in 1,019 ms at 20°/s"
    );
    // Dead-man 250 ms + one repeat period 50 ms.
    b.run(last_refresh + 300 - b.host.now);
    let stopped_at = b.sim.state().motor_yaw_deg;
    assert_eq!(b.sim.state().rate, (0.0, 0.0));
    b.run(1000);
    assert_eq!(
        b.sim.state().motor_yaw_deg,
        stopped_at,
        "no motion after the dead-man"
    );
    assert!(b
        .host
        .events
        .iter()
        .any(|(_, e)| *e == Event::RateHoldExpired));
    // The last rate frame on the bus is the zero one.
    let last_rate = b
        .seen
        .iter()
        .rev()
        .find(|(_, id, d)| *id == ids::CONTROL && d[1] == 0x04)
        .unwrap();
    assert_eq!(last_rate.2, [0x0F, 0x04, 0, 0, 0, 0, 0, 0]);
}

#[test]
fn vehicle_frames_at_their_rates_stop_when_stale_and_resume() {
    let bus = TestBus::new(3);
    let mut b = Bench::new(&bus, Config::default(), SimConfig::default(), 0);
    // Fresh data every 20 ms for 10 s.
    for _ in 0..500 {
        push_vehicle(&mut b);
        b.run(20);
    }
    assert_eq!(b.count(ids::ATTITUDE, 0, 10_000), 100);
    assert_eq!(b.count(ids::GPS, 0, 10_000), 50);
    assert_eq!(b.count(ids::ALTITUDE, 0, 10_000), 50);
    assert!(b.sim.state().north_referenced);
    // No new data: pushed until 1 s old, then nothing.
    b.run(3000);
    // The last data is stamped 9,980 and pushed until 1 s old: at 10,000, 10,100, … 10,900.
    assert_eq!(b.count(ids::ATTITUDE, 10_000, 13_000), 10);
    assert_eq!(b.count(ids::ATTITUDE, 11_001, 13_000), 0);
    assert!(
        !b.sim.state().north_referenced,
        "the gimbal falls back to the nose reference"
    );
    // Fresh again: resumes at once.
    push_vehicle(&mut b);
    b.run(2);
    assert_eq!(b.count(ids::ATTITUDE, 13_000, 13_002), 1);
}

#[test]
fn link_lost_and_restored() {
    let bus = TestBus::new(4);
    let mut b = Bench::new(&bus, Config::default(), SimConfig::default(), 0);
    b.run(1000);
    assert!(b.host.link.is_link_up());
    b.sim.set_silent(true);
    let silent_from = b.host.now;
    b.run(2100);
    let down = b
        .host
        .events
        .iter()
        .find(|(_, e)| *e == Event::LinkDown)
        .expect("link down")
        .0;
    // The last postback came at most 500 ms before silence; down 1.5 s after it.
    assert!(
        down > silent_from + 1000 && down <= silent_from + 1501,
        "down at {down}"
    );
    b.sim.set_silent(false);
    b.run(600);
    assert!(b.host.link.is_link_up());
    let ups: Vec<_> = b
        .host
        .events
        .iter()
        .filter(|(_, e)| *e == Event::LinkUp)
        .collect();
    assert_eq!(ups.len(), 2);
}

#[test]
fn full_mailboxes_lose_no_command_and_keep_priority() {
    let bus = TestBus::new(5);
    let mut b = Bench::new(&bus, Config::default(), SimConfig::default(), 0);
    bus.set_auto_deliver(false);
    push_vehicle(&mut b);
    b.host.link.send_text(b"MAILBOX PRESSURE TEST").unwrap(); // 3 frames
                                                              // Text and vehicle frames fill the three mailboxes first.
    let now = b.host.instant();
    b.host.port.poll(&mut b.host.link, now).unwrap();
    assert_eq!(bus.pending(), 3);
    // Control commands now displace the lower-priority frames from the mailboxes.
    let pitches = [-10.0, -20.0, -30.0, -40.0, -50.0];
    for p in pitches {
        b.host.send(GimbalCommand::Pitch(Pitch::new(p).unwrap()));
    }
    let now = b.host.instant();
    b.host.port.poll(&mut b.host.link, now).unwrap();
    assert!(
        b.host.link.stats().requeued >= 3,
        "{:?}",
        b.host.link.stats()
    );
    // Drain one frame per millisecond, as a busy bus would.
    for _ in 0..40 {
        bus.deliver_one();
        b.tick();
    }
    bus.set_auto_deliver(true);
    b.run(50);
    let order: Vec<(u32, Vec<u8>)> = b
        .seen
        .iter()
        .filter(|(_, id, _)| *id != ids::POSTBACK)
        .map(|(_, id, d)| (*id, d.clone()))
        .collect();
    let controls: Vec<i16> = order
        .iter()
        .filter(|(id, _)| *id == ids::CONTROL)
        .map(|(_, d)| i16::from_le_bytes([d[3], d[4]]))
        .collect();
    assert_eq!(
        controls,
        [-100, -200, -300, -400, -500],
        "every command, in order"
    );
    // Priority: every control frame went out before any vehicle or text frame did.
    let first_other = order
        .iter()
        .position(|(id, _)| *id != ids::CONTROL)
        .unwrap();
    assert!(order[..first_other].len() == 5);
    // The text arrived whole, in order.
    assert_eq!(b.sim.state().last_text.as_str(), "MAILBOX PRESSURE TEST");
}

#[test]
fn soak_a_million_frames_with_loss_corruption_and_duplication() {
    let bus = TestBus::new(0x5EED);
    // Fast schedules to pump frames: a postback every 5 ms, vehicle and rate every 5 ms.
    let config = Config {
        attitude_period_ms: 5,
        gps_period_ms: 5,
        altitude_period_ms: 5,
        rate_repeat_ms: NonZeroU16::new(5).unwrap(),
        link_timeout_ms: 1500,
        ..Config::default()
    };
    let sim_config = SimConfig {
        postback_period_ms: NonZeroU32::new(5).unwrap(),
        ..SimConfig::default()
    };
    let mut b = Bench::new(&bus, config, sim_config, u32::MAX - 100_000);
    bus.set_faults(Faults {
        loss: 0.05,
        corruption: 0.01,
        duplication: 0.01,
        ..Faults::default()
    });
    let mut step = 0u32;
    while bus.stats().sent < 1_000_000 {
        if step.is_multiple_of(5) {
            push_vehicle(&mut b);
            // Keep the gimbal turning so postbacks differ.
            let yaw = if (step / 20_000).is_multiple_of(2) {
                30.0
            } else {
                -30.0
            };
            let now = b.host.instant();
            b.host
                .link
                .set_rate(Rate::new(yaw, 0.0).unwrap(), now)
                .unwrap();
        }
        b.tick();
        b.host.events.clear();
        b.seen.clear();
        step += 1;
    }
    b.settle();
    let delivered = core::mem::take(&mut b.host.delivered);
    // Every delivered postback is one the simulator sent, in order.
    let mut sent = b.sent_postbacks.iter();
    for p in &delivered {
        assert!(
            sent.any(|s| s == p),
            "delivered a postback the simulator never sent: {p:?}"
        );
    }
    let s = b.host.link.stats();
    let a = b.host.link.assembler().stats();
    let bs = bus.stats();
    assert!(
        delivered.len() as f64 > 0.7 * b.sent_postbacks.len() as f64,
        "{} of {}",
        delivered.len(),
        b.sent_postbacks.len()
    );
    assert_eq!(s.postbacks as usize, delivered.len());
    // Every postback frame the driver received ended in a message, was discarded, or waits.
    assert_eq!(
        a.frames,
        4 * a.messages + a.discarded_frames + b.host.link.assembler().pending() as u32
    );
    // Every frame the bus delivered reached the driver, the simulator or the sniffer.
    assert_eq!(bs.delivered, s.frames_received + b.sim_received + b.sniffed);
    assert!(
        s.crc_errors + s.restarts > 0,
        "corruption and loss were seen: {s:?}"
    );
    assert_eq!(
        bs.delivered + bs.overruns,
        (bs.sent - bs.lost + bs.duplicated) * (E as u32 - 1)
    );
    assert_eq!(bs.overruns, 0);
    assert_eq!(b.host.port.stats().driver_errors.total(), 0);
    println!(
        "bus {bs:?}\nlink {s:?}\ndelivered {} of {} postbacks",
        delivered.len(),
        b.sent_postbacks.len()
    );
}

#[test]
fn the_tick_wraps_mid_run_without_a_hiccup() {
    let bus = TestBus::new(6);
    let start = u32::MAX - 2_000;
    let mut b = Bench::new(&bus, Config::default(), SimConfig::default(), start);
    for _ in 0..250 {
        push_vehicle(&mut b);
        if b.host.now == start.wrapping_add(1000) {
            b.host
                .send(GimbalCommand::Pitch(Pitch::new(-60.0).unwrap()));
        }
        b.run(20);
    }
    // 5 s across the wrap: rates exact, the command done, the link never dropped.
    assert_eq!(b.count(ids::ATTITUDE, start, start.wrapping_add(5000)), 50);
    assert_eq!(b.count(ids::GPS, start, start.wrapping_add(5000)), 25);
    assert_eq!(b.latest().pitch, -6000);
    assert!(!b.host.events.iter().any(|(_, e)| *e == Event::LinkDown));
    assert_eq!(b.host.link.stats().dropped_partials, 0);
}

#[test]
fn blocking_drivers_work_through_the_adapter() {
    use idu_gimbal::port::Blocking;
    let bus = TestBus::new(7);
    let can = Blocking::new(bus.endpoint(0).unwrap(), |ep: &mut Endpoint<'_, E, RXQ>| {
        ep.rx_pending() > 0
    });
    let mut gimbal: Link = Link::new(Config::default());
    let mut port = CanPort::new(can);
    let mut sim = Simulator::new(SimConfig::default(), Instant::from_millis(0));
    let mut sim_can = bus.endpoint(1).unwrap();
    gimbal
        .send(GimbalCommand::Pitch(Pitch::new(-20.0).unwrap()))
        .unwrap();
    for t in 0..1600u32 {
        let now = Instant::from_millis(t);
        port.poll(&mut gimbal, now).unwrap(); // never blocks: rx_ready says whether a frame waits
        while let Ok(f) = Can::receive(&mut sim_can) {
            sim.receive(f.raw_id(), f.data(), now).unwrap();
        }
        sim.poll(now);
        while let Some(f) = sim.pop_frame() {
            Can::transmit(&mut sim_can, &MockFrame::extended(f.id, &f.data).unwrap()).unwrap();
        }
    }
    assert_eq!(
        gimbal
            .latest_postback(Instant::from_millis(1600))
            .unwrap()
            .0
            .pitch,
        -2000
    );
    // Errors from a blocking driver reach the caller with their kind and are counted.
    bus.inject_error(0, embedded_can::ErrorKind::Bit);
    gimbal.send(GimbalCommand::Recenter).unwrap();
    let e = port
        .poll(&mut gimbal, Instant::from_millis(1600))
        .unwrap_err();
    assert_eq!(e.0, embedded_can::ErrorKind::Bit);
    assert_eq!(port.stats().driver_errors.bit, 1);
    // The command was not lost: the next poll sends it.
    port.poll(&mut gimbal, Instant::from_millis(1601)).unwrap();
    assert!(Can::receive(&mut sim_can).is_ok_and(|f| f.data()[1] == 0x03));
    // release() hands back the adapter, and the adapter the driver it wraps.
    assert_eq!(port.release().release().index(), 0);
}

#[test]
fn driver_errors_are_counted_and_never_stop_the_driver() {
    let bus = TestBus::new(8);
    let mut b = Bench::new(&bus, Config::default(), SimConfig::default(), 0);
    bus.set_faults(Faults {
        rx_error: 0.2,
        tx_error: 0.2,
        ..Faults::default()
    });
    b.host
        .send(GimbalCommand::Pitch(Pitch::new(-30.0).unwrap()));
    for _ in 0..100 {
        push_vehicle(&mut b);
        b.run(20);
    }
    let errors = b.host.port.stats().driver_errors;
    assert!(errors.total() > 100, "{errors:?}");
    assert_eq!(
        errors.total(),
        bus.stats().injected_errors - b_sim_errors(&b)
    );
    // Despite a fifth of all calls failing, the command got through and postbacks flow.
    assert_eq!(b.latest().pitch, -3000);
    assert!(b.host.link.is_link_up());
}

/// Errors the simulator side's endpoint saw (the bench ignores them).
fn b_sim_errors(b: &Bench) -> u32 {
    b.sim_errors
}
