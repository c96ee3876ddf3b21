//! A scripted bench session: the flight controller's link and port against the simulated gimbal, over the in-memory
//! CAN bus or the in-memory serial line, shared by the root crate's two examples, `host_sim`
//! (host) and `qemu_demo` (an emulated STM32F405). `no_std`, no allocation; telemetry goes to
//! any `core::fmt::Write`.
//!
//! Time is simulated: one loop iteration is one millisecond, so the session is
//! deterministic whatever the host or emulator speed.
//!
//! The script is the same on both transports; what differs is what the transport carries
//! (see [`Medium`]): over serial no vehicle frames reach the gimbal, so its headings are
//! nose-referenced, and there is no text.

use core::fmt::Write;

use embedded_can::{nb::Can, Frame as _};
use idu_gimbal::link::{LinkStats, Medium, Serial};
use idu_gimbal::mock::serial::{Pipe, Rx, Tx};
use idu_gimbal::mock::{Bus, Endpoint, MockFrame};
use idu_gimbal::port::{CanPort, Io, Port, SerialPort};
use idu_gimbal::sim::serial::SerialSimulator;
use idu_gimbal::sim::{SimConfig, SimState, SimStats, Simulator};
use idu_gimbal::wire::control::{GimbalCommand, Heading, Photo, Pitch, Rate, Video, ZoomRatio};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Config, Event, Instant, Link};

/// Endpoints and receive FIFO depth of the in-memory bus.
pub type DemoBus = Bus<2, 32>;
/// The in-memory serial line: 256 bytes of receive buffer each way.
pub type DemoPipe = Pipe<256>;

/// One transport between two ports: the flight controller's port on one end, the
/// simulated gimbal on the other.
pub trait Rig {
    /// What connects them, for the telemetry.
    const WIRE: &'static str;
    /// What the transport carries.
    type Medium: Medium;
    /// The flight controller's port.
    type Port: Port<Medium = Self::Medium>;
    /// The flight controller's port, to poll.
    fn port(&mut self) -> &mut Self::Port;
    /// Moves what the port sent to the gimbal, runs it, and sends back its postbacks.
    fn run_gimbal(&mut self, now: Instant);
    /// Queues a text: `None` when the transport carries none, `Some(false)` when refused.
    fn send_text(link: &mut Link<8, 8, Self::Medium>, text: &[u8]) -> Option<bool>;
    /// The simulated gimbal's state and counters.
    fn sim_state(&self) -> &SimState;
    /// The simulated gimbal's counters.
    fn sim_stats(&self) -> SimStats;
    /// One line of the link's and the port's counters.
    fn summary(&self, link: &LinkStats, out: &mut dyn Write);
}

/// The CAN rig: a [`CanPort`] on endpoint 0, [`Simulator`] on endpoint 1.
pub struct CanRig<'a> {
    port: CanPort<Endpoint<'a, 2, 32>>,
    sim: Simulator,
    sim_can: Endpoint<'a, 2, 32>,
}

impl<'a> CanRig<'a> {
    /// A rig on `bus`, its clock starting at `now`.
    pub fn new(bus: &'a DemoBus, now: Instant) -> Option<Self> {
        Some(CanRig {
            port: CanPort::new(bus.endpoint(0)?),
            sim: Simulator::new(SimConfig::default(), now),
            sim_can: bus.endpoint(1)?,
        })
    }
}

impl<'a> Rig for CanRig<'a> {
    const WIRE: &'static str = "an in-memory CAN bus";
    type Medium = idu_gimbal::link::Can;
    type Port = CanPort<Endpoint<'a, 2, 32>>;
    fn port(&mut self) -> &mut Self::Port {
        &mut self.port
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
    fn send_text(link: &mut Link<8, 8>, text: &[u8]) -> Option<bool> {
        Some(link.send_text(text).is_ok())
    }
    fn sim_state(&self) -> &SimState {
        self.sim.state()
    }
    fn sim_stats(&self) -> SimStats {
        self.sim.stats()
    }
    fn summary(&self, s: &LinkStats, out: &mut dyn Write) {
        let _ = writeln!(
            out,
            "frames sent {} received {}; postbacks {}; superseded vehicle frames {}; driver errors {}",
            s.frames_sent,
            s.frames_received,
            s.postbacks,
            s.superseded,
            self.port.stats().driver_errors.total()
        );
    }
}

/// The serial rig: a [`SerialPort`] on port 0 through the `embedded-io` adapter,
/// [`SerialSimulator`] on port 1.
pub struct SerialRig<'a> {
    port: SerialPort<Io<Rx<'a, 256>, Tx<'a, 256>>>,
    sim: SerialSimulator,
    sim_port: Io<Rx<'a, 256>, Tx<'a, 256>>,
}

impl<'a> SerialRig<'a> {
    /// A rig on `pipe`, its clock starting at `now`.
    pub fn new(pipe: &'a DemoPipe, now: Instant) -> Option<Self> {
        let (rx, tx) = pipe.port(0)?;
        let (sim_rx, sim_tx) = pipe.port(1)?;
        Some(SerialRig {
            port: SerialPort::new(Io::new(rx, tx)),
            sim: SerialSimulator::new(SimConfig::default(), now),
            sim_port: Io::new(sim_rx, sim_tx),
        })
    }
}

impl<'a> Rig for SerialRig<'a> {
    const WIRE: &'static str = "an in-memory serial line (the 24/27-byte UART framing)";
    type Medium = Serial;
    type Port = SerialPort<Io<Rx<'a, 256>, Tx<'a, 256>>>;
    fn port(&mut self) -> &mut Self::Port {
        &mut self.port
    }
    fn run_gimbal(&mut self, now: Instant) {
        let _ = self.sim.serve(&mut self.sim_port, now);
    }
    fn send_text(_link: &mut Link<8, 8, Serial>, _text: &[u8]) -> Option<bool> {
        None
    }
    fn sim_state(&self) -> &SimState {
        self.sim.sim().state()
    }
    fn sim_stats(&self) -> SimStats {
        self.sim.sim().stats()
    }
    fn summary(&self, link: &LinkStats, out: &mut dyn Write) {
        let s = self.port.stats();
        let _ = writeln!(
            out,
            "bytes sent {} received {}; frames sent {}; postbacks {}; bytes skipped {}, CRC errors {}",
            s.bytes_sent,
            s.bytes_received,
            link.frames_sent,
            link.postbacks,
            s.stream.skipped_bytes,
            s.stream.crc_errors
        );
    }
}

/// The scripted session: the link, the rig, the telemetry output and the clock.
pub struct Script<R: Rig, W: Write> {
    out: W,
    link: Link<8, 8, R::Medium>,
    rig: R,
    now: u32,
    start: u32,
    latest: Option<Postback>,
    failures: u32,
}

/// What a step waits for.
type Check<'s> = &'s dyn Fn(&Postback, &SimState) -> bool;

impl<R: Rig, W: Write> Script<R, W> {
    /// A session over `rig`, its clock starting at `start` ms (the rig's too).
    pub fn new(rig: R, out: W, start: u32) -> Self {
        Script {
            out,
            link: Link::new(Config::default()),
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
    /// port, the simulated gimbal, and a telemetry line per postback.
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
                self.link.set_attitude(att, now);
                self.link.set_gps(gps, now);
                self.link.set_altitude(alt, now);
            }
        }
        // A port error is counted in the port's stats; the session goes on.
        let _ = self.rig.port().poll(&mut self.link, now);
        while let Some(event) = self.link.next_event() {
            match event {
                Event::Postback => {
                    let Some(p) = self.link.latest_postback(now).map(|(p, _age)| p) else {
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
                        if self.link.is_link_up() { "up" } else { "down" },
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
        let mut seen = self.link.stats().postbacks;
        for _ in 0..timeout_ms {
            self.tick();
            let count = self.link.stats().postbacks;
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
        if self.link.send(command).is_err() {
            self.failures += 1;
            let _ = writeln!(self.out, "  FAIL queue full");
        }
    }

    /// Plays the script; returns the number of steps whose effect was not seen.
    pub fn play(mut self) -> u32 {
        let _ = writeln!(
            self.out,
            "idu-gimbal session: link and port <-> simulated gimbal over {}",
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
                if R::Medium::VEHICLE_FRAMES {
                    "heading 90° (north-referenced: attitude is pushed, vehicle heading 30°)"
                } else {
                    "heading 90° (nose-referenced: the serial link carries no attitude)"
                },
                GimbalCommand::Heading(heading),
            );
        }
        if R::Medium::VEHICLE_FRAMES {
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
                let _ = self.link.set_rate(rate, now);
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

        match R::send_text(&mut self.link, b"HELLO FROM THE FLIGHT CONTROLLER") {
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

        self.rig.summary(&self.link.stats(), &mut self.out);
        let sim = self.rig.sim_stats();
        let _ = writeln!(
            self.out,
            "gimbal saw {} vehicle frames, {} commands",
            sim.vehicle_frames, sim.commands
        );
        // Vehicle frames reach the gimbal exactly when the transport carries them.
        if (sim.vehicle_frames > 0) != R::Medium::VEHICLE_FRAMES {
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
