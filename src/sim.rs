//! A simulated gimbal: frames in, postbacks out, time passed in.
//!
//! [`Simulator`] behaves like the real unit as far as the protocol document (and
//! the protocol notes) describe it, and makes a documented choice wherever they are silent. It is
//! `no_std`, allocates nothing, never panics and does no I/O: the caller hands it every
//! received frame with [`Simulator::receive`], calls [`Simulator::poll`] regularly (every
//! 10 ms is plenty), and transmits what [`Simulator::pop_frame`] gives back. The same code
//! serves host tests over an in-memory bus, emulated firmware, and a TCP simulator (which
//! sends each postback returned by `poll` as its 27-byte
//! [stream form](Postback::to_stream_bytes) and sets
//! [`emit_can_frames`](SimConfig::emit_can_frames) to `false`).
//!
//! ```
//! use idu_gimbal::sim::{SimConfig, Simulator};
//! use idu_gimbal::wire::control::{Command, GimbalCommand, Pitch};
//! use idu_gimbal::wire::postback::Postback;
//! use idu_gimbal::Instant;
//!
//! let t0 = Instant::from_millis(0);
//! let mut sim = Simulator::new(SimConfig::default(), t0);
//!
//! // Ask for pitch -45°: the gimbal slews there at 60°/s.
//! let cmd = Command::from(GimbalCommand::Pitch(Pitch::new(-45.0)?)).to_frame();
//! assert!(sim.receive(cmd.id, &cmd.data, t0).is_ok());
//!
//! // Nothing is due before the first period has passed.
//! assert_eq!(sim.poll(t0.add_millis(499)), None);
//! let status = sim.poll(t0.add_millis(500)).expect("a postback every 500 ms");
//! assert_eq!(status.pitch, -3000); // -30.00° after half a second
//!
//! // The same postback, queued as four CAN frames.
//! let mut bytes = [0u8; 32];
//! for chunk in bytes.chunks_exact_mut(8) {
//!     let frame = sim.pop_frame().expect("four frames per postback");
//!     assert_eq!(frame.id, 0x030F_0001);
//!     chunk.copy_from_slice(&frame.data);
//! }
//! assert_eq!(Postback::parse(&bytes), Ok(status));
//!
//! sim.poll(t0.add_millis(800));
//! assert_eq!(sim.state().pitch_deg, -45.0); // reached exactly, no overshoot
//! # Ok::<(), idu_gimbal::wire::RangeError>(())
//! ```
//!
//! # Model and decisions
//!
//! **Time.** Every call takes the caller's wrapping [`Instant`]. `receive` and `poll` first
//! advance the model to `now` (integrating motion over `now.millis_since(last)`), then act,
//! so a command takes effect exactly at the instant it is received. Time is correct across
//! the `u32` wrap. A `now` earlier than the last one seen (by the wrapping difference, as
//! [`Instant::is_at_or_after`] decides) is treated as the last one: time never goes back.
//! As for every `Instant`, calls must come less than 2^31 ms (24.8 days) apart. A long gap
//! cannot make anything blow up: targets are reached exactly, rates run for at most
//! `rate_timeout_ms`, the zoom stays within its range.
//!
//! **Axes.** Pitch is limited to [−110°, 60°] (the postback's range) and the yaw motor,
//! relative to the nose, to ±170° (the motor's range): every angle is clamped there, and
//! the motor never wraps through the back. Positive pitch is up, positive yaw is right.
//!
//! **Rate** (`0x04`, either peripheral): the rates are integrated for `rate_timeout_ms`
//! after each rate command (the document: the gimbal moves only while the commands keep
//! coming), then stop; a zero-rate command stops at once. A rate command, zero or not,
//! cancels any angle target and sets the mode to full lock (1, "controllable speed").
//!
//! **Angles.** Targets are kept in motor coordinates ([`SimState::target_yaw_deg`] is the
//! yaw motor angle) and stay set after they are reached; both axes slew toward them
//! independently at up to `slew_dps` and land on them exactly, never overshooting (a step
//! that ends within 0.001° of a target lands on it, so the rounding of many small steps
//! cannot leave it short). Any angle command stops rate motion.
//! - Heading (`0x08` type 1): while the attitude is fresh (an attitude frame arrived within
//!   `attitude_timeout_ms`) the heading is north-referenced and the motor target is
//!   heading − vehicle heading, computed once when the command arrives (a vehicle that
//!   turns afterwards turns the camera with it); otherwise it is relative to the nose. The
//!   target is normalised to [−180°, 180°) and clamped to ±170°. Mode: lock (3).
//! - Pitch (type 2): clamped to [−110°, 60°]. Mode: lock (3).
//! - Recenter: targets pitch 0°, yaw 0°. Look down: targets pitch −90°, yaw unchanged.
//!   Neither changes the mode, except that full lock (rate control) becomes lock.
//! - Nose-following: mode heading follow (2), yaw target 0°, pitch unchanged.
//!
//! **Reported heading.** [`SimState::heading_deg`] (and the postback's heading) is
//! vehicle heading + motor yaw while the attitude is fresh, the motor yaw alone otherwise,
//! in [0°, 360°).
//!
//! **Camera.** The optical zoom ranges over [1, 30] (the X30's camera), whatever the
//! configured gimbal type: a zoom ratio command (type 3, up to 35 on the wire) is clamped
//! to it and applies at once; zoom in/out move at 5×/s until zoom stop; reset sets 1×;
//! "2× in" and "2× out" double and halve. Pointing zoom on the gimbal doubles the zoom
//! (the document: "amplifies it twice"); no image is simulated, so the gimbal does not
//! move. Every zoom command but in/out ends continuous zooming. Photos: single +1, burst
//! +N, a timer takes one photo after its delay, a time-lapse one photo every delay until
//! photo stop (which cancels both). Video start/stop sets [`SimState::recording`]. Focus,
//! pointing focus and fast calibration are accepted and counted.
//!
//! **Dual-light camera.** Rate, start and stop tracking act as on the gimbal; the palette
//! is stored; electronic zoom in/out/stop sets [`SimState::electronic_zooming`] only;
//! pointing zoom is counted only (the thermal zoom is not modelled).
//!
//! **Tracking.** Start tracking sets the flag and stores the box; stop tracking clears
//! both. Tracking does not move the gimbal.
//!
//! **Vehicle frames** are stored (the last attitude stays in [`SimState::vehicle`] when it
//! goes stale). **Text** frames go through a [`TextAssembler<64>`](TextAssembler); the last
//! complete text is kept in [`SimState::last_text`].
//!
//! **Errors.** A control frame [`Command::decode`] rejects, a bad vehicle frame or a bad
//! text frame changes nothing but its counter and is returned as a [`SimError`]. Frames on
//! any other ID are ignored and counted.
//!
//! **Postbacks** are due every `postback_period_ms` (at least 1) from [`Simulator::new`],
//! on a fixed grid of deadlines: `poll` emits one when a deadline has passed, and the next
//! deadline is the first one on the grid after `now`, so there is no drift and a long gap
//! gives one postback, not a burst. The first is due one period after `new`. The postback
//! carries the state at the poll (pitch, heading and motor ×100, rounded and clamped to
//! their documented ranges), Data_id attitude and the configured gimbal type. While
//! [silent](Simulator::set_silent), deadlines pass without postbacks. With
//! `emit_can_frames`, each postback is queued as four frames on [`ids::POSTBACK`]; when the
//! queue (`TX` frames) lacks room for all four the whole postback is dropped, counted in
//! [`SimStats::tx_overflows`] and `poll` returns `None` (a `TX` below 4 drops them all).

pub mod serial;

use core::fmt;

use heapless::Deque;

use crate::link::text::TextAssembler;
use crate::time::Instant;
use crate::wire::control::{
    self, Command, DualLightCommand, ElectronicZoom, GimbalCommand, Palette, Photo, Rate,
    TrackingBox, Video, Zoom,
};
use crate::wire::postback::{self, ControlMode, DataId, GimbalType, Postback};
use crate::wire::vehicle::{self, Altitude, Attitude, Gps, VehicleFrame};
use crate::wire::{ids, text, Frame};

/// The lowest pitch the gimbal reaches, degrees.
pub const PITCH_MIN_DEG: f32 = -110.0;
/// The highest pitch the gimbal reaches, degrees.
pub const PITCH_MAX_DEG: f32 = 60.0;
/// The yaw motor's limit either side of the nose, degrees.
pub const MOTOR_YAW_LIMIT_DEG: f32 = 170.0;
/// The pitch "look down" points at, degrees.
pub const LOOK_DOWN_PITCH_DEG: f32 = -90.0;
/// The smallest optical zoom ratio.
pub const ZOOM_MIN: f32 = 1.0;
/// The largest optical zoom ratio of the simulated camera.
pub const ZOOM_MAX: f32 = 30.0;
/// Continuous zoom speed, ratio per second.
pub const ZOOM_SPEED_PER_S: f32 = 5.0;
/// The longest text kept, in bytes.
pub const TEXT_CAPACITY: usize = 64;

/// How the simulated gimbal behaves.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SimConfig {
    /// Largest angular speed toward angle targets, deg/s (60). Not positive or NaN: the
    /// gimbal does not slew; infinite: targets are reached at once.
    pub slew_dps: f32,
    /// Period of the postback, ms (500; 0 is taken as 1).
    pub postback_period_ms: u32,
    /// The gimbal type reported in the postback (X30).
    pub gimbal_type: GimbalType,
    /// How long a rate command is honoured after it arrives, ms (200).
    pub rate_timeout_ms: u32,
    /// Headings are north-referenced while an attitude frame arrived within this, ms (1000).
    pub attitude_timeout_ms: u32,
    /// Queue each postback as four CAN frames for [`Simulator::pop_frame`] (true).
    pub emit_can_frames: bool,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            slew_dps: 60.0,
            postback_period_ms: 500,
            gimbal_type: GimbalType::X30,
            rate_timeout_ms: 200,
            attitude_timeout_ms: 1000,
            emit_can_frames: true,
        }
    }
}

/// What the simulated gimbal is doing now (as of the last call that took a time).
#[derive(Clone, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub struct SimState {
    /// Pitch, degrees in [−110, 60]; positive is up.
    pub pitch_deg: f32,
    /// Yaw motor angle relative to the nose, degrees in [−170, 170]; positive is right.
    pub motor_yaw_deg: f32,
    /// Reported heading, degrees in [0, 360): vehicle heading + motor yaw while the
    /// attitude is fresh, the motor yaw otherwise.
    pub heading_deg: f32,
    /// Pitch being slewed to or held, degrees.
    pub target_pitch_deg: Option<f32>,
    /// Yaw motor angle being slewed to or held, degrees relative to the nose.
    pub target_yaw_deg: Option<f32>,
    /// Active rates (yaw, pitch), deg/s; (0, 0) when no rate command is being honoured.
    pub rate: (f32, f32),
    /// Optical zoom ratio in [1, 30].
    pub zoom_ratio: f32,
    /// Continuous optical zoom in progress: `Some(Zoom::In)` or `Some(Zoom::Out)`.
    pub zooming: Option<Zoom>,
    /// Continuous electronic zoom of the dual-light camera in progress (`In` or `Out`).
    pub electronic_zooming: Option<ElectronicZoom>,
    /// Whether the camera records video.
    pub recording: bool,
    /// Whether the gimbal is tracking a target.
    pub tracking: bool,
    /// The box given by the last start tracking, while tracking.
    pub tracking_box: Option<TrackingBox>,
    /// Control mode.
    pub mode: ControlMode,
    /// Photos taken.
    pub photos: u32,
    /// A timer or time-lapse in progress (`Photo::Timer` or `Photo::TimeLapse`).
    pub photo_mode: Option<Photo>,
    /// Thermal palette last selected on the dual-light camera.
    pub palette: Option<Palette>,
    /// Focus and pointing focus commands received.
    pub focus_commands: u32,
    /// Fast calibration commands received.
    pub calibrations: u32,
    /// Pointing zoom commands received (either peripheral).
    pub pointing_zooms: u32,
    /// The last command accepted.
    pub last_command: Option<Command>,
    /// Last vehicle attitude received (kept when it goes stale).
    pub vehicle: Option<Attitude>,
    /// Last vehicle position received.
    pub gps: Option<Gps>,
    /// Last vehicle altitude received.
    pub altitude: Option<Altitude>,
    /// Last complete text received.
    pub last_text: heapless::String<TEXT_CAPACITY>,
    /// Whether headings are north-referenced now (attitude fresh).
    pub north_referenced: bool,
}

impl SimState {
    fn initial() -> Self {
        SimState {
            pitch_deg: 0.0,
            motor_yaw_deg: 0.0,
            heading_deg: 0.0,
            target_pitch_deg: None,
            target_yaw_deg: None,
            rate: (0.0, 0.0),
            zoom_ratio: ZOOM_MIN,
            zooming: None,
            electronic_zooming: None,
            recording: false,
            tracking: false,
            tracking_box: None,
            mode: ControlMode::HeadingFollow,
            photos: 0,
            photo_mode: None,
            palette: None,
            focus_commands: 0,
            calibrations: 0,
            pointing_zooms: 0,
            last_command: None,
            vehicle: None,
            gps: None,
            altitude: None,
            last_text: heapless::String::new(),
            north_referenced: false,
        }
    }
}

/// Counters of what the simulator received and sent (all wrap at `u32::MAX`).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SimStats {
    /// Control commands accepted.
    pub commands: u32,
    /// Control frames [`Command::decode`] rejected.
    pub rejected: u32,
    /// Vehicle frames (GPS, altitude, attitude) accepted.
    pub vehicle_frames: u32,
    /// Vehicle frames rejected.
    pub vehicle_errors: u32,
    /// Complete texts received.
    pub texts: u32,
    /// Text frames rejected.
    pub text_errors: u32,
    /// Frames on other IDs.
    pub ignored: u32,
    /// Postbacks emitted.
    pub postbacks: u32,
    /// Postbacks dropped because the TX queue lacked room for all four frames.
    pub tx_overflows: u32,
}

/// Why [`Simulator::receive`] rejected a frame (the frame changed nothing).
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SimError {
    /// A control frame that does not decode.
    Command(control::DecodeError),
    /// A vehicle frame that does not decode.
    Vehicle(vehicle::VehicleError),
    /// A text frame the assembler rejected.
    Text(text::TextError),
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::Command(e) => write!(f, "simulated gimbal rejected a command: {e}"),
            SimError::Vehicle(e) => write!(f, "simulated gimbal rejected a vehicle frame: {e}"),
            SimError::Text(e) => write!(f, "simulated gimbal rejected a text frame: {e}"),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for SimError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            SimError::Command(e) => Some(e),
            SimError::Vehicle(e) => Some(e),
            SimError::Text(e) => Some(e),
        }
    }
}

/// A simulated gimbal with a transmit queue of `TX` CAN frames (see the
/// [module docs](self)).
#[derive(Clone, Debug)]
pub struct Simulator<const TX: usize = 16> {
    config: SimConfig,
    state: SimState,
    stats: SimStats,
    /// The time the model has been advanced to.
    last: Instant,
    /// The next postback deadline.
    next_postback: Instant,
    silent: bool,
    /// How much longer the current rate is honoured, ms.
    rate_left_ms: u32,
    /// Time since the last attitude frame, ms (saturating).
    attitude_age_ms: Option<u32>,
    /// Time to the next timer or time-lapse photo, ms, while `state.photo_mode` is set.
    photo_left_ms: u32,
    text: TextAssembler<TEXT_CAPACITY>,
    tx: Deque<Frame, TX>,
}

impl Simulator {
    /// A gimbal at rest (level, motor centred, 1×, heading follow) with a queue of 16
    /// frames; the first postback is due one period after `now`.
    pub fn new(config: SimConfig, now: Instant) -> Self {
        Self::with_tx_capacity(config, now)
    }
}

impl<const TX: usize> Simulator<TX> {
    /// As [`Simulator::new`], with a queue of `TX` frames: `Simulator::<8>::with_tx_capacity(..)`.
    pub fn with_tx_capacity(config: SimConfig, now: Instant) -> Self {
        let mut sim = Simulator {
            config,
            state: SimState::initial(),
            stats: SimStats::default(),
            last: now,
            next_postback: now.add_millis(config.postback_period_ms.max(1)),
            silent: false,
            rate_left_ms: 0,
            attitude_age_ms: None,
            photo_left_ms: 0,
            text: TextAssembler::new(),
            tx: Deque::new(),
        };
        sim.refresh();
        sim
    }

    /// The configuration.
    pub fn config(&self) -> &SimConfig {
        &self.config
    }

    /// Takes one received frame: control, vehicle and text frames act on the model,
    /// frames on other IDs are counted as ignored. The model is advanced to `now` first.
    pub fn receive(&mut self, id: u32, data: &[u8], now: Instant) -> Result<(), SimError> {
        self.advance(now);
        let result = match id {
            ids::CONTROL => match Command::decode(data) {
                Ok(command) => {
                    self.stats.commands = self.stats.commands.wrapping_add(1);
                    self.apply(command);
                    Ok(())
                }
                Err(e) => {
                    self.stats.rejected = self.stats.rejected.wrapping_add(1);
                    Err(SimError::Command(e))
                }
            },
            ids::GPS | ids::ALTITUDE | ids::ATTITUDE => match VehicleFrame::decode(id, data) {
                Ok(frame) => {
                    self.stats.vehicle_frames = self.stats.vehicle_frames.wrapping_add(1);
                    match frame {
                        VehicleFrame::Gps(g) => self.state.gps = Some(g),
                        VehicleFrame::Altitude(a) => self.state.altitude = Some(a),
                        VehicleFrame::Attitude(a) => {
                            self.state.vehicle = Some(a);
                            self.attitude_age_ms = Some(0);
                        }
                    }
                    Ok(())
                }
                Err(e) => {
                    self.stats.vehicle_errors = self.stats.vehicle_errors.wrapping_add(1);
                    Err(SimError::Vehicle(e))
                }
            },
            ids::TEXT | ids::TEXT_END => match self.text.feed(id, data) {
                Ok(Some(t)) => {
                    self.state.last_text = heapless::String::try_from(t).unwrap_or_default();
                    self.stats.texts = self.stats.texts.wrapping_add(1);
                    Ok(())
                }
                Ok(None) => Ok(()),
                Err(e) => {
                    self.stats.text_errors = self.stats.text_errors.wrapping_add(1);
                    Err(SimError::Text(e))
                }
            },
            _ => {
                self.stats.ignored = self.stats.ignored.wrapping_add(1);
                Ok(())
            }
        };
        self.refresh();
        result
    }

    /// Advances the model to `now` and returns the postback emitted at this call, if one
    /// was due (queuing its four frames when [`SimConfig::emit_can_frames`] is set).
    ///
    /// Returns `None` when none was due, while silent, and when the queue lacked room for
    /// the frames (the postback is then dropped and counted in [`SimStats::tx_overflows`]).
    pub fn poll(&mut self, now: Instant) -> Option<Postback> {
        self.advance(now);
        let now = self.last;
        let period = self.config.postback_period_ms.max(1);
        if !now.is_at_or_after(self.next_postback) {
            // Normally at most one period ahead; more only if calls came ≥ 2^31 ms apart
            // and the deadline looks to be in the future: restart the grid.
            if self.next_postback.millis_since(now) > period {
                self.next_postback = now.add_millis(period);
            }
            return None;
        }
        let late = now.millis_since(self.next_postback);
        self.next_postback = now.add_millis(period - late % period);
        if self.silent {
            return None;
        }
        let status = self.postback();
        if self.config.emit_can_frames {
            if self.tx.capacity().saturating_sub(self.tx.len()) < postback::FRAMES {
                self.stats.tx_overflows = self.stats.tx_overflows.wrapping_add(1);
                return None;
            }
            for data in status.to_can_frames() {
                // Room for all four was checked above.
                let _ = self.tx.push_back(Frame::new(ids::POSTBACK, data));
            }
        }
        self.stats.postbacks = self.stats.postbacks.wrapping_add(1);
        Some(status)
    }

    /// The next CAN frame to transmit (postback frames on [`ids::POSTBACK`], in order).
    pub fn pop_frame(&mut self) -> Option<Frame> {
        self.tx.pop_front()
    }

    /// Frames waiting in the TX queue.
    pub fn pending_frames(&self) -> usize {
        self.tx.len()
    }

    /// The model's state as of the last call that took a time.
    pub fn state(&self) -> &SimState {
        &self.state
    }

    /// The counters so far.
    pub fn stats(&self) -> SimStats {
        self.stats
    }

    /// Stops (`true`) or resumes (`false`) postbacks, e.g. to test link loss. While silent
    /// the deadlines pass unsent; after resuming, the next one on the grid is sent.
    pub fn set_silent(&mut self, silent: bool) {
        self.silent = silent;
    }

    /// Whether postbacks are stopped.
    pub fn is_silent(&self) -> bool {
        self.silent
    }

    /// The current state as a postback (without advancing time or sending anything).
    pub fn postback(&self) -> Postback {
        let s = &self.state;
        let heading = centi(s.heading_deg, 0.0, 36_000.0) as u16;
        Postback {
            data_id: DataId::Attitude,
            gimbal_type: self.config.gimbal_type,
            tracking: s.tracking,
            mode: s.mode,
            pitch: centi(s.pitch_deg, -11_000.0, 6_000.0) as i16,
            // 360.00° after rounding is 0.00°: the field is in [0, 36000).
            heading: if heading >= 36_000 { 0 } else { heading },
            motor_heading: centi(s.motor_yaw_deg, -17_000.0, 17_000.0) as i16,
        }
    }

    /// Moves the model from `self.last` to `now` (never backwards).
    fn advance(&mut self, now: Instant) {
        if !now.is_at_or_after(self.last) {
            return;
        }
        let dt = now.millis_since(self.last);
        self.last = now;
        if dt == 0 {
            return;
        }
        self.integrate_rate(dt);
        self.slew(dt);
        self.integrate_zoom(dt);
        self.run_photo_timers(dt);
        self.attitude_age_ms = self.attitude_age_ms.map(|a| a.saturating_add(dt));
        self.refresh();
    }

    fn integrate_rate(&mut self, dt: u32) {
        if self.rate_left_ms == 0 {
            return;
        }
        let t = dt.min(self.rate_left_ms);
        let seconds = t as f32 / 1000.0;
        let (yaw, pitch) = self.state.rate;
        self.state.motor_yaw_deg = clamp_yaw(self.state.motor_yaw_deg + yaw * seconds);
        self.state.pitch_deg = clamp_pitch(self.state.pitch_deg + pitch * seconds);
        self.rate_left_ms -= t;
        if self.rate_left_ms == 0 {
            self.state.rate = (0.0, 0.0);
        }
    }

    fn slew(&mut self, dt: u32) {
        // NaN and non-positive speeds do not slew; +inf reaches the target at once.
        let dps = if self.config.slew_dps > 0.0 {
            self.config.slew_dps
        } else {
            0.0
        };
        let step = dps * (dt as f32 / 1000.0);
        if let Some(target) = self.state.target_pitch_deg {
            self.state.pitch_deg = approach(self.state.pitch_deg, target, step);
        }
        if let Some(target) = self.state.target_yaw_deg {
            self.state.motor_yaw_deg = approach(self.state.motor_yaw_deg, target, step);
        }
    }

    fn integrate_zoom(&mut self, dt: u32) {
        let delta = ZOOM_SPEED_PER_S * (dt as f32 / 1000.0);
        self.state.zoom_ratio = match self.state.zooming {
            Some(Zoom::In) => clamp_zoom(self.state.zoom_ratio + delta),
            Some(Zoom::Out) => clamp_zoom(self.state.zoom_ratio - delta),
            _ => return,
        };
    }

    fn run_photo_timers(&mut self, dt: u32) {
        match self.state.photo_mode {
            Some(Photo::Timer(_)) => {
                if dt >= self.photo_left_ms {
                    self.state.photos = self.state.photos.saturating_add(1);
                    self.state.photo_mode = None;
                } else {
                    self.photo_left_ms -= dt;
                }
            }
            Some(Photo::TimeLapse(s)) => {
                let period = u32::from(s.get()) * 1000;
                if dt >= self.photo_left_ms {
                    let over = dt - self.photo_left_ms;
                    let taken = 1 + over / period;
                    self.state.photos = self.state.photos.saturating_add(taken);
                    self.photo_left_ms = period - over % period;
                } else {
                    self.photo_left_ms -= dt;
                }
            }
            _ => {}
        }
    }

    /// Recomputes the derived fields: reference and reported heading.
    fn refresh(&mut self) {
        let fresh = self
            .attitude_age_ms
            .is_some_and(|age| age <= self.config.attitude_timeout_ms);
        let vehicle_heading = match (fresh, self.state.vehicle) {
            (true, Some(v)) => Some(v.heading_deg()),
            _ => None,
        };
        self.state.north_referenced = vehicle_heading.is_some();
        self.state.heading_deg =
            wrap_360(vehicle_heading.unwrap_or(0.0) + self.state.motor_yaw_deg);
    }

    fn apply(&mut self, command: Command) {
        self.state.last_command = Some(command);
        match command {
            Command::Gimbal(c) => self.apply_gimbal(c),
            Command::DualLight(c) => self.apply_dual_light(c),
        }
    }

    fn apply_gimbal(&mut self, command: GimbalCommand) {
        let s = &mut self.state;
        match command {
            GimbalCommand::PointingZoom(_) => {
                s.pointing_zooms = s.pointing_zooms.wrapping_add(1);
                let doubled = s.zoom_ratio * 2.0;
                self.set_zoom(doubled);
            }
            GimbalCommand::NoseFollowing => {
                self.stop_rate();
                self.state.mode = ControlMode::HeadingFollow;
                self.state.target_yaw_deg = Some(0.0);
            }
            GimbalCommand::Recenter => {
                self.stop_rate_keep_mode();
                self.state.target_pitch_deg = Some(0.0);
                self.state.target_yaw_deg = Some(0.0);
            }
            GimbalCommand::Rate(r) => self.start_rate(r),
            GimbalCommand::StartTracking(b) => self.start_tracking(b),
            GimbalCommand::StopTracking => self.stop_tracking(),
            GimbalCommand::LookDown => {
                self.stop_rate_keep_mode();
                self.state.target_pitch_deg = Some(LOOK_DOWN_PITCH_DEG);
            }
            GimbalCommand::Heading(h) => {
                self.stop_rate();
                let reference = if self.state.north_referenced {
                    self.state.vehicle.map_or(0.0, |v| v.heading_deg())
                } else {
                    0.0
                };
                self.state.target_yaw_deg = Some(clamp_yaw(wrap_180(h.degrees() - reference)));
                self.state.mode = ControlMode::Lock;
            }
            GimbalCommand::Pitch(p) => {
                self.stop_rate();
                self.state.target_pitch_deg = Some(clamp_pitch(p.degrees()));
                self.state.mode = ControlMode::Lock;
            }
            GimbalCommand::ZoomRatio(z) => self.set_zoom(z.ratio()),
            GimbalCommand::Photo(p) => self.photo(p),
            GimbalCommand::Video(v) => s.recording = v == Video::Start,
            GimbalCommand::Zoom(z) => match z {
                Zoom::In | Zoom::Out => s.zooming = Some(z),
                Zoom::Stop => s.zooming = None,
                Zoom::Reset => self.set_zoom(ZOOM_MIN),
                Zoom::Double => {
                    let z = s.zoom_ratio * 2.0;
                    self.set_zoom(z);
                }
                Zoom::Half => {
                    let z = s.zoom_ratio / 2.0;
                    self.set_zoom(z);
                }
            },
            GimbalCommand::Focus(_) | GimbalCommand::PointingFocus(_) => {
                s.focus_commands = s.focus_commands.wrapping_add(1);
            }
            GimbalCommand::FastCalibration => s.calibrations = s.calibrations.wrapping_add(1),
        }
    }

    fn apply_dual_light(&mut self, command: DualLightCommand) {
        let s = &mut self.state;
        match command {
            DualLightCommand::PointingZoom(_) => {
                s.pointing_zooms = s.pointing_zooms.wrapping_add(1);
            }
            DualLightCommand::Palette(p) => s.palette = Some(p),
            DualLightCommand::Rate(r) => self.start_rate(r),
            DualLightCommand::StartTracking(b) => self.start_tracking(b),
            DualLightCommand::StopTracking => self.stop_tracking(),
            DualLightCommand::ElectronicZoom(z) => {
                s.electronic_zooming = match z {
                    ElectronicZoom::In | ElectronicZoom::Out => Some(z),
                    ElectronicZoom::Stop => None,
                };
            }
        }
    }

    fn start_rate(&mut self, rate: Rate) {
        let s = &mut self.state;
        s.mode = ControlMode::FullLock;
        s.target_pitch_deg = None;
        s.target_yaw_deg = None;
        if rate.is_zero() {
            s.rate = (0.0, 0.0);
            self.rate_left_ms = 0;
        } else {
            s.rate = (rate.yaw_dps(), rate.pitch_dps());
            self.rate_left_ms = self.config.rate_timeout_ms;
        }
    }

    /// Ends rate motion (an angle command follows and sets the mode).
    fn stop_rate(&mut self) {
        self.state.rate = (0.0, 0.0);
        self.rate_left_ms = 0;
    }

    /// Ends rate motion for recenter and look down: full lock becomes lock, other modes
    /// stay.
    fn stop_rate_keep_mode(&mut self) {
        self.stop_rate();
        if self.state.mode == ControlMode::FullLock {
            self.state.mode = ControlMode::Lock;
        }
    }

    fn start_tracking(&mut self, b: TrackingBox) {
        self.state.tracking = true;
        self.state.tracking_box = Some(b);
    }

    fn stop_tracking(&mut self) {
        self.state.tracking = false;
        self.state.tracking_box = None;
    }

    /// Sets the optical zoom (clamped) and ends continuous zooming.
    fn set_zoom(&mut self, ratio: f32) {
        self.state.zoom_ratio = clamp_zoom(ratio);
        self.state.zooming = None;
    }

    fn photo(&mut self, p: Photo) {
        let s = &mut self.state;
        match p {
            Photo::Single => s.photos = s.photos.saturating_add(1),
            Photo::Burst(n) => s.photos = s.photos.saturating_add(n.get().into()),
            Photo::TimeLapse(secs) | Photo::Timer(secs) => {
                s.photo_mode = Some(p);
                self.photo_left_ms = u32::from(secs.get()) * 1000;
            }
            Photo::Stop => s.photo_mode = None,
        }
    }
}

/// Within this of a target after a step, the gimbal lands on it, degrees: below the
/// postback's resolution, and large enough to absorb the rounding of many small steps.
const SNAP_DEG: f32 = 1e-3;

/// Moves `current` toward `target` by at most `step` (plus [`SNAP_DEG`]), landing on it
/// exactly.
fn approach(current: f32, target: f32, step: f32) -> f32 {
    let distance = target - current;
    if libm::fabsf(distance) <= step + SNAP_DEG {
        target
    } else if distance > 0.0 {
        current + step
    } else {
        current - step
    }
}

fn clamp_pitch(deg: f32) -> f32 {
    deg.clamp(PITCH_MIN_DEG, PITCH_MAX_DEG)
}

fn clamp_yaw(deg: f32) -> f32 {
    deg.clamp(-MOTOR_YAW_LIMIT_DEG, MOTOR_YAW_LIMIT_DEG)
}

fn clamp_zoom(ratio: f32) -> f32 {
    ratio.clamp(ZOOM_MIN, ZOOM_MAX)
}

/// `deg` in [0, 360).
fn wrap_360(deg: f32) -> f32 {
    let r = libm::fmodf(deg, 360.0);
    let r = if r < 0.0 { r + 360.0 } else { r };
    // A tiny negative remainder plus 360 rounds to 360; NaN cannot occur but maps to 0.
    if (0.0..360.0).contains(&r) {
        r
    } else {
        0.0
    }
}

/// `deg` in [−180, 180).
fn wrap_180(deg: f32) -> f32 {
    wrap_360(deg + 180.0) - 180.0
}

/// `deg` ×100, rounded, clamped to [min, max] (wire units; the caller casts).
fn centi(deg: f32, min: f32, max: f32) -> f32 {
    libm::roundf(deg * 100.0).clamp(min, max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::control::{Focus, Heading, ImageOffset, ImagePoint, Pitch, ZoomRatio};
    use proptest::prelude::*;

    fn t(ms: u32) -> Instant {
        Instant::from_millis(ms)
    }

    fn send<const TX: usize>(sim: &mut Simulator<TX>, c: impl Into<Command>, at: Instant) {
        let f = c.into().to_frame();
        sim.receive(f.id, &f.data, at).unwrap();
    }

    fn attitude<const TX: usize>(sim: &mut Simulator<TX>, heading: f32, at: Instant) {
        let f = VehicleFrame::from(Attitude::new(0.0, 0.0, heading).unwrap()).to_frame();
        sim.receive(f.id, &f.data, at).unwrap();
    }

    fn close(a: f32, b: f32) -> bool {
        (a - b).abs() < 1e-3
    }

    /// Pops the four frames of one postback and parses them.
    fn pop_postback<const TX: usize>(sim: &mut Simulator<TX>) -> Postback {
        let mut bytes = [0u8; 32];
        for chunk in bytes.chunks_exact_mut(8) {
            let f = sim.pop_frame().unwrap();
            assert_eq!(f.id, ids::POSTBACK);
            chunk.copy_from_slice(&f.data);
        }
        Postback::parse(&bytes).unwrap()
    }

    #[test]
    fn angle_targets_are_reached_at_the_slew_rate_exactly() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()),
            t(0),
        );
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(90.0).unwrap()),
            t(0),
        );
        assert_eq!(sim.state().mode, ControlMode::Lock);
        assert_eq!(sim.state().target_pitch_deg, Some(-45.0));
        assert_eq!(sim.state().target_yaw_deg, Some(90.0));
        let mut prev = (0.0f32, 0.0f32);
        for ms in (10..=2000).step_by(10) {
            sim.poll(t(ms));
            let s = sim.state();
            // Never faster than 60°/s (0.6° per 10 ms), never past the target.
            assert!((s.pitch_deg - prev.0).abs() <= 0.6 + SNAP_DEG + 1e-4);
            assert!((s.motor_yaw_deg - prev.1).abs() <= 0.6 + SNAP_DEG + 1e-4);
            assert!(s.pitch_deg >= -45.0 && s.motor_yaw_deg <= 90.0);
            prev = (s.pitch_deg, s.motor_yaw_deg);
            match ms {
                500 => {
                    assert!(close(s.pitch_deg, -30.0), "{}", s.pitch_deg);
                    assert!(close(s.motor_yaw_deg, 30.0));
                }
                800 => assert_eq!(s.pitch_deg, -45.0),
                1000 => assert!(close(s.motor_yaw_deg, 60.0)),
                1500 => assert_eq!(s.motor_yaw_deg, 90.0),
                _ => {}
            }
        }
        assert_eq!(sim.state().pitch_deg, -45.0);
        assert_eq!(sim.state().heading_deg, 90.0);
    }

    #[test]
    fn one_long_gap_reaches_the_target_without_overshoot() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-100.0).unwrap()),
            t(0),
        );
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(200.0).unwrap()),
            t(0),
        );
        sim.poll(t(10 * 3600 * 1000)); // ten hours later
        assert_eq!(sim.state().pitch_deg, -100.0);
        assert_eq!(sim.state().motor_yaw_deg, -160.0); // 200° nose-relative is -160°
        assert_eq!(sim.state().heading_deg, 200.0);
    }

    #[test]
    fn rate_integrates_only_while_commands_keep_coming() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-20.0).unwrap()),
            t(0),
        );
        let rate = GimbalCommand::Rate(Rate::new(10.0, -5.0).unwrap());
        for ms in (0..=1000).step_by(50) {
            send(&mut sim, rate, t(1000 + ms));
            sim.poll(t(1000 + ms + 10));
        }
        // Rate cancelled the pitch target, which had been reached.
        assert_eq!(sim.state().target_pitch_deg, None);
        assert_eq!(sim.state().mode, ControlMode::FullLock);
        assert_eq!(sim.state().rate, (10.0, -5.0));
        // Last command at 2000: honoured until 2200.
        sim.poll(t(2150));
        assert!(close(sim.state().motor_yaw_deg, 11.5));
        assert_eq!(sim.state().rate, (10.0, -5.0));
        sim.poll(t(5000));
        assert!(
            close(sim.state().motor_yaw_deg, 12.0),
            "{}",
            sim.state().motor_yaw_deg
        );
        assert!(close(sim.state().pitch_deg, -26.0));
        assert_eq!(sim.state().rate, (0.0, 0.0));
        sim.poll(t(6000));
        assert!(close(sim.state().motor_yaw_deg, 12.0));

        // A single command followed by hours of silence moves for 200 ms only.
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::new(-50.0, 0.0).unwrap()),
            t(7000),
        );
        sim.poll(t(7000 + 5 * 3600 * 1000));
        assert!(close(sim.state().motor_yaw_deg, 2.0));

        // A zero rate stops at once.
        let at = t(30_000_000);
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::new(0.0, 20.0).unwrap()),
            at,
        );
        sim.poll(at.add_millis(100));
        assert!(close(sim.state().pitch_deg, -24.0));
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::ZERO),
            at.add_millis(100),
        );
        assert_eq!(sim.state().rate, (0.0, 0.0));
        sim.poll(at.add_millis(200));
        assert!(close(sim.state().pitch_deg, -24.0));
        assert_eq!(sim.state().mode, ControlMode::FullLock);
    }

    #[test]
    fn rates_stop_at_the_mechanical_limits_and_work_on_the_dual_light_peripheral() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        let rate = DualLightCommand::Rate(Rate::new(100.0, -100.0).unwrap());
        for ms in (0..3000).step_by(100) {
            send(&mut sim, rate, t(ms));
        }
        sim.poll(t(3000));
        assert_eq!(sim.state().motor_yaw_deg, 170.0);
        assert_eq!(sim.state().pitch_deg, -110.0);
        assert_eq!(sim.postback().motor_heading, 17_000);
        assert_eq!(sim.postback().pitch, -11_000);
    }

    #[test]
    fn heading_is_north_referenced_only_while_attitude_is_fresh() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        // No attitude: nose-relative.
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(90.0).unwrap()),
            t(0),
        );
        assert!(!sim.state().north_referenced);
        assert_eq!(sim.state().target_yaw_deg, Some(90.0));
        sim.poll(t(2000));
        assert_eq!(sim.state().heading_deg, 90.0);

        // Vehicle heading 30°: the reported heading is north-referenced.
        attitude(&mut sim, 30.0, t(2000));
        assert!(sim.state().north_referenced);
        assert_eq!(sim.state().heading_deg, 120.0);
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(90.0).unwrap()),
            t(2000),
        );
        assert_eq!(sim.state().target_yaw_deg, Some(60.0));
        for ms in (2100..=3000).step_by(100) {
            attitude(&mut sim, 30.0, t(ms));
            sim.poll(t(ms));
        }
        assert_eq!(sim.state().motor_yaw_deg, 60.0);
        assert_eq!(sim.state().heading_deg, 90.0);
        assert_eq!(sim.postback().heading, 9000);
        assert_eq!(sim.postback().motor_heading, 6000);

        // Attitude frames stop: after the timeout the heading is nose-relative again.
        sim.poll(t(4000));
        assert!(sim.state().north_referenced);
        sim.poll(t(4001));
        assert!(!sim.state().north_referenced);
        assert_eq!(sim.state().heading_deg, 60.0);
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(90.0).unwrap()),
            t(4001),
        );
        assert_eq!(sim.state().target_yaw_deg, Some(90.0));

        // North-referenced targets are normalised and kept within the motor's ±170°.
        attitude(&mut sim, -170.0, t(5000)); // vehicle heading 190°
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(10.0).unwrap()),
            t(5000),
        );
        assert_eq!(sim.state().target_yaw_deg, Some(-170.0)); // 180° → -180° → -170°
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(150.0).unwrap()),
            t(5000),
        );
        assert_eq!(sim.state().target_yaw_deg, Some(-40.0));
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(360.0).unwrap()),
            t(5000),
        );
        assert_eq!(sim.state().target_yaw_deg, Some(170.0));
        sim.poll(t(5100));
        assert!(sim.state().heading_deg >= 0.0 && sim.state().heading_deg < 360.0);
    }

    #[test]
    fn postbacks_come_every_500_ms_as_four_parsable_frames_matching_the_state() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-80.0).unwrap()),
            t(0),
        );
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(300.0).unwrap()),
            t(0),
        );
        send(
            &mut sim,
            GimbalCommand::StartTracking(TrackingBox::from_raw(
                ImagePoint::new(4096, 4096).unwrap(),
                8,
                8,
            )),
            t(0),
        );
        let mut times = heapless::Vec::<u32, 32>::new();
        for ms in (0..=10_000).step_by(10) {
            if let Some(pb) = sim.poll(t(ms)) {
                times.push(ms).unwrap();
                assert_eq!(sim.pending_frames(), 4);
                let parsed = pop_postback(&mut sim);
                assert_eq!(parsed, pb);
                let s = sim.state();
                assert_eq!(pb.data_id, DataId::Attitude);
                assert_eq!(pb.gimbal_type, GimbalType::X30);
                assert!(pb.tracking);
                assert_eq!(pb.mode, ControlMode::Lock);
                assert_eq!(f32::from(pb.pitch), libm::roundf(s.pitch_deg * 100.0));
                assert_eq!(f32::from(pb.heading), libm::roundf(s.heading_deg * 100.0));
                assert_eq!(
                    f32::from(pb.motor_heading),
                    libm::roundf(s.motor_yaw_deg * 100.0)
                );
            }
        }
        assert_eq!(times.len(), 20);
        assert!(times
            .iter()
            .enumerate()
            .all(|(i, &ms)| ms == 500 * (i as u32 + 1)));
        assert_eq!(sim.stats().postbacks, 20);
        assert_eq!(sim.pop_frame(), None);
        let last = sim.postback();
        assert_eq!(
            (last.pitch, last.heading, last.motor_heading),
            (-8000, 30_000, -6000)
        );
    }

    #[test]
    fn postbacks_keep_to_the_deadline_grid_without_drift_or_bursts() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        let mut times = heapless::Vec::<u32, 32>::new();
        for ms in (0..=5010).step_by(7) {
            if sim.poll(t(ms)).is_some() {
                times.push(ms).unwrap();
                pop_postback(&mut sim);
            }
        }
        // The first poll at or after each multiple of 500.
        let expected: heapless::Vec<u32, 32> =
            (1..=10u32).map(|k| (500 * k).div_ceil(7) * 7).collect();
        assert_eq!(times, expected);
        // A long gap gives one postback, then the grid continues.
        assert!(sim.poll(t(60_123)).is_some());
        assert_eq!(sim.pending_frames(), 4);
        assert!(sim.poll(t(60_124)).is_none());
        assert!(sim.poll(t(60_499)).is_none());
        assert!(sim.poll(t(60_500)).is_some());
        assert_eq!(sim.stats().postbacks, 12);
    }

    #[test]
    fn silent_mode_stops_postbacks_and_resumes_on_the_grid() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        sim.set_silent(true);
        assert!(sim.is_silent());
        for ms in (0..=2000).step_by(10) {
            assert_eq!(sim.poll(t(ms)), None);
        }
        assert_eq!(sim.pop_frame(), None);
        assert_eq!(sim.stats().postbacks, 0);
        sim.set_silent(false);
        assert_eq!(sim.poll(t(2010)), None);
        assert!(sim.poll(t(2500)).is_some());
        assert_eq!(sim.pending_frames(), 4);
    }

    #[test]
    fn stream_mode_queues_no_frames() {
        let config = SimConfig {
            emit_can_frames: false,
            gimbal_type: GimbalType::X30T,
            postback_period_ms: 100,
            ..SimConfig::default()
        };
        let mut sim = Simulator::new(config, t(0));
        let pb = sim.poll(t(100)).unwrap();
        assert_eq!(pb.gimbal_type, GimbalType::X30T);
        assert_eq!(Postback::parse(&pb.to_stream_bytes()), Ok(pb));
        assert_eq!(sim.pop_frame(), None);
        assert!(sim.poll(t(200)).is_some());
    }

    #[test]
    fn every_gimbal_command_changes_the_state_as_documented() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        let now = t(0);
        // Zoom ratio, reset, double, half, continuous.
        send(
            &mut sim,
            GimbalCommand::ZoomRatio(ZoomRatio::new(10.0).unwrap()),
            now,
        );
        assert_eq!(sim.state().zoom_ratio, 10.0);
        send(
            &mut sim,
            GimbalCommand::ZoomRatio(ZoomRatio::new(35.0).unwrap()),
            now,
        );
        assert_eq!(sim.state().zoom_ratio, 30.0);
        send(&mut sim, GimbalCommand::Zoom(Zoom::Reset), now);
        assert_eq!(sim.state().zoom_ratio, 1.0);
        send(&mut sim, GimbalCommand::Zoom(Zoom::Half), now);
        assert_eq!(sim.state().zoom_ratio, 1.0);
        send(&mut sim, GimbalCommand::Zoom(Zoom::Double), now);
        send(&mut sim, GimbalCommand::Zoom(Zoom::Double), now);
        assert_eq!(sim.state().zoom_ratio, 4.0);
        send(&mut sim, GimbalCommand::Zoom(Zoom::Half), now);
        assert_eq!(sim.state().zoom_ratio, 2.0);
        send(&mut sim, GimbalCommand::Zoom(Zoom::In), now);
        assert_eq!(sim.state().zooming, Some(Zoom::In));
        sim.poll(t(1000));
        assert!(close(sim.state().zoom_ratio, 7.0));
        send(&mut sim, GimbalCommand::Zoom(Zoom::Stop), t(1000));
        assert_eq!(sim.state().zooming, None);
        sim.poll(t(2000));
        assert!(close(sim.state().zoom_ratio, 7.0));
        send(&mut sim, GimbalCommand::Zoom(Zoom::In), t(2000));
        sim.poll(t(20_000));
        assert_eq!(sim.state().zoom_ratio, 30.0);
        send(&mut sim, GimbalCommand::Zoom(Zoom::Out), t(20_000));
        sim.poll(t(21_000));
        assert!(close(sim.state().zoom_ratio, 25.0));
        sim.poll(t(40_000));
        assert_eq!(sim.state().zoom_ratio, 1.0);
        send(
            &mut sim,
            GimbalCommand::PointingZoom(ImageOffset::new(100, -200).unwrap()),
            t(40_000),
        );
        assert_eq!(sim.state().zoom_ratio, 2.0);
        assert_eq!(sim.state().zooming, None);
        assert_eq!(sim.state().pointing_zooms, 1);
        let now = t(40_000);

        // Pointing: look down, recenter, nose-following.
        send(&mut sim, GimbalCommand::LookDown, now);
        assert_eq!(sim.state().target_pitch_deg, Some(-90.0));
        assert_eq!(sim.state().target_yaw_deg, None);
        assert_eq!(sim.state().mode, ControlMode::HeadingFollow);
        sim.poll(t(42_000));
        assert_eq!(sim.state().pitch_deg, -90.0);
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::new(20.0, 0.0).unwrap()),
            t(42_000),
        );
        sim.poll(t(42_200));
        assert!(close(sim.state().motor_yaw_deg, 4.0));
        send(&mut sim, GimbalCommand::Recenter, t(42_200));
        assert_eq!(sim.state().mode, ControlMode::Lock);
        assert_eq!(
            (sim.state().target_pitch_deg, sim.state().target_yaw_deg),
            (Some(0.0), Some(0.0))
        );
        sim.poll(t(44_000));
        assert_eq!(
            (sim.state().pitch_deg, sim.state().motor_yaw_deg),
            (0.0, 0.0)
        );
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(45.0).unwrap()),
            t(44_000),
        );
        sim.poll(t(46_000));
        send(&mut sim, GimbalCommand::NoseFollowing, t(46_000));
        assert_eq!(sim.state().mode, ControlMode::HeadingFollow);
        assert_eq!(sim.state().target_yaw_deg, Some(0.0));
        sim.poll(t(48_000));
        assert_eq!(sim.state().motor_yaw_deg, 0.0);
        let now = t(48_000);

        // Tracking.
        let b = TrackingBox::from_raw(ImagePoint::new(100, 200).unwrap(), 4, 5);
        send(&mut sim, GimbalCommand::StartTracking(b), now);
        assert!(sim.state().tracking);
        assert_eq!(sim.state().tracking_box, Some(b));
        assert!(sim.postback().tracking);
        send(&mut sim, GimbalCommand::StopTracking, now);
        assert!(!sim.state().tracking);
        assert_eq!(sim.state().tracking_box, None);

        // Video.
        send(&mut sim, GimbalCommand::Video(Video::Start), now);
        assert!(sim.state().recording);
        send(&mut sim, GimbalCommand::Video(Video::Stop), now);
        assert!(!sim.state().recording);

        // Photos: single, burst, timer, time-lapse, stop.
        send(&mut sim, GimbalCommand::Photo(Photo::Single), now);
        assert_eq!(sim.state().photos, 1);
        send(
            &mut sim,
            GimbalCommand::Photo(Photo::burst(5).unwrap()),
            now,
        );
        assert_eq!(sim.state().photos, 6);
        send(
            &mut sim,
            GimbalCommand::Photo(Photo::timer(3).unwrap()),
            now,
        );
        sim.poll(now.add_millis(2999));
        assert_eq!(sim.state().photos, 6);
        sim.poll(now.add_millis(3000));
        assert_eq!(sim.state().photos, 7);
        assert_eq!(sim.state().photo_mode, None);
        let now = now.add_millis(3000);
        send(
            &mut sim,
            GimbalCommand::Photo(Photo::time_lapse(2).unwrap()),
            now,
        );
        sim.poll(now.add_millis(1000));
        assert_eq!(sim.state().photos, 7);
        sim.poll(now.add_millis(2000));
        assert_eq!(sim.state().photos, 8);
        sim.poll(now.add_millis(9000)); // photos at 4, 6, 8 s
        assert_eq!(sim.state().photos, 11);
        send(
            &mut sim,
            GimbalCommand::Photo(Photo::Stop),
            now.add_millis(9000),
        );
        sim.poll(now.add_millis(60_000));
        assert_eq!(sim.state().photos, 11);
        let now = now.add_millis(60_000);

        // Focus and calibration are counted.
        send(&mut sim, GimbalCommand::Focus(Focus::Auto), now);
        send(
            &mut sim,
            GimbalCommand::PointingFocus(ImagePoint::new(1, 2).unwrap()),
            now,
        );
        send(&mut sim, GimbalCommand::FastCalibration, now);
        assert_eq!(sim.state().focus_commands, 2);
        assert_eq!(sim.state().calibrations, 1);
        assert_eq!(
            sim.state().last_command,
            Some(Command::Gimbal(GimbalCommand::FastCalibration))
        );
        assert_eq!(sim.stats().commands, 29);
        assert_eq!(sim.stats().rejected, 0);
    }

    #[test]
    fn every_dual_light_command_changes_the_state_as_documented() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        send(&mut sim, DualLightCommand::Palette(Palette::IceBlue), t(0));
        assert_eq!(sim.state().palette, Some(Palette::IceBlue));
        send(
            &mut sim,
            DualLightCommand::ElectronicZoom(ElectronicZoom::In),
            t(0),
        );
        assert_eq!(sim.state().electronic_zooming, Some(ElectronicZoom::In));
        send(
            &mut sim,
            DualLightCommand::ElectronicZoom(ElectronicZoom::Stop),
            t(0),
        );
        assert_eq!(sim.state().electronic_zooming, None);
        send(
            &mut sim,
            DualLightCommand::PointingZoom(ImageOffset::CENTRE),
            t(0),
        );
        assert_eq!(sim.state().pointing_zooms, 1);
        assert_eq!(sim.state().zoom_ratio, 1.0);
        let b = TrackingBox::from_raw(ImagePoint::new(8191, 0).unwrap(), 1, 1);
        send(&mut sim, DualLightCommand::StartTracking(b), t(0));
        assert!(sim.state().tracking);
        send(&mut sim, DualLightCommand::StopTracking, t(0));
        assert!(!sim.state().tracking);
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(10.0).unwrap()),
            t(0),
        );
        send(
            &mut sim,
            DualLightCommand::Rate(Rate::new(0.0, 10.0).unwrap()),
            t(0),
        );
        assert_eq!(sim.state().target_pitch_deg, None);
        assert_eq!(sim.state().mode, ControlMode::FullLock);
        sim.poll(t(1000));
        assert!(close(sim.state().pitch_deg, 2.0));
    }

    #[test]
    fn vehicle_frames_are_stored() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        let gps = Gps::new(47.3977, 8.5456).unwrap();
        let alt = Altitude::new(488.25).unwrap();
        for f in [VehicleFrame::from(gps), VehicleFrame::from(alt)] {
            let f = f.to_frame();
            sim.receive(f.id, &f.data, t(0)).unwrap();
        }
        attitude(&mut sim, 270.0, t(0));
        assert_eq!(sim.state().gps, Some(gps));
        assert_eq!(sim.state().altitude, Some(alt));
        assert_eq!(sim.state().vehicle.map(|a| a.heading_deg()), Some(-90.0));
        assert_eq!(sim.state().heading_deg, 270.0);
        assert_eq!(sim.stats().vehicle_frames, 3);
        assert_eq!(
            sim.receive(ids::ALTITUDE, &[0, 0, 0, 0, 1, 0, 0, 0], t(0)),
            Err(SimError::Vehicle(vehicle::VehicleError::NonZeroPadding {
                id: ids::ALTITUDE
            }))
        );
        assert_eq!(sim.stats().vehicle_errors, 1);
        assert_eq!(sim.state().altitude, Some(alt));
    }

    #[test]
    fn texts_are_received_and_bad_frames_counted() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        for f in text::chunks(b"WAYPOINT 7 REACHED").unwrap() {
            sim.receive(f.id, &f.data, t(0)).unwrap();
        }
        assert_eq!(sim.state().last_text.as_str(), "WAYPOINT 7 REACHED");
        assert_eq!(sim.stats().texts, 1);
        let bad = sim.receive(ids::TEXT_END, &[b'A', 0x80, 0, 0, 0, 0, 0, 0], t(0));
        assert!(matches!(
            bad,
            Err(SimError::Text(text::TextError::InvalidByte { .. }))
        ));
        assert_eq!(sim.stats().text_errors, 1);
        assert_eq!(sim.state().last_text.as_str(), "WAYPOINT 7 REACHED");
        for f in text::chunks(b"HI").unwrap() {
            sim.receive(f.id, &f.data, t(0)).unwrap();
        }
        assert_eq!(sim.state().last_text.as_str(), "HI");
        assert_eq!(sim.stats().texts, 2);
    }

    #[test]
    fn bad_control_frames_and_foreign_ids_change_nothing() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        let before = sim.state().clone();
        let err = sim.receive(ids::CONTROL, &[0x0F, 0x08, 0x02, 0x00, 0x80, 0, 0, 0], t(0));
        assert!(matches!(
            err,
            Err(SimError::Command(control::DecodeError::InvalidValue { .. }))
        ));
        let err = sim.receive(ids::CONTROL, &[0x0F, 0x07], t(0));
        assert_eq!(
            err,
            Err(SimError::Command(control::DecodeError::WrongLength {
                len: 2
            }))
        );
        assert_eq!(sim.receive(ids::POSTBACK, &[0; 8], t(0)), Ok(()));
        assert_eq!(sim.receive(0x123, &[], t(0)), Ok(()));
        assert_eq!(sim.state(), &before);
        let stats = sim.stats();
        assert_eq!((stats.rejected, stats.ignored, stats.commands), (2, 2, 0));
        #[cfg(feature = "std")]
        {
            let e: &dyn std::error::Error = &err.unwrap_err();
            assert!(e.source().is_some());
        }
        assert!(std::format!("{}", err.unwrap_err()).contains("8 bytes"));
    }

    #[test]
    fn time_never_goes_backwards() {
        let mut sim = Simulator::new(SimConfig::default(), t(1000));
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-60.0).unwrap()),
            t(1000),
        );
        sim.poll(t(1500));
        assert!(close(sim.state().pitch_deg, -30.0));
        sim.poll(t(1200)); // earlier: ignored
        assert!(close(sim.state().pitch_deg, -30.0));
        sim.poll(t(1600)); // 100 ms after 1500, not 400 ms after 1200
        assert!(close(sim.state().pitch_deg, -36.0));
    }

    #[test]
    fn slew_rate_and_postbacks_are_correct_across_the_u32_wrap() {
        let t0 = Instant::from_millis(u32::MAX - 300);
        let mut sim = Simulator::new(SimConfig::default(), t0);
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()),
            t0,
        );
        sim.poll(t0.add_millis(250));
        assert!(close(sim.state().pitch_deg, -15.0));
        let pb = sim.poll(t0.add_millis(500)).unwrap(); // tick 199, after the wrap
        assert!(t0.add_millis(500).as_millis() < 1000);
        assert_eq!(pb.pitch, -3000);
        sim.poll(t0.add_millis(800));
        assert_eq!(sim.state().pitch_deg, -45.0);
        assert!(sim.poll(t0.add_millis(999)).is_none());
        assert!(sim.poll(t0.add_millis(1000)).is_some());

        // A rate across the wrap.
        let t1 = Instant::from_millis(u32::MAX - 50);
        let mut sim = Simulator::new(SimConfig::default(), t1);
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::new(10.0, 0.0).unwrap()),
            t1,
        );
        sim.poll(t1.add_millis(100));
        assert!(close(sim.state().motor_yaw_deg, 1.0));
        sim.poll(t1.add_millis(1000));
        assert!(close(sim.state().motor_yaw_deg, 2.0));
    }

    #[test]
    fn a_full_tx_queue_drops_whole_postbacks_and_counts_them() {
        let mut sim: Simulator<6> = Simulator::with_tx_capacity(SimConfig::default(), t(0));
        assert!(sim.poll(t(500)).is_some());
        assert_eq!(sim.pending_frames(), 4);
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()),
            t(500),
        );
        assert_eq!(sim.poll(t(1000)), None); // two free slots: dropped whole
        assert_eq!(sim.stats().tx_overflows, 1);
        assert_eq!(sim.stats().postbacks, 1);
        assert_eq!(sim.pending_frames(), 4);
        assert_eq!(pop_postback(&mut sim).pitch, 0);
        assert_eq!(sim.pop_frame(), None);
        let pb = sim.poll(t(1500)).unwrap();
        assert_eq!(pop_postback(&mut sim), pb);
        assert_eq!(pb.pitch, -1000);

        // The default queue holds four postbacks; the fifth is dropped.
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        for k in 1..=5u32 {
            let pb = sim.poll(t(500 * k));
            assert_eq!(pb.is_some(), k <= 4);
        }
        assert_eq!(sim.pending_frames(), 16);
        assert_eq!(sim.stats().tx_overflows, 1);
        for _ in 0..4 {
            pop_postback(&mut sim);
        }
        assert_eq!(sim.pop_frame(), None);

        // A queue too small for one postback drops them all.
        let mut sim: Simulator<3> = Simulator::with_tx_capacity(SimConfig::default(), t(0));
        assert_eq!(sim.poll(t(500)), None);
        assert_eq!(sim.pop_frame(), None);
        assert_eq!(sim.stats().tx_overflows, 1);
    }

    /// Bytes that often decode as control commands, sometimes not.
    fn control_bytes() -> impl Strategy<Value = [u8; 8]> {
        let small = prop_oneof![3 => Just(0u8), 1 => 0u8..8, 1 => any::<u8>()];
        (
            prop_oneof![Just(0x0Fu8), Just(0x1F), any::<u8>()],
            prop_oneof![
                prop::sample::select(vec![
                    1u8, 2, 3, 4, 5, 6, 7, 8, 0x10, 0x11, 0x12, 0x13, 0x14, 0xF0
                ]),
                any::<u8>()
            ],
            0u8..8,
            [
                small.clone(),
                small.clone(),
                small.clone(),
                small.clone(),
                small,
            ],
        )
            .prop_map(|(p, c, d1, rest)| {
                let [a, b, c2, d, e] = rest;
                [p, c, d1, a, b, c2, d, e]
            })
    }

    fn event() -> impl Strategy<Value = (u32, Vec<u8>, u32)> {
        let id = prop_oneof![
            Just(ids::CONTROL),
            Just(ids::ATTITUDE),
            Just(ids::GPS),
            Just(ids::ALTITUDE),
            Just(ids::TEXT),
            Just(ids::TEXT_END),
            any::<u32>(),
        ];
        let data = prop_oneof![
            3 => control_bytes().prop_map(|b| b.to_vec()),
            1 => prop::collection::vec(any::<u8>(), 0..12),
        ];
        let dt = prop_oneof![4 => 0u32..300, 1 => any::<u32>()];
        (id, data, dt)
    }

    proptest! {
        #[test]
        fn arbitrary_input_never_panics_and_keeps_invariants(
            slew in prop_oneof![Just(60.0f32), any::<f32>()],
            period in prop_oneof![Just(500u32), 0u32..50, any::<u32>()],
            rate_timeout in prop_oneof![Just(200u32), any::<u32>()],
            attitude_timeout in any::<u32>(),
            emit in any::<bool>(),
            start in any::<u32>(),
            events in prop::collection::vec(event(), 0..60),
        ) {
            let config = SimConfig {
                slew_dps: slew,
                postback_period_ms: period,
                gimbal_type: GimbalType::Unknown(9),
                rate_timeout_ms: rate_timeout,
                attitude_timeout_ms: attitude_timeout,
                emit_can_frames: emit,
            };
            let mut sim: Simulator<7> = Simulator::with_tx_capacity(config, t(start));
            let mut now = t(start);
            for (i, (id, data, dt)) in events.into_iter().enumerate() {
                now = now.add_millis(dt);
                let _ = sim.receive(id, &data, now);
                if i % 3 == 0 {
                    sim.set_silent(i % 9 == 0);
                }
                if let Some(pb) = sim.poll(now) {
                    prop_assert_eq!(pb, sim.postback());
                }
                if i % 2 == 0 && sim.pending_frames() >= 4 {
                    let pb = pop_postback(&mut sim);
                    prop_assert_eq!(pb.gimbal_type, GimbalType::Unknown(9));
                }
                prop_assert_eq!(sim.pending_frames() % 4, 0);
                let s = sim.state();
                prop_assert!((PITCH_MIN_DEG..=PITCH_MAX_DEG).contains(&s.pitch_deg));
                prop_assert!(s.motor_yaw_deg.abs() <= MOTOR_YAW_LIMIT_DEG);
                prop_assert!((0.0..360.0).contains(&s.heading_deg));
                prop_assert!((ZOOM_MIN..=ZOOM_MAX).contains(&s.zoom_ratio));
                prop_assert!(s.rate.0.is_finite() && s.rate.1.is_finite());
                prop_assert!(sim.pending_frames() <= 7);
                let pb = sim.postback();
                prop_assert!(pb.heading < 36_000);
                prop_assert!((-11_000..=6_000).contains(&pb.pitch));
                prop_assert!((-17_000..=17_000).contains(&pb.motor_heading));
            }
            // Whatever is queued is whole postbacks.
            while sim.pending_frames() >= 4 {
                pop_postback(&mut sim);
            }
            prop_assert_eq!(sim.pending_frames(), 0);
        }
    }
}
