//! A scripted bench session: the driver against the simulated gimbal over the in-memory
//! bus, shared by `host_sim` (host) and `qemu_demo` (emulated STM32F405). `no_std`, no
//! allocation; telemetry goes to any `core::fmt::Write`.
//!
//! Time is simulated: one loop iteration is one millisecond, so the session is
//! deterministic whatever the host or emulator speed.

use core::fmt::Write;

use embedded_can::{nb::Can, Frame as _};
use idu_gimbal::mock::{Bus, Endpoint, MockFrame};
use idu_gimbal::sim::{SimConfig, Simulator};
use idu_gimbal::wire::control::{GimbalCommand, Heading, Photo, Pitch, Rate, Video, ZoomRatio};
use idu_gimbal::wire::postback::Postback;
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::{Config, Event, Gimbal, Instant};

/// Endpoints and receive FIFO depth of the in-memory bus.
pub type DemoBus = Bus<2, 32>;

/// The driver, the simulator and the clock.
pub struct Session<'a, W: Write> {
    out: W,
    gimbal: Gimbal<Endpoint<'a, 2, 32>>,
    sim: Simulator,
    sim_can: Endpoint<'a, 2, 32>,
    now: u32,
    start: u32,
    latest: Option<Postback>,
    failures: u32,
}

/// What a step waits for.
type Check<'s> = &'s dyn Fn(&Postback, &Simulator) -> bool;

impl<'a, W: Write> Session<'a, W> {
    /// A session on `bus`, its clock starting at `start` ms.
    pub fn new(bus: &'a DemoBus, out: W, start: u32) -> Option<Self> {
        let now = Instant::from_millis(start);
        Some(Session {
            out,
            gimbal: Gimbal::new(bus.endpoint(0)?, Config::default()),
            sim: Simulator::new(SimConfig::default(), now),
            sim_can: bus.endpoint(1)?,
            now: start,
            start,
            latest: None,
            failures: 0,
        })
    }

    fn seconds(&self) -> (u32, u32) {
        let ms = self.now.wrapping_sub(self.start);
        (ms / 1000, ms % 1000)
    }

    /// One millisecond: vehicle push at 10 Hz from a stand-in flight controller, the
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
                self.gimbal.set_attitude(att, now);
                self.gimbal.set_gps(gps, now);
                self.gimbal.set_altitude(alt, now);
            }
        }
        let _ = self.gimbal.poll(now);
        while let Some(event) = self.gimbal.next_event() {
            match event {
                Event::Postback => {
                    let Some((p, _)) = self.gimbal.latest_postback(now) else {
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
                        if self.gimbal.is_link_up() { "up" } else { "down" },
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
            }
        }
        while let Ok(f) = Can::receive(&mut self.sim_can) {
            let _ = self.sim.receive(f.raw_id(), f.data(), now);
        }
        let _ = self.sim.poll(now);
        while let Some(f) = self.sim.pop_frame() {
            if let Some(frame) = MockFrame::extended(f.id, &f.data) {
                let _ = Can::transmit(&mut self.sim_can, &frame);
            }
        }
        self.now = self.now.wrapping_add(1);
    }

    fn run(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    /// Runs until `check` holds on a postback received after this call, or `timeout_ms`.
    fn expect(&mut self, what: &str, timeout_ms: u32, check: Check<'_>) {
        let mut seen = self.gimbal.stats().link.postbacks;
        for _ in 0..timeout_ms {
            self.tick();
            let count = self.gimbal.stats().link.postbacks;
            if count != seen {
                seen = count;
                if let Some(p) = self.latest {
                    if check(&p, &self.sim) {
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
        if self.gimbal.send(command).is_err() {
            self.failures += 1;
            let _ = writeln!(self.out, "  FAIL queue full");
        }
    }

    /// Plays the script; returns the number of steps whose effect was not seen.
    pub fn play(mut self) -> u32 {
        let _ = writeln!(
            self.out,
            "idu-gimbal session: driver <-> simulated gimbal over an in-memory CAN bus"
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
                "heading 90° (north-referenced: attitude is pushed, vehicle heading 30°)",
                GimbalCommand::Heading(heading),
            );
        }
        self.expect("heading 90.00°, motor 60.00°", 3000, &|p, _| {
            p.heading == 9000 && p.motor_heading == 6000
        });

        let _ = writeln!(
            self.out,
            "> rate hold: yaw 20°/s, refreshed for 1 s, then released"
        );
        let before = self.latest.map_or(0, |p| p.motor_heading);
        if let Ok(rate) = Rate::new(20.0, 0.0) {
            for _ in 0..50 {
                let now = Instant::from_millis(self.now);
                let _ = self.gimbal.set_rate(rate, now);
                self.run(20);
            }
        }
        self.run(400);
        let after = self.sim.state().motor_yaw_deg;
        self.run(1000);
        let still = self.sim.state().motor_yaw_deg;
        let turned = self.latest.map_or(0, |p| p.motor_heading) - before;
        let _ = writeln!(
            self.out,
            "  turned {:.2}° during the hold",
            f32::from(turned) / 100.0
        );
        if turned > 1500 && after == still && self.sim.state().rate == (0.0, 0.0) {
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
        self.expect("zoom 10x", 1500, &|_, s| s.state().zoom_ratio == 10.0);

        self.step("photo", GimbalCommand::Photo(Photo::Single));
        self.expect("one photo taken", 1500, &|_, s| s.state().photos == 1);

        self.step("recording on", GimbalCommand::Video(Video::Start));
        self.expect("recording", 1500, &|_, s| s.state().recording);
        self.step("recording off", GimbalCommand::Video(Video::Stop));
        self.expect("not recording", 1500, &|_, s| !s.state().recording);

        let _ = writeln!(self.out, "> text message");
        if self
            .gimbal
            .send_text(b"HELLO FROM THE FLIGHT CONTROLLER")
            .is_err()
        {
            self.failures += 1;
        }
        self.expect("text received", 1500, &|_, s| {
            s.state().last_text.as_str() == "HELLO FROM THE FLIGHT CONTROLLER"
        });

        let stats = self.gimbal.stats().link;
        let sim = self.sim.stats();
        let _ = writeln!(
            self.out,
            "frames sent {} received {}; postbacks {}; superseded vehicle frames {}; gimbal saw {} vehicle frames, {} commands",
            stats.frames_sent, stats.frames_received, stats.postbacks, stats.superseded, sim.vehicle_frames, sim.commands
        );
        if sim.vehicle_frames == 0 {
            self.failures += 1;
            let _ = writeln!(self.out, "  FAIL no vehicle frames reached the gimbal");
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
