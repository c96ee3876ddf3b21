//! The bridge: MAVLink 2 bytes in and out, the gimbal driven through the application's
//! [`Link`], time passed in.
//!
//! Here the bridge's state and what it sends with; by concern beside it: `dispatch` (each
//! frame and command to what handles it), `autopilot` (the streams asked of the autopilot,
//! the vehicle it describes), `device` (the gimbal device's heartbeats, information and
//! attitude status); the setpoints are the `setpoint` module's, the camera
//! [`crate::camera`]'s.

use core::fmt;

use idu_gimbal::wire::control::{Command as GimbalCmd, GimbalCommand};
use idu_gimbal::Instant;
use mavio::dialects::common::enums::MavResult;

use crate::camera::{CameraComponent, CameraConfig};
use crate::capture::Vantage;
use crate::framing::{self, Check, FrameReader, Outbox, ReaderStats, ReceivedFrame};
use crate::status::Pose;
use crate::tx::{bump, Sender, Tx};
use idu_gimbal::link::{Link, Medium};

mod autopilot;
mod device;
mod dispatch;
mod period;
mod serial_input;

pub use crate::tx::OUTBOX_LEN;
use autopilot::{StreamState, Vehicle};
pub use device::yaw_limit_deg;
pub use period::{Period, PeriodOutOfRange};
pub use serial_input::SerialInput;

/// The autopilot's component id (`MAV_COMP_ID_AUTOPILOT1`).
pub const AUTOPILOT_COMPONENT: u8 = 1;
/// `MAV_COMP_ID_GIMBAL`.
pub const GIMBAL_COMPONENT: u8 = 154;

/// Outbox room a frame needs to be acted on: the most one can ask for, a command's ACK and
/// two messages (an image's report and the capture status), 595 bytes of the 1,024, every
/// frame signed. A frame arriving with less room waits in the bridge (see
/// [`Bridge::receive`]); answers longer than that (all the streams, kept images) are sent
/// as room comes.
pub const ANSWER_ROOM: usize = framing::HEADER_LEN
    + crate::codec::command_ack::LEN
    + framing::CHECKSUM_LEN
    + framing::SIGNATURE_LEN
    + 2 * framing::MAX_FRAME_LEN;

// A frame that waits for more room than the outbox has would wait for ever.
const _: () = assert!(ANSWER_ROOM <= OUTBOX_LEN);

/// [`BridgeConfig::heartbeat`]'s default: MAVLink's 1 Hz.
pub const HEARTBEAT: Period = match Period::from_millis(1_000) {
    Ok(p) => p,
    // Evaluated at compile time: a period out of range would not build.
    Err(_) => panic!("the heartbeat period is in range"),
};

/// [`BridgeConfig::attitude_status`]'s default: 10 Hz (the gimbal reports at 2 Hz, and
/// ArduPilot calls a mount unhealthy when its status is over a second old).
pub const ATTITUDE_STATUS: Period = match Period::from_millis(100) {
    Ok(p) => p,
    // Evaluated at compile time: a period out of range would not build.
    Err(_) => panic!("the attitude status period is in range"),
};

/// How long the autopilot followed must be silent (no heartbeat, ms) before another
/// autopilot's heartbeat is taken instead: 5 missed heartbeats at MAVLink's 1 Hz, longer
/// than QGroundControl's 3.5 s link loss, shorter than a flight controller's restart.
pub const AUTOPILOT_SILENCE_MS: u32 = 5_000;

/// What [`Bridge::receive_datagram`] took of a datagram.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Taken {
    /// Bytes taken: the whole datagram, or those before a frame that waits for room in the
    /// outbox; offer the rest again once the outbox has drained.
    pub bytes: usize,
    /// Frames taken that were messages the bridge handles with a good CRC: a sender worth
    /// answering.
    pub good: u32,
}

/// How the bridge presents itself and paces what it sends.
#[derive(Clone, PartialEq, Debug)]
pub struct BridgeConfig {
    /// System id; `None`: the autopilot's, from its HEARTBEAT (component 1, an autopilot
    /// type other than `MAV_AUTOPILOT_INVALID`, a system other than 0), and 1 until one
    /// arrives. The first autopilot heard is kept while it is heard: another one's
    /// heartbeats (a second autopilot, a multi-vehicle network, a forged heartbeat) are
    /// ignored and counted (`BridgeStats::other_autopilots`) until the one followed has
    /// been silent [`AUTOPILOT_SILENCE_MS`]. `Some(id)` pins it: only system `id`'s
    /// autopilot is followed.
    pub system_id: Option<u8>,
    /// The gimbal device's component id (default [`GIMBAL_COMPONENT`], 154).
    pub gimbal_component: u8,
    /// HEARTBEAT period (default [`HEARTBEAT`], 1 s).
    pub heartbeat: Period,
    /// GIMBAL_DEVICE_ATTITUDE_STATUS period (default [`ATTITUDE_STATUS`], 100 ms); `None`:
    /// not sent until asked for. `MAV_CMD_SET_MESSAGE_INTERVAL` changes it at run time, and
    /// its "default" is this.
    pub attitude_status: Option<Period>,
    /// The camera component; `None`: the bridge is a gimbal device only.
    pub camera: Option<CameraConfig>,
    /// MAVLink 2 signing (feature `signing`; see [`crate::signing`]): with a key, only
    /// frames signed with it and newer than their stream's last are acted on, and
    /// everything sent is signed. `None` (the default): nothing is signed or checked.
    #[cfg(feature = "signing")]
    pub signing: Option<crate::signing::SigningConfig>,
}

impl BridgeConfig {
    /// The attitude status period as the bridge keeps it at run time, ms: 0 for none.
    fn attitude_status_ms(&self) -> u32 {
        self.attitude_status.map_or(0, Period::millis)
    }
}

/// What is wrong with a [`BridgeConfig`]: [`Bridge::new`] refuses it, since the bridge
/// could not be addressed as configured.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BridgeConfigError {
    /// [`BridgeConfig::system_id`] is `Some(0)`, MAVLink's broadcast system, which no
    /// autopilot sends as and no frame may come from: valid 1 to 255.
    SystemIdZero,
    /// [`BridgeConfig::gimbal_component`] is 0 (`MAV_COMP_ID_ALL`, the broadcast
    /// component): valid 1 to 255.
    GimbalComponentZero,
    /// The camera's [`component`](CameraConfig::component) is 0 (`MAV_COMP_ID_ALL`):
    /// valid 1 to 255, other than the gimbal device's.
    CameraComponentZero,
    /// The camera's [`component`](CameraConfig::component) is the gimbal device's (this
    /// id): each needs its own, or one would not be told from the other.
    CameraComponentIsGimbals(u8),
}

impl fmt::Display for BridgeConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            BridgeConfigError::SystemIdZero => {
                f.write_str("system id 0 is the broadcast system: valid 1 to 255")
            }
            BridgeConfigError::GimbalComponentZero => f.write_str(
                "gimbal component 0 is the broadcast component (MAV_COMP_ID_ALL): valid 1 to 255",
            ),
            BridgeConfigError::CameraComponentZero => f.write_str(
                "camera component 0 is the broadcast component (MAV_COMP_ID_ALL): valid 1 to 255, other than the gimbal's",
            ),
            BridgeConfigError::CameraComponentIsGimbals(id) => write!(
                f,
                "camera component {id} is the gimbal device's: valid 1 to 255, other than {id}"
            ),
        }
    }
}

impl core::error::Error for BridgeConfigError {}

impl BridgeConfig {
    /// This configuration, checked: what [`Bridge::new`] takes. An error when the bridge
    /// could not be addressed as configured (a system or component id of 0, or the
    /// camera's component the gimbal device's).
    ///
    /// ```
    /// use idu_gimbal_mavlink::{Bridge, BridgeConfig, BridgeConfigError};
    ///
    /// let bridge = Bridge::new(BridgeConfig::default().check()?);
    /// assert_eq!(bridge.system_id(), 1);
    /// let broadcast = BridgeConfig { system_id: Some(0), ..BridgeConfig::default() };
    /// assert_eq!(broadcast.check().err(), Some(BridgeConfigError::SystemIdZero));
    /// # Ok::<(), BridgeConfigError>(())
    /// ```
    #[inline]
    pub fn check(self) -> Result<CheckedConfig, BridgeConfigError> {
        if self.system_id == Some(0) {
            return Err(BridgeConfigError::SystemIdZero);
        }
        let gimbal = self.gimbal_component;
        if gimbal == 0 {
            return Err(BridgeConfigError::GimbalComponentZero);
        }
        match self.camera.as_ref().map(|c| c.component) {
            Some(0) => Err(BridgeConfigError::CameraComponentZero),
            Some(camera) if camera == gimbal => {
                Err(BridgeConfigError::CameraComponentIsGimbals(gimbal))
            }
            _ => Ok(CheckedConfig(self)),
        }
    }
}

/// A [`BridgeConfig`] that [`BridgeConfig::check`] found usable: the bridge can be
/// addressed as configured.
#[derive(Clone, PartialEq, Debug)]
pub struct CheckedConfig(BridgeConfig);

impl CheckedConfig {
    /// The configuration.
    pub fn get(&self) -> &BridgeConfig {
        &self.0
    }
}

impl Default for BridgeConfig {
    fn default() -> Self {
        BridgeConfig {
            system_id: None,
            gimbal_component: GIMBAL_COMPONENT,
            heartbeat: HEARTBEAT,
            attitude_status: Some(ATTITUDE_STATUS),
            camera: None,
            #[cfg(feature = "signing")]
            signing: None,
        }
    }
}

/// Counters of the bridge, each wrapping at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BridgeStats {
    /// The frame reader's counters.
    pub reader: ReaderStats,
    /// Messages for another system or component, not acted on; and `GLOBAL_POSITION_INT`
    /// (broadcast) from any but the autopilot followed (another vehicle's, or before an
    /// autopilot's heartbeat is heard).
    pub not_for_us: u32,
    /// Commands answered (every COMMAND_LONG and COMMAND_INT for us gets exactly one ACK).
    pub acks: u32,
    /// Angle setpoints taken (as the aim the link holds; neutral and retract included). The
    /// link counts what it sends for them: `LinkStats::aim_recommands`,
    /// `LinkStats::aim_not_reached`.
    pub angle_setpoints: u32,
    /// Rate setpoints passed to the core's rate hold.
    pub rate_setpoints: u32,
    /// Setpoints not followed: out of the gimbal's range, NaN without rates, a roll the
    /// gimbal cannot do, or a yaw frame needing a vehicle heading (or, for a rate, a
    /// vehicle yaw rate) the bridge does not have.
    pub refused_setpoints: u32,
    /// Commands the gimbal's queue had no room for.
    pub queue_full: u32,
    /// Frames not sent: the outbox was full (or, a bug, `mavio` could not encode one).
    pub outbox_full: u32,
    /// Vehicle attitude and position updates passed to the core.
    pub vehicle_updates: u32,
    /// Vehicle updates for us not passed to the core: an `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE`
    /// whose quaternion is not finite or gives no finite attitude (one far from unit length
    /// overflows), a `GLOBAL_POSITION_INT` whose latitude is beyond ±90° or longitude
    /// beyond ±180° (its altitude is still passed on).
    pub refused_vehicle_updates: u32,
    /// Component-1 heartbeats not taken as the autopilot's: another autopilot's while the
    /// one followed is heard ([`AUTOPILOT_SILENCE_MS`]), another system's than the
    /// configured [`BridgeConfig::system_id`], system 0's, or `MAV_AUTOPILOT_INVALID`'s.
    pub other_autopilots: u32,
}

/// A MAVLink Gimbal Device (gimbal protocol v2) in front of an IDU gimbal; see the crate
/// docs.
// `repr(C)`, the frame reader first: the receive loop's fields stay at small offsets from
// the bridge's address, in reach of the M4's short load and store forms (LDRD and VLDR
// reach 1020 bytes); the order the compiler chose put them beyond, at about 3 instructions
// more a received byte.
#[repr(C)]
pub struct Bridge {
    reader: FrameReader,
    state: State,
}

/// Everything but the reader, so that the reader's callback can borrow it.
pub(crate) struct State {
    pub(crate) config: BridgeConfig,
    /// Every frame the bridge sends goes through it, as its system ID.
    pub(crate) out: Sender,
    /// The autopilot's (system, component), from its heartbeat, and when it was last heard
    /// (see [`AUTOPILOT_SILENCE_MS`]).
    autopilot: Option<(u8, u8)>,
    autopilot_heard: Option<Instant>,
    next_heartbeat: Option<Instant>,
    next_status: Option<Instant>,
    status_ms: u32,
    position_stream: StreamState,
    autopilot_state_stream: StreamState,
    setpoint_stream: StreamState,
    /// Whether the autopilot takes an ask for the setpoint stream (PX4; not ArduPilot, see
    /// `SETPOINT_STREAM`).
    setpoints_askable: bool,
    /// When to look at the streams again (`None`: at the next poll). The asks are due at
    /// whole seconds; looking every `STREAM_CHECK_MS` keeps the idle poll short.
    next_stream_check: Option<Instant>,
    pub(crate) vehicle: Vehicle,
    /// The rate hold last set has its yaw in the earth frame (for the status's `YAW_LOCK`).
    pub(crate) rate_earth: bool,
    /// When the latest postback arrived, and the vehicle's yaw then: the heading its motor
    /// angle is turned into the earth frame with (see [`State::postback_vehicle_yaw`]).
    postback_yaw: Option<(Instant, Option<f32>)>,
    /// The aim's troubles already said in a `STATUSTEXT` (at the yaw limit, not reached),
    /// so that each is said once when it begins.
    pub(crate) aim_told: device::AimTold,
    /// The last setpoint's neutral/retract flags, to act on a change only.
    pub(crate) last_flags: u16,
    /// The pose last commanded, for the status flags.
    pub(crate) pose: Pose,
    camera: Option<CameraComponent>,
    pub(crate) stats: BridgeStats,
}

impl Bridge {
    /// A bridge with the given configuration, checked ([`BridgeConfig::check`]); each call
    /// that acts on the gimbal takes the application's link.
    pub fn new(config: CheckedConfig) -> Self {
        let CheckedConfig(config) = config;
        let camera = config
            .camera
            .as_ref()
            .map(|c| CameraComponent::new(c, config.gimbal_component));
        let system_id = config.system_id.unwrap_or(1);
        let status_ms = config.attitude_status_ms();
        #[allow(unused_mut)]
        let mut out = Outbox::new();
        #[cfg(feature = "signing")]
        if let Some(signing) = config.signing.clone() {
            out.sign_with(signing);
        }
        Bridge {
            reader: FrameReader::new(),
            state: State {
                config,
                out: Sender::new(out, system_id),
                autopilot: None,
                autopilot_heard: None,
                next_heartbeat: None,
                next_status: None,
                status_ms,
                position_stream: StreamState::default(),
                autopilot_state_stream: StreamState::default(),
                setpoint_stream: StreamState::default(),
                setpoints_askable: false,
                next_stream_check: None,
                vehicle: Vehicle::default(),
                rate_earth: false,
                postback_yaw: None,
                aim_told: device::AimTold::default(),
                last_flags: 0,
                pose: Pose::Other,
                camera,
                stats: BridgeStats::default(),
            },
        }
    }

    /// Takes MAVLink bytes from a byte stream (a serial port), in any split. Returns how
    /// many it took: all of them, unless a frame waits for room in the outbox for what it
    /// asks ([`ANSWER_ROOM`]). Then the frame waits in the bridge, to be acted on at the next
    /// [`Bridge::poll`] or `receive` that finds room, and the bytes after it are not taken:
    /// send what [`Bridge::transmit_bytes`] holds, then offer them again. So a burst of
    /// requests is answered in full, each exactly once, never faster than the link drains.
    #[must_use = "bytes not taken must be offered again once the outbox has drained"]
    pub fn receive<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        link: &mut Link<Q, T, M>,
        bytes: &[u8],
        now: Instant,
    ) -> usize {
        let Bridge { reader, state } = self;
        reader.feed(bytes, |frame| state.take(link, frame, now))
    }

    /// Takes one UDP datagram: MAVLink on UDP carries whole frames, so a frame cut at the
    /// datagram's end is dropped (its bytes counted as skipped) rather than joined to the
    /// next datagram, which may come from another sender. Takes the datagram up to a frame
    /// that waits for room in the outbox ([`ANSWER_ROOM`]), as [`Bridge::receive`] does, but
    /// keeps nothing of it: send what [`Bridge::transmit_bytes`] holds and offer the rest
    /// (`&datagram[taken.bytes..]`), until all of it is taken.
    #[must_use = "a datagram not taken whole must be offered again once the outbox has drained"]
    pub fn receive_datagram<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        link: &mut Link<Q, T, M>,
        datagram: &[u8],
        now: Instant,
    ) -> Taken {
        let Bridge { reader, state } = self;
        let mut good = 0u32;
        let mut check = |frame: &ReceivedFrame<'_>| {
            let verdict = state.take(link, frame, now);
            if verdict == Check::Handled {
                good = good.wrapping_add(1);
            }
            verdict
        };
        let mut taken = reader.feed(datagram, &mut check);
        if !reader.is_waiting() {
            reader.end_datagram(&mut check);
        }
        if reader.is_waiting() {
            // What the reader holds is the end of what it took of this datagram (it starts
            // each one empty): hand those bytes back, the waiting frame first.
            taken = taken.saturating_sub(reader.pending());
            reader.clear();
        }
        Taken { bytes: taken, good }
    }

    /// Sends what is due at `now`: heartbeats, the attitude status, the stream requests,
    /// scheduled images.
    pub fn poll<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        link: &mut Link<Q, T, M>,
        now: Instant,
    ) {
        // A frame waiting for room goes first: it came before anything due now.
        if self.reader.is_waiting() {
            let _none_taken = self.receive(link, &[], now);
        }
        self.state.poll(link, now);
    }

    /// The MAVLink bytes to write next; empty when nothing waits. Report with
    /// [`Bridge::transmit_written`].
    pub fn transmit_bytes(&self) -> &[u8] {
        self.state.out.outbox.bytes()
    }

    /// `n` bytes of [`Bridge::transmit_bytes`] were written.
    pub fn transmit_written(&mut self, n: usize) {
        self.state.out.outbox.written(n)
    }

    /// The system id in use (configured, or learned from the autopilot).
    pub fn system_id(&self) -> u8 {
        self.state.out.system_id
    }

    /// The configuration.
    pub fn config(&self) -> &BridgeConfig {
        &self.state.config
    }

    /// The frame reader, for its state ([`FrameReader::pending`]).
    pub fn reader(&self) -> &FrameReader {
        &self.reader
    }

    /// The camera's FTP server's counters (requests, replies, malformed requests, bursts
    /// cut, sessions reclaimed); `None` without a camera.
    pub fn ftp_stats(&self) -> Option<crate::ftp::FtpStats> {
        self.state.camera.as_ref().map(CameraComponent::ftp_stats)
    }

    /// What signing accepted and turned away; `None` when not signing (feature `signing`).
    #[cfg(feature = "signing")]
    pub fn signing_stats(&self) -> Option<crate::signing::SigningStats> {
        self.state.out.outbox.signing().map(|s| s.stats())
    }

    /// The timestamps signed from now on are at least `timestamp` (10 µs units since
    /// 2015-01-01 GMT, as the specification counts): a host with a clock gives it, so that
    /// receivers that know the time take its first frames (feature `signing`).
    #[cfg(feature = "signing")]
    pub fn signing_time_at_least(&mut self, timestamp: u64) {
        if let Some(s) = self.state.out.outbox.signing_mut() {
            s.at_least(timestamp);
        }
    }

    /// All counters.
    pub fn stats(&self) -> BridgeStats {
        BridgeStats {
            reader: self.reader.stats(),
            outbox_full: self.state.out.outbox_full,
            ..self.state.stats
        }
    }
}

impl State {
    /// Queues `me`'s ACK of `command` to `to`, counted.
    pub(super) fn ack(&mut self, me: u8, to: (u8, u8), command: u16, result: MavResult) {
        bump(&mut self.stats.acks);
        self.out.ack(me, command, result, to);
    }

    fn camera_component(&self) -> Option<u8> {
        self.camera
            .as_ref()
            .and(self.config.camera.as_ref())
            .map(|c| c.component)
    }

    /// Whether a message to `(system, component)` is for one of the bridge's components.
    fn for_us(&self, system: u8, component: u8) -> bool {
        (system == 0 || system == self.out.system_id)
            && (component == 0
                || component == self.config.gimbal_component
                || Some(component) == self.camera_component())
    }

    /// Whether a gimbal message (set attitude, autopilot state) to `(system, component)` is
    /// the gimbal device's.
    fn for_gimbal(&self, system: u8, component: u8) -> bool {
        (system == 0 || system == self.out.system_id)
            && (component == 0 || component == self.config.gimbal_component)
    }

    /// Runs `f` with the camera, the gimbal and a sender into the outbox; `None` without a
    /// camera.
    fn with_camera<const Q: usize, const T: usize, M: Medium, R>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        now: Instant,
        f: impl FnOnce(&mut CameraComponent, &CameraConfig, &mut Link<Q, T, M>, &mut Tx<'_>) -> R,
    ) -> Option<R> {
        let vantage = self.vantage(gimbal, now);
        let State {
            camera,
            config,
            out,
            ..
        } = self;
        let (camera, config) = (camera.as_mut()?, config.camera.as_ref()?);
        let mut tx = Tx {
            out,
            vantage,
            gimbal_type: gimbal.gimbal_type(),
        };
        Some(f(camera, config, gimbal, &mut tx))
    }

    fn poll<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        now: Instant,
    ) {
        self.note_postback(gimbal, now);
        self.send_heartbeats(gimbal, now);
        if self.camera.as_ref().is_some_and(|c| c.has_work(now)) {
            self.with_camera(gimbal, now, |camera, config, gimbal, tx| {
                camera.poll(config, gimbal, now, tx)
            });
        }
        if self.status_ms > 0 && self.next_status.is_none_or(|t| now.is_at_or_after(t)) {
            self.next_status = Some(now.add_millis(self.status_ms));
            self.status(gimbal, now);
        }
        self.ask_for_streams(now);
    }

    /// A postback new since the last poll: the vehicle's yaw now goes with it.
    fn note_postback<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &Link<Q, T, M>,
        now: Instant,
    ) {
        if let Some((_, age)) = gimbal.latest_postback(now) {
            let at = Instant::from_millis(now.as_millis().wrapping_sub(age));
            if self.postback_yaw.is_none_or(|(seen, _)| seen != at) {
                self.postback_yaw = Some((at, self.vehicle.yaw(now)));
            }
        }
    }

    /// The vehicle's yaw (radians from north) when the latest postback arrived, which its
    /// motor angle is turned into the earth frame with: a motor angle up to 500 ms old
    /// beside the heading now would be off by the vehicle's turn since (15° at 30°/s).
    /// The heading now while no postback was noted.
    pub(crate) fn postback_vehicle_yaw<const Q: usize, const T: usize, M: Medium>(
        &self,
        gimbal: &Link<Q, T, M>,
        now: Instant,
    ) -> Option<f32> {
        let latest = gimbal
            .latest_postback(now)
            .map(|(_, age)| Instant::from_millis(now.as_millis().wrapping_sub(age)));
        match self.postback_yaw {
            Some((at, yaw)) if Some(at) == latest => yaw,
            _ => self.vehicle.yaw(now),
        }
    }

    /// Whether the yaw is held in the earth frame (the status's `YAW_LOCK`): an earth-frame
    /// aim, or an earth-frame rate hold.
    pub(crate) fn holds_earth_yaw<const Q: usize, const T: usize, M: Medium>(
        &self,
        gimbal: &Link<Q, T, M>,
    ) -> bool {
        gimbal.holds_earth_yaw() || (self.rate_earth && gimbal.is_rate_holding())
    }

    /// The heading that turns the latest postback's motor angle into the camera's yaw from
    /// north now: the vehicle's heading then while the yaw is held in the earth frame (the
    /// motor has turned back by the vehicle's turn since), its heading now while the yaw
    /// follows the vehicle (the motor kept its angle). At the travel's end the motor stops
    /// instead: until the next postback (2 Hz) shows it, the status says `AT_YAW_LIMIT`.
    pub(crate) fn postback_heading<const Q: usize, const T: usize, M: Medium>(
        &self,
        gimbal: &Link<Q, T, M>,
        now: Instant,
    ) -> Option<f32> {
        if self.holds_earth_yaw(gimbal) {
            self.postback_vehicle_yaw(gimbal, now)
        } else {
            self.vehicle.yaw(now)
        }
    }

    /// Where an image taken now is taken from: the vehicle's position, and the camera's
    /// attitude from north (the latest postback's motor angle and pitch, with
    /// [`State::postback_heading`]; none while the gimbal link is down).
    pub(crate) fn vantage<const Q: usize, const T: usize, M: Medium>(
        &self,
        gimbal: &Link<Q, T, M>,
        now: Instant,
    ) -> Vantage {
        let yaw = self.postback_heading(gimbal, now);
        let attitude = match (gimbal.latest_postback(now), yaw) {
            (Some((p, _)), Some(yaw)) if gimbal.is_link_up() => {
                // |yaw| <= π: its 0.01° fit; the sum is wrapped into [-18000, 18000). (The
                // saturating forms never saturate here.)
                let yaw_cdeg = libm::roundf(yaw.to_degrees() * 100.0) as i32;
                let earth = i32::from(p.motor_heading)
                    .saturating_add(yaw_cdeg)
                    .saturating_add(18_000)
                    .rem_euclid(36_000)
                    .saturating_sub(18_000);
                Some((earth as i16, p.pitch))
            }
            _ => None,
        };
        Vantage {
            position: self.vehicle.position,
            attitude,
        }
    }

    /// Queues a command for the gimbal other than an angle; a full queue is counted.
    fn command_gimbal_raw<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        c: GimbalCommand,
    ) -> bool {
        let sent = gimbal.send(GimbalCmd::from(c)).is_ok();
        if !sent {
            bump(&mut self.stats.queue_full);
        }
        sent
    }

    /// Queues a setpoint's command for the gimbal, counted in `angle_setpoints`; a full
    /// queue is counted.
    pub(crate) fn command_gimbal<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        c: GimbalCommand,
    ) -> bool {
        let sent = self.command_gimbal_raw(gimbal, c);
        if sent {
            bump(&mut self.stats.angle_setpoints);
        }
        sent
    }
}
