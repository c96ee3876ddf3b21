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
//! cancels any angle target and sets the mode to full lock (1, "controllable speed"),
//! except while tracking (see **Tracking**).
//!
//! **Angles.** Targets are kept in motor coordinates ([`SimState::target_yaw_deg`] is the
//! yaw motor angle) and stay set after they are reached; both axes slew toward them
//! independently at up to `slew_dps` and land on them exactly, never overshooting (a step
//! that ends within 0.001° of a target lands on it, so the rounding of many small steps
//! cannot leave it short). Any angle command stops rate motion and ends tracking.
//! - Heading (`0x08` type 1): while the attitude is fresh (an attitude frame arrived within
//!   `attitude_timeout_ms`) the heading is north-referenced and the motor target is
//!   heading − vehicle heading; otherwise it is relative to the nose. The target is
//!   normalised to [−180°, 180°) and clamped to ±170°. Mode: lock (3).
//!
//! **Lock while the vehicle turns.** The document does not say what a gimbal in lock (or
//! full lock) holds when the vehicle turns under it, so both are modelled
//! ([`SimConfig::lock_holds`]):
//! - [`LockHolds::North`] (the default): while north-referenced, in lock or full lock, and
//!   neither tracking nor moving at a rate, the gimbal holds its north heading: the motor
//!   target is recomputed from each attitude frame as that heading − the vehicle's. The
//!   heading held is the one commanded, or, after anything else set the yaw (re-centre, a
//!   rate, tracking, the attitude arriving), vehicle heading + motor target at that moment.
//!   The default because the document names the modes by what the yaw does: heading
//!   follow (2) follows the vehicle, so lock and full lock do not, and it reports the
//!   postback's heading "(geomagnetism)", from north.
//! - [`LockHolds::Motor`]: the motor target is computed once, when the command arrives; a
//!   vehicle that turns afterwards turns the camera with it.
//!
//! Nose-referenced (no fresh attitude) both hold the motor angle: the simulated gimbal
//! knows of the vehicle's turns only from the attitude frames.
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
//! move. Every zoom command but in/out ends continuous zooming. The field of view is
//! [`CAMERA_HFOV_DEG`] (60°) wide at 1×, narrower when zoomed (hfov = 2·atan(tan 30° /
//! zoom)), and 16:9 ([`field_of_view_deg`]). Photos: single +1, burst +N, a timer takes one
//! photo after its delay, a time-lapse one photo every delay until photo stop (which
//! cancels both). Video start/stop sets [`SimState::recording`]. Focus
//! ([`SimState::focus`], 0 near to 1 far, [`FOCUS_INITIAL`] at first): focus + moves it
//! toward far and focus − toward near at [`FOCUS_SPEED_PER_S`] (0.5/s) until focus stop,
//! stopping at the end of the range (still focusing, as zoom in/out); either ends auto
//! focus. Auto focus and pointing focus end continuous focusing and set
//! [`SimState::auto_focus`]; pointing focus also keeps its point in
//! [`SimState::focus_point`] (auto focus, focus + and − clear it). No image is simulated,
//! so auto focus does not move the focus. All focus commands are counted in
//! [`SimState::focus_commands`]. Fast calibration is counted and sets
//! [`SimState::calibrating`] for [`CALIBRATION_MS`] (2 s; a new one restarts it); the
//! gimbal keeps obeying meanwhile.
//!
//! **Dual-light camera.** Rate, start and stop tracking act as on the gimbal; the palette
//! is stored in [`SimState::palette`]; electronic zoom in/out/stop sets
//! [`SimState::electronic_zooming`] only (no ratio); pointing zoom is counted only (the
//! thermal zoom is not modelled).
//!
//! **Tracking.** Start tracking (either peripheral) tracks the target at the box centre:
//! image coordinates [0, 8191] on both axes, (0, 0) top-left, the centre (4096, 4096); x
//! right is yaw right, y down is pitch down. The target is a fixed direction in the world:
//! the pointing at that instant plus the box centre's angular offset, for a pinhole camera
//! with the field of view at the current zoom, each axis on its own (yaw offset
//! atan((x − 4096)/4096 · tan(hfov/2)), pitch offset −atan((y − 4096)/4096 · tan(vfov/2))).
//! Its azimuth is kept relative to the last vehicle heading received (stale or not; 0
//! before any), so a vehicle that turns is made up for. The angle targets aim at it and the
//! gimbal slews there at `slew_dps` as for any angle target, within the pitch and motor
//! limits. [`SimState::tracking_box`] keeps the box's size and its centre follows the
//! target in the image, recomputed from the remaining angular offset and the current zoom
//! (back to (4096, 4096) when the gimbal points at it). Start tracking stops any rate,
//! sets lock (3) and replaces any target tracked. Tracking ends, the gimbal then holding
//! its angles (targets = where it points; mode lock), on:
//! - stop tracking (either peripheral; when not tracking it changes nothing);
//! - a manual pointing command, as a real tracker hands the gimbal back to the operator:
//!   heading, pitch, recenter, look down, nose-following (which then act as above), and a
//!   non-zero rate (which then acts as above). A zero rate while tracking is a joystick at
//!   rest: it is counted and otherwise ignored. Zoom, pointing zoom (only a zoom here) and
//!   camera commands do not end it;
//! - loss of the target, counted in [`SimState::targets_lost`]: exactly
//!   [`SimConfig::tracking_lost_ms`] after start tracking (0: never), or as soon as the
//!   target is out of the image (by zooming in, or past a pitch or motor limit).
//!
//! The postback's tracking flag is [`SimState::tracking`].
//!
//! **Vehicle frames** are stored (the last attitude stays in [`SimState::vehicle`] when it
//! goes stale). **Text** frames go through a [`TextAssembler<64>`](TextAssembler); the last
//! complete text is kept in [`SimState::last_text`].
//!
//! **Errors.** A control frame [`Command::decode`] rejects, a bad vehicle frame or a bad
//! text frame changes nothing but its counter and is returned as a [`SimError`]. Frames on
//! any other ID are ignored and counted.
//!
//! **Postbacks** are due every `postback_period_ms` from [`Simulator::new`], on a fixed
//! grid of deadlines: `poll` emits one when a deadline has passed, and the next deadline
//! is the first one on the grid after `now`, so there is no drift and a long gap
//! gives one postback, not a burst. The first is due one period after `new`. The postback
//! carries the state at the poll (pitch, heading and motor ×100, rounded and clamped to
//! their documented ranges), Data_id attitude and the configured gimbal type. While
//! [silent](Simulator::set_silent), deadlines pass without postbacks. With
//! `emit_can_frames`, each postback is queued as four frames on [`ids::POSTBACK`]; when the
//! queue (`TX` frames) lacks room for all four the whole postback is dropped, counted in
//! [`SimStats::tx_overflows`] and `poll` returns `None` (a `TX` below 4 drops them all).

mod commands;
mod optics;
mod physics;
pub mod serial;
#[cfg(test)]
mod tests;
mod tracking;

pub use optics::field_of_view_deg;
use optics::*;
use physics::*;

use core::fmt;
use core::num::NonZeroU32;

use heapless::Deque;

use crate::link::text::TextAssembler;
use crate::time::Instant;
use crate::wire::control::{
    self, Command, DualLightCommand, ElectronicZoom, Focus, GimbalCommand, ImagePoint, Palette,
    Photo, Rate, TrackingBox, Video, Zoom,
};
use crate::wire::postback::{self, ControlMode, DataId, GimbalType, Postback};
use crate::wire::vehicle::{self, Altitude, Attitude, Gps, VehicleFrame};
use crate::wire::{ids, text, Frame};

/// The lowest pitch the gimbal's motor reaches, degrees: the postback's range
/// ([−11000, 6000] in 0.01°). A specify-angle command reaches only
/// [`Pitch::MIN_DEG`](control::Pitch::MIN_DEG); a rate hold goes further.
pub const PITCH_TRAVEL_MIN_DEG: f32 = -110.0;
/// The highest pitch the gimbal's motor reaches, degrees (as commanded:
/// [`Pitch::MAX_DEG`](control::Pitch::MAX_DEG)).
pub const PITCH_TRAVEL_MAX_DEG: f32 = control::Pitch::MAX_DEG;
/// The yaw motor's limit either side of the nose, degrees.
pub const MOTOR_YAW_LIMIT_DEG: f32 = 170.0;
/// The pitch "look down" points at, degrees.
pub const LOOK_DOWN_PITCH_DEG: f32 = -90.0;
/// The smallest optical zoom ratio.
pub const ZOOM_MIN: f32 = control::ZoomRatio::MIN;
/// The largest optical zoom ratio of the simulated camera, an X30's 30×. The command
/// carries up to [`ZoomRatio::MAX`](control::ZoomRatio::MAX) (35×, some models' reach);
/// the simulated camera stops at 30×, as the document's range for the command says.
pub const OPTICAL_ZOOM_MAX: f32 = 30.0;
/// Continuous zoom speed, ratio per second.
pub const ZOOM_SPEED_PER_S: f32 = 5.0;
/// The longest text kept, in bytes.
pub const TEXT_CAPACITY: usize = 64;
/// The camera's horizontal field of view at 1×, degrees (see [`field_of_view_deg`]).
pub const CAMERA_HFOV_DEG: f32 = 60.0;
/// The image's width over its height (16:9): sets the vertical field of view.
pub const CAMERA_ASPECT: f32 = 16.0 / 9.0;
/// The image centre on both axes, image units (the image spans [0, 8192) on each).
pub const IMAGE_CENTRE: f32 = 4096.0;
/// Focus position at power-on, in [0, 1] (0 near, 1 far).
pub const FOCUS_INITIAL: f32 = 0.5;
/// Continuous focus speed (focus + / −), focus range per second.
pub const FOCUS_SPEED_PER_S: f32 = 0.5;
/// How long a fast calibration lasts, ms.
pub const CALIBRATION_MS: u32 = 2000;

/// A second, in ms: a time-lapse's period is its seconds times this.
const SECOND_MS: NonZeroU32 = non_zero!(NonZeroU32, 1000);

/// [`SimConfig::postback_period_ms`]'s default: 500 ms, as the document's gimbal sends them.
const POSTBACK_PERIOD_MS: NonZeroU32 = non_zero!(NonZeroU32, 500);

/// What a gimbal in lock or full lock holds while the vehicle turns under it (see the
/// [module docs](self#model-and-decisions)).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LockHolds {
    /// Its north heading, from the pushed attitude (the default).
    #[default]
    North,
    /// Its motor angle: it turns with the vehicle.
    Motor,
}

/// How the simulated gimbal behaves.
#[derive(Clone, Copy, PartialEq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SimConfig {
    /// Largest angular speed toward angle targets, deg/s (60). Not positive or NaN: the
    /// gimbal does not slew; infinite: targets are reached at once.
    pub slew_dps: f32,
    /// Period of the postback, ms (500).
    pub postback_period_ms: NonZeroU32,
    /// The gimbal type reported in the postback (X30).
    pub gimbal_type: GimbalType,
    /// How long a rate command is honoured after it arrives, ms (200).
    pub rate_timeout_ms: u32,
    /// Headings are north-referenced while an attitude frame arrived within this, ms (1000).
    pub attitude_timeout_ms: u32,
    /// Queue each postback as four CAN frames for [`Simulator::pop_frame`] (true).
    pub emit_can_frames: bool,
    /// A tracked target is lost this long after start tracking, ms (10 000; 0: never).
    pub tracking_lost_ms: u32,
    /// What lock and full lock hold while the vehicle turns ([`LockHolds::North`]).
    pub lock_holds: LockHolds,
    /// How long [`Simulator::reboot`] keeps the gimbal starting up, ms (3000): no
    /// postbacks, frames ignored.
    pub boot_ms: u32,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            slew_dps: 60.0,
            postback_period_ms: POSTBACK_PERIOD_MS,
            gimbal_type: GimbalType::X30,
            rate_timeout_ms: 200,
            attitude_timeout_ms: 1000,
            emit_can_frames: true,
            tracking_lost_ms: 10_000,
            lock_holds: LockHolds::North,
            boot_ms: 3000,
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
    /// The tracked box, while tracking: the size given by start tracking, the centre where
    /// the target is in the image now (back at (4096, 4096) once the gimbal points at it).
    pub tracking_box: Option<TrackingBox>,
    /// Targets lost: by timeout ([`SimConfig::tracking_lost_ms`]) or out of the image.
    pub targets_lost: u32,
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
    /// Focus position in [0, 1]: 0 near, 1 far (starts at [`FOCUS_INITIAL`]).
    pub focus: f32,
    /// Continuous focus in progress: `Some(Focus::Plus)` (toward far) or
    /// `Some(Focus::Minus)` (toward near).
    pub focusing: Option<Focus>,
    /// Whether the camera auto-focuses (set by auto focus and pointing focus, cleared by
    /// focus + / −).
    pub auto_focus: bool,
    /// The point the last pointing focus asked for, while auto-focusing on it.
    pub focus_point: Option<ImagePoint>,
    /// Fast calibration commands received.
    pub calibrations: u32,
    /// Whether a fast calibration is running (for [`CALIBRATION_MS`] after the command).
    pub calibrating: bool,
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
            targets_lost: 0,
            mode: ControlMode::HeadingFollow,
            photos: 0,
            photo_mode: None,
            palette: None,
            focus_commands: 0,
            focus: FOCUS_INITIAL,
            focusing: None,
            auto_focus: false,
            focus_point: None,
            calibrations: 0,
            calibrating: false,
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
    /// Restarts ([`Simulator::reboot`]).
    pub reboots: u32,
    /// Frames received while starting up after a reboot, ignored.
    pub while_booting: u32,
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
    /// The tracked target while tracking: (azimuth, elevation) degrees, the azimuth
    /// relative to the last vehicle heading received (0 before any), in [0, 360).
    track_target: Option<(f32, f32)>,
    /// Time left before the target is lost, ms, while tracking with a timeout.
    tracking_left_ms: u32,
    /// Time left of the fast calibration, ms, while `state.calibrating`.
    calibration_left_ms: u32,
    /// The north heading held in lock ([`LockHolds::North`]), degrees in [0, 360).
    held_north: Option<f32>,
    /// Time left of a restart, ms: no postbacks, frames ignored.
    booting_left_ms: u32,
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
            next_postback: now.add_millis(config.postback_period_ms.get()),
            silent: false,
            rate_left_ms: 0,
            attitude_age_ms: None,
            photo_left_ms: 0,
            track_target: None,
            tracking_left_ms: 0,
            calibration_left_ms: 0,
            held_north: None,
            booting_left_ms: 0,
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
        if self.booting_left_ms > 0 {
            self.stats.while_booting = self.stats.while_booting.wrapping_add(1);
            return Ok(());
        }
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
        let period = self.config.postback_period_ms;
        if !now.is_at_or_after(self.next_postback) {
            // Normally at most one period ahead; more only if calls came ≥ 2^31 ms apart
            // and the deadline looks to be in the future: restart the grid.
            if self.next_postback.millis_since(now) > period.get() {
                self.next_postback = now.add_millis(period.get());
            }
            return None;
        }
        let late = now.millis_since(self.next_postback);
        // The next point of the grid: 1 to `period` ms ahead (exact).
        self.next_postback = now.add_millis(period.get().saturating_sub(late % period));
        if self.silent || self.booting_left_ms > 0 {
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

    /// Restarts the gimbal at `now`, as a power cycle does: for
    /// [`SimConfig::boot_ms`] it sends no postbacks and ignores every frame (counted in
    /// [`SimStats::while_booting`]); it comes back at rest (level, motor centred, 1×,
    /// heading follow) having forgotten the vehicle's data, with its frames not yet sent
    /// dropped. The postback grid and the counters run on.
    pub fn reboot(&mut self, now: Instant) {
        self.advance(now);
        // A gimbal as at power-on, but its counters, clock, postback schedule and silence
        // carried over, and starting up.
        let fresh = Self::with_tx_capacity(self.config, now);
        *self = Simulator {
            stats: SimStats {
                reboots: self.stats.reboots.wrapping_add(1),
                ..self.stats
            },
            last: self.last,
            next_postback: self.next_postback,
            silent: self.silent,
            booting_left_ms: self.config.boot_ms,
            ..fresh
        };
        self.refresh();
    }

    /// Whether the gimbal is starting up after [`Simulator::reboot`].
    pub fn is_booting(&self) -> bool {
        self.booting_left_ms > 0
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
}
