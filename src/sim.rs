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

/// A second, in ms (1000 is not zero): a time-lapse's period is its seconds times this.
const SECOND_MS: NonZeroU32 = match NonZeroU32::new(1000) {
    Some(n) => n,
    None => NonZeroU32::MIN,
};

/// The camera's field of view at `zoom_ratio`, (horizontal, vertical) degrees.
///
/// Zooming divides the tangent of the half angle: hfov = 2·atan(tan(30°)/zoom), so 60° at
/// 1×, 32.2° at 2×; the vertical half angle's tangent is the horizontal one's × 9/16. A
/// ratio below 1 (or NaN) is taken as 1.
pub fn field_of_view_deg(zoom_ratio: f32) -> (f32, f32) {
    let (tx, ty) = half_fov_tangents(zoom_ratio);
    (
        2.0 * libm::atanf(tx).to_degrees(),
        2.0 * libm::atanf(ty).to_degrees(),
    )
}

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
            postback_period_ms: 500,
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
            next_postback: now.add_millis(config.postback_period_ms.max(1)),
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
        let period = NonZeroU32::new(self.config.postback_period_ms).unwrap_or(NonZeroU32::MIN);
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
        if let Some(ms) = self.tracking_ends_within(dt) {
            // Slew toward the target until the instant it is lost, then hold there.
            self.slew(ms);
            self.lose_target();
        }
        // After a loss the targets are where the gimbal stopped: this moves nothing more.
        self.slew(dt);
        self.integrate_zoom(dt);
        self.integrate_focus(dt);
        self.run_photo_timers(dt);
        self.run_calibration(dt);
        self.booting_left_ms = self.booting_left_ms.saturating_sub(dt);
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
        // Counted down to 0 at most (`t` is no more than what is left).
        self.rate_left_ms = self.rate_left_ms.saturating_sub(t);
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

    /// While tracking with a timeout: the ms into a `dt` step at which the target is lost,
    /// if within it; otherwise counts the step off the time left.
    fn tracking_ends_within(&mut self, dt: u32) -> Option<u32> {
        if !self.state.tracking || self.config.tracking_lost_ms == 0 {
            return None;
        }
        match self.tracking_left_ms.checked_sub(dt) {
            Some(left) if left > 0 => {
                self.tracking_left_ms = left;
                None
            }
            // The step reaches the end.
            _ => Some(self.tracking_left_ms),
        }
    }

    fn integrate_focus(&mut self, dt: u32) {
        let delta = FOCUS_SPEED_PER_S * (dt as f32 / 1000.0);
        self.state.focus = match self.state.focusing {
            Some(Focus::Plus) => (self.state.focus + delta).min(1.0),
            Some(Focus::Minus) => (self.state.focus - delta).max(0.0),
            _ => return,
        };
    }

    fn run_calibration(&mut self, dt: u32) {
        if !self.state.calibrating {
            return;
        }
        self.calibration_left_ms = self.calibration_left_ms.saturating_sub(dt);
        if self.calibration_left_ms == 0 {
            self.state.calibrating = false;
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
            Some(Photo::Timer(_)) => match self.photo_left_ms.checked_sub(dt) {
                Some(left) if left > 0 => self.photo_left_ms = left,
                _ => {
                    self.state.photos = self.state.photos.saturating_add(1);
                    self.state.photo_mode = None;
                }
            },
            Some(Photo::TimeLapse(s)) => match self.photo_left_ms.checked_sub(dt) {
                Some(left) if left > 0 => self.photo_left_ms = left,
                _ => {
                    // 1 to 255 s, in ms: not zero, no overflow.
                    let period = NonZeroU32::from(s).saturating_mul(SECOND_MS);
                    // The step runs `over` ms past the photo due: one photo then, one more
                    // per whole period after it, and the next one is 1 to `period` ms away.
                    let over = dt.saturating_sub(self.photo_left_ms);
                    let taken = (over / period).saturating_add(1);
                    self.state.photos = self.state.photos.saturating_add(taken);
                    self.photo_left_ms = period.get().saturating_sub(over % period);
                }
            },
            _ => {}
        }
    }

    /// Recomputes the derived fields: reference and reported heading, and while tracking
    /// the angle targets and the box (losing a target now out of the image).
    fn refresh(&mut self) {
        self.refresh_heading();
        self.hold_north();
        self.follow_target();
    }

    /// [`LockHolds::North`]: in lock or full lock, north-referenced, neither tracking nor
    /// at a rate, the yaw target keeps the north heading held (taken from where the yaw is
    /// aimed when the hold begins).
    fn hold_north(&mut self) {
        let s = &self.state;
        let vehicle = match (self.config.lock_holds, s.north_referenced, s.vehicle) {
            (LockHolds::North, true, Some(v))
                if matches!(s.mode, ControlMode::Lock | ControlMode::FullLock)
                    && !s.tracking
                    && self.rate_left_ms == 0 =>
            {
                v.heading_deg()
            }
            _ => {
                self.held_north = None;
                return;
            }
        };
        let aimed = s.target_yaw_deg.unwrap_or(s.motor_yaw_deg);
        let held = *self
            .held_north
            .get_or_insert_with(|| wrap_360(vehicle + aimed));
        self.state.target_yaw_deg = Some(clamp_yaw(wrap_180(held - vehicle)));
    }

    fn refresh_heading(&mut self) {
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

    /// The heading tracked targets are kept relative to: the last vehicle heading
    /// received, stale or not (a fixed frame, so that a stale attitude moves nothing), 0
    /// before any.
    fn tracking_reference(&self) -> f32 {
        self.state.vehicle.map_or(0.0, |v| v.heading_deg())
    }

    /// While tracking: aims the angle targets at the target (a vehicle turn is made up for
    /// within the motor's range) and moves the box to where the target is in the image.
    fn follow_target(&mut self) {
        let Some((azimuth, elevation)) = self.track_target else {
            return;
        };
        let relative = azimuth - self.tracking_reference();
        let s = &mut self.state;
        s.target_yaw_deg = Some(clamp_yaw(wrap_180(relative)));
        s.target_pitch_deg = Some(clamp_pitch(elevation));
        let offset = (
            wrap_180(relative - s.motor_yaw_deg),
            elevation - s.pitch_deg,
        );
        match (image_point(offset, s.zoom_ratio), s.tracking_box) {
            (Some(centre), Some(b)) => {
                s.tracking_box = Some(TrackingBox::from_raw(centre, b.width16(), b.height16()));
            }
            _ => self.lose_target(),
        }
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
                self.end_tracking();
                self.stop_rate();
                self.held_north = None;
                self.state.mode = ControlMode::HeadingFollow;
                self.state.target_yaw_deg = Some(0.0);
            }
            GimbalCommand::Recenter => {
                self.end_tracking();
                self.stop_rate_keep_mode();
                self.held_north = None;
                self.state.target_pitch_deg = Some(0.0);
                self.state.target_yaw_deg = Some(0.0);
            }
            GimbalCommand::Rate(r) => self.start_rate(r),
            GimbalCommand::StartTracking(b) => self.start_tracking(b),
            GimbalCommand::StopTracking => self.end_tracking(),
            GimbalCommand::LookDown => {
                self.end_tracking();
                self.stop_rate_keep_mode();
                self.state.target_pitch_deg = Some(LOOK_DOWN_PITCH_DEG);
            }
            GimbalCommand::Heading(h) => {
                self.end_tracking();
                self.stop_rate();
                let reference = if self.state.north_referenced {
                    self.state.vehicle.map_or(0.0, |v| v.heading_deg())
                } else {
                    0.0
                };
                self.state.target_yaw_deg = Some(clamp_yaw(wrap_180(h.degrees() - reference)));
                self.state.mode = ControlMode::Lock;
                // Held as commanded, even where the motor stops at its limit.
                self.held_north = self.state.north_referenced.then(|| wrap_360(h.degrees()));
            }
            GimbalCommand::Pitch(p) => {
                self.end_tracking();
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
            GimbalCommand::Focus(f) => {
                s.focus_commands = s.focus_commands.wrapping_add(1);
                match f {
                    Focus::Plus | Focus::Minus => {
                        s.focusing = Some(f);
                        s.auto_focus = false;
                        s.focus_point = None;
                    }
                    Focus::Stop => s.focusing = None,
                    Focus::Auto => {
                        s.focusing = None;
                        s.auto_focus = true;
                        s.focus_point = None;
                    }
                }
            }
            GimbalCommand::PointingFocus(p) => {
                s.focus_commands = s.focus_commands.wrapping_add(1);
                s.focusing = None;
                s.auto_focus = true;
                s.focus_point = Some(p);
            }
            GimbalCommand::FastCalibration => {
                s.calibrations = s.calibrations.wrapping_add(1);
                s.calibrating = true;
                self.calibration_left_ms = CALIBRATION_MS;
            }
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
            DualLightCommand::StopTracking => self.end_tracking(),
            DualLightCommand::ElectronicZoom(z) => {
                s.electronic_zooming = match z {
                    ElectronicZoom::In | ElectronicZoom::Out => Some(z),
                    ElectronicZoom::Stop => None,
                };
            }
        }
    }

    fn start_rate(&mut self, rate: Rate) {
        if rate.is_zero() && self.state.tracking {
            // A joystick at rest is no manual input: the tracker keeps the gimbal.
            return;
        }
        self.end_tracking();
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

    /// Starts tracking the target at the box centre (replacing any target tracked): it
    /// becomes a fixed direction, the current pointing plus the box's angular offset.
    fn start_tracking(&mut self, b: TrackingBox) {
        self.stop_rate();
        let (yaw, pitch) = angular_offset(b.centre(), self.state.zoom_ratio);
        let azimuth = wrap_360(self.tracking_reference() + self.state.motor_yaw_deg + yaw);
        self.track_target = Some((azimuth, self.state.pitch_deg + pitch));
        self.tracking_left_ms = self.config.tracking_lost_ms;
        let s = &mut self.state;
        s.tracking = true;
        s.tracking_box = Some(b);
        s.mode = ControlMode::Lock;
    }

    /// Ends tracking, if on, holding the gimbal where it points now.
    fn end_tracking(&mut self) {
        let s = &mut self.state;
        if self.track_target.take().is_some() {
            self.held_north = None;
            s.target_pitch_deg = Some(s.pitch_deg);
            s.target_yaw_deg = Some(s.motor_yaw_deg);
        }
        s.tracking = false;
        s.tracking_box = None;
    }

    /// Ends tracking as [`Self::end_tracking`] and counts the target lost.
    fn lose_target(&mut self) {
        self.end_tracking();
        self.state.targets_lost = self.state.targets_lost.wrapping_add(1);
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

/// How far past the image edge (in half widths) a target may be before it counts as out of
/// the image: absorbs the rounding of the angle round trip for a box on the edge.
const EDGE_MARGIN: f32 = 1e-3;

/// Tangents of the camera's half angles (horizontal, vertical) at `zoom_ratio`.
fn half_fov_tangents(zoom_ratio: f32) -> (f32, f32) {
    let zoom = if zoom_ratio > ZOOM_MIN {
        zoom_ratio
    } else {
        ZOOM_MIN
    };
    let tx = libm::tanf((CAMERA_HFOV_DEG / 2.0).to_radians()) / zoom;
    (tx, tx / CAMERA_ASPECT)
}

/// The direction of an image point from the camera's axis, (yaw, pitch) degrees: positive
/// right and up. A pinhole camera, each axis on its own.
fn angular_offset(p: ImagePoint, zoom_ratio: f32) -> (f32, f32) {
    let (tx, ty) = half_fov_tangents(zoom_ratio);
    let nx = (f32::from(p.x()) - IMAGE_CENTRE) / IMAGE_CENTRE;
    let ny = (f32::from(p.y()) - IMAGE_CENTRE) / IMAGE_CENTRE;
    // Image y grows downwards, pitch upwards.
    (
        libm::atanf(nx * tx).to_degrees(),
        -libm::atanf(ny * ty).to_degrees(),
    )
}

/// Where a direction (yaw, pitch) degrees from the camera's axis is in the image, or
/// `None` when outside it: the inverse of [`angular_offset`], rounded and kept in
/// [0, 8191].
fn image_point((yaw, pitch): (f32, f32), zoom_ratio: f32) -> Option<ImagePoint> {
    // At or beyond 90° the tangent no longer says the side: out of any image.
    if !(libm::fabsf(yaw) < 90.0 && libm::fabsf(pitch) < 90.0) {
        return None;
    }
    let (tx, ty) = half_fov_tangents(zoom_ratio);
    let nx = libm::tanf(yaw.to_radians()) / tx;
    let ny = -libm::tanf(pitch.to_radians()) / ty;
    let limit = 1.0 + EDGE_MARGIN;
    if !(libm::fabsf(nx) <= limit && libm::fabsf(ny) <= limit) {
        return None;
    }
    let max = f32::from(ImagePoint::MAX);
    let coordinate = |n: f32| libm::roundf(IMAGE_CENTRE + n * IMAGE_CENTRE).clamp(0.0, max) as i32;
    ImagePoint::new(coordinate(nx), coordinate(ny)).ok()
}

fn clamp_pitch(deg: f32) -> f32 {
    deg.clamp(PITCH_TRAVEL_MIN_DEG, PITCH_TRAVEL_MAX_DEG)
}

fn clamp_yaw(deg: f32) -> f32 {
    deg.clamp(-MOTOR_YAW_LIMIT_DEG, MOTOR_YAW_LIMIT_DEG)
}

fn clamp_zoom(ratio: f32) -> f32 {
    ratio.clamp(ZOOM_MIN, OPTICAL_ZOOM_MAX)
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

    /// A vehicle turning from `from` to `to` degrees at 30°/s, an attitude frame every
    /// 100 ms, the simulator polled as it goes; then 3 s at `to` (time to slew 180°).
    fn turn<const TX: usize>(sim: &mut Simulator<TX>, from: f32, to: f32, start: u32) -> u32 {
        let mut ms = start;
        let mut heading = from;
        while heading != to {
            ms += 100;
            heading = approach(heading, to, 3.0);
            attitude(sim, heading, t(ms));
            sim.poll(t(ms));
        }
        for _ in 0..30 {
            ms += 100;
            attitude(sim, to, t(ms));
            sim.poll(t(ms));
        }
        ms
    }

    #[test]
    fn lock_holds_the_north_heading_or_the_motor_angle_as_the_vehicle_turns() {
        for (holds, motor, heading) in [
            // Heading 100 from north with the vehicle at 30: motor 70. The vehicle turns to
            // 120: holding north, the motor goes to -20; holding the motor, the camera
            // turns with the vehicle to 190.
            (LockHolds::North, -20.0, 100.0),
            (LockHolds::Motor, 70.0, 190.0),
        ] {
            let mut sim = Simulator::new(
                SimConfig {
                    lock_holds: holds,
                    ..SimConfig::default()
                },
                t(0),
            );
            attitude(&mut sim, 30.0, t(0));
            send(
                &mut sim,
                GimbalCommand::Heading(Heading::new(100.0).unwrap()),
                t(0),
            );
            let start = turn(&mut sim, 30.0, 30.0, 0);
            assert_eq!(sim.state().motor_yaw_deg, 70.0, "{holds:?}");
            let end = turn(&mut sim, 30.0, 120.0, start);
            let s = sim.state();
            assert_eq!(
                (s.motor_yaw_deg, s.heading_deg),
                (motor, heading),
                "{holds:?}"
            );
            assert_eq!(s.mode, ControlMode::Lock);
            // Heading follow follows in both: the motor stays where it was put.
            send(&mut sim, GimbalCommand::NoseFollowing, t(end));
            turn(&mut sim, 120.0, 60.0, end);
            assert_eq!(sim.state().motor_yaw_deg, 0.0, "{holds:?}");
        }
    }

    #[test]
    fn holding_north_stops_at_the_motor_limit_and_keeps_the_heading_commanded() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        attitude(&mut sim, 0.0, t(0));
        // North 175 with the vehicle at 0 needs the motor at 175: it stops at 170.
        send(
            &mut sim,
            GimbalCommand::Heading(Heading::new(175.0).unwrap()),
            t(0),
        );
        let end = turn(&mut sim, 0.0, 0.0, 0);
        assert_eq!(sim.state().motor_yaw_deg, 170.0);
        // The vehicle turns right to 20: 155 is within reach, and the heading held is the
        // one commanded, not the limit's 170.
        let end = turn(&mut sim, 0.0, 20.0, end);
        assert_eq!(sim.state().motor_yaw_deg, 155.0);
        turn(&mut sim, 20.0, 0.0, end);
        assert_eq!(sim.state().motor_yaw_deg, 170.0);
    }

    #[test]
    fn a_rate_or_a_recentre_sets_the_north_heading_held_from_where_it_leaves_the_yaw() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        attitude(&mut sim, 40.0, t(0));
        send(&mut sim, GimbalCommand::Recenter, t(0));
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-10.0).unwrap()),
            t(0),
        );
        // Lock, motor 0 with the vehicle at 40: north 40 is held.
        let end = turn(&mut sim, 40.0, 10.0, 0);
        assert_eq!(sim.state().motor_yaw_deg, 30.0);
        // A rate of 10°/s, refreshed every 100 ms for 1 s, honoured 200 ms past the last
        // (1.1 s in all), then it ends: where it stops (motor 41, north 51) is held.
        for ms in (end..end + 1000).step_by(100) {
            send(
                &mut sim,
                GimbalCommand::Rate(Rate::new(10.0, 0.0).unwrap()),
                t(ms),
            );
            attitude(&mut sim, 10.0, t(ms));
            sim.poll(t(ms));
        }
        let stopped = end + 1300;
        attitude(&mut sim, 10.0, t(stopped));
        sim.poll(t(stopped));
        assert_eq!(sim.state().mode, ControlMode::FullLock);
        // f32 steps of 10 × 0.1 s: within 1e-3° of the exact 41.
        let motor = sim.state().motor_yaw_deg;
        assert!((motor - 41.0).abs() < 1e-3, "{motor}");
        turn(&mut sim, 10.0, 0.0, stopped);
        let motor = sim.state().motor_yaw_deg;
        assert!((motor - 51.0).abs() < 1e-3, "{motor}");
    }

    #[test]
    fn a_reboot_is_silent_for_its_boot_time_ignores_frames_and_comes_back_at_rest() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        attitude(&mut sim, 30.0, t(0));
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-45.0).unwrap()),
            t(0),
        );
        send(&mut sim, GimbalCommand::Zoom(Zoom::In), t(0));
        assert!(sim.poll(t(1000)).is_some());
        assert_eq!(sim.state().pitch_deg, -45.0);
        sim.reboot(t(1100));
        assert!(sim.is_booting());
        assert_eq!(sim.pending_frames(), 0, "frames not yet sent are lost");
        let s = sim.state();
        assert_eq!(
            (s.pitch_deg, s.motor_yaw_deg, s.zoom_ratio),
            (0.0, 0.0, 1.0)
        );
        assert_eq!(s.mode, ControlMode::HeadingFollow);
        assert!(
            !s.north_referenced && s.vehicle.is_none(),
            "the vehicle forgotten"
        );
        // 3 s of start-up: no postbacks, every frame ignored and counted.
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-20.0).unwrap()),
            t(2000),
        );
        attitude(&mut sim, 30.0, t(2000));
        for ms in (1100..4100).step_by(100) {
            assert_eq!(sim.poll(t(ms)), None, "at {ms}");
        }
        assert_eq!(sim.stats().while_booting, 2);
        assert_eq!(sim.state().pitch_deg, 0.0);
        // Back on the same postback grid, and obeying again.
        assert_eq!(sim.poll(t(4100)), None);
        assert!(sim.poll(t(4500)).is_some());
        assert!(!sim.is_booting());
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-20.0).unwrap()),
            t(4500),
        );
        sim.poll(t(5000));
        assert_eq!(sim.state().pitch_deg, -20.0);
        assert_eq!(sim.stats().reboots, 1);
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
        let mut times = heapless::Vec::<u32, 32>::new();
        for ms in (0..=10_000).step_by(10) {
            if ms == 2000 {
                // On target by now: tracking the image centre keeps it there.
                send(
                    &mut sim,
                    GimbalCommand::StartTracking(TrackingBox::from_raw(
                        ImagePoint::new(4096, 4096).unwrap(),
                        8,
                        8,
                    )),
                    t(ms),
                );
            }
            if let Some(pb) = sim.poll(t(ms)) {
                times.push(ms).unwrap();
                assert_eq!(sim.pending_frames(), 4);
                let parsed = pop_postback(&mut sim);
                assert_eq!(parsed, pb);
                let s = sim.state();
                assert_eq!(pb.data_id, DataId::Attitude);
                assert_eq!(pb.gimbal_type, GimbalType::X30);
                assert_eq!(pb.tracking, ms >= 2000);
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
        assert!(sim.state().auto_focus);
        assert_eq!(sim.state().focus_point, ImagePoint::new(1, 2).ok());
        assert_eq!(sim.state().calibrations, 1);
        assert!(sim.state().calibrating);
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

    /// The yaw and pitch offsets, degrees, of image point (x, y) for a camera of 60°
    /// horizontal field of view at 1× and 16:9, at `zoom`: computed in f64 from the
    /// field of view, independently of the simulator's code.
    fn expected_offset(x: f64, y: f64, zoom: f64) -> (f64, f64) {
        let hfov = 2.0 * ((30f64).to_radians().tan() / zoom).atan();
        let vfov = 2.0 * ((hfov / 2.0).tan() * 9.0 / 16.0).atan();
        let nx = (x - 4096.0) / 4096.0;
        let ny = (y - 4096.0) / 4096.0;
        (
            (nx * (hfov / 2.0).tan()).atan().to_degrees(),
            -(ny * (vfov / 2.0).tan()).atan().to_degrees(),
        )
    }

    fn track<const TX: usize>(sim: &mut Simulator<TX>, x: i32, y: i32, at: Instant) {
        let b = TrackingBox::from_raw(ImagePoint::new(x, y).unwrap(), 4, 3);
        send(sim, GimbalCommand::StartTracking(b), at);
    }

    fn box_centre<const TX: usize>(sim: &Simulator<TX>) -> (u16, u16) {
        let c = sim.state().tracking_box.unwrap().centre();
        (c.x(), c.y())
    }

    #[test]
    fn tracking_slews_toward_the_box_and_brings_it_back_to_the_centre() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        // Right of and below the centre, at 1×.
        track(&mut sim, 6144, 6144, t(0));
        let (yaw, pitch) = expected_offset(6144.0, 6144.0, 1.0);
        assert!((yaw - 16.102).abs() < 1e-3, "{yaw}"); // atan(0.5·tan 30°)
        assert!((pitch + 9.223).abs() < 1e-3, "{pitch}"); // −atan(0.5·tan 30°·9/16)
        let s = sim.state();
        assert!(s.tracking);
        assert_eq!(s.mode, ControlMode::Lock);
        assert!((f64::from(s.target_yaw_deg.unwrap()) - yaw).abs() < 1e-3);
        assert!((f64::from(s.target_pitch_deg.unwrap()) - pitch).abs() < 1e-3);
        assert_eq!(box_centre(&sim), (6144, 6144));
        assert!(sim.postback().tracking);

        // After 100 ms at 60°/s: 6° on each axis, the box centre where the rest is.
        sim.poll(t(100));
        assert!(close(sim.state().heading_deg, 6.0));
        assert!(close(sim.state().pitch_deg, -6.0));
        let tan30 = (30f64).to_radians().tan();
        let x = 4096.0 + 4096.0 * (yaw - 6.0).to_radians().tan() / tan30;
        let y = 4096.0 - 4096.0 * (pitch + 6.0).to_radians().tan() / (tan30 * 9.0 / 16.0);
        let (bx, by) = box_centre(&sim);
        assert!((f64::from(bx) - x).abs() <= 1.0, "{bx} {x}");
        assert!((f64::from(by) - y).abs() <= 1.0, "{by} {y}");

        // The heading rises and the box comes back to the centre, both monotonically.
        let mut prev = (sim.state().heading_deg, bx, by);
        for ms in (110..=1000).step_by(10) {
            if let Some(pb) = sim.poll(t(ms)) {
                assert!(pb.tracking);
            }
            let (bx, by) = box_centre(&sim);
            let heading = sim.state().heading_deg;
            assert!(heading >= prev.0 && bx <= prev.1 && by <= prev.2);
            assert!(bx >= 4096 && by >= 4096);
            prev = (heading, bx, by);
        }
        let s = sim.state();
        assert!((f64::from(s.heading_deg) - yaw).abs() < 1e-3);
        assert!((f64::from(s.pitch_deg) - pitch).abs() < 1e-3);
        assert_eq!(box_centre(&sim), (4096, 4096));
        assert_eq!(s.tracking_box.unwrap().width16(), 4); // the size is kept
        let pb = sim.postback();
        assert!(pb.tracking);
        assert_eq!((pb.heading, pb.pitch), (1610, -922));

        // Left of and above the centre by as much: back to where it started.
        track(&mut sim, 2048, 2048, t(1000));
        let s = sim.state();
        assert!(close(s.target_yaw_deg.unwrap(), 0.0));
        assert!(close(s.target_pitch_deg.unwrap(), 0.0));
        sim.poll(t(2000));
        assert!(close(sim.state().motor_yaw_deg, 0.0));
        assert_eq!(box_centre(&sim), (4096, 4096));
    }

    #[test]
    fn zoom_narrows_the_field_of_view_so_the_same_box_is_a_smaller_angle() {
        let (h1, v1) = field_of_view_deg(1.0);
        assert!(close(h1, 60.0));
        let v1_expected = 2.0
            * ((30f64).to_radians().tan() * 9.0 / 16.0)
                .atan()
                .to_degrees();
        assert!((f64::from(v1) - v1_expected).abs() < 1e-3); // 35.98°
        let (h2, _) = field_of_view_deg(2.0);
        let h2_expected = 2.0 * ((30f64).to_radians().tan() / 2.0).atan().to_degrees();
        assert!((f64::from(h2) - h2_expected).abs() < 1e-3); // 32.20°
        assert_eq!(field_of_view_deg(0.5), field_of_view_deg(1.0));

        let target_yaw = |zoom: f32| {
            let mut sim = Simulator::new(SimConfig::default(), t(0));
            send(
                &mut sim,
                GimbalCommand::ZoomRatio(ZoomRatio::new(zoom).unwrap()),
                t(0),
            );
            track(&mut sim, 6144, 4096, t(0));
            f64::from(sim.state().target_yaw_deg.unwrap())
        };
        let at_1 = target_yaw(1.0);
        let at_2 = target_yaw(2.0);
        let at_10 = target_yaw(10.0);
        assert!((at_1 - expected_offset(6144.0, 4096.0, 1.0).0).abs() < 1e-3);
        assert!((at_2 - expected_offset(6144.0, 4096.0, 2.0).0).abs() < 1e-3);
        assert!((at_2 - 8.213).abs() < 1e-3, "{at_2}"); // atan(0.5·tan 30° / 2)
        assert!((at_10 - expected_offset(6144.0, 4096.0, 10.0).0).abs() < 1e-3);
        assert!(at_1 > at_2 && at_2 > at_10);

        // Zooming while tracking moves the box away from the centre; out of the image,
        // the target is lost and the gimbal holds.
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        track(&mut sim, 6144, 4096, t(0));
        send(&mut sim, GimbalCommand::Zoom(Zoom::Double), t(0));
        assert!(sim.state().tracking);
        assert_eq!(box_centre(&sim), (8191, 4096)); // offset 0.5 × 2: the right edge
        sim.poll(t(100));
        assert!(close(sim.state().motor_yaw_deg, 6.0));
        send(&mut sim, GimbalCommand::Zoom(Zoom::Double), t(100));
        let s = sim.state();
        assert!(!s.tracking);
        assert_eq!(s.tracking_box, None);
        assert_eq!(s.targets_lost, 1);
        assert!(close(s.target_yaw_deg.unwrap(), 6.0));
        assert!(!sim.postback().tracking);
        sim.poll(t(1000));
        assert!(close(sim.state().motor_yaw_deg, 6.0));
    }

    #[test]
    fn tracking_is_lost_after_tracking_lost_ms_exactly_across_the_tick_wrap() {
        let t0 = Instant::from_millis(u32::MAX - 3000);
        let mut sim = Simulator::new(SimConfig::default(), t0);
        track(&mut sim, 6144, 4096, t0);
        let yaw = expected_offset(6144.0, 4096.0, 1.0).0;
        sim.poll(t0.add_millis(9_999));
        assert!(sim.state().tracking);
        assert!(sim.postback().tracking);
        assert!(t0.add_millis(10_000).as_millis() < 10_000); // past the wrap
        let pb = sim.poll(t0.add_millis(10_000)).unwrap(); // a postback deadline too
        assert!(!pb.tracking);
        let s = sim.state();
        assert!(!s.tracking);
        assert_eq!(s.tracking_box, None);
        assert_eq!(s.targets_lost, 1);
        assert_eq!(s.mode, ControlMode::Lock);
        assert!((f64::from(s.target_yaw_deg.unwrap()) - yaw).abs() < 1e-3);

        // In one long step: the gimbal slews until the loss, then holds there.
        let config = SimConfig {
            slew_dps: 1.0,
            tracking_lost_ms: 5_000,
            ..SimConfig::default()
        };
        let mut sim = Simulator::new(config, t0);
        track(&mut sim, 6144, 4096, t0);
        sim.poll(t0.add_millis(60_000));
        assert!(!sim.state().tracking);
        assert!(close(sim.state().motor_yaw_deg, 5.0));
        assert_eq!(sim.state().target_yaw_deg, Some(sim.state().motor_yaw_deg));

        // A new start tracking restarts the time; 0 never loses the target.
        let mut sim = Simulator::new(SimConfig::default(), t0);
        track(&mut sim, 4096, 4096, t0);
        track(&mut sim, 4096, 4096, t0.add_millis(5_000));
        sim.poll(t0.add_millis(14_999));
        assert!(sim.state().tracking);
        sim.poll(t0.add_millis(15_000));
        assert!(!sim.state().tracking);
        let config = SimConfig {
            tracking_lost_ms: 0,
            ..SimConfig::default()
        };
        let mut sim = Simulator::new(config, t0);
        track(&mut sim, 6144, 4096, t0);
        sim.poll(t0.add_millis(3_600_000));
        assert!(sim.state().tracking);
        assert_eq!(box_centre(&sim), (4096, 4096));
        assert_eq!(sim.state().targets_lost, 0);
    }

    #[test]
    fn manual_pointing_ends_tracking_but_a_zero_rate_and_zoom_do_not() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        track(&mut sim, 6144, 4096, t(0));
        let target = sim.state().target_yaw_deg;
        send(&mut sim, GimbalCommand::Rate(Rate::ZERO), t(0));
        send(&mut sim, DualLightCommand::Rate(Rate::ZERO), t(0));
        send(&mut sim, GimbalCommand::Zoom(Zoom::In), t(0));
        send(&mut sim, GimbalCommand::Zoom(Zoom::Stop), t(0));
        send(&mut sim, GimbalCommand::Photo(Photo::Single), t(0));
        assert!(sim.state().tracking);
        assert_eq!(sim.state().mode, ControlMode::Lock);
        assert_eq!(sim.state().target_yaw_deg, target);

        // A non-zero rate: the operator takes over.
        sim.poll(t(100));
        send(
            &mut sim,
            GimbalCommand::Rate(Rate::new(0.0, 10.0).unwrap()),
            t(100),
        );
        let s = sim.state();
        assert!(!s.tracking && s.tracking_box.is_none());
        assert_eq!(s.mode, ControlMode::FullLock);
        assert_eq!((s.target_yaw_deg, s.target_pitch_deg), (None, None));
        assert_eq!(s.rate, (0.0, 10.0));

        // An angle command: it acts, the other axis holds where it was.
        track(&mut sim, 6144, 4096, t(300));
        assert_eq!(sim.state().rate, (0.0, 0.0));
        assert_eq!(sim.state().mode, ControlMode::Lock);
        sim.poll(t(400));
        let yaw_now = sim.state().motor_yaw_deg;
        send(
            &mut sim,
            GimbalCommand::Pitch(Pitch::new(-30.0).unwrap()),
            t(400),
        );
        assert!(!sim.state().tracking);
        assert_eq!(sim.state().target_yaw_deg, Some(yaw_now));
        assert_eq!(sim.state().target_pitch_deg, Some(-30.0));

        // Stop tracking when not tracking changes nothing (the pitch slew goes on).
        send(&mut sim, GimbalCommand::StopTracking, t(400));
        assert_eq!(sim.state().target_pitch_deg, Some(-30.0));
        sim.poll(t(1000));
        assert!(close(sim.state().pitch_deg, -30.0));

        // Recenter, look down, nose-following and stop tracking all end it, not as a loss.
        let enders: [Command; 5] = [
            GimbalCommand::Recenter.into(),
            GimbalCommand::LookDown.into(),
            GimbalCommand::NoseFollowing.into(),
            GimbalCommand::StopTracking.into(),
            DualLightCommand::StopTracking.into(),
        ];
        for c in enders {
            track(&mut sim, 100, 100, t(1000));
            send(&mut sim, c, t(1000));
            assert!(!sim.state().tracking, "{c:?}");
        }
        assert_eq!(sim.state().targets_lost, 0);
    }

    #[test]
    fn tracking_makes_up_for_a_vehicle_turn() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        attitude(&mut sim, 30.0, t(0));
        track(&mut sim, 4096, 4096, t(0));
        assert_eq!(sim.state().target_yaw_deg, Some(0.0));
        attitude(&mut sim, 40.0, t(0));
        assert!(close(sim.state().target_yaw_deg.unwrap(), -10.0));
        for ms in (100..=1000).step_by(100) {
            attitude(&mut sim, 40.0, t(ms));
        }
        sim.poll(t(1000));
        assert!(close(sim.state().motor_yaw_deg, -10.0));
        assert!(close(sim.state().heading_deg, 30.0));
        assert_eq!(box_centre(&sim), (4096, 4096));
        // A stale attitude moves nothing.
        sim.poll(t(5000));
        assert!(!sim.state().north_referenced);
        assert!(close(sim.state().motor_yaw_deg, -10.0));
        assert!(sim.state().tracking);
    }

    #[test]
    fn focus_moves_at_its_speed_and_stops_at_the_ends_and_on_stop() {
        let mut sim = Simulator::new(SimConfig::default(), t(0));
        assert_eq!(sim.state().focus, FOCUS_INITIAL);
        assert!(!sim.state().auto_focus);
        send(&mut sim, GimbalCommand::Focus(Focus::Auto), t(0));
        assert!(sim.state().auto_focus);
        send(&mut sim, GimbalCommand::Focus(Focus::Plus), t(0));
        assert!(!sim.state().auto_focus);
        assert_eq!(sim.state().focusing, Some(Focus::Plus));
        sim.poll(t(500));
        assert!(close(sim.state().focus, 0.75));
        sim.poll(t(5000));
        assert_eq!(sim.state().focus, 1.0); // the far end
        send(&mut sim, GimbalCommand::Focus(Focus::Minus), t(5000));
        sim.poll(t(5400));
        assert!(close(sim.state().focus, 0.8));
        send(&mut sim, GimbalCommand::Focus(Focus::Stop), t(5400));
        assert_eq!(sim.state().focusing, None);
        sim.poll(t(9000));
        assert!(close(sim.state().focus, 0.8));
        send(&mut sim, GimbalCommand::Focus(Focus::Minus), t(9000));
        sim.poll(t(20_000));
        assert_eq!(sim.state().focus, 0.0); // the near end

        // Auto focus and pointing focus stop the motion and keep the focus where it is.
        let p = ImagePoint::new(1000, 7000).unwrap();
        send(&mut sim, GimbalCommand::PointingFocus(p), t(20_000));
        let s = sim.state();
        assert!(s.auto_focus);
        assert_eq!((s.focusing, s.focus_point), (None, Some(p)));
        send(&mut sim, GimbalCommand::Focus(Focus::Plus), t(20_000));
        assert_eq!(sim.state().focus_point, None);
        send(&mut sim, GimbalCommand::Focus(Focus::Auto), t(20_200));
        let s = sim.state();
        assert!(s.auto_focus && s.focusing.is_none() && s.focus_point.is_none());
        assert!(close(s.focus, 0.1));
        assert_eq!(s.focus_commands, 8);
    }

    #[test]
    fn fast_calibration_lasts_two_seconds_across_the_tick_wrap() {
        let t0 = Instant::from_millis(u32::MAX - 500);
        let mut sim = Simulator::new(SimConfig::default(), t0);
        send(&mut sim, GimbalCommand::FastCalibration, t0);
        assert!(sim.state().calibrating);
        sim.poll(t0.add_millis(1000));
        send(
            &mut sim,
            GimbalCommand::FastCalibration,
            t0.add_millis(1000),
        );
        sim.poll(t0.add_millis(2999));
        assert!(sim.state().calibrating);
        sim.poll(t0.add_millis(3000));
        assert!(!sim.state().calibrating);
        assert_eq!(sim.state().calibrations, 2);
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
            lost in prop_oneof![Just(10_000u32), Just(0), any::<u32>()],
            north in any::<bool>(),
            boot in prop_oneof![Just(3000u32), any::<u32>()],
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
                tracking_lost_ms: lost,
                lock_holds: if north { LockHolds::North } else { LockHolds::Motor },
                boot_ms: boot,
            };
            let mut sim: Simulator<7> = Simulator::with_tx_capacity(config, t(start));
            let mut now = t(start);
            for (i, (id, data, dt)) in events.into_iter().enumerate() {
                now = now.add_millis(dt);
                let _ = sim.receive(id, &data, now);
                if i % 3 == 0 {
                    sim.set_silent(i % 9 == 0);
                }
                if i % 17 == 16 {
                    sim.reboot(now);
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
                prop_assert!((PITCH_TRAVEL_MIN_DEG..=PITCH_TRAVEL_MAX_DEG).contains(&s.pitch_deg));
                prop_assert!(s.motor_yaw_deg.abs() <= MOTOR_YAW_LIMIT_DEG);
                prop_assert!((0.0..360.0).contains(&s.heading_deg));
                prop_assert!((ZOOM_MIN..=OPTICAL_ZOOM_MAX).contains(&s.zoom_ratio));
                prop_assert!(s.rate.0.is_finite() && s.rate.1.is_finite());
                prop_assert!((0.0..=1.0).contains(&s.focus));
                prop_assert_eq!(s.tracking, s.tracking_box.is_some());
                prop_assert!(!(s.tracking && s.rate != (0.0, 0.0)));
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
