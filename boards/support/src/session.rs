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
use idu_gimbal::link::{LinkStats, Medium, Serial, TextQueueError};
use idu_gimbal::mock::serial::{Pipe, Rx, Tx};
use idu_gimbal::mock::{Bus, Endpoint, MockFrame};
use idu_gimbal::port::{CanPort, Io, Port, SerialPort};
use idu_gimbal::sim::serial::SerialSimulator;
use idu_gimbal::sim::{SimConfig, SimState, SimStats, Simulator};
use idu_gimbal::wire::control::{GimbalCommand, Heading, Photo, Pitch, Rate, Video, ZoomRatio};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Config, Event, Instant, Link};

use crate::vehicle::Vehicle;

/// The text the script sends where the transport carries text.
pub const TEXT: &[u8] = b"HELLO FROM THE FLIGHT CONTROLLER";

/// What a step waits for: a postback received after the step began, with the simulated
/// gimbal's state.
pub type Check = fn(&Postback, &SimState) -> bool;

/// One step of the scripted session. The script is [`steps`]; each player takes its steps
/// in order: [`Script`] here (a millisecond at a time), and `boards/embassy_qemu`'s session
/// (in embassy time, the link in a task of its own).
#[derive(Clone, Copy)]
pub enum Step {
    /// Say `.0` and send the command.
    Command(&'static str, GimbalCommand),
    /// Wait, at most `.1` ms, for a postback that passes the check; `.0` says what.
    Expect(&'static str, u32, Check),
    /// The rate hold ([`RATE_HOLD`]), judged by [`RateHold::verdict`].
    RateHold,
    /// Send [`TEXT`] and wait, at most `.0` ms, for the gimbal to have it.
    Text(u32),
}

/// The session's stand-in vehicle, measured at `now`: level, heading 30°, hovering over
/// Zurich at 450 m.
pub fn vehicle(now: Instant) -> Option<Vehicle> {
    Some(Vehicle {
        gps: Gps::new(47.397_742, 8.545_594).ok()?,
        altitude: Altitude::new(450.0).ok()?,
        attitude: Attitude::new(0.0, 0.0, 30.0).ok()?,
        stamp: now,
    })
}

/// The script, for a transport that carries the vehicle's attitude (`north`: headings are
/// then north-referenced) or not. Text is sent where the player's transport carries it.
pub fn steps(north: bool) -> heapless::Vec<Step, 20> {
    let mut steps: heapless::Vec<Step, 20> = heapless::Vec::new();
    let mut push = |step| {
        // At most 17 steps: the capacity holds them all.
        let _ = steps.push(step);
    };
    push(Step::Expect("postbacks arrive, link up", 1500, |_, _| true));
    push(Step::Command("re-center", GimbalCommand::Recenter));
    push(Step::Expect("pitch 0°, motor 0°", 3000, |p, _| {
        p.pitch == 0 && p.motor_heading == 0
    }));
    if let Ok(pitch) = Pitch::new(-45.0) {
        push(Step::Command("pitch -45°", GimbalCommand::Pitch(pitch)));
    }
    push(Step::Expect("pitch -45.00° reported", 3000, |p, _| {
        p.pitch == -4500
    }));
    if let Ok(heading) = Heading::new(90.0) {
        push(Step::Command(
            if north {
                "heading 90° (north-referenced: attitude is pushed, vehicle heading 30°)"
            } else {
                "heading 90° (nose-referenced: the serial link carries no attitude)"
            },
            GimbalCommand::Heading(heading),
        ));
    }
    if north {
        push(Step::Expect(
            "heading 90.00°, motor 60.00°",
            3000,
            |p, _| p.heading == 9000 && p.motor_heading == 6000,
        ));
    } else {
        push(Step::Expect(
            "heading 90.00°, motor 90.00°",
            3000,
            |p, _| p.heading == 9000 && p.motor_heading == 9000,
        ));
    }
    push(Step::RateHold);
    if let Ok(zoom) = ZoomRatio::new(10.0) {
        push(Step::Command("zoom to 10x", GimbalCommand::ZoomRatio(zoom)));
    }
    push(Step::Expect("zoom 10x", 1500, |_, s| s.zoom_ratio == 10.0));
    push(Step::Command("photo", GimbalCommand::Photo(Photo::Single)));
    push(Step::Expect("one photo taken", 1500, |_, s| s.photos == 1));
    push(Step::Command(
        "recording on",
        GimbalCommand::Video(Video::Start),
    ));
    push(Step::Expect("recording", 1500, |_, s| s.recording));
    push(Step::Command(
        "recording off",
        GimbalCommand::Video(Video::Stop),
    ));
    push(Step::Expect("not recording", 1500, |_, s| !s.recording));
    push(Step::Text(1500));
    steps
}

/// The rate hold's timing: a yaw rate refreshed every `refresh_ms`, `refreshes` times, then
/// left to the link's dead-man; the gimbal looked at `release_ms` after the last refresh
/// and again `settle_ms` later.
pub struct RateHold {
    /// The yaw rate, °/s.
    pub yaw_dps: f32,
    /// Between two refreshes, ms.
    pub refresh_ms: u32,
    /// How many refreshes.
    pub refreshes: u32,
    /// From the last refresh to the first look, ms (beyond the dead-man's 250).
    pub release_ms: u32,
    /// From the first look to the second, ms.
    pub settle_ms: u32,
}

/// The script's rate hold: 20°/s for a second.
pub const RATE_HOLD: RateHold = RateHold {
    yaw_dps: 20.0,
    refresh_ms: 20,
    refreshes: 50,
    release_ms: 400,
    settle_ms: 1000,
};

impl RateHold {
    /// What the player says as the hold begins.
    pub fn say_start(&self, out: &mut dyn Write) {
        let _ = writeln!(
            out,
            "> rate hold: yaw {}°/s, refreshed every {} ms for {} s, then released",
            self.yaw_dps,
            self.refresh_ms,
            self.refresh_ms * self.refreshes / 1000
        );
    }

    /// Whether the gimbal turned during the hold (`turned_cdeg`, from the postbacks) and
    /// stopped after it (the motor's yaw at both looks the same, its rate zero), said.
    pub fn verdict(
        &self,
        out: &mut dyn Write,
        turned_cdeg: i32,
        looks: Option<(f32, f32)>,
        stopped: bool,
    ) -> bool {
        let _ = writeln!(
            out,
            "  turned {:.2}° during the hold",
            turned_cdeg as f32 / 100.0
        );
        let still = looks.is_some_and(|(after, later)| after == later) && stopped;
        if turned_cdeg > 1500 && still {
            let _ = writeln!(out, "  ok  gimbal turned, then stopped after the dead-man");
            true
        } else {
            let _ = writeln!(
                out,
                "  FAIL rate hold: turned {turned_cdeg} cdeg, stopped: {still}"
            );
            false
        }
    }
}

/// The telemetry line of a postback, `elapsed_ms` into the session.
pub fn say_postback(out: &mut dyn Write, elapsed_ms: u64, p: &Postback, link_up: bool) {
    let (s, ms) = (elapsed_ms / 1000, elapsed_ms % 1000);
    let _ = writeln!(
        out,
        "t={s:3}.{ms:03} s  pitch {:7.2}°  heading {:6.2}°  motor {:7.2}°  mode {:<14}  link {}",
        p.pitch_deg(),
        p.heading_deg(),
        p.motor_heading_deg(),
        p.mode.name().unwrap_or("unknown"),
        if link_up { "up" } else { "down" },
    );
}

/// The line of an event other than a postback (some have none).
pub fn say_event(out: &mut dyn Write, event: Event) {
    let line = match event {
        Event::LinkUp => "link up",
        Event::LinkDown => "link down",
        Event::RateHoldExpired => "rate hold released: dead-man sent zero rate",
        Event::AimNotReached => "aim not reached",
        Event::Postback | Event::TargetUnreachable { .. } => return,
    };
    let _ = writeln!(out, "{line}");
}

/// An expected effect seen, `elapsed_ms` into the session.
pub fn say_ok(out: &mut dyn Write, what: &str, elapsed_ms: u64) {
    let (s, ms) = (elapsed_ms / 1000, elapsed_ms % 1000);
    let _ = writeln!(out, "  ok  {what} (t={s}.{ms:03} s)");
}

/// An expected effect not seen in time.
pub fn say_fail(out: &mut dyn Write, what: &str, timeout_ms: u32) {
    let _ = writeln!(out, "  FAIL {what}: not seen within {timeout_ms} ms");
}

/// Whether vehicle frames reached the gimbal exactly when the transport carries them
/// (`carried`), said with the gimbal's counts.
pub fn vehicle_frames_verdict(out: &mut dyn Write, sim: &SimStats, carried: bool) -> bool {
    let _ = writeln!(
        out,
        "gimbal saw {} vehicle frames, {} commands",
        sim.vehicle_frames, sim.commands
    );
    if (sim.vehicle_frames > 0) == carried {
        true
    } else {
        let _ = writeln!(
            out,
            "  FAIL vehicle frames: {} reached the gimbal",
            sim.vehicle_frames
        );
        false
    }
}

/// The session's last line.
pub fn say_verdict(out: &mut dyn Write, failures: u32) {
    let _ = writeln!(
        out,
        "{}",
        if failures == 0 {
            "session passed"
        } else {
            "session FAILED"
        }
    );
}

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
    /// Queues a text: `None` when the transport carries none, `Some(Err(_))` when refused.
    fn send_text(
        link: &mut Link<8, 8, Self::Medium>,
        text: &[u8],
    ) -> Option<Result<(), TextQueueError>>;
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
    /// The simulated gimbal's frames the bus did not take (a transmit error, as the mock
    /// bus injects): counted and said in the summary, never lost quietly. (A full receive
    /// FIFO on the port's side is not one: the bus takes the frame and the port counts an
    /// overrun.)
    sim_unsent: u32,
}

impl<'a> CanRig<'a> {
    /// A rig on `bus`, its clock starting at `now`.
    pub fn new(bus: &'a DemoBus, now: Instant) -> Option<Self> {
        Self::with_gimbal(bus, SimConfig::default(), now)
    }

    /// A rig on `bus` whose simulated gimbal is set up by `config`.
    pub fn with_gimbal(bus: &'a DemoBus, config: SimConfig, now: Instant) -> Option<Self> {
        Some(CanRig {
            port: CanPort::new(bus.endpoint(0)?),
            sim: Simulator::new(config, now),
            sim_can: bus.endpoint(1)?,
            sim_unsent: 0,
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
            // A frame the simulator refuses is in its own counts (`SimStats::rejected`).
            let _ = self.sim.receive(f.raw_id(), f.data(), now);
        }
        // The postback it returns is also queued as frames, taken below.
        let _ = self.sim.poll(now);
        while let Some(f) = self.sim.pop_frame() {
            // The demo's bus delivers at once, so a transmit never hands a frame back;
            // one that did would be lost too, and is counted with the refused.
            let sent = MockFrame::extended(f.id, &f.data)
                .is_some_and(|frame| Can::transmit(&mut self.sim_can, &frame) == Ok(None));
            if !sent {
                self.sim_unsent = self.sim_unsent.wrapping_add(1);
            }
        }
    }
    fn send_text(link: &mut Link<8, 8>, text: &[u8]) -> Option<Result<(), TextQueueError>> {
        Some(link.send_text(text))
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
            "frames sent {} received {}; postbacks {}; superseded vehicle frames {}; driver errors {}; gimbal frames the bus refused {}",
            s.frames_sent,
            s.frames_received,
            s.postbacks,
            s.superseded,
            self.port.stats().driver_errors.total(),
            self.sim_unsent
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
    fn send_text(
        _link: &mut Link<8, 8, Serial>,
        _text: &[u8],
    ) -> Option<Result<(), TextQueueError>> {
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

    /// One millisecond: vehicle data at 10 Hz from a stand-in flight controller, the
    /// port, the simulated gimbal, and a telemetry line per postback.
    fn tick(&mut self) {
        let now = Instant::from_millis(self.now);
        let elapsed = self.now.wrapping_sub(self.start);
        if elapsed.is_multiple_of(100) {
            if let Some(v) = vehicle(now) {
                v.push(&mut self.link);
            }
        }
        // A port error is counted in the port's stats; the session goes on.
        let _ = self.rig.port().poll(&mut self.link, now);
        while let Some(event) = self.link.next_event() {
            if event == Event::Postback {
                if let Some((p, _age)) = self.link.latest_postback(now) {
                    self.latest = Some(p);
                    let elapsed = u64::from(self.now.wrapping_sub(self.start));
                    say_postback(&mut self.out, elapsed, &p, self.link.is_link_up());
                }
            } else {
                say_event(&mut self.out, event);
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
    fn expect(&mut self, what: &str, timeout_ms: u32, check: Check) {
        let mut seen = self.link.stats().postbacks;
        for _ in 0..timeout_ms {
            self.tick();
            let count = self.link.stats().postbacks;
            if count != seen {
                seen = count;
                if let Some(p) = self.latest {
                    if check(&p, self.rig.sim_state()) {
                        let elapsed = u64::from(self.now.wrapping_sub(self.start));
                        say_ok(&mut self.out, what, elapsed);
                        return;
                    }
                }
            }
        }
        self.failures += 1;
        say_fail(&mut self.out, what, timeout_ms);
    }

    fn command(&mut self, what: &str, command: GimbalCommand) {
        let _ = writeln!(self.out, "> {what}");
        if self.link.send(command).is_err() {
            self.failures += 1;
            let _ = writeln!(self.out, "  FAIL queue full");
        }
    }

    fn rate_hold(&mut self) {
        let hold = RATE_HOLD;
        hold.say_start(&mut self.out);
        let before = self.latest.map_or(0, |p| p.motor_heading);
        if let Ok(rate) = Rate::new(hold.yaw_dps, 0.0) {
            for _ in 0..hold.refreshes {
                let now = Instant::from_millis(self.now);
                let _ = self.link.set_rate(rate, now);
                self.run(hold.refresh_ms);
            }
        }
        self.run(hold.release_ms);
        let after = self.rig.sim_state().motor_yaw_deg;
        self.run(hold.settle_ms);
        let later = self.rig.sim_state().motor_yaw_deg;
        let turned = i32::from(self.latest.map_or(0, |p| p.motor_heading)) - i32::from(before);
        let stopped = self.rig.sim_state().rate == (0.0, 0.0);
        if !hold.verdict(&mut self.out, turned, Some((after, later)), stopped) {
            self.failures += 1;
        }
    }

    fn text(&mut self, timeout_ms: u32) {
        match R::send_text(&mut self.link, TEXT) {
            Some(Ok(())) => {
                let _ = writeln!(self.out, "> text message");
                self.expect("text received", timeout_ms, |_, s| {
                    s.last_text.as_bytes() == TEXT
                });
            }
            Some(Err(e)) => {
                let _ = writeln!(self.out, "> text message");
                let _ = writeln!(self.out, "  FAIL text not queued: {e}");
                self.failures += 1;
            }
            None => {
                let _ = writeln!(self.out, "> text message: not carried by this transport");
            }
        }
    }

    /// Plays the script ([`steps`]); returns the number of steps whose effect was not
    /// seen.
    pub fn play(mut self) -> u32 {
        let _ = writeln!(
            self.out,
            "idu-gimbal session: link and port <-> simulated gimbal over {}",
            R::WIRE
        );
        for step in steps(R::Medium::VEHICLE_FRAMES) {
            match step {
                Step::Command(what, command) => self.command(what, command),
                Step::Expect(what, timeout_ms, check) => self.expect(what, timeout_ms, check),
                Step::RateHold => self.rate_hold(),
                Step::Text(timeout_ms) => self.text(timeout_ms),
            }
        }
        self.rig.summary(&self.link.stats(), &mut self.out);
        if !vehicle_frames_verdict(
            &mut self.out,
            &self.rig.sim_stats(),
            R::Medium::VEHICLE_FRAMES,
        ) {
            self.failures += 1;
        }
        say_verdict(&mut self.out, self.failures);
        self.failures
    }
}

#[cfg(test)]
mod tests;
