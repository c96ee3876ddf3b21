//! Closed-loop aiming (`Link::aim`, `Link::point_at`) against the simulated gimbal, on CAN
//! and on the UART, with the simulator holding its north heading in lock and with it
//! holding its motor angle: the two behaviours the document leaves open. Whatever the
//! gimbal does, the camera must stay where the aim says, in the aim's frame.
//!
//! The expectations are the aim itself: an earth yaw is checked as the vehicle's heading
//! (the test's own) + the simulator's motor angle, a vehicle yaw as the motor angle alone.
//!
//! `with_the_gimbal` holds aims against the simulated gimbal through the [`Rig`] here;
//! `link_alone` tests the link's decisions with no gimbal, its postbacks given by hand.

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

mod link_alone;
mod with_the_gimbal;

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

/// An aim at `yaw`, level.
fn level(yaw: Yaw) -> Aim {
    Aim {
        yaw,
        pitch: Pitch::LEVEL,
    }
}
