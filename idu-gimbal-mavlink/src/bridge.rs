//! The bridge: MAVLink 2 bytes in and out, the gimbal driven through [`GimbalControl`], time
//! passed in.

use idu_gimbal::wire::control::{Command, GimbalCommand, Heading, Pitch, Rate};
use idu_gimbal::wire::postback::{GimbalType, Postback};
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{
    GimbalDeviceCapFlags, GimbalDeviceErrorFlags, GimbalDeviceFlags, MavAutopilot, MavCmd,
    MavModeFlag, MavResult, MavState, MavType,
};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandAck, CommandLong, GimbalDeviceAttitudeStatus,
    GimbalDeviceInformation, GimbalDeviceSetAttitude, GlobalPositionInt, Heartbeat,
};
use mavio::mavspec::rust::spec::MessageSpecStatic;
use mavio::Message;

use crate::attitude::{is_nan_quaternion, wrap_pi, YawPitch};
use crate::camera::{self, Camera, CameraConfig, Tx};

use crate::framing::{Check, FrameReader, Outbox, ReaderStats, ReceivedFrame};
use crate::gimbal::GimbalControl;

/// The autopilot's component id (`MAV_COMP_ID_AUTOPILOT1`).
pub const AUTOPILOT_COMPONENT: u8 = 1;
/// `MAV_COMP_ID_GIMBAL`.
pub const GIMBAL_COMPONENT: u8 = 154;
/// Bytes of serialized frames the bridge holds for the transport.
pub const OUTBOX_LEN: usize = 1024;

/// The gimbal's pitch range, degrees (the wire's command range).
const PITCH_MIN_DEG: f32 = -100.0;
const PITCH_MAX_DEG: f32 = 60.0;
/// The yaw motor's range either side of the nose, degrees (the postback's ±170.00°).
const YAW_LIMIT_DEG: f32 = 170.0;
/// `GLOBAL_POSITION_INT`'s message id, asked of the autopilot at [`POSITION_INTERVAL_US`].
const GLOBAL_POSITION_INT_ID: u32 = 33;
const POSITION_INTERVAL_US: f32 = 200_000.0;
/// How often to ask again while no position arrives.
const POSITION_RETRY_MS: u32 = 5_000;

/// How the bridge presents itself and paces what it sends.
#[derive(Clone, PartialEq, Debug)]
pub struct BridgeConfig {
    /// System id; `None`: the autopilot's, from its HEARTBEAT (component 1), and 1 until one
    /// arrives.
    pub system_id: Option<u8>,
    /// The gimbal device's component id (default [`GIMBAL_COMPONENT`], 154).
    pub gimbal_component: u8,
    /// HEARTBEAT period, ms (1000).
    pub heartbeat_ms: u32,
    /// GIMBAL_DEVICE_ATTITUDE_STATUS period, ms (100: the gimbal reports at 2 Hz, and
    /// ArduPilot calls a mount unhealthy when its status is over a second old); 0 stops it.
    /// `MAV_CMD_SET_MESSAGE_INTERVAL` changes it at run time.
    pub attitude_status_ms: u32,
    /// An angle setpoint re-commands the gimbal only when heading or pitch moved by more
    /// than this, 0.1° units (default 2: 0.2°, twice the wire's resolution).
    pub deadband_deci: u16,
    /// The camera component; `None`: the bridge is a gimbal device only.
    pub camera: Option<CameraConfig>,
}

impl Default for BridgeConfig {
    fn default() -> Self {
        BridgeConfig {
            system_id: None,
            gimbal_component: GIMBAL_COMPONENT,
            heartbeat_ms: 1000,
            attitude_status_ms: 100,
            deadband_deci: 2,
            camera: None,
        }
    }
}

/// Counters of the bridge, each wrapping at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct BridgeStats {
    /// The frame reader's counters.
    pub reader: ReaderStats,
    /// Messages for another system or component, not acted on.
    pub not_for_us: u32,
    /// Commands answered (every COMMAND_LONG for us gets exactly one ACK).
    pub acks: u32,
    /// Angle setpoints turned into heading or pitch commands.
    pub angle_commands: u32,
    /// Rate setpoints passed to the core's rate hold.
    pub rate_setpoints: u32,
    /// Setpoints not followed: out of the gimbal's range, NaN without rates, a roll the
    /// gimbal cannot do, or a yaw frame needing a vehicle heading the bridge does not have.
    pub refused_setpoints: u32,
    /// Commands the gimbal's queue had no room for.
    pub queue_full: u32,
    /// Frames not sent: the outbox was full (or, a bug, `mavio` could not encode one).
    pub outbox_full: u32,
    /// Vehicle attitude and position updates passed to the core.
    pub vehicle_updates: u32,
}

/// A MAVLink Gimbal Device (gimbal protocol v2) in front of an IDU gimbal; see the crate
/// docs.
pub struct Bridge<G: GimbalControl> {
    gimbal: G,
    reader: FrameReader,
    state: State,
}

/// Everything but the gimbal and the reader, so that the reader's callback can borrow it.
struct State {
    config: BridgeConfig,
    out: Outbox<OUTBOX_LEN>,
    system_id: u8,
    /// The autopilot's (system, component), from its heartbeat.
    autopilot: Option<(u8, u8)>,
    next_heartbeat: Option<Instant>,
    next_status: Option<Instant>,
    status_ms: u32,
    /// When the position was last asked for; whether one arrived since.
    position_asked: Option<Instant>,
    position_seen: bool,
    /// The vehicle's yaw (radians, NED) and when it was measured.
    vehicle_yaw: Option<(f32, Instant)>,
    /// The last angles commanded (heading, pitch), 0.1° units.
    commanded: (Option<u16>, Option<i16>),
    /// The last setpoint's neutral/retract flags, to act on a change only.
    last_flags: u16,
    /// The vehicle's position from GLOBAL_POSITION_INT: lat, lon (1e-7°), alt and relative
    /// alt (mm), for the camera's captures.
    position: Option<[i32; 4]>,
    camera: Option<Camera>,
    stats: BridgeStats,
}

/// A vehicle yaw older than this cannot convert a setpoint's yaw frame (as the core's
/// vehicle data staleness, 1 s).
const VEHICLE_YAW_STALE_MS: u32 = 1_000;

impl<G: GimbalControl> Bridge<G> {
    /// A bridge in front of `gimbal`.
    pub fn new(gimbal: G, config: BridgeConfig) -> Self {
        let camera = config.camera.clone().map(Camera::new);
        let system_id = config.system_id.unwrap_or(1);
        let status_ms = config.attitude_status_ms;
        Bridge {
            gimbal,
            reader: FrameReader::new(),
            state: State {
                config,
                out: Outbox::new(),
                system_id,
                autopilot: None,
                next_heartbeat: None,
                next_status: None,
                status_ms,
                position_asked: None,
                position_seen: false,
                vehicle_yaw: None,
                commanded: (None, None),
                last_flags: 0,
                position: None,
                camera,
                stats: BridgeStats::default(),
            },
        }
    }

    /// Takes MAVLink bytes from the autopilot or ground station, in any split.
    pub fn receive(&mut self, bytes: &[u8], now: Instant) {
        let Bridge {
            gimbal,
            reader,
            state,
            ..
        } = self;
        reader.feed(bytes, |frame| state.dispatch(gimbal, frame, now));
    }

    /// Sends what is due at `now`: heartbeats, the attitude status, the position request.
    pub fn poll(&mut self, now: Instant) {
        self.state.poll(&self.gimbal, now);
    }

    /// The MAVLink bytes to write next; empty when nothing waits. Report with
    /// [`Bridge::transmit_written`].
    pub fn transmit_bytes(&self) -> &[u8] {
        self.state.out.bytes()
    }

    /// `n` bytes of [`Bridge::transmit_bytes`] were written.
    pub fn transmit_written(&mut self, n: usize) {
        self.state.out.written(n)
    }

    /// The system id in use (configured, or learned from the autopilot).
    pub fn system_id(&self) -> u8 {
        self.state.system_id
    }

    /// The configuration.
    pub fn config(&self) -> &BridgeConfig {
        &self.state.config
    }

    /// The gimbal.
    pub fn gimbal(&self) -> &G {
        &self.gimbal
    }

    /// The gimbal, mutably (to poll its driver).
    pub fn gimbal_mut(&mut self) -> &mut G {
        &mut self.gimbal
    }

    /// The frame reader, for its state ([`FrameReader::pending`]).
    pub fn reader(&self) -> &FrameReader {
        &self.reader
    }

    /// All counters.
    pub fn stats(&self) -> BridgeStats {
        BridgeStats {
            reader: self.reader.stats(),
            ..self.state.stats
        }
    }
}

/// Decodes `frame` as `M` when its CRC holds with `M`'s `CRC_EXTRA`.
fn decode<M>(frame: &ReceivedFrame<'_>) -> Option<M>
where
    M: MessageSpecStatic + for<'p> TryFrom<&'p mavio::protocol::Payload>,
{
    frame.decode::<M>().ok()
}

/// A message's id.
fn id_of<M: MessageSpecStatic>() -> u32 {
    M::spec().id()
}

fn deg(rad: f32) -> f32 {
    rad.to_degrees()
}

fn bump(counter: &mut u32) {
    *counter = counter.wrapping_add(1);
}

/// A name in a fixed MAVLink char field, zero-padded.
fn name<const N: usize>(s: &str) -> [u8; N] {
    let mut out = [0u8; N];
    for (dst, src) in out.iter_mut().zip(s.bytes()) {
        *dst = src;
    }
    out
}

fn model_name(t: Option<GimbalType>) -> &'static str {
    match t {
        Some(GimbalType::X30) => "X30/X30GT",
        Some(GimbalType::X30T) => "X30T",
        Some(GimbalType::Zoom3_5x) => "3.5x",
        Some(GimbalType::DualLight3_5x) => "3.5x dual light",
        Some(GimbalType::LaserRanging) => "laser ranging",
        Some(GimbalType::A2000) => "A2000",
        Some(GimbalType::DualLight30x) => "30x dual light",
        Some(GimbalType::Unknown(_)) | None => "IDU gimbal",
    }
}

impl State {
    fn send(&mut self, component: u8, message: &dyn Message) {
        if self.out.push(self.system_id, component, message).is_err() {
            bump(&mut self.stats.outbox_full);
        }
    }

    fn camera_component(&self) -> Option<u8> {
        self.camera.as_ref().map(|c| c.config.component)
    }

    /// Whether a message to `(system, component)` is for one of the bridge's components.
    fn for_us(&self, system: u8, component: u8) -> bool {
        (system == 0 || system == self.system_id)
            && (component == 0
                || component == self.config.gimbal_component
                || Some(component) == self.camera_component())
    }

    /// Whether a gimbal message (set attitude, autopilot state) to `(system, component)` is
    /// the gimbal device's.
    fn for_gimbal(&self, system: u8, component: u8) -> bool {
        (system == 0 || system == self.system_id)
            && (component == 0 || component == self.config.gimbal_component)
    }

    // Out of line: decoding needs a large stack frame (mavio's 255-byte payload and the
    // message), which would otherwise be set up on every `receive` call, a frame or not.
    #[inline(never)]
    fn dispatch<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        frame: &ReceivedFrame<'_>,
        now: Instant,
    ) -> Check {
        let id = frame.message_id();
        if id == id_of::<Heartbeat>() {
            // Decoded for its CRC; only who sent it matters.
            if decode::<Heartbeat>(frame).is_none() {
                return Check::Bad;
            }
            self.heartbeat(frame.system_id(), frame.component_id());
            Check::Handled
        } else if id == id_of::<CommandLong>() {
            let Some(cmd) = decode::<CommandLong>(frame) else {
                return Check::Bad;
            };
            self.command(gimbal, frame.system_id(), frame.component_id(), &cmd, now);
            Check::Handled
        } else if id == id_of::<GimbalDeviceSetAttitude>() {
            let Some(set) = decode::<GimbalDeviceSetAttitude>(frame) else {
                return Check::Bad;
            };
            if self.for_gimbal(set.target_system, set.target_component) {
                self.set_attitude(gimbal, &set, now);
            } else {
                bump(&mut self.stats.not_for_us);
            }
            Check::Handled
        } else if id == id_of::<AutopilotStateForGimbalDevice>() {
            let Some(state) = decode::<AutopilotStateForGimbalDevice>(frame) else {
                return Check::Bad;
            };
            if self.for_gimbal(state.target_system, state.target_component) {
                self.autopilot_state(gimbal, &state, now);
            } else {
                bump(&mut self.stats.not_for_us);
            }
            Check::Handled
        } else if id == id_of::<GlobalPositionInt>() {
            let Some(pos) = decode::<GlobalPositionInt>(frame) else {
                return Check::Bad;
            };
            if frame.component_id() == AUTOPILOT_COMPONENT {
                self.position(gimbal, &pos, now);
            }
            Check::Handled
        } else {
            Check::Unhandled
        }
    }

    fn heartbeat(&mut self, system: u8, component: u8) {
        if component != AUTOPILOT_COMPONENT {
            return;
        }
        if self.autopilot.is_none() {
            // A new autopilot: ask it for the position at once.
            self.position_asked = None;
        }
        self.autopilot = Some((system, component));
        if self.config.system_id.is_none() {
            self.system_id = system;
        }
    }

    fn ack(&mut self, from: u8, to: (u8, u8), command: MavCmd, result: MavResult) {
        bump(&mut self.stats.acks);
        let ack = CommandAck {
            command,
            result,
            progress: 0,
            result_param2: 0,
            target_system: to.0,
            target_component: to.1,
        };
        self.send(from, &ack);
    }

    fn command<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        system: u8,
        component: u8,
        cmd: &CommandLong,
        now: Instant,
    ) {
        if !self.for_us(cmd.target_system, cmd.target_component) {
            bump(&mut self.stats.not_for_us);
            return;
        }
        let from = (system, component);
        let gimbal_id = self.config.gimbal_component;
        let camera_id = self.camera_component();
        let camera_owns = camera_id.is_some() && camera::owns(cmd);
        let gimbal_owns = Self::gimbal_owns(cmd);
        // Broadcast: the owner answers, or nobody (another component may own it).
        // Addressed: the addressee answers, UNSUPPORTED if it does not own the command.
        let (me, owner) = match cmd.target_component {
            0 if gimbal_owns => (gimbal_id, true),
            0 if camera_owns => (camera_id.unwrap_or(gimbal_id), true),
            0 => {
                bump(&mut self.stats.not_for_us);
                return;
            }
            c if c == gimbal_id => (gimbal_id, gimbal_owns),
            c => (c, camera_owns),
        };
        if !owner {
            self.ack(me, from, cmd.command, MavResult::Unsupported);
            return;
        }
        if me == gimbal_id {
            let result = self.gimbal_command(cmd, now);
            self.ack(me, from, cmd.command, result);
            // The information follows the ACK.
            if result == MavResult::Accepted && cmd.command == MavCmd::RequestMessage {
                if cmd.param1 == id_of::<GimbalDeviceInformation>() as f32 {
                    self.information(gimbal, now);
                } else {
                    self.status(gimbal, now);
                }
            }
        } else {
            let acked = self.with_camera(|camera, tx| {
                let (result, reply) = camera.command(gimbal, cmd, now);
                // The ACK first, then what the command produced.
                let ack = CommandAck {
                    command: cmd.command,
                    result,
                    progress: 0,
                    result_param2: 0,
                    target_system: from.0,
                    target_component: from.1,
                };
                (tx.send)(me, &ack);
                camera.reply(reply, now, tx);
            });
            if acked.is_some() {
                bump(&mut self.stats.acks);
            }
        }
    }

    /// Runs `f` with the camera and a sender into the outbox; `None` without a camera.
    fn with_camera<R>(&mut self, f: impl FnOnce(&mut Camera, &mut Tx<'_>) -> R) -> Option<R> {
        let State {
            camera,
            out,
            system_id,
            stats,
            position,
            ..
        } = self;
        let camera = camera.as_mut()?;
        let mut send = |c: u8, m: &dyn Message| {
            if out.push(*system_id, c, m).is_err() {
                bump(&mut stats.outbox_full);
            }
        };
        let mut tx = Tx {
            send: &mut send,
            position: *position,
        };
        Some(f(camera, &mut tx))
    }

    fn gimbal_owns(cmd: &CommandLong) -> bool {
        match cmd.command {
            MavCmd::RequestMessage => {
                cmd.param1 == id_of::<GimbalDeviceInformation>() as f32
                    || cmd.param1 == id_of::<GimbalDeviceAttitudeStatus>() as f32
            }
            MavCmd::SetMessageInterval => {
                cmd.param1 == id_of::<GimbalDeviceAttitudeStatus>() as f32
            }
            _ => false,
        }
    }

    /// A gimbal command's result (the gimbal owns it).
    fn gimbal_command(&mut self, cmd: &CommandLong, now: Instant) -> MavResult {
        match cmd.command {
            MavCmd::SetMessageInterval => self.set_status_interval(cmd.param2, now),
            MavCmd::RequestMessage => MavResult::Accepted,
            _ => MavResult::Unsupported,
        }
    }

    /// `MAV_CMD_SET_MESSAGE_INTERVAL` for the attitude status: µs; −1 stops it, 0 restores
    /// the configured default. Below 1 ms or above a minute is out of range.
    fn set_status_interval(&mut self, interval_us: f32, now: Instant) -> MavResult {
        if interval_us == -1.0 {
            self.status_ms = 0;
        } else if interval_us == 0.0 {
            self.status_ms = self.config.attitude_status_ms;
        } else if (1_000.0..=60_000_000.0).contains(&interval_us) {
            // In range: the cast is exact to the millisecond.
            self.status_ms = (interval_us / 1_000.0) as u32;
        } else {
            return MavResult::Denied;
        }
        self.next_status = Some(now);
        MavResult::Accepted
    }

    fn information<G: GimbalControl>(&mut self, gimbal: &G, now: Instant) {
        let gimbal_type = gimbal.latest_postback(now).map(|(p, _)| p.gimbal_type);
        let info = GimbalDeviceInformation {
            time_boot_ms: now.as_millis(),
            vendor_name: name("IDU"),
            model_name: name(model_name(gimbal_type)),
            custom_name: [0; 32],
            firmware_version: 0,
            hardware_version: 0,
            uid: 0,
            cap_flags: GimbalDeviceCapFlags::HAS_NEUTRAL
                | GimbalDeviceCapFlags::HAS_PITCH_AXIS
                | GimbalDeviceCapFlags::HAS_PITCH_LOCK
                | GimbalDeviceCapFlags::HAS_YAW_AXIS
                | GimbalDeviceCapFlags::HAS_YAW_FOLLOW
                | GimbalDeviceCapFlags::HAS_YAW_LOCK
                | GimbalDeviceCapFlags::SUPPORTS_YAW_IN_EARTH_FRAME,
            custom_cap_flags: 0,
            // No roll axis: unknown, as the message says to give it.
            roll_min: f32::NAN,
            roll_max: f32::NAN,
            pitch_min: PITCH_MIN_DEG.to_radians(),
            pitch_max: PITCH_MAX_DEG.to_radians(),
            yaw_min: (-YAW_LIMIT_DEG).to_radians(),
            yaw_max: YAW_LIMIT_DEG.to_radians(),
            gimbal_device_id: 0,
        };
        self.send(self.config.gimbal_component, &info);
    }

    fn set_attitude<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        set: &GimbalDeviceSetAttitude,
        now: Instant,
    ) {
        let flags = set.flags;
        // Neutral and retract act once, when the flag appears.
        let edge = |f: GimbalDeviceFlags| flags.contains(f) && self.last_flags & f.bits() == 0;
        let neutral = edge(GimbalDeviceFlags::NEUTRAL);
        // No retracted position: the gimbal's stowed pose is looking straight down.
        let retract = edge(GimbalDeviceFlags::RETRACT);
        self.last_flags = flags.bits();
        if neutral || retract {
            let c = if retract {
                GimbalCommand::LookDown
            } else {
                GimbalCommand::Recenter
            };
            self.command_gimbal(gimbal, c);
            self.commanded = (None, None);
            return;
        }
        if flags.intersects(GimbalDeviceFlags::NEUTRAL | GimbalDeviceFlags::RETRACT) {
            return;
        }
        if is_nan_quaternion(set.q) {
            self.rate(gimbal, set, now);
            return;
        }
        let Some(a) = YawPitch::from_quaternion(set.q) else {
            bump(&mut self.stats.refused_setpoints);
            return;
        };
        // The gimbal has no roll: a setpoint rolled by more than about a degree
        // (sin(roll)·cos(pitch) over sin 1° = 0.01745) cannot be followed.
        if libm::fabsf(YawPitch::roll_of(set.q)) > 0.017_45 {
            bump(&mut self.stats.refused_setpoints);
            return;
        }
        let earth_yaw = if flags.contains(GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME) {
            false
        } else {
            flags.contains(GimbalDeviceFlags::YAW_IN_EARTH_FRAME)
                || flags.contains(GimbalDeviceFlags::YAW_LOCK)
        };
        let north = gimbal.north_referenced(now);
        // The heading command's frame is the gimbal's reference: north while attitude is
        // pushed, the nose otherwise.
        let heading_rad = match (earth_yaw, north) {
            (true, true) | (false, false) => Some(a.yaw_rad),
            (false, true) => self.vehicle_yaw(now).map(|v| a.yaw_rad + v),
            (true, false) => self.vehicle_yaw(now).map(|v| a.yaw_rad - v),
        };
        let pitch = Pitch::new(deg(a.pitch_rad));
        let heading = heading_rad.map(|h| {
            // (−180°, 180°] to the command's [0°, 360°].
            let d = deg(wrap_pi(h));
            Heading::new(if d < 0.0 { d + 360.0 } else { d })
        });
        let (Ok(pitch), Some(Ok(heading))) = (pitch, heading) else {
            bump(&mut self.stats.refused_setpoints);
            return;
        };
        let band = i32::from(self.config.deadband_deci);
        let heading_moved = self.commanded.0.is_none_or(|h| {
            let d = (i32::from(heading.deci()) - i32::from(h)).rem_euclid(3600);
            d.min(3600 - d) > band
        });
        let pitch_moved = self
            .commanded
            .1
            .is_none_or(|p| (i32::from(pitch.deci()) - i32::from(p)).abs() > band);
        if heading_moved && self.command_gimbal(gimbal, GimbalCommand::Heading(heading)) {
            self.commanded.0 = Some(heading.deci());
        }
        if pitch_moved && self.command_gimbal(gimbal, GimbalCommand::Pitch(pitch)) {
            self.commanded.1 = Some(pitch.deci());
        }
    }

    fn command_gimbal<G: GimbalControl>(&mut self, gimbal: &mut G, c: GimbalCommand) -> bool {
        if gimbal.send(Command::from(c)) {
            bump(&mut self.stats.angle_commands);
            true
        } else {
            bump(&mut self.stats.queue_full);
            false
        }
    }

    fn rate<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        set: &GimbalDeviceSetAttitude,
        now: Instant,
    ) {
        // Body rates in FRD: about y is pitch (positive raises the camera, as the wire's
        // positive pitch rate), about z is yaw (positive to the right, as the wire's).
        let (pitch_dps, yaw_dps) = (deg(set.angular_velocity_y), deg(set.angular_velocity_z));
        let Ok(rate) = Rate::new(yaw_dps, pitch_dps) else {
            bump(&mut self.stats.refused_setpoints);
            return;
        };
        // A rate ends any angle: the next angle setpoint is sent whatever its value.
        self.commanded = (None, None);
        if gimbal.set_rate(rate, now) {
            bump(&mut self.stats.rate_setpoints);
        } else {
            bump(&mut self.stats.queue_full);
        }
    }

    fn vehicle_yaw(&self, now: Instant) -> Option<f32> {
        self.vehicle_yaw
            .filter(|&(_, at)| now.millis_since(at) <= VEHICLE_YAW_STALE_MS)
            .map(|(yaw, _)| yaw)
    }

    fn autopilot_state<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        state: &AutopilotStateForGimbalDevice,
        now: Instant,
    ) {
        // The vehicle's attitude: 3-2-1 Euler is right here (a vehicle does not pitch past
        // ±90° in flight, and the frame carries roll).
        let [w, x, y, z] = state.q;
        if !state.q.iter().all(|v| v.is_finite()) {
            return;
        }
        let roll = libm::atan2f(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
        let pitch = libm::asinf((2.0 * (w * y - z * x)).clamp(-1.0, 1.0));
        let yaw = libm::atan2f(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
        self.vehicle_yaw = Some((yaw, now));
        // The wire's heading is in [−180°, 180°).
        let heading = deg(yaw).min(179.99);
        if let Ok(a) = Attitude::new(deg(pitch), deg(roll), heading) {
            gimbal.set_attitude(a, now);
            bump(&mut self.stats.vehicle_updates);
        }
    }

    fn position<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        pos: &GlobalPositionInt,
        now: Instant,
    ) {
        self.position_seen = true;
        self.position = Some([pos.lat, pos.lon, pos.alt, pos.relative_alt]);
        if let Ok(g) = Gps::from_e7(pos.lat, pos.lon) {
            gimbal.set_gps(g, now);
            bump(&mut self.stats.vehicle_updates);
        }
        // Millimetres above mean sea level to centimetres, rounded toward zero.
        gimbal.set_altitude(Altitude::from_cm(pos.alt / 10), now);
    }

    fn poll<G: GimbalControl>(&mut self, gimbal: &G, now: Instant) {
        if self.next_heartbeat.is_none_or(|t| now.is_at_or_after(t)) {
            self.next_heartbeat = Some(now.add_millis(self.config.heartbeat_ms.max(1)));
            let hb = Heartbeat {
                type_: MavType::Gimbal,
                autopilot: MavAutopilot::Invalid,
                base_mode: MavModeFlag::empty(),
                custom_mode: 0,
                system_status: MavState::Active,
                mavlink_version: 3,
            };
            self.send(self.config.gimbal_component, &hb);
            if let Some(camera) = self.camera_component() {
                self.send(
                    camera,
                    &Heartbeat {
                        type_: MavType::Camera,
                        ..hb
                    },
                );
            }
        }
        self.with_camera(|camera, tx| camera.poll(now, tx));
        if self.status_ms > 0 && self.next_status.is_none_or(|t| now.is_at_or_after(t)) {
            self.next_status = Some(now.add_millis(self.status_ms));
            self.status(gimbal, now);
        }
        if let Some(ap) = self.autopilot {
            let due = self
                .position_asked
                .is_none_or(|t| now.millis_since(t) >= POSITION_RETRY_MS);
            if !self.position_seen && due {
                self.position_asked = Some(now);
                let ask = CommandLong {
                    target_system: ap.0,
                    target_component: ap.1,
                    command: MavCmd::SetMessageInterval,
                    confirmation: 0,
                    param1: GLOBAL_POSITION_INT_ID as f32,
                    param2: POSITION_INTERVAL_US,
                    param3: 0.0,
                    param4: 0.0,
                    param5: 0.0,
                    param6: 0.0,
                    param7: 0.0,
                };
                self.send(self.config.gimbal_component, &ask);
            }
        }
    }

    fn status<G: GimbalControl>(&mut self, gimbal: &G, now: Instant) {
        let latest = gimbal.latest_postback(now).map(|(p, _)| p);
        let north = gimbal.north_referenced(now);
        let (q, flags, delta_yaw) = match latest {
            Some(p) => status_attitude(&p, north),
            None => ([f32::NAN; 4], GimbalDeviceFlags::empty(), f32::NAN),
        };
        let mut failure = GimbalDeviceErrorFlags::empty();
        if !gimbal.is_link_up() {
            failure |= GimbalDeviceErrorFlags::COMMS_ERROR;
        }
        let status = GimbalDeviceAttitudeStatus {
            target_system: 0,
            target_component: 0,
            time_boot_ms: now.as_millis(),
            flags,
            q,
            angular_velocity_x: f32::NAN,
            angular_velocity_y: f32::NAN,
            angular_velocity_z: f32::NAN,
            failure_flags: failure,
            delta_yaw,
            delta_yaw_velocity: f32::NAN,
            gimbal_device_id: 0,
        };
        self.send(self.config.gimbal_component, &status);
    }
}

/// The attitude status of a postback: pitch from the horizon; yaw north-referenced while
/// attitude is pushed (the postback's heading is then the gimbal's bearing), the motor
/// angle in the vehicle frame otherwise. `delta_yaw` is the motor angle in either case.
pub fn status_attitude(p: &Postback, north: bool) -> ([f32; 4], GimbalDeviceFlags, f32) {
    let motor = p.motor_heading_deg().to_radians();
    let (yaw, frame) = if north {
        (
            wrap_pi(p.heading_deg().to_radians()),
            GimbalDeviceFlags::YAW_IN_EARTH_FRAME,
        )
    } else {
        (motor, GimbalDeviceFlags::YAW_IN_VEHICLE_FRAME)
    };
    let q = YawPitch {
        yaw_rad: yaw,
        pitch_rad: p.pitch_deg().to_radians(),
    }
    .to_quaternion();
    (
        q,
        frame | GimbalDeviceFlags::PITCH_LOCK | GimbalDeviceFlags::ROLL_LOCK,
        motor,
    )
}
