//! A scripted bench session: the driver against the simulated gimbal, over the in-memory
//! CAN bus or the in-memory serial line, shared by the root crate's two examples, `host_sim`
//! (host) and `qemu_demo` (an emulated STM32F405). `no_std`, no allocation; telemetry goes to
//! any `core::fmt::Write`.
//!
//! Time is simulated: one loop iteration is one millisecond, so the session is
//! deterministic whatever the host or emulator speed.
//!
//! The script is the same on both transports; what differs is what the transport carries
//! (see [`Rig`]): over serial no vehicle frames reach the gimbal, so its headings are
//! nose-referenced, and there is no text.

use core::fmt::Write;

use embedded_can::{nb::Can, Frame as _};
use idu_gimbal::driver::Io;
use idu_gimbal::mock::serial::{Pipe, Rx, Tx};
use idu_gimbal::mock::{Bus, Endpoint, MockFrame};
use idu_gimbal::sim::serial::SerialSimulator;
use idu_gimbal::sim::{SimConfig, SimState, SimStats, Simulator};
use idu_gimbal::wire::control::{GimbalCommand, Heading, Photo, Pitch, Rate, Video, ZoomRatio};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Config, Event, Gimbal, GimbalControl, Instant, SerialGimbal};

/// Endpoints and receive FIFO depth of the in-memory bus.
pub type DemoBus = Bus<2, 32>;
/// The in-memory serial line: 256 bytes of receive buffer each way.
pub type DemoPipe = Pipe<256>;

/// One transport with the driver on one end and the simulated gimbal on the other.
pub trait Rig {
    /// What connects them, for the telemetry.
    const WIRE: &'static str;
    /// Whether the vehicle attitude reaches the gimbal (headings north-referenced).
    const CARRIES_VEHICLE: bool;
    /// Polls the driver.
    fn poll(&mut self, now: Instant);
    /// The driver: commands, vehicle data, events and postbacks through the core's command
    /// surface, the same on both transports.
    type Driver: GimbalControl;
    /// The driver, to ask.
    fn driver(&self) -> &Self::Driver;
    /// The driver, to command.
    fn driver_mut(&mut self) -> &mut Self::Driver;
    /// Moves what the driver sent to the gimbal, runs it, and sends back its postbacks.
    fn run_gimbal(&mut self, now: Instant);
    /// Postbacks the driver received.
    fn postbacks(&self) -> u32;
    /// Queues a text: `None` when the transport carries none, `Some(false)` when refused.
    fn send_text(&mut self, text: &[u8]) -> Option<bool>;
    /// The simulated gimbal's state and counters.
    fn sim_state(&self) -> &SimState;
    fn sim_stats(&self) -> SimStats;
    /// One line of the driver's counters.
    fn summary(&self, out: &mut dyn Write);
}

/// The CAN rig: [`Gimbal`] on endpoint 0, [`Simulator`] on endpoint 1.
pub struct CanRig<'a> {
    gimbal: Gimbal<Endpoint<'a, 2, 32>>,
    sim: Simulator,
    sim_can: Endpoint<'a, 2, 32>,
}

impl<'a> CanRig<'a> {
    /// A rig on `bus`, its clock starting at `now`.
    pub fn new(bus: &'a DemoBus, now: Instant) -> Option<Self> {
        Some(CanRig {
            gimbal: Gimbal::new(bus.endpoint(0)?, Config::default()),
            sim: Simulator::new(SimConfig::default(), now),
            sim_can: bus.endpoint(1)?,
        })
    }
}

impl<'a> Rig for CanRig<'a> {
    const WIRE: &'static str = "an in-memory CAN bus";
    const CARRIES_VEHICLE: bool = true;
    type Driver = Gimbal<Endpoint<'a, 2, 32>>;
    fn driver(&self) -> &Self::Driver {
        &self.gimbal
    }
    fn driver_mut(&mut self) -> &mut Self::Driver {
        &mut self.gimbal
    }
    fn poll(&mut self, now: Instant) {
        // A driver error is counted in the stats; the session goes on.
        let _ = self.gimbal.poll(now);
    }
    fn run_gimbal(&mut self, now: Instant) {
        while let Ok(f) = Can::receive(&mut self.sim_can) {
            let _ = self.sim.receive(f.raw_id(), f.data(), now);
        }
        let _ = self.sim.poll(now);
        while let Some(f) = self.sim.pop_frame() {
            if let Some(frame) = MockFrame::extended(f.id, &f.data) {
                let _ = Can::transmit(&mut self.sim_can, &frame);
            }
        }
    }
    fn postbacks(&self) -> u32 {
        self.gimbal.stats().link.postbacks
    }
    fn send_text(&mut self, text: &[u8]) -> Option<bool> {
        Some(self.gimbal.send_text(text).is_ok())
    }
    fn sim_state(&self) -> &SimState {
        self.sim.state()
    }
    fn sim_stats(&self) -> SimStats {
        self.sim.stats()
    }
    fn summary(&self, out: &mut dyn Write) {
        let s = self.gimbal.stats().link;
        let _ = writeln!(
            out,
            "frames sent {} received {}; postbacks {}; superseded vehicle frames {}",
            s.frames_sent, s.frames_received, s.postbacks, s.superseded
        );
    }
}

/// The serial rig: [`SerialGimbal`] on port 0 through the `embedded-io` adapter,
/// [`SerialSimulator`] on port 1.
pub struct SerialRig<'a> {
    gimbal: SerialGimbal<Io<Rx<'a, 256>, Tx<'a, 256>>>,
    sim: SerialSimulator,
    sim_port: Io<Rx<'a, 256>, Tx<'a, 256>>,
}

impl<'a> SerialRig<'a> {
    /// A rig on `pipe`, its clock starting at `now`.
    pub fn new(pipe: &'a DemoPipe, now: Instant) -> Option<Self> {
        let (rx, tx) = pipe.port(0)?;
        let (sim_rx, sim_tx) = pipe.port(1)?;
        Some(SerialRig {
            gimbal: SerialGimbal::new(Io::new(rx, tx), Config::default()),
            sim: SerialSimulator::new(SimConfig::default(), now),
            sim_port: Io::new(sim_rx, sim_tx),
        })
    }
}

impl<'a> Rig for SerialRig<'a> {
    const WIRE: &'static str = "an in-memory serial line (the 24/27-byte UART framing)";
    const CARRIES_VEHICLE: bool = false;
    type Driver = SerialGimbal<Io<Rx<'a, 256>, Tx<'a, 256>>>;
    fn driver(&self) -> &Self::Driver {
        &self.gimbal
    }
    fn driver_mut(&mut self) -> &mut Self::Driver {
        &mut self.gimbal
    }
    fn poll(&mut self, now: Instant) {
        // A port error is counted in stats().port_errors; the session goes on.
        let _ = self.gimbal.poll(now);
    }
    fn run_gimbal(&mut self, now: Instant) {
        let _ = self.sim.serve(&mut self.sim_port, now);
    }
    fn postbacks(&self) -> u32 {
        self.gimbal.stats().link.postbacks
    }
    fn send_text(&mut self, _text: &[u8]) -> Option<bool> {
        None
    }
    fn sim_state(&self) -> &SimState {
        self.sim.sim().state()
    }
    fn sim_stats(&self) -> SimStats {
        self.sim.sim().stats()
    }
    fn summary(&self, out: &mut dyn Write) {
        let s = self.gimbal.stats();
        let _ = writeln!(
            out,
            "bytes sent {} received {}; frames sent {}; postbacks {}; bytes skipped {}, CRC errors {}",
            s.bytes_sent,
            s.bytes_received,
            s.link.frames_sent,
            s.link.postbacks,
            s.stream.skipped_bytes,
            s.stream.crc_errors
        );
    }
}

/// The rig, the telemetry output and the clock.
pub struct Session<R: Rig, W: Write> {
    out: W,
    rig: R,
    now: u32,
    start: u32,
    latest: Option<Postback>,
    failures: u32,
}

/// What a step waits for.
type Check<'s> = &'s dyn Fn(&Postback, &SimState) -> bool;

impl<R: Rig, W: Write> Session<R, W> {
    /// A session over `rig`, its clock starting at `start` ms (the rig's too).
    pub fn new(rig: R, out: W, start: u32) -> Self {
        Session {
            out,
            rig,
            now: start,
            start,
            latest: None,
            failures: 0,
        }
    }

    fn seconds(&self) -> (u32, u32) {
        let ms = self.now.wrapping_sub(self.start);
        (ms / 1000, ms % 1000)
    }

    /// One millisecond: vehicle data at 10 Hz from a stand-in flight controller, the
    /// driver, the simulated gimbal, and a telemetry line per postback.
    fn tick(&mut self) {
        let now = Instant::from_millis(self.now);
        let elapsed = self.now.wrapping_sub(self.start);
        if elapsed.is_multiple_of(100) {
            // Stand-in vehicle: level, heading 30°, hovering over Zurich at 450 m.
            if let (Ok(att), Ok(gps), Ok(alt)) = (
                Attitude::new(0.0, 0.0, 30.0),
                Gps::new(47.397_742, 8.545_594),
                Altitude::new(450.0),
            ) {
                let driver = self.rig.driver_mut();
                driver.set_attitude(att, now);
                driver.set_gps(gps, now);
                driver.set_altitude(alt, now);
            }
        }
        self.rig.poll(now);
        while let Some(event) = self.rig.driver_mut().next_event() {
            match event {
                Event::Postback => {
                    let Some(p) = self.rig.driver().latest_postback(now).map(|(p, _age)| p) else {
                        continue;
                    };
                    self.latest = Some(p);
                    let (s, ms) = self.seconds();
                    let _ = writeln!(
                        self.out,
                        "t={s:3}.{ms:03} s  pitch {:7.2}°  heading {:6.2}°  motor {:7.2}°  mode {:<14}  link {}",
                        p.pitch_deg(),
                        p.heading_deg(),
                        p.motor_heading_deg(),
                        p.mode.name().unwrap_or("unknown"),
                        if self.rig.driver().is_link_up() { "up" } else { "down" },
                    );
                }
                Event::LinkUp => {
                    let _ = writeln!(self.out, "link up");
                }
                Event::LinkDown => {
                    let _ = writeln!(self.out, "link down");
                }
                Event::RateHoldExpired => {
                    let _ = writeln!(self.out, "rate hold released: dead-man sent zero rate");
                }
                Event::TargetUnreachable { .. } => {}
                Event::AimNotReached => {
                    let _ = writeln!(self.out, "aim not reached");
                }
            }
        }
        self.rig.run_gimbal(now);
        self.now = self.now.wrapping_add(1);
    }

    fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    /// Runs until `check` holds on a postback received after this call, or `timeout_ms`.
    fn expect(&mut self, what: &str, timeout_ms: u32, check: Check<'_>) {
        let mut seen = self.rig.postbacks();
        for _ in 0..timeout_ms {
            self.tick();
            let count = self.rig.postbacks();
            if count != seen {
                seen = count;
                if let Some(p) = self.latest {
                    if check(&p, self.rig.sim_state()) {
                        let (s, ms) = self.seconds();
                        let _ = writeln!(self.out, "  ok  {what} (t={s}.{ms:03} s)");
                        return;
                    }
                }
            }
        }
        self.failures += 1;
        let _ = writeln!(self.out, "  FAIL {what}: not seen within {timeout_ms} ms");
    }

    fn step(&mut self, what: &str, command: GimbalCommand) {
        let _ = writeln!(self.out, "> {what}");
        if self.rig.driver_mut().send(command).is_err() {
            self.failures += 1;
            let _ = writeln!(self.out, "  FAIL queue full");
        }
    }

    /// Plays the script; returns the number of steps whose effect was not seen.
    pub fn play(mut self) -> u32 {
        let _ = writeln!(
            self.out,
            "idu-gimbal session: driver <-> simulated gimbal over {}",
            R::WIRE
        );
        self.expect("postbacks arrive, link up", 1500, &|_, _| true);

        self.step("re-center", GimbalCommand::Recenter);
        self.expect("pitch 0°, motor 0°", 3000, &|p, _| {
            p.pitch == 0 && p.motor_heading == 0
        });

        if let Ok(pitch) = Pitch::new(-45.0) {
            self.step("pitch -45°", GimbalCommand::Pitch(pitch));
        }
        self.expect("pitch -45.00° reported", 3000, &|p, _| p.pitch == -4500);

        if let Ok(heading) = Heading::new(90.0) {
            self.step(
                if R::CARRIES_VEHICLE {
                    "heading 90° (north-referenced: attitude is pushed, vehicle heading 30°)"
                } else {
                    "heading 90° (nose-referenced: the serial link carries no attitude)"
                },
                GimbalCommand::Heading(heading),
            );
        }
        if R::CARRIES_VEHICLE {
            self.expect("heading 90.00°, motor 60.00°", 3000, &|p, _| {
                p.heading == 9000 && p.motor_heading == 6000
            });
        } else {
            self.expect("heading 90.00°, motor 90.00°", 3000, &|p, _| {
                p.heading == 9000 && p.motor_heading == 9000
            });
        }

        let _ = writeln!(
            self.out,
            "> rate hold: yaw 20°/s, refreshed for 1 s, then released"
        );
        let before = self.latest.map_or(0, |p| p.motor_heading);
        if let Ok(rate) = Rate::new(20.0, 0.0) {
            for _ in 0..50 {
                let now = Instant::from_millis(self.now);
                let _ = self.rig.driver_mut().set_rate(rate, now);
                self.run(20);
            }
        }
        self.run(400);
        let after = self.rig.sim_state().motor_yaw_deg;
        self.run(1000);
        let still = self.rig.sim_state().motor_yaw_deg;
        let turned = self.latest.map_or(0, |p| p.motor_heading) - before;
        let _ = writeln!(
            self.out,
            "  turned {:.2}° during the hold",
            f32::from(turned) / 100.0
        );
        if turned > 1500 && after == still && self.rig.sim_state().rate == (0.0, 0.0) {
            let _ = writeln!(
                self.out,
                "  ok  gimbal turned, then stopped after the dead-man"
            );
        } else {
            self.failures += 1;
            let _ = writeln!(
                self.out,
                "  FAIL rate hold: turned {turned} cdeg, stopped: {}",
                after == still
            );
        }

        if let Ok(zoom) = ZoomRatio::new(10.0) {
            self.step("zoom to 10x", GimbalCommand::ZoomRatio(zoom));
        }
        self.expect("zoom 10x", 1500, &|_, s| s.zoom_ratio == 10.0);

        self.step("photo", GimbalCommand::Photo(Photo::Single));
        self.expect("one photo taken", 1500, &|_, s| s.photos == 1);

        self.step("recording on", GimbalCommand::Video(Video::Start));
        self.expect("recording", 1500, &|_, s| s.recording);
        self.step("recording off", GimbalCommand::Video(Video::Stop));
        self.expect("not recording", 1500, &|_, s| !s.recording);

        match self.rig.send_text(b"HELLO FROM THE FLIGHT CONTROLLER") {
            Some(queued) => {
                let _ = writeln!(self.out, "> text message");
                if !queued {
                    self.failures += 1;
                }
                self.expect("text received", 1500, &|_, s| {
                    s.last_text.as_str() == "HELLO FROM THE FLIGHT CONTROLLER"
                });
            }
            None => {
                let _ = writeln!(self.out, "> text message: not carried by this transport");
            }
        }

        self.rig.summary(&mut self.out);
        let sim = self.rig.sim_stats();
        let _ = writeln!(
            self.out,
            "gimbal saw {} vehicle frames, {} commands",
            sim.vehicle_frames, sim.commands
        );
        // Vehicle frames reach the gimbal exactly when the transport carries them.
        if (sim.vehicle_frames > 0) != R::CARRIES_VEHICLE {
            self.failures += 1;
            let _ = writeln!(
                self.out,
                "  FAIL vehicle frames: {} reached the gimbal",
                sim.vehicle_frames
            );
        }
        let _ = writeln!(
            self.out,
            "{}",
            if self.failures == 0 {
                "session passed"
            } else {
                "session FAILED"
            }
        );
        self.failures
    }
}
