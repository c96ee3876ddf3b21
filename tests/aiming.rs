//! Closed-loop aiming (`Link::aim`, `Link::point_at`) against the simulated gimbal, on CAN
//! and on the UART, with the simulator holding its north heading in lock and with it
//! holding its motor angle: the two behaviours the document leaves open. Whatever the
//! gimbal does, the camera must stay where the aim says, in the aim's frame.
//!
//! The expectations are the aim itself: an earth yaw is checked as the vehicle's heading
//! (the test's own) + the simulator's motor angle, a vehicle yaw as the motor angle alone.

#![cfg(feature = "mock")]

use idu_gimbal::geo::{look_at, Position};
use idu_gimbal::link::{aim, Aim, AimError, Config, Link, LinkStats, Yaw};
use idu_gimbal::link::{Medium, SerialLink};
use idu_gimbal::port::SerialStream;
use idu_gimbal::sim::serial::SerialSimulator;
use idu_gimbal::sim::{LockHolds, SimConfig, SimState, Simulator};
use idu_gimbal::wire::control::{
    Command, GimbalCommand, Heading, ImagePoint, Pitch, Rate, TrackingBox,
};
use idu_gimbal::wire::ids;
use idu_gimbal::wire::postback::{ControlMode, GimbalType, Postback};
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Event, Instant};

const BOTH: [LockHolds; 2] = [LockHolds::North, LockHolds::Motor];
const WIRES: [Wire; 2] = [Wire::Can, Wire::Uart];

#[derive(Clone, Copy, PartialEq, Debug)]
enum Wire {
    Can,
    Uart,
}

/// The link and the simulated gimbal on one transport, moved a millisecond at a time, the
/// vehicle's attitude set every 20 ms (as an autopilot streaming at 50 Hz).
struct Rig {
    wire: Wire,
    can: Link,
    can_sim: Simulator,
    uart: SerialLink,
    uart_stream: SerialStream,
    uart_sim: SerialSimulator<512>,
    now: u32,
    vehicle_deg: f32,
    /// Heading commands the gimbal received (after any dropped), with their time.
    headings: Vec<(u32, Heading)>,
    /// Heading commands to drop on the way (lost frames).
    drop_headings: usize,
    events: Vec<Event>,
    /// The vehicle's position and altitude, set every 20 ms beside the attitude.
    position: Option<(Gps, Altitude)>,
}

impl Rig {
    fn new(wire: Wire, holds: LockHolds) -> Self {
        Self::with(
            wire,
            SimConfig {
                lock_holds: holds,
                ..SimConfig::default()
            },
        )
    }

    fn with(wire: Wire, sim: SimConfig) -> Self {
        let t0 = Instant::from_millis(0);
        Rig {
            wire,
            can: Link::new(Config::default()),
            can_sim: Simulator::new(sim, t0),
            uart: SerialLink::new(Config::default()),
            uart_stream: SerialStream::new(),
            uart_sim: SerialSimulator::new(sim, t0),
            now: 0,
            vehicle_deg: 0.0,
            headings: Vec::new(),
            drop_headings: 0,
            events: Vec::new(),
            position: None,
        }
    }

    fn instant(&self) -> Instant {
        Instant::from_millis(self.now)
    }

    fn state(&self) -> &SimState {
        match self.wire {
            Wire::Can => self.can_sim.state(),
            Wire::Uart => self.uart_sim.sim().state(),
        }
    }

    fn stats(&self) -> LinkStats {
        match self.wire {
            Wire::Can => self.can.stats(),
            Wire::Uart => self.uart.stats(),
        }
    }

    fn reboot(&mut self) {
        let now = self.instant();
        match self.wire {
            Wire::Can => self.can_sim.reboot(now),
            Wire::Uart => self.uart_sim.reboot(now),
        }
    }

    fn set_vehicle(&mut self) {
        let now = self.instant();
        let attitude = Attitude::new(0.0, 0.0, self.vehicle_deg).unwrap();
        let gimbal: &mut dyn Vehicle = match self.wire {
            Wire::Can => &mut self.can,
            Wire::Uart => &mut self.uart,
        };
        gimbal.attitude(attitude, now);
        if let Some((gps, alt)) = self.position {
            gimbal.position(gps, alt, now);
        }
    }

    fn aim(&mut self, yaw: Yaw, pitch_deg: f32) -> Result<(), AimError> {
        let now = self.instant();
        let aim = Aim {
            yaw,
            pitch: Pitch::new(pitch_deg).unwrap(),
        };
        match self.wire {
            Wire::Can => self.can.aim(aim, now),
            Wire::Uart => self.uart.aim(aim, now),
        }
    }

    fn aim_state(&self) -> Option<idu_gimbal::link::AimState> {
        match self.wire {
            Wire::Can => self.can.aim_state(),
            Wire::Uart => self.uart.aim_state(),
        }
    }

    fn send(&mut self, c: GimbalCommand) {
        match self.wire {
            Wire::Can => self.can.send(c).unwrap(),
            Wire::Uart => self.uart.send(c).unwrap(),
        }
    }

    /// Whether a control frame reaches the gimbal (not dropped); heading commands logged.
    fn passes(&mut self, data: [u8; 8]) -> bool {
        if let Ok(Command::Gimbal(GimbalCommand::Heading(h))) = Command::decode(&data) {
            if self.drop_headings > 0 {
                self.drop_headings -= 1;
                return false;
            }
            self.headings.push((self.now, h));
        }
        true
    }

    /// One millisecond of both sides.
    fn tick(&mut self) {
        let now = self.instant();
        if self.now.is_multiple_of(20) {
            self.set_vehicle();
        }
        match self.wire {
            Wire::Can => {
                self.can.poll(now);
                while let Some(f) = self.can.next_transmit() {
                    self.can.transmit_done(None);
                    if f.id != ids::CONTROL || self.passes(f.data) {
                        let _ = self.can_sim.receive(f.id, &f.data, now);
                    }
                }
                let _ = self.can_sim.poll(now);
                while let Some(f) = self.can_sim.pop_frame() {
                    self.can.receive(f.id, &f.data, now);
                }
                while let Some(e) = self.can.next_event() {
                    self.events.push(e);
                }
            }
            Wire::Uart => {
                self.uart.poll(now);
                loop {
                    let bytes = self.uart_stream.transmit_bytes(&mut self.uart).to_vec();
                    if bytes.is_empty() {
                        break;
                    }
                    self.uart_stream
                        .transmit_written(&mut self.uart, bytes.len());
                    // One whole 24-byte frame at a time: its 8 data bytes at 14..22.
                    let data: [u8; 8] = bytes[14..22].try_into().unwrap();
                    if self.passes(data) {
                        self.uart_sim.receive(&bytes, now);
                    }
                }
                let _ = self.uart_sim.poll(now);
                loop {
                    let bytes = self.uart_sim.transmit_bytes().to_vec();
                    if bytes.is_empty() {
                        break;
                    }
                    self.uart_sim.transmit_written(bytes.len());
                    self.uart_stream.receive(&mut self.uart, &bytes, now);
                }
                while let Some(e) = self.uart.next_event() {
                    self.events.push(e);
                }
            }
        }
        self.now += 1;
    }

    fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    /// Turns the vehicle to `to` at `dps` degrees a second; `each` sees the rig every ms.
    fn turn(&mut self, to: f32, dps: f32, mut each: impl FnMut(&Rig)) {
        let step = dps / 1000.0;
        while self.vehicle_deg != to {
            let d = to - self.vehicle_deg;
            self.vehicle_deg = if d.abs() <= step {
                to
            } else {
                self.vehicle_deg + step * d.signum()
            };
            self.tick();
            each(self);
        }
    }

    /// The camera's yaw from north as the simulated gimbal points it.
    fn earth_yaw(&self) -> f32 {
        wrap(self.vehicle_deg + self.state().motor_yaw_deg)
    }

    fn motor(&self) -> f32 {
        self.state().motor_yaw_deg
    }

    /// The simulated gimbal tracks, the aim has yielded to its tracker, and no heading
    /// command went since `sent` of them had.
    fn assert_tracker_owns(&self, sent: usize, what: &str) {
        assert!(self.state().tracking, "{what}");
        assert!(self.aim_state().unwrap().yielded_to_tracker, "{what}");
        assert_eq!(
            self.headings.len(),
            sent,
            "{what}: nothing sent while tracking"
        );
    }
}

/// The vehicle's data into either link.
trait Vehicle {
    fn attitude(&mut self, a: Attitude, now: Instant);
    fn position(&mut self, g: Gps, a: Altitude, now: Instant);
}

impl<const Q: usize, const T: usize, M: Medium> Vehicle for Link<Q, T, M> {
    fn attitude(&mut self, a: Attitude, now: Instant) {
        self.set_attitude(a, now);
    }
    fn position(&mut self, g: Gps, a: Altitude, now: Instant) {
        self.set_gps(g, now);
        self.set_altitude(a, now);
    }
}

/// `deg` in [-180, 180).
fn wrap(deg: f32) -> f32 {
    (deg + 180.0).rem_euclid(360.0) - 180.0
}

fn off(a: f32, b: f32) -> f32 {
    wrap(a - b).abs()
}

fn earth(deg: f32) -> Yaw {
    Yaw::Earth(Heading::new(deg).unwrap())
}

fn vehicle(deg: f32) -> Yaw {
    Yaw::Vehicle(Heading::new(deg.rem_euclid(360.0)).unwrap())
}

/// How far a settled yaw may be off its aim, degrees: the command's rounding to tenths
/// (0.05°) and the simulator's state in `f32` (every case here settles within 0.051°; a
/// heading left within the 0.2° dead-band of the last command's would show more).
const SETTLED_DEG: f32 = 0.06;

/// How far the camera may lag its aim while the vehicle turns at `dps`. The gimbal turns a
/// command into a motor angle with a vehicle heading up to 170 ms old (the vehicle's
/// heading set every 20 ms, the attitude pushed every 100 ms, the loop looking every
/// 50 ms); the simulator, slewing at 60°/s (twice the fastest turn here), takes up to half
/// that again to catch up with each new target. Plus the command's 0.1° rounding.
fn turn_lag(dps: f32) -> f32 {
    dps * (0.170 + 0.085) + 0.1
}

#[test]
fn an_earth_yaw_is_held_through_a_90_degree_turn() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 60.0;
            rig.run(200);
            rig.aim(earth(20.0), -30.0).unwrap();
            rig.run(3000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.earth_yaw(), 20.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            assert!((rig.state().pitch_deg + 30.0).abs() < 0.01, "{what}");
            let mut worst = 0.0f32;
            rig.turn(150.0, 30.0, |r| worst = worst.max(off(r.earth_yaw(), 20.0)));
            assert!(
                worst < turn_lag(30.0),
                "{what}: {worst}° off during the turn"
            );
            rig.run(1000);
            assert!(
                off(rig.earth_yaw(), 20.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            assert!(
                off(rig.motor(), -130.0) < SETTLED_DEG,
                "{what}: motor {}",
                rig.motor()
            );
            let state = rig.aim_state().unwrap();
            assert!(
                state.on_target && !state.not_reached && !state.at_yaw_limit,
                "{what}: {state:?} {:?}",
                rig.stats()
            );
            let given = Aim {
                yaw: earth(20.0),
                pitch: Pitch::new(-30.0).unwrap(),
            };
            assert_eq!(state.aim, given, "{what}");
        }
    }
}

#[test]
fn a_vehicle_yaw_turns_with_the_vehicle() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 60.0;
            rig.run(200);
            rig.aim(vehicle(40.0), -10.0).unwrap();
            rig.run(3000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.motor(), 40.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            let mut worst = 0.0f32;
            rig.turn(150.0, 30.0, |r| worst = worst.max(off(r.motor(), 40.0)));
            assert!(
                worst < turn_lag(30.0),
                "{what}: {worst}° off during the turn"
            );
            rig.run(1000);
            assert!(
                off(rig.motor(), 40.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            assert!(off(rig.earth_yaw(), 190.0) < SETTLED_DEG, "{what}");
            let given = Aim {
                yaw: vehicle(40.0),
                pitch: Pitch::new(-10.0).unwrap(),
            };
            assert_eq!(rig.aim_state().unwrap().aim, given, "{what}");
        }
    }
}

#[test]
fn the_first_aim_with_the_first_attitude_lands_in_the_gimbals_reference() {
    // The aim and the first attitude in the same millisecond, as when an autopilot starts
    // both streams together: on CAN the aim goes out nose-referenced ahead of the attitude
    // frame (control first), then north-referenced once the attitude is there.
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 30.0;
            rig.set_vehicle();
            rig.aim(vehicle(40.0), 0.0).unwrap();
            rig.run(2000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.motor(), 40.0) < SETTLED_DEG,
                "{what}: motor {}",
                rig.motor()
            );
            let firsts: Vec<u16> = rig.headings.iter().map(|(_, h)| h.deci()).collect();
            match wire {
                // 40 from the nose, then 70 from north once the gimbal has the attitude.
                Wire::Can => assert_eq!(firsts, [400, 700], "{what}"),
                Wire::Uart => assert_eq!(firsts, [400], "{what}"),
            }
        }
    }
}

#[test]
fn a_lost_command_is_sent_again_from_the_postbacks() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 10.0;
            rig.run(500);
            // Every heading command of the aim lost on the way but the third.
            rig.drop_headings = 2;
            rig.aim(earth(100.0), -20.0).unwrap();
            rig.run(6000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(
                off(rig.earth_yaw(), 100.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            // The aim, then one re-command from the postbacks, both lost; the second
            // re-command arrives, and is the only heading that does.
            let stats = rig.stats();
            assert_eq!(stats.aim_recommands, 2, "{what}: {stats:?}");
            assert_eq!(rig.headings.len(), 1, "{what}: {:?}", rig.headings);
            assert_eq!(stats.aim_not_reached, 0, "{what}");
        }
    }
}

#[test]
fn a_gimbal_that_reboots_mid_hold_is_brought_back() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 45.0;
            rig.run(200);
            rig.aim(earth(300.0), -45.0).unwrap();
            rig.run(4000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(off(rig.earth_yaw(), 300.0) < SETTLED_DEG, "{what}");
            rig.reboot();
            rig.run(100);
            assert_eq!(rig.motor(), 0.0, "{what}: at rest after the restart");
            // 3 s of start-up, the link down after 1.5 s and up at the first postback,
            // which the loop judges at once; then the slew (255°... at most 170° of motor
            // at 60°/s).
            rig.run(3000 + 500 + 100 + 3500);
            assert!(
                off(rig.earth_yaw(), 300.0) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            assert!((rig.state().pitch_deg + 45.0).abs() < 0.01, "{what}");
            assert!(rig.events.contains(&Event::LinkDown), "{what}");
        }
    }
}

#[test]
fn a_gimbal_that_does_not_move_is_tried_three_times_then_reported() {
    for wire in WIRES {
        // A gimbal that takes commands and never moves.
        let mut rig = Rig::with(
            wire,
            SimConfig {
                slew_dps: 0.0,
                ..SimConfig::default()
            },
        );
        rig.vehicle_deg = 0.0;
        rig.run(200);
        rig.aim(vehicle(90.0), 0.0).unwrap();
        rig.run(20_000);
        let stats = rig.stats();
        assert_eq!(
            (stats.aim_recommands, stats.aim_not_reached),
            (aim::ATTEMPTS.into(), 1),
            "{wire:?}"
        );
        // The first command, then one a postback apart for each attempt: nothing more in
        // 20 s.
        assert_eq!(
            rig.headings.len(),
            1 + usize::from(aim::ATTEMPTS),
            "{wire:?}"
        );
        assert_eq!(
            rig.events
                .iter()
                .filter(|e| **e == Event::AimNotReached)
                .count(),
            1
        );
        let state = rig.aim_state().unwrap();
        assert!(state.not_reached && !state.on_target, "{wire:?}");
        // A new aim is a new chance.
        rig.aim(vehicle(80.0), 0.0).unwrap();
        rig.run(100);
        assert!(!rig.aim_state().unwrap().not_reached);
        assert_eq!(rig.headings.len(), 2 + usize::from(aim::ATTEMPTS));
        rig.run(20_000);
        assert!(rig.aim_state().unwrap().not_reached, "{wire:?}");
        assert_eq!(rig.stats().aim_not_reached, 2, "{wire:?}");
        // So is the gimbal restarting: its first postback, no closer than the last one
        // before, is the first of the attempts again, which end as before.
        rig.reboot();
        rig.run(3000 + 500 + 100);
        assert!(!rig.aim_state().unwrap().not_reached, "{wire:?}");
        rig.run(20_000);
        let stats = rig.stats();
        assert_eq!(
            (stats.aim_recommands, stats.aim_not_reached),
            (3 * u32::from(aim::ATTEMPTS), 3),
            "{wire:?}"
        );
        assert_eq!(
            rig.headings.len(),
            2 + 3 * usize::from(aim::ATTEMPTS),
            "{wire:?}"
        );
    }
}

#[test]
fn a_yaw_beyond_the_motors_travel_stops_at_the_limit_reported_and_not_hammered() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.vehicle_deg = 0.0;
            rig.run(200);
            // North 175 with the vehicle at 0: the motor stops at 170.
            rig.aim(earth(175.0), 0.0).unwrap();
            rig.run(10_000);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert_eq!(rig.motor(), 170.0, "{what}");
            let state = rig.aim_state().unwrap();
            assert!(state.at_yaw_limit && state.on_target, "{what}: {state:?}");
            assert_eq!(rig.headings.len(), 1, "{what}");
            assert_eq!(rig.stats().aim_not_reached, 0, "{what}");
            // The vehicle turns right: in reach again.
            rig.turn(30.0, 30.0, |_| {});
            rig.run(3000);
            assert!(off(rig.earth_yaw(), 175.0) < SETTLED_DEG, "{what}");
            assert!(!rig.aim_state().unwrap().at_yaw_limit, "{what}");
            // The limit itself is in reach; a tenth of a degree past it is not.
            rig.aim(vehicle(170.0), 0.0).unwrap();
            rig.run(1000);
            assert!(!rig.aim_state().unwrap().at_yaw_limit, "{what}");
            rig.aim(vehicle(-170.1), 0.0).unwrap();
            rig.run(1000);
            assert!(rig.aim_state().unwrap().at_yaw_limit, "{what}");
        }
    }
}

#[test]
fn a_3_5x_gimbal_reaches_a_yaw_behind_the_vehicle() {
    let mut rig = Rig::with(
        Wire::Can,
        SimConfig {
            gimbal_type: GimbalType::Zoom3_5x,
            ..SimConfig::default()
        },
    );
    rig.run(1000);
    rig.aim(vehicle(175.0), 0.0).unwrap();
    rig.run(1000);
    // The simulator's motor stops at 170 whatever the model; the 3.5x's 325 travel means
    // the link takes 175 as in reach (no limit reported).
    assert!(!rig.aim_state().unwrap().at_yaw_limit);
}

#[test]
fn the_tracker_owns_the_gimbal_while_it_tracks() {
    for wire in WIRES {
        for holds in BOTH {
            let what = format!("{wire:?}, lock holds {holds:?}");
            let mut rig = Rig::new(wire, holds);
            rig.run(200);
            rig.aim(vehicle(0.0), 0.0).unwrap();
            rig.run(1000);
            // Stop tracking with no tracker running changes nothing: no command goes.
            let sent = rig.headings.len();
            rig.send(GimbalCommand::StopTracking);
            rig.run(500);
            assert_eq!(rig.headings.len(), sent, "{what}");
            assert_eq!(rig.stats().aim_recommands, 0, "{what}");
            // Track a target right of the centre: the gimbal turns toward it. Started twice
            // (a ground station repeating itself), the tracker still owns the gimbal.
            let centre = ImagePoint::new(6000, 4096).unwrap();
            let track = TrackingBox::new(centre, 256.0, 256.0).unwrap();
            rig.send(GimbalCommand::StartTracking(track));
            rig.send(GimbalCommand::StartTracking(track));
            // The same aim again (a setpoint stream), and the vehicle turns.
            rig.aim(vehicle(0.0), 0.0).unwrap();
            rig.turn(20.0, 30.0, |_| {});
            rig.run(3000);
            rig.assert_tracker_owns(sent, &what);
            // The target, 15° right of the nose when tracking began, is 5° left of it once
            // the vehicle has turned 20° right: the tracker turned the gimbal there, on CAN,
            // where the simulated gimbal sees the vehicle turn (on the UART it cannot).
            let tracked = if wire == Wire::Can { -5.0 } else { 15.0 };
            assert!(off(rig.motor(), tracked) < 0.1, "{what}: {}", rig.motor());
            // Tracking stops: the aim takes the gimbal back.
            rig.send(GimbalCommand::StopTracking);
            rig.run(3000);
            assert!(!rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            assert!(
                off(rig.motor(), 0.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            // A target lost lets go too.
            rig.send(GimbalCommand::StartTracking(track));
            rig.run(12_000);
            assert_eq!(rig.state().targets_lost, 1, "{what}");
            assert!(
                off(rig.motor(), 0.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
            // Stopped before any postback showed it tracking: the aim is back at once.
            rig.send(GimbalCommand::StartTracking(track));
            assert!(rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.send(GimbalCommand::StopTracking);
            assert!(!rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.run(1000);
            // And a new aim takes the gimbal from the tracker, at once.
            rig.send(GimbalCommand::StartTracking(track));
            rig.run(1000);
            assert!(rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.aim(vehicle(10.0), 0.0).unwrap();
            assert!(!rig.aim_state().unwrap().yielded_to_tracker, "{what}");
            rig.run(1000);
            assert!(!rig.state().tracking, "{what}");
            assert!(
                off(rig.motor(), 10.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
        }
    }
}

#[test]
fn an_earth_yaw_without_a_fresh_vehicle_heading_is_refused() {
    let mut link = alone();
    let now = Instant::from_millis(5000);
    assert_eq!(
        link.aim(level(earth(10.0)), now),
        Err(AimError::NoVehicleHeading)
    );
    assert_eq!(link.aim_state(), None);
    link.set_attitude(
        Attitude::new(0.0, 0.0, 5.0).unwrap(),
        Instant::from_millis(3000),
    );
    assert_eq!(
        link.aim(level(earth(10.0)), now),
        Err(AimError::NoVehicleHeading),
        "stale (2 s old)"
    );
    // A vehicle yaw needs no heading on a nose-referenced gimbal.
    assert_eq!(link.aim(level(vehicle(10.0)), now), Ok(()));
}

#[test]
fn an_aim_ends_a_rate_hold_and_a_rate_hold_that_ended_elsewhere_is_corrected() {
    for wire in WIRES {
        for holds in BOTH {
            let mut rig = Rig::new(wire, holds);
            rig.run(200);
            rig.aim(vehicle(0.0), 0.0).unwrap();
            rig.run(2000);
            // Someone else's rate hold moves the gimbal 20° (as a joystick on the gimbal's
            // own remote would), then stops.
            let rate = GimbalCommand::Rate(Rate::new(20.0, 0.0).unwrap());
            for _ in 0..10 {
                match wire {
                    Wire::Can => {
                        let f = Command::from(rate).to_frame();
                        let _ = rig.can_sim.receive(f.id, &f.data, rig.instant());
                    }
                    Wire::Uart => {
                        let frame =
                            idu_gimbal::wire::serial::control_frame(&Command::from(rate).encode());
                        rig.uart_sim.receive(&frame, rig.instant());
                    }
                }
                rig.run(100);
            }
            rig.run(300);
            let what = format!("{wire:?}, lock holds {holds:?}");
            assert!(rig.motor().abs() > 15.0, "{what}: {}", rig.motor());
            // The loop finds the gimbal off and not coming back: it sends the aim again.
            rig.run(3000);
            assert!(
                off(rig.motor(), 0.0) < SETTLED_DEG,
                "{what}: {}",
                rig.motor()
            );
        }
    }
}

#[test]
fn point_at_holds_a_ground_target_while_the_vehicle_turns_in_place() {
    // Hovering 100 m up, 200 m south of the target: the bearing is north whatever the
    // vehicle's heading. The vehicle turns through 180°.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let here = Position::new(47.0, 8.0, 500.0).unwrap();
    let truth = look_at(&here, &target).unwrap();
    let (bearing, elevation) = (truth.bearing_deg as f32, truth.elevation_deg as f32);
    for wire in WIRES {
        for holds in BOTH {
            let what = format!("{wire:?}, lock holds {holds:?}");
            let mut rig = Rig::new(wire, holds);
            rig.position = Some((Gps::new(47.0, 8.0).unwrap(), Altitude::new(500.0).unwrap()));
            rig.vehicle_deg = -90.0;
            rig.run(100);
            match wire {
                Wire::Can => rig.can.point_at(target),
                Wire::Uart => rig.uart.point_at(target),
            }
            rig.run(3000);
            assert!(
                off(rig.earth_yaw(), bearing) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            let mut worst = 0.0f32;
            rig.turn(90.0, 30.0, |r| {
                worst = worst.max(off(r.earth_yaw(), bearing))
            });
            assert!(worst < turn_lag(30.0), "{what}: {worst}");
            rig.run(2000);
            assert!(
                off(rig.earth_yaw(), bearing) < SETTLED_DEG,
                "{what}: {}",
                rig.earth_yaw()
            );
            // The pitch command's 0.1°, and the postback's 0.01°.
            assert!((rig.state().pitch_deg - elevation).abs() < 0.06, "{what}");
            assert!(rig.aim_state().unwrap().aim.yaw.is_earth());
        }
    }
}

#[test]
fn a_point_at_moving_with_the_vehicle_leaves_the_gimbal_to_a_tracker_started_through_the_link() {
    // 200 m south of the target, then flying 100 m east in 3 s: the bearing turns from
    // north to about 26.6° west of it, far past the dead-band.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let east = 8.0 + 100.0 / (111_320.0 * 47.0f64.to_radians().cos());
    for wire in WIRES {
        let what = format!("{wire:?}");
        let mut rig = Rig::new(wire, LockHolds::North);
        rig.position = Some((Gps::new(47.0, 8.0).unwrap(), Altitude::new(500.0).unwrap()));
        rig.run(100);
        match wire {
            Wire::Can => rig.can.point_at(target),
            Wire::Uart => rig.uart.point_at(target),
        }
        rig.run(3000);
        let sent = rig.headings.len();
        let centre = ImagePoint::new(4096, 4096).unwrap();
        rig.send(GimbalCommand::StartTracking(
            TrackingBox::new(centre, 256.0, 256.0).unwrap(),
        ));
        for ms in 1..=3000u32 {
            let lon = 8.0 + (east - 8.0) * f64::from(ms) / 3000.0;
            rig.position = Some((Gps::new(47.0, lon).unwrap(), Altitude::new(500.0).unwrap()));
            rig.tick();
        }
        rig.assert_tracker_owns(sent, &what);
        // The tracker stopped: the aim at the target from where the vehicle is now.
        rig.send(GimbalCommand::StopTracking);
        rig.run(3000);
        let here = Position::new(47.0, east, 500.0).unwrap();
        let bearing = wrap(look_at(&here, &target).unwrap().bearing_deg as f32);
        assert!(bearing < -26.0 && bearing > -27.0, "{bearing}");
        assert!(
            off(rig.earth_yaw(), bearing) < SETTLED_DEG,
            "{what}: {} against {bearing}",
            rig.earth_yaw()
        );
    }
}

#[test]
fn an_earth_yaw_waits_for_the_vehicle_heading_while_it_is_stale() {
    // The link alone: the aim's state as the attitude goes stale and comes back.
    let mut link = alone();
    link.set_attitude(Attitude::new(0.0, 0.0, 30.0).unwrap(), at(0));
    link.aim(level(earth(100.0)), at(0)).unwrap();
    // Nose-referenced (no attitude has reached the gimbal yet when the aim went): 100 - 30.
    assert_eq!(poll_headings(&mut link, 0), [700]);
    assert!(!link.aim_state().unwrap().waiting_for_heading);
    // No attitude since 0: stale past 1,000 ms (the default `vehicle_stale_ms`).
    for ms in (50..=1500).step_by(50) {
        poll_headings(&mut link, ms);
    }
    assert!(link.aim_state().unwrap().waiting_for_heading);
    link.set_attitude(Attitude::new(0.0, 0.0, 40.0).unwrap(), at(1510));
    for ms in (1510..=1600).step_by(10) {
        poll_headings(&mut link, ms);
    }
    assert!(!link.aim_state().unwrap().waiting_for_heading);
}

/// Polls the link alone at `ms`, every frame taken: the heading commands among them, 0.1°.
fn poll_headings(link: &mut Link, ms: u32) -> Vec<u16> {
    link.poll(Instant::from_millis(ms));
    let mut headings = Vec::new();
    while let Some(f) = link.next_transmit() {
        link.transmit_done(None);
        if let Ok(Command::Gimbal(GimbalCommand::Heading(h))) = Command::decode(&f.data) {
            headings.push(h.deci());
        }
    }
    headings
}

#[test]
fn getting_closer_means_by_more_than_the_tolerance() {
    // The link alone, its postbacks made here: a vehicle yaw of 10° (motor 1,000 in
    // 0.01°), the default tolerance 0.5° (50) and loop period 50 ms. The first postback
    // after the command is not judged (it may predate any movement); each later one is,
    // against the one before: an error that shrank by more than the tolerance is getting
    // closer; one that shrank by the tolerance or less is an attempt (a re-command).
    for (second_motor, recommands) in [(51, 0), (50, 1)] {
        let mut link = alone();
        postback(&mut link, 0, false, at(0));
        link.aim(level(vehicle(10.0)), at(0)).unwrap();
        assert_eq!(poll_headings(&mut link, 0), [100]);
        // Error 1,000 (not judged), then 1,000 - motor.
        postback(&mut link, 0, false, at(10));
        poll_headings(&mut link, 50);
        postback(&mut link, second_motor, false, at(60));
        poll_headings(&mut link, 100);
        poll_headings(&mut link, 150);
        assert_eq!(
            link.stats().aim_recommands,
            recommands,
            "motor {second_motor}"
        );
    }
}

#[test]
fn an_aim_within_the_dead_band_of_the_one_held_changes_nothing() {
    // The link alone; the default dead-band is 0.2° (`aim_deadband_mdeg` 200): an aim that
    // far from the one held on each axis is the same aim (a setpoint stream re-sending
    // it), a tenth of a degree more is a new one, commanded at once.
    let mut link = alone();
    let aim = |yaw: f32, pitch: f32| Aim {
        yaw: vehicle(yaw),
        pitch: Pitch::new(pitch).unwrap(),
    };
    let now = Instant::from_millis(0);
    link.aim(aim(10.0, -10.0), now).unwrap();
    assert_eq!(poll_headings(&mut link, 0), [100]);
    assert!(!link.holds_earth_yaw());
    for (yaw, pitch, new) in [
        (10.2, -10.0, false),
        (9.8, -10.0, false),
        (10.0, -10.2, false),
        (10.0, -9.8, false),
        (10.3, -10.0, true),
        (10.3, -10.3, true),
    ] {
        link.aim(aim(yaw, pitch), now).unwrap();
        assert_eq!(link.has_transmit(), new, "{yaw} {pitch}");
        poll_headings(&mut link, 0);
        let held = link.aim_state().unwrap().aim;
        let expected = if new { aim(yaw, pitch) } else { held };
        assert_eq!(held, expected, "{yaw} {pitch}");
    }
    // The frame is part of the aim: the same angle from north is a new aim, held in the
    // earth frame.
    link.set_attitude(Attitude::new(0.0, 0.0, 0.0).unwrap(), now);
    link.aim(
        Aim {
            yaw: earth(10.3),
            pitch: Pitch::new(-10.3).unwrap(),
        },
        now,
    )
    .unwrap();
    assert!(link.has_transmit());
    assert!(link.holds_earth_yaw());
    link.stop_aiming();
    assert!(!link.holds_earth_yaw());
    assert_eq!(link.aim_state(), None);
}

/// A postback of the gimbal holding its angle (lock mode), its motor at `motor_cdeg`, its
/// tracker tracking or not.
fn postback(link: &mut Link, motor_cdeg: i16, tracking: bool, now: Instant) {
    let p = Postback {
        mode: ControlMode::Lock,
        motor_heading: motor_cdeg,
        tracking,
        ..Postback::default()
    };
    for d in p.to_can_frames() {
        link.receive(ids::POSTBACK, &d, now);
    }
}

#[test]
fn a_tracker_started_through_the_link_owns_the_gimbal_until_its_postbacks_let_go() {
    // The link alone, the postbacks made here (the gimbal's motor stays at 0, 10° off the
    // aim, all along: the tracker holds it elsewhere).
    let mut link = alone();
    postback(&mut link, 0, false, at(0));
    link.aim(level(vehicle(10.0)), at(0)).unwrap();
    assert_eq!(poll_headings(&mut link, 0), [100]);
    let track = TrackingBox::new(ImagePoint::new(4096, 4096).unwrap(), 256.0, 256.0).unwrap();
    link.send(GimbalCommand::StartTracking(track)).unwrap();
    // Yielded, and nothing else about the aim changed.
    let state = link.aim_state().unwrap();
    assert!(
        state.yielded_to_tracker && !state.waiting_for_heading,
        "{state:?}"
    );
    poll_headings(&mut link, 0);
    // The first postback after the start may not say it tracks yet: still the tracker's.
    postback(&mut link, 0, false, at(10));
    assert_eq!(poll_headings(&mut link, 50), []);
    assert!(link.aim_state().unwrap().yielded_to_tracker);
    // It tracks for a while, the gimbal far off the aim: nothing is sent, nothing judged
    // (no attempt counted, nothing "not reached").
    for look in 2..10u32 {
        postback(&mut link, 0, true, at(look * 50 - 40));
        assert_eq!(poll_headings(&mut link, look * 50), [], "look {look}");
    }
    let state = link.aim_state().unwrap();
    assert!(state.yielded_to_tracker && !state.not_reached, "{state:?}");
    assert_eq!(link.stats().aim_not_reached, 0);
    assert_eq!(link.stats().aim_recommands, 0);
    // It lets go (target lost): the aim is sent again at the next look.
    postback(&mut link, 0, false, at(510));
    assert_eq!(poll_headings(&mut link, 550), [100]);
    assert!(!link.aim_state().unwrap().yielded_to_tracker);
    assert_eq!(link.stats().aim_recommands, 1);
}

#[test]
fn a_turn_within_the_dead_band_re_sends_nothing_and_one_past_it_re_sends_the_aim() {
    // The link alone, north-referenced (the attitude pushed): a vehicle yaw's command is
    // the yaw plus the vehicle's heading, so a turn must re-send it; a turn within the
    // dead-band (0.2°) need not.
    let mut link = aiming_north_referenced();
    // The gimbal is there (motor 10°): on target.
    postback(&mut link, 1000, false, at(10));
    poll_headings(&mut link, 50);
    assert!(link.aim_state().unwrap().on_target);
    let mut sent = Vec::new();
    // 0.1°, then exactly the dead-band: nothing.
    for (deg, from) in [(0.1, 60), (0.2, 610)] {
        for ms in (from..from + 550).step_by(10) {
            set_heading(&mut link, deg, ms);
            sent.extend(poll_headings(&mut link, ms));
        }
        assert_eq!(sent, [], "{deg}° of turn");
    }
    assert!(link.aim_state().unwrap().on_target);
    for ms in (1160..=1600).step_by(10) {
        set_heading(&mut link, 0.3, ms);
        sent.extend(poll_headings(&mut link, ms));
    }
    assert_eq!(sent, [103], "0.3° of turn");
    // Re-commanded: not on target until a postback says so.
    assert!(!link.aim_state().unwrap().on_target);
    assert_eq!(link.stats().aim_recommands, 1);
}

#[test]
fn an_aim_waiting_for_room_is_not_judged_before_it_is_sent() {
    // The link alone, its command queue (8) left with one slot: the aim's two commands wait
    // while postbacks (the gimbal far off the aim) come in at every look.
    let mut link = alone();
    for _ in 0..7 {
        link.send(GimbalCommand::Zoom(idu_gimbal::wire::control::Zoom::Stop))
            .unwrap();
    }
    link.aim(level(vehicle(10.0)), at(0)).unwrap();
    for look in 1..10u32 {
        postback(&mut link, 0, false, at(look * 50 - 40));
        link.poll(at(look * 50));
    }
    let state = link.aim_state().unwrap();
    assert!(!state.not_reached && !state.on_target, "{state:?}");
    assert_eq!(link.stats().aim_not_reached, 0);
    // Room again: the aim goes, as a first command (not a re-command).
    let mut headings = Vec::new();
    while let Some(f) = link.next_transmit() {
        link.transmit_done(None);
        if let Ok(Command::Gimbal(GimbalCommand::Heading(h))) = Command::decode(&f.data) {
            headings.push(h.deci());
        }
    }
    assert_eq!(headings, []);
    assert_eq!(poll_headings(&mut link, 500), [100]);
    assert_eq!(link.stats().aim_recommands, 0);
}

/// An aim at `yaw`, level.
fn level(yaw: Yaw) -> Aim {
    Aim {
        yaw,
        pitch: Pitch::LEVEL,
    }
}

#[test]
fn a_point_at_re_aims_only_past_the_dead_band() {
    // 200 m south of the target, 100 m above it: moving 0.45 m east turns the bearing by
    // 0.13° (within the 0.2° dead-band: nothing re-sent), 1.5 m by 0.43° (re-aimed).
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let metre_east = 1.0 / (111_320.0 * 47.0f64.to_radians().cos());
    let at = |east_m: f64| {
        (
            Gps::new(47.0, 8.0 + east_m * metre_east).unwrap(),
            Altitude::new(500.0).unwrap(),
        )
    };
    let mut rig = Rig::new(Wire::Can, LockHolds::North);
    rig.position = Some(at(0.0));
    rig.run(100);
    rig.can.point_at(target);
    rig.run(3000);
    let sent = rig.headings.len();
    rig.position = Some(at(0.45));
    rig.run(2000);
    assert_eq!(rig.headings.len(), sent, "0.13°: within the dead-band");
    rig.position = Some(at(1.5));
    rig.run(2000);
    assert_eq!(rig.headings.len(), sent + 1, "0.43°: past it");
}

/// The link alone (no gimbal: the tests give its postbacks by hand), default configuration.
fn alone() -> Link {
    Link::new(Config::default())
}

/// The instant `ms` milliseconds from the start.
fn at(ms: u32) -> Instant {
    Instant::from_millis(ms)
}

#[test]
fn a_turn_and_an_off_postback_at_the_same_look_re_send_the_aim_at_that_look() {
    // The link alone, north-referenced, polled every 10 ms; the attitude is pushed every
    // 100 ms and the loop looks every 50. Two reasons to re-send at the 150 ms look: the
    // attitude frame taken at 100 ms carries a 0.3° turn, and the postback of 110 ms is off
    // the aim and no closer than the one before. One command goes, at that look.
    let mut link = aiming_north_referenced();
    let mut sent = Vec::new();
    for ms in (10..=300).step_by(10) {
        set_heading(&mut link, if ms < 95 { 0.0 } else { 0.3 }, ms);
        match ms {
            // On target, then 1° off.
            10 => postback(&mut link, 1000, false, at(ms)),
            110 => postback(&mut link, 900, false, at(ms)),
            _ => {}
        }
        sent.extend(poll_headings(&mut link, ms).into_iter().map(|h| (ms, h)));
    }
    assert_eq!(sent, [(150, 103)]);
}

#[test]
fn a_point_at_waits_for_both_the_position_and_the_altitude() {
    // The link alone: with only one of the two fresh, no aim is computed (it would take the
    // other from nothing); with both, the aim goes.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let gps = Gps::new(47.0, 8.0).unwrap();
    let altitude = Altitude::new(500.0).unwrap();
    for gps_first in [true, false] {
        let mut link = alone();
        link.point_at(target);
        // A ground target is fixed in the earth frame, aim or not yet.
        assert!(link.holds_earth_yaw());
        let mut sent = Vec::new();
        for ms in (0..=1000).step_by(10) {
            link.set_attitude(Attitude::new(0.0, 0.0, 0.0).unwrap(), at(ms));
            if gps_first {
                link.set_gps(gps, at(ms));
            } else {
                link.set_altitude(altitude, at(ms));
            }
            sent.extend(poll_headings(&mut link, ms));
        }
        assert_eq!(sent, [], "gps first: {gps_first}");
        assert_eq!(link.aim_state(), None);
        link.set_gps(gps, at(1010));
        link.set_altitude(altitude, at(1010));
        for ms in (1010..=1200).step_by(10) {
            sent.extend(poll_headings(&mut link, ms));
        }
        // Due north of the vehicle, its heading 0: a heading command of 0.
        assert_eq!(sent, [0], "gps first: {gps_first}");
    }
}

#[test]
fn a_point_at_that_cannot_send_its_first_aim_sends_it_when_it_can_wherever_the_clock_is() {
    // The link alone, at a clock near 0 and at one more than 2^31 ms past 0 (a firmware's
    // clock may start anywhere, and runs past 2^31 ms after 24.8 days): the first aim is
    // computed but cannot go, once for want of the vehicle's heading (no attitude yet, the
    // gimbal nose-referenced), once for want of room in the queue. It goes at the first
    // look that can send it: within one point-at period (100 ms) of the heading, or at the
    // first poll after the queue drains.
    let target = Position::new(47.0018, 8.0, 400.0).unwrap();
    let gps = Gps::new(47.0, 8.0).unwrap();
    let altitude = Altitude::new(500.0).unwrap();
    for base in [1_000u32, 3_000_000_000] {
        let ms = |offset: u32| base.wrapping_add(offset);

        // No heading yet.
        let mut link = alone();
        link.point_at(target);
        link.set_gps(gps, at(ms(0)));
        link.set_altitude(altitude, at(ms(0)));
        assert_eq!(poll_headings(&mut link, ms(0)), [], "base {base}");
        assert!(link.aim_state().unwrap().waiting_for_heading, "base {base}");
        let mut sent = Vec::new();
        for offset in (10..=200).step_by(10) {
            set_heading(&mut link, 0.0, ms(offset));
            link.set_gps(gps, at(ms(offset)));
            link.set_altitude(altitude, at(ms(offset)));
            sent.extend(
                poll_headings(&mut link, ms(offset))
                    .into_iter()
                    .map(|h| (offset, h)),
            );
        }
        // Due north of the vehicle, its heading 0: a heading command of 0, at the look
        // 100 ms after the first.
        assert_eq!(sent, [(100, 0)], "base {base}");

        // No room in the queue.
        let mut link = alone();
        set_heading(&mut link, 0.0, ms(0));
        link.set_gps(gps, at(ms(0)));
        link.set_altitude(altitude, at(ms(0)));
        poll_headings(&mut link, ms(0));
        while link.send(GimbalCommand::LookDown).is_ok() {}
        link.point_at(target);
        let full = link.stats().queue_full;
        link.poll(at(ms(10)));
        assert!(link.stats().queue_full > full, "base {base}");
        let mut sent = poll_headings(&mut link, ms(20));
        sent.extend(poll_headings(&mut link, ms(30)));
        assert_eq!(sent, [0], "base {base}");
    }
}

#[test]
fn a_point_at_with_no_bearing_or_beyond_the_geodesys_altitude_sends_nothing() {
    // The target at the vehicle (no bearing), and a vehicle above ALT_MAX_M: no aim, no
    // command, whatever is fresh; a target 200 m north then aims at once.
    let gps = Gps::new(47.0, 8.0).unwrap();
    for (what, target, altitude) in [
        (
            "target at the vehicle",
            Position::new(47.0, 8.0, 500.0).unwrap(),
            Altitude::new(500.0).unwrap(),
        ),
        (
            "vehicle above the geodesy's range",
            Position::new(47.0018, 8.0, 400.0).unwrap(),
            Altitude::from_cm(10_000_001),
        ),
    ] {
        let mut link = alone();
        link.point_at(target);
        let mut sent = Vec::new();
        for ms in (0..=1000).step_by(10) {
            set_heading(&mut link, 0.0, ms);
            link.set_gps(gps, at(ms));
            link.set_altitude(altitude, at(ms));
            sent.extend(poll_headings(&mut link, ms));
        }
        assert_eq!(sent, [], "{what}");
        assert_eq!(link.aim_state(), None, "{what}");
        link.point_at(Position::new(47.0018, 8.0, 400.0).unwrap());
        link.set_altitude(Altitude::new(500.0).unwrap(), at(1010));
        assert_eq!(poll_headings(&mut link, 1010), [0], "{what}");
    }
}

/// The vehicle's heading `deg` from north, measured at `ms`, level.
fn set_heading(link: &mut Link, deg: f32, ms: u32) {
    link.set_attitude(Attitude::new(0.0, 0.0, deg).unwrap(), at(ms));
}

/// The link alone, north-referenced (an attitude of heading 0 pushed at 0 ms), holding a
/// vehicle yaw of 10°: its command, 10° from north, sent at 0 ms.
fn aiming_north_referenced() -> Link {
    let mut link = alone();
    set_heading(&mut link, 0.0, 0);
    poll_headings(&mut link, 0);
    assert!(link.north_referenced(at(0)));
    link.aim(level(vehicle(10.0)), at(0)).unwrap();
    assert_eq!(poll_headings(&mut link, 0), [100]);
    link
}
