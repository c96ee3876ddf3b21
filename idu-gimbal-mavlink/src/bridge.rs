//! The bridge: MAVLink 2 bytes in and out, the gimbal driven through [`GimbalControl`], time
//! passed in.

#[cfg(feature = "roi")]
use idu_gimbal::geo::Position;
use idu_gimbal::wire::control::{Command as GimbalCmd, GimbalCommand};
use idu_gimbal::wire::postback::GimbalType;
use idu_gimbal::wire::vehicle::{Altitude, Attitude, Gps};
use idu_gimbal::Instant;
#[cfg(feature = "roi")]
use mavio::dialects::common::enums::MavFrame;
use mavio::dialects::common::enums::{
    GimbalDeviceCapFlags, GimbalDeviceErrorFlags, MavAutopilot, MavCmd, MavModeFlag, MavResult,
    MavState, MavType,
};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandAck, CommandInt, CommandLong, FileTransferProtocol,
    GimbalDeviceAttitudeStatus, GimbalDeviceInformation, GimbalDeviceSetAttitude,
    GlobalPositionInt, Heartbeat, ParamExtRequestList, ParamExtRequestRead, ParamExtSet,
};
use mavio::mavspec::rust::spec::MessageSpecStatic;
use mavio::Message;

use crate::attitude;
use crate::camera::{self, Camera, CameraConfig};
use crate::codec;
use crate::command::{Command, Xy};
use crate::framing::{Check, FrameReader, Outbox, ReaderStats, ReceivedFrame};
use crate::gimbal::GimbalControl;
use crate::status::{self, Pose};

/// The autopilot's component id (`MAV_COMP_ID_AUTOPILOT1`).
pub const AUTOPILOT_COMPONENT: u8 = 1;
/// `MAV_COMP_ID_GIMBAL`.
pub const GIMBAL_COMPONENT: u8 = 154;
/// Bytes of serialized frames the bridge holds for the transport.
pub const OUTBOX_LEN: usize = 1024;

/// The gimbal's pitch range, degrees (the wire's command range).
pub(crate) const PITCH_MIN_DEG: f32 = -100.0;
pub(crate) const PITCH_MAX_DEG: f32 = 60.0;

/// How often to ask the autopilot again for a stream that does not come.
const STREAM_RETRY_MS: u32 = 5_000;
/// How often the streams are looked at, ms: an ask is at most this late.
const STREAM_CHECK_MS: u32 = 100;
/// A stream not heard for this long is asked for again (an autopilot that rebooted has
/// forgotten the interval it was asked for).
const STREAM_LOST_MS: u32 = 5_000;

/// A stream the bridge asks the autopilot for with `MAV_CMD_SET_MESSAGE_INTERVAL`.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
struct Wanted {
    /// The message id.
    id: u32,
    /// The interval asked for, µs.
    interval_us: u32,
    /// Asked for once per autopilot, whether it comes or not (a stream that comes anyway,
    /// but may come too slowly); otherwise until it comes.
    once: bool,
}

/// `GLOBAL_POSITION_INT` at 5 Hz: the vehicle position for the gimbal, point-at and the
/// captures. Neither autopilot sends it to a gimbal port unasked.
const POSITION_STREAM: Wanted = Wanted {
    id: 33,
    interval_us: 200_000,
    once: false,
};
/// `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE` at 20 Hz: the vehicle attitude pushed to the
/// gimbal and the yaw that relates the setpoint and status frames. ArduPilot sends it to
/// a MAVLink gimbal by itself; PX4 streams it only on a port in mode Gimbal (its
/// `configure_streams`), so on any other port it must be asked for.
const AUTOPILOT_STATE_STREAM: Wanted = Wanted {
    id: 286,
    interval_us: 50_000,
    once: false,
};
/// `GIMBAL_DEVICE_SET_ATTITUDE` at 20 Hz, asked once: PX4 re-sends its latest setpoint at
/// the stream's rate, 5 Hz on a port in mode Normal (`configure_streams`), too slow for a
/// smooth rate or ROI; ArduPilot sends its setpoints at 50 Hz unasked and refuses the
/// request, which costs one command.
const SETPOINT_STREAM: Wanted = Wanted {
    id: 284,
    interval_us: 50_000,
    once: true,
};

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
    /// Commands answered (every COMMAND_LONG and COMMAND_INT for us gets exactly one ACK).
    pub acks: u32,
    /// Angle setpoints turned into heading or pitch commands.
    pub angle_commands: u32,
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
}

/// A MAVLink Gimbal Device (gimbal protocol v2) in front of an IDU gimbal; see the crate
/// docs.
// `repr(C)`, the frame reader first: the receive loop's fields stay at small offsets from
// the bridge's address, in reach of the M4's short load and store forms (LDRD and VLDR
// reach 1020 bytes). In the order the compiler chose once the camera's state grew, the
// receive bench measured 58.2 instructions a byte; in this one, 55.5.
#[repr(C)]
pub struct Bridge<G: GimbalControl> {
    reader: FrameReader,
    gimbal: G,
    state: State,
}

/// A stream asked of the autopilot: when it was last asked for and last heard.
#[derive(Clone, Copy, Debug, Default)]
struct StreamState {
    asked: Option<Instant>,
    heard: Option<Instant>,
}

impl StreamState {
    /// Whether to ask (again) at `now`: not heard lately, and not asked lately; a stream
    /// asked for once, when never asked.
    fn due(&self, wanted: &Wanted, now: Instant) -> bool {
        if wanted.once {
            return self.asked.is_none();
        }
        let lost = self
            .heard
            .is_none_or(|t| now.millis_since(t) >= STREAM_LOST_MS);
        lost && self
            .asked
            .is_none_or(|t| now.millis_since(t) >= STREAM_RETRY_MS)
    }
}

/// The vehicle, as the autopilot last described it.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Vehicle {
    /// Yaw (radians, NED: from north) and when it was measured.
    pub(crate) yaw: Option<(f32, Instant)>,
    /// Yaw rate (rad/s, about NED's down axis), when the autopilot gave one.
    pub(crate) yaw_rate: Option<(f32, Instant)>,
    /// From GLOBAL_POSITION_INT: lat, lon (1e-7°), alt and relative alt (mm).
    pub(crate) position: Option<[i32; 4]>,
}

/// A vehicle yaw older than this cannot convert a setpoint's yaw frame or be reported as
/// `delta_yaw` (as the core's vehicle data staleness, 1 s).
pub(crate) const VEHICLE_YAW_STALE_MS: u32 = 1_000;

impl Vehicle {
    /// The vehicle's yaw from north, radians, when fresh.
    pub(crate) fn yaw(&self, now: Instant) -> Option<f32> {
        fresh(self.yaw, now)
    }

    /// The vehicle's yaw rate, rad/s, when fresh.
    pub(crate) fn yaw_rate(&self, now: Instant) -> Option<f32> {
        fresh(self.yaw_rate, now)
    }
}

fn fresh(v: Option<(f32, Instant)>, now: Instant) -> Option<f32> {
    v.filter(|&(_, at)| now.millis_since(at) <= VEHICLE_YAW_STALE_MS)
        .map(|(v, _)| v)
}

/// Everything but the gimbal and the reader, so that the reader's callback can borrow it.
pub(crate) struct State {
    pub(crate) config: BridgeConfig,
    out: Outbox<OUTBOX_LEN>,
    system_id: u8,
    /// The autopilot's (system, component), from its heartbeat.
    autopilot: Option<(u8, u8)>,
    next_heartbeat: Option<Instant>,
    next_status: Option<Instant>,
    status_ms: u32,
    position_stream: StreamState,
    autopilot_state_stream: StreamState,
    setpoint_stream: StreamState,
    /// When to look at the streams again (`None`: at the next poll). The asks are due at
    /// whole seconds; looking every [`STREAM_CHECK_MS`] keeps the idle poll short.
    next_stream_check: Option<Instant>,
    pub(crate) vehicle: Vehicle,
    /// The last angles commanded (heading, pitch), 0.1° units.
    pub(crate) commanded: (Option<u16>, Option<i16>),
    /// The last setpoint's neutral/retract flags, to act on a change only.
    pub(crate) last_flags: u16,
    /// The pose last commanded, for the status flags.
    pub(crate) pose: Pose,
    camera: Option<Camera>,
    pub(crate) stats: BridgeStats,
}

/// What the camera is given to send with: the outbox, and what it reports from the
/// bridge's state.
pub(crate) struct Tx<'a> {
    out: &'a mut Outbox<OUTBOX_LEN>,
    system_id: u8,
    outbox_full: &'a mut u32,
    /// The vehicle position (lat, lon ×1e7, alt and relative alt in mm), for captures.
    pub(crate) position: Option<[i32; 4]>,
    /// The gimbal type from the latest postback.
    pub(crate) gimbal_type: Option<GimbalType>,
}

/// Queues `message` from `(system_id, component)`; a full outbox is counted in `full`.
/// The one way every frame the bridge sends goes out.
fn push_counted(
    out: &mut Outbox<OUTBOX_LEN>,
    system_id: u8,
    full: &mut u32,
    component: u8,
    message: &dyn Message,
) {
    if out.push(system_id, component, message).is_err() {
        bump(full);
    }
}

/// [`push_counted`] for message `M`, its `len`-byte payload written in place by its codec
/// ([`crate::codec`]).
fn push_encoded<M: MessageSpecStatic>(
    out: &mut Outbox<OUTBOX_LEN>,
    system_id: u8,
    full: &mut u32,
    component: u8,
    len: usize,
    encode: impl FnOnce(&mut [u8]),
) {
    if out
        .push_with(
            system_id,
            component,
            M::message_id(),
            M::crc_extra(),
            len,
            encode,
        )
        .is_err()
    {
        bump(full);
    }
}

/// The `COMMAND_ACK` of `command` with `result`, to its sender `to`.
fn ack_of(command: MavCmd, result: MavResult, to: (u8, u8)) -> CommandAck {
    CommandAck {
        command,
        result,
        progress: 0,
        result_param2: 0,
        target_system: to.0,
        target_component: to.1,
    }
}

impl Tx<'_> {
    /// Queues `message` from `component`; a full outbox is counted.
    pub(crate) fn send(&mut self, component: u8, message: &dyn Message) {
        push_counted(
            self.out,
            self.system_id,
            self.outbox_full,
            component,
            message,
        );
    }

    /// Queues message `M` from `component`, its `len`-byte payload written by its codec.
    pub(crate) fn send_encoded<M: MessageSpecStatic>(
        &mut self,
        component: u8,
        len: usize,
        encode: impl FnOnce(&mut [u8]),
    ) {
        push_encoded::<M>(
            self.out,
            self.system_id,
            self.outbox_full,
            component,
            len,
            encode,
        );
    }

    /// Bytes the outbox has room for.
    pub(crate) fn room(&self) -> usize {
        OUTBOX_LEN - self.out.len()
    }
}

impl<G: GimbalControl> Bridge<G> {
    /// A bridge in front of `gimbal`.
    pub fn new(gimbal: G, config: BridgeConfig) -> Self {
        let camera = config
            .camera
            .as_ref()
            .map(|c| Camera::new(c, config.gimbal_component));
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
                position_stream: StreamState::default(),
                autopilot_state_stream: StreamState::default(),
                setpoint_stream: StreamState::default(),
                next_stream_check: None,
                vehicle: Vehicle::default(),
                commanded: (None, None),
                last_flags: 0,
                pose: Pose::Other,
                camera,
                stats: BridgeStats::default(),
            },
        }
    }

    /// Takes MAVLink bytes from a byte stream (a serial port), in any split.
    pub fn receive(&mut self, bytes: &[u8], now: Instant) {
        let Bridge {
            gimbal,
            reader,
            state,
            ..
        } = self;
        reader.feed(bytes, |frame| state.dispatch(gimbal, frame, now));
    }

    /// Takes one UDP datagram: MAVLink on UDP carries whole frames, so a frame cut at the
    /// datagram's end is dropped (its bytes counted as skipped) rather than joined to the
    /// next datagram, which may come from another sender. Returns how many frames in it
    /// were messages the bridge handles with a good CRC: a sender worth answering.
    pub fn receive_datagram(&mut self, datagram: &[u8], now: Instant) -> u32 {
        let Bridge {
            gimbal,
            reader,
            state,
            ..
        } = self;
        let mut good = 0u32;
        let mut check = |frame: &ReceivedFrame<'_>| {
            let verdict = state.dispatch(gimbal, frame, now);
            if verdict == Check::Handled {
                good = good.wrapping_add(1);
            }
            verdict
        };
        reader.feed(datagram, &mut check);
        reader.end_datagram(&mut check);
        good
    }

    /// Sends what is due at `now`: heartbeats, the attitude status, the stream requests,
    /// scheduled images.
    pub fn poll(&mut self, now: Instant) {
        self.state.poll(&mut self.gimbal, now);
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
pub(crate) fn id_of<M: MessageSpecStatic>() -> u32 {
    M::spec().id()
}

pub(crate) fn bump(counter: &mut u32) {
    *counter = counter.wrapping_add(1);
}

/// A name in a fixed MAVLink char field, zero-padded.
pub(crate) fn name<const N: usize>(s: &str) -> [u8; N] {
    let mut out = [0u8; N];
    for (dst, src) in out.iter_mut().zip(s.bytes()) {
        *dst = src;
    }
    out
}

/// The yaw motor's range either side of the nose, degrees: the postback's ±170.00°, or
/// ±325.00° on the 3.5× models (the document's Motor_psi scope).
pub fn yaw_limit_deg(t: Option<GimbalType>) -> f32 {
    match t {
        Some(GimbalType::Zoom3_5x | GimbalType::DualLight3_5x) => 325.0,
        _ => 170.0,
    }
}

impl State {
    /// Queues message `M` from `component`, its `len`-byte payload written by its codec
    /// ([`crate::codec`]); a full outbox is counted.
    fn send_encoded<M: MessageSpecStatic>(
        &mut self,
        component: u8,
        len: usize,
        encode: impl FnOnce(&mut [u8]),
    ) {
        push_encoded::<M>(
            &mut self.out,
            self.system_id,
            &mut self.stats.outbox_full,
            component,
            len,
            encode,
        );
    }

    pub(crate) fn send(&mut self, component: u8, message: &dyn Message) {
        push_counted(
            &mut self.out,
            self.system_id,
            &mut self.stats.outbox_full,
            component,
            message,
        );
    }

    fn camera_component(&self) -> Option<u8> {
        self.camera
            .as_ref()
            .and(self.config.camera.as_ref())
            .map(|c| c.component)
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
        let from = (frame.system_id(), frame.component_id());
        // The messages received many times a second first, each decoded by its own codec
        // (crate::codec); the CRC is checked with the message's CRC_EXTRA before anything.
        if id == id_of::<AutopilotStateForGimbalDevice>() {
            if !frame.checksum_holds(AutopilotStateForGimbalDevice::crc_extra()) {
                return Check::Bad;
            }
            let Some(state) = codec::autopilot_state::decode(frame.payload()) else {
                return Check::Bad;
            };
            if self.for_gimbal(state.target_system, state.target_component) {
                self.autopilot_state(gimbal, &state, now);
            } else {
                bump(&mut self.stats.not_for_us);
            }
        } else if id == id_of::<GimbalDeviceSetAttitude>() {
            if !frame.checksum_holds(GimbalDeviceSetAttitude::crc_extra()) {
                return Check::Bad;
            }
            let set = codec::set_attitude::decode(frame.payload());
            if self.for_gimbal(set.target_system, set.target_component) {
                self.set_attitude(gimbal, &set, now);
            } else {
                bump(&mut self.stats.not_for_us);
            }
        } else if id == id_of::<Heartbeat>() {
            // Checked for its CRC; only who sent it matters.
            if !frame.checksum_holds(Heartbeat::crc_extra()) {
                return Check::Bad;
            }
            self.heartbeat(from.0, from.1);
        } else if id == id_of::<CommandLong>() {
            let Some(cmd) = decode::<CommandLong>(frame) else {
                return Check::Bad;
            };
            self.command(gimbal, from, &Command::from(&cmd), now);
        } else if id == id_of::<CommandInt>() {
            let Some(cmd) = decode::<CommandInt>(frame) else {
                return Check::Bad;
            };
            self.command(gimbal, from, &Command::from(&cmd), now);
        } else if id == id_of::<GlobalPositionInt>() {
            if !frame.checksum_holds(GlobalPositionInt::crc_extra()) {
                return Check::Bad;
            }
            let pos = codec::global_position::decode(frame.payload());
            if from.1 == AUTOPILOT_COMPONENT {
                self.position(gimbal, &pos, now);
            }
        } else if camera::handles(id) {
            return self.camera_message(gimbal, frame, from, now);
        } else {
            return Check::Unhandled;
        }
        Check::Handled
    }

    /// FTP and the extended parameters, for the camera; unhandled without one. Out of line:
    /// rare messages, kept from adding to the common path's frame (receive cost per byte).
    #[inline(never)]
    fn camera_message<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        frame: &ReceivedFrame<'_>,
        from: (u8, u8),
        now: Instant,
    ) -> Check {
        let Some(me) = self.camera_component() else {
            return Check::Unhandled;
        };
        let id = frame.message_id();
        // Each is decoded (CRC and payload checked) before its target is looked at.
        let (message, target, broadcast_ok) = if id == id_of::<FileTransferProtocol>() {
            let Some(m) = decode::<FileTransferProtocol>(frame) else {
                return Check::Bad;
            };
            // FTP is a conversation with one server: never broadcast.
            let target = (m.target_system, m.target_component);
            (camera::Message::Ftp(m.payload), target, false)
        } else if id == id_of::<ParamExtSet>() {
            let Some(m) = decode::<ParamExtSet>(frame) else {
                return Check::Bad;
            };
            let target = (m.target_system, m.target_component);
            (camera::Message::ParamSet(m), target, false)
        } else if id == id_of::<ParamExtRequestRead>() {
            let Some(m) = decode::<ParamExtRequestRead>(frame) else {
                return Check::Bad;
            };
            let target = (m.target_system, m.target_component);
            (
                camera::Message::ParamRead(m.param_id, m.param_index),
                target,
                true,
            )
        } else {
            let Some(m) = decode::<ParamExtRequestList>(frame) else {
                return Check::Bad;
            };
            // A list request to every component is answered by each that has parameters.
            (
                camera::Message::ParamList,
                (m.target_system, m.target_component),
                true,
            )
        };
        let for_camera = (target.0 == self.system_id || target.0 == 0 && broadcast_ok)
            && (target.1 == me || target.1 == 0 && broadcast_ok);
        if !for_camera {
            bump(&mut self.stats.not_for_us);
            return Check::Handled;
        }
        self.with_camera(gimbal, |camera, config, gimbal, tx| {
            camera.message(config, gimbal, message, from, now, tx)
        });
        Check::Handled
    }

    fn heartbeat(&mut self, system: u8, component: u8) {
        if component != AUTOPILOT_COMPONENT {
            return;
        }
        if self.autopilot != Some((system, component)) {
            // A new autopilot: ask it for the streams at once.
            self.position_stream.asked = None;
            self.autopilot_state_stream.asked = None;
            self.setpoint_stream.asked = None;
            self.next_stream_check = None;
        }
        self.autopilot = Some((system, component));
        if self.config.system_id.is_none() {
            self.system_id = system;
        }
    }

    fn ack(&mut self, me: u8, to: (u8, u8), command: MavCmd, result: MavResult) {
        bump(&mut self.stats.acks);
        self.send(me, &ack_of(command, result, to));
    }

    fn command<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        from: (u8, u8),
        cmd: &Command,
        now: Instant,
    ) {
        if !self.for_us(cmd.target.0, cmd.target.1) {
            bump(&mut self.stats.not_for_us);
            return;
        }
        let gimbal_id = self.config.gimbal_component;
        let camera_id = self.camera_component();
        let camera_owns = camera_id.is_some() && camera::owns(cmd);
        let gimbal_owns = self.gimbal_owns(cmd);
        // Broadcast: the owner answers, or nobody (another component may own it).
        // Addressed: the addressee answers, UNSUPPORTED if it does not own the command.
        let (me, owner) = match cmd.target.1 {
            0 if gimbal_owns => (gimbal_id, true),
            0 if camera_owns => (camera_id.unwrap_or(gimbal_id), true),
            0 => {
                bump(&mut self.stats.not_for_us);
                return;
            }
            c if c == gimbal_id => (gimbal_id, gimbal_owns || self.gimbal_owns_addressed(cmd)),
            c => (c, camera_owns),
        };
        if !owner {
            self.ack(me, from, cmd.command, MavResult::Unsupported);
            return;
        }
        if me == gimbal_id {
            let result = self.gimbal_command(gimbal, cmd, now);
            self.ack(me, from, cmd.command, result);
            // The information follows the ACK.
            if result == MavResult::Accepted && cmd.command == MavCmd::RequestMessage {
                if cmd.requests(id_of::<GimbalDeviceInformation>()) {
                    self.information(gimbal, now);
                } else {
                    self.status(gimbal, now);
                }
            }
        } else {
            let position = self.vehicle.position;
            let acked = self.with_camera(gimbal, |camera, config, gimbal, tx| {
                let (result, reply) = camera.command(config, gimbal, cmd, now, position);
                // The ACK first, then what the command produced.
                tx.send(me, &ack_of(cmd.command, result, from));
                camera.reply(config, gimbal, reply, now, tx);
            });
            if acked.is_some() {
                bump(&mut self.stats.acks);
            }
        }
    }

    /// Runs `f` with the camera, the gimbal and a sender into the outbox; `None` without a
    /// camera.
    fn with_camera<G: GimbalControl, R>(
        &mut self,
        gimbal: &mut G,
        f: impl FnOnce(&mut Camera, &CameraConfig, &mut G, &mut Tx<'_>) -> R,
    ) -> Option<R> {
        let State {
            camera,
            config,
            out,
            system_id,
            stats,
            vehicle,
            ..
        } = self;
        let (camera, config) = (camera.as_mut()?, config.camera.as_ref()?);
        let mut tx = Tx {
            out,
            system_id: *system_id,
            outbox_full: &mut stats.outbox_full,
            position: vehicle.position,
            gimbal_type: gimbal.gimbal_type(),
        };
        Some(f(camera, config, gimbal, &mut tx))
    }

    /// Commands the gimbal device answers, broadcast or addressed.
    fn gimbal_owns(&self, cmd: &Command) -> bool {
        match cmd.command {
            MavCmd::RequestMessage => {
                cmd.requests(id_of::<GimbalDeviceInformation>())
                    || cmd.requests(id_of::<GimbalDeviceAttitudeStatus>())
            }
            MavCmd::SetMessageInterval => {
                cmd.params[0] == id_of::<GimbalDeviceAttitudeStatus>() as f32
            }
            _ => false,
        }
    }

    /// Commands the gimbal device acts on only when addressed to it: a region of interest
    /// broadcast is the autopilot's (its gimbal manager's) to act on, and it hands the
    /// device only what it decides.
    fn gimbal_owns_addressed(&self, cmd: &Command) -> bool {
        matches!(
            cmd.command,
            MavCmd::DoSetRoiLocation | MavCmd::DoSetRoiNone | MavCmd::PreflightCalibration
        )
    }

    /// A gimbal command's result (the gimbal owns it).
    #[cfg_attr(not(feature = "roi"), allow(unused_variables))]
    fn gimbal_command<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        cmd: &Command,
        now: Instant,
    ) -> MavResult {
        match cmd.command {
            MavCmd::SetMessageInterval => self.set_status_interval(cmd.params[1], now),
            MavCmd::RequestMessage => MavResult::Accepted,
            MavCmd::PreflightCalibration => self.calibrate(gimbal, cmd),
            #[cfg(feature = "roi")]
            MavCmd::DoSetRoiLocation => self.roi_location(gimbal, cmd),
            #[cfg(feature = "roi")]
            MavCmd::DoSetRoiNone => {
                if !self.addresses_this_gimbal(cmd.params[0]) {
                    return MavResult::Denied;
                }
                gimbal.stop_pointing();
                MavResult::Accepted
            }
            _ => MavResult::Unsupported,
        }
    }

    /// `MAV_CMD_PREFLIGHT_CALIBRATION` addressed to the gimbal device: param1 (gyroscope)
    /// 1 and nothing else asked is the gimbal's fast calibration (0x0F 0xF0). common.xml
    /// has no gimbal calibration of its own; the gyroscope's is the one a gimbal's
    /// quick calibration is (its IMU's zero). The gimbal does not report the calibration
    /// running, so `CALIBRATION_RUNNING` is never set in the status.
    fn calibrate<G: GimbalControl>(&mut self, gimbal: &mut G, cmd: &Command) -> MavResult {
        let [gyro, p2, p3, p4] = cmd.params;
        let (p5, p6) = match cmd.xy {
            Xy::Float(a, b) => (a, b),
            Xy::Int(a, b) => (a as f32, b as f32),
        };
        // Unset parameters are 0, or NaN from MAVSDK.
        let unset = |v: f32| v == 0.0 || v.is_nan();
        if gyro != 1.0 || ![p2, p3, p4, p5, p6, cmd.z].into_iter().all(unset) {
            return MavResult::Denied;
        }
        if self.command_gimbal_raw(gimbal, GimbalCommand::FastCalibration) {
            MavResult::Accepted
        } else {
            MavResult::TemporarilyRejected
        }
    }

    #[cfg(feature = "roi")]
    /// Whether a ROI command's param1 (common.xml: "component ID of gimbal device to
    /// address (or 1-6 for non-MAVLink gimbal), 0 for all gimbal device components")
    /// names this gimbal.
    fn addresses_this_gimbal(&self, param1: f32) -> bool {
        param1 == 0.0 || param1 == f32::from(self.config.gimbal_component)
    }

    #[cfg(feature = "roi")]
    /// `MAV_CMD_DO_SET_ROI_LOCATION`: the core's point-at, at the location's height above
    /// mean sea level (the height the vehicle's altitude is pushed in). A height relative
    /// to home needs home's, from GLOBAL_POSITION_INT (alt − relative_alt); a height above
    /// terrain cannot be known here and is refused.
    fn roi_location<G: GimbalControl>(&mut self, gimbal: &mut G, cmd: &Command) -> MavResult {
        if !self.addresses_this_gimbal(cmd.params[0]) {
            return MavResult::Denied;
        }
        let Some((lat, lon)) = cmd.xy.lat_lon_deg() else {
            return MavResult::Denied;
        };
        let amsl_m = match cmd.frame {
            MavFrame::Global | MavFrame::GlobalInt => f64::from(cmd.z),
            MavFrame::GlobalRelativeAlt | MavFrame::GlobalRelativeAltInt => {
                let Some([_, _, alt_mm, rel_mm]) = self.vehicle.position else {
                    // Home's height comes with the position: not yet.
                    return MavResult::TemporarilyRejected;
                };
                f64::from(cmd.z) + f64::from(alt_mm - rel_mm) / 1000.0
            }
            _ => return MavResult::Denied,
        };
        let Ok(target) = Position::new(lat, lon, amsl_m) else {
            return MavResult::Denied;
        };
        gimbal.point_at(target);
        self.pose = Pose::Other;
        self.commanded = (None, None);
        MavResult::Accepted
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
        let gimbal_type = gimbal.gimbal_type();
        let yaw_limit = yaw_limit_deg(gimbal_type).to_radians();
        let info = GimbalDeviceInformation {
            time_boot_ms: now.as_millis(),
            vendor_name: name("IDU"),
            model_name: name(
                gimbal_type
                    .and_then(GimbalType::model_name)
                    .unwrap_or("IDU gimbal"),
            ),
            custom_name: [0; 32],
            firmware_version: 0,
            hardware_version: 0,
            uid: 0,
            cap_flags: GimbalDeviceCapFlags::HAS_NEUTRAL
                | GimbalDeviceCapFlags::HAS_RETRACT
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
            yaw_min: -yaw_limit,
            yaw_max: yaw_limit,
            gimbal_device_id: 0,
        };
        self.send(self.config.gimbal_component, &info);
    }

    fn autopilot_state<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        state: &AutopilotStateForGimbalDevice,
        now: Instant,
    ) {
        self.autopilot_state_stream.heard = Some(now);
        // The vehicle's attitude: 3-2-1 Euler is right here (a vehicle does not pitch past
        // ±90° in flight, and the frame carries roll).
        let [w, x, y, z] = state.q;
        if !state.q.iter().all(|v| v.is_finite()) {
            return;
        }
        let roll = libm::atan2f(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
        let pitch = attitude::asin((2.0 * (w * y - z * x)).clamp(-1.0, 1.0));
        let yaw = libm::atan2f(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
        self.vehicle.yaw = Some((yaw, now));
        // common.xml: "Z component of angular velocity in NED (North, East, Down). NaN if
        // unknown".
        self.vehicle.yaw_rate = state
            .angular_velocity_z
            .is_finite()
            .then_some((state.angular_velocity_z, now));
        // The wire's heading is in [−180°, 180°).
        let heading = yaw.to_degrees().min(179.99);
        if let Ok(a) = Attitude::new(pitch.to_degrees(), roll.to_degrees(), heading) {
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
        self.position_stream.heard = Some(now);
        self.vehicle.position = Some([pos.lat, pos.lon, pos.alt, pos.relative_alt]);
        if let Ok(g) = Gps::from_e7(pos.lat, pos.lon) {
            gimbal.set_gps(g, now);
            bump(&mut self.stats.vehicle_updates);
        }
        // Millimetres above mean sea level to centimetres, rounded toward zero.
        gimbal.set_altitude(Altitude::from_cm(pos.alt / 10), now);
    }

    fn poll<G: GimbalControl>(&mut self, gimbal: &mut G, now: Instant) {
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
            self.send_encoded::<Heartbeat>(
                self.config.gimbal_component,
                codec::heartbeat::LEN,
                |p| codec::heartbeat::encode(&hb, p),
            );
            if let Some(camera) = self.camera_component() {
                let hb = Heartbeat {
                    type_: MavType::Camera,
                    ..hb
                };
                self.send_encoded::<Heartbeat>(camera, codec::heartbeat::LEN, |p| {
                    codec::heartbeat::encode(&hb, p)
                });
            }
        }
        if self.camera.as_ref().is_some_and(|c| c.has_work(now)) {
            self.with_camera(gimbal, |camera, config, gimbal, tx| {
                camera.poll(config, gimbal, now, tx)
            });
        }
        if self.status_ms > 0 && self.next_status.is_none_or(|t| now.is_at_or_after(t)) {
            self.next_status = Some(now.add_millis(self.status_ms));
            self.status(gimbal, now);
        }
        let check_streams = self.next_stream_check.is_none_or(|t| now.is_at_or_after(t));
        if let (Some(ap), true) = (self.autopilot, check_streams) {
            self.next_stream_check = Some(now.add_millis(STREAM_CHECK_MS));
            for (wanted, stream) in [
                (AUTOPILOT_STATE_STREAM, &mut self.autopilot_state_stream),
                (POSITION_STREAM, &mut self.position_stream),
                (SETPOINT_STREAM, &mut self.setpoint_stream),
            ] {
                if !stream.due(&wanted, now) {
                    continue;
                }
                stream.asked = Some(now);
                let ask = CommandLong {
                    target_system: ap.0,
                    target_component: ap.1,
                    command: MavCmd::SetMessageInterval,
                    confirmation: 0,
                    param1: wanted.id as f32,
                    param2: wanted.interval_us as f32,
                    param3: 0.0,
                    param4: 0.0,
                    param5: 0.0,
                    param6: 0.0,
                    param7: 0.0,
                };
                push_counted(
                    &mut self.out,
                    self.system_id,
                    &mut self.stats.outbox_full,
                    self.config.gimbal_component,
                    &ask,
                );
            }
        }
    }

    fn status<G: GimbalControl>(&mut self, gimbal: &G, now: Instant) {
        let latest = gimbal.latest_postback(now).map(|(p, _)| p);
        let vehicle_yaw = self.vehicle.yaw(now);
        let (q, flags) = match latest {
            Some(p) => status::attitude(&p, self.pose),
            None => ([f32::NAN; 4], status::flags(None, self.pose)),
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
            delta_yaw: vehicle_yaw.unwrap_or(f32::NAN),
            delta_yaw_velocity: vehicle_yaw
                .and(self.vehicle.yaw_rate(now))
                .unwrap_or(f32::NAN),
            gimbal_device_id: 0,
        };
        self.send_encoded::<GimbalDeviceAttitudeStatus>(
            self.config.gimbal_component,
            codec::attitude_status::LEN,
            |p| codec::attitude_status::encode(&status, p),
        );
    }

    /// Queues a command for the gimbal other than an angle; a full queue is counted.
    fn command_gimbal_raw<G: GimbalControl>(&mut self, gimbal: &mut G, c: GimbalCommand) -> bool {
        let sent = gimbal.send(GimbalCmd::from(c)).is_ok();
        if !sent {
            bump(&mut self.stats.queue_full);
        }
        sent
    }

    /// Queues a command for the gimbal; a full queue is counted.
    pub(crate) fn command_gimbal<G: GimbalControl>(
        &mut self,
        gimbal: &mut G,
        c: GimbalCommand,
    ) -> bool {
        if gimbal.send(GimbalCmd::from(c)).is_ok() {
            bump(&mut self.stats.angle_commands);
            true
        } else {
            bump(&mut self.stats.queue_full);
            false
        }
    }
}
