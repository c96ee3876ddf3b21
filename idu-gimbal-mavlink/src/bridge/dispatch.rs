//! What comes in: each frame to what handles its message, after its checksum; each command
//! to the component that owns it, with exactly one `COMMAND_ACK` for every command addressed
//! to one of the bridge's components.

#[cfg(feature = "roi")]
use idu_gimbal::geo::Position;
use idu_gimbal::wire::control::GimbalCommand;
use idu_gimbal::Instant;
#[cfg(feature = "roi")]
use mavio::dialects::common::enums::MavFrame;
use mavio::dialects::common::enums::{MavCmd, MavResult};
use mavio::dialects::common::messages::{
    AutopilotStateForGimbalDevice, CommandInt, CommandLong, FileTransferProtocol,
    GimbalDeviceAttitudeStatus, GimbalDeviceInformation, GimbalDeviceSetAttitude,
    GlobalPositionInt, Heartbeat, ParamExtRequestList, ParamExtRequestRead, ParamExtSet,
};
use mavio::mavspec::rust::spec::MessageSpecStatic;

use super::{State, ANSWER_ROOM};
use crate::camera;
use crate::codec;
use crate::command::{Command, Interval, Xy};
use crate::framing::{Check, ReceivedFrame};
#[cfg(feature = "roi")]
use crate::status::Pose;
use crate::tx::{bump, id_of};
use idu_gimbal::link::{Link, Medium};

/// Decodes `frame` as `M` when its CRC holds with `M`'s `CRC_EXTRA`.
fn decode<M>(frame: &ReceivedFrame<'_>) -> Option<M>
where
    M: MessageSpecStatic + for<'p> TryFrom<&'p mavio::protocol::Payload>,
{
    frame.decode::<M>().ok()
}

/// The `CRC_EXTRA` of a message the bridge handles, by id.
#[cfg(feature = "signing")]
fn crc_extra_of(id: u32) -> Option<u8> {
    [
        (
            id_of::<AutopilotStateForGimbalDevice>(),
            AutopilotStateForGimbalDevice::crc_extra(),
        ),
        (
            id_of::<GimbalDeviceSetAttitude>(),
            GimbalDeviceSetAttitude::crc_extra(),
        ),
        (id_of::<Heartbeat>(), Heartbeat::crc_extra()),
        (id_of::<CommandLong>(), CommandLong::crc_extra()),
        (id_of::<CommandInt>(), CommandInt::crc_extra()),
        (id_of::<GlobalPositionInt>(), GlobalPositionInt::crc_extra()),
        (
            id_of::<FileTransferProtocol>(),
            FileTransferProtocol::crc_extra(),
        ),
        (id_of::<ParamExtSet>(), ParamExtSet::crc_extra()),
        (
            id_of::<ParamExtRequestRead>(),
            ParamExtRequestRead::crc_extra(),
        ),
        (
            id_of::<ParamExtRequestList>(),
            ParamExtRequestList::crc_extra(),
        ),
    ]
    .into_iter()
    .find_map(|(m, extra)| (m == id).then_some(extra))
}

impl State {
    /// A whole frame from the reader: acted on when the outbox has room for the most it can
    /// ask ([`ANSWER_ROOM`]), else it waits, so that no answer is promised and then dropped.
    pub(super) fn take<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        frame: &ReceivedFrame<'_>,
        now: Instant,
    ) -> Check {
        if self.out.room() < ANSWER_ROOM {
            return Check::Wait;
        }
        self.dispatch(gimbal, frame, now)
    }

    // Out of line: decoding needs a large stack frame (mavio's 255-byte payload and the
    // message), which would otherwise be set up on every `receive` call, a frame or not.
    #[inline(never)]
    pub(super) fn dispatch<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        frame: &ReceivedFrame<'_>,
        now: Instant,
    ) -> Check {
        let id = frame.message_id();
        // Signing: only frames signed with the key, newer than their stream's last. A
        // message the bridge knows whose checksum fails is a corrupt frame, not a forged
        // one: found bad first, so that the reader reads past it byte by byte (taken whole,
        // a length changed in transit would swallow the frames after it).
        #[cfg(feature = "signing")]
        if let Some(signing) = self.out.outbox.signing_mut() {
            if crc_extra_of(id).is_some_and(|extra| !frame.checksum_holds(extra)) {
                return Check::Bad;
            }
            let (system, component) = (frame.system_id(), frame.component_id());
            if !signing.verify(frame.bytes(), frame.is_signed(), system, component) {
                return Check::Unhandled;
            }
        }
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
            // The followed autopilot's only (PX4 addresses it to every component; another
            // vehicle's, on a shared link, would move this one's horizon and north).
            if self.for_gimbal(state.target_system, state.target_component)
                && self.autopilot == Some(from)
            {
                let rate_sent = frame.payload().len() > codec::autopilot_state::LEN_WITHOUT_RATE;
                self.autopilot_state(gimbal, &state, rate_sent, now);
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
            // Checked for its CRC; who sent it matters, and which autopilot it is.
            if !frame.checksum_holds(Heartbeat::crc_extra()) {
                return Check::Bad;
            }
            // MAVLink 2 drops trailing zeros only: `autopilot` (offset 5) is followed by
            // `mavlink_version`, never 0, so it is there; absent it reads as 0 (generic).
            let autopilot = frame.payload().get(5).copied().unwrap_or(0);
            self.heartbeat(from.0, from.1, autopilot, now);
        } else if id == id_of::<CommandLong>() {
            let Some(cmd) = decode::<CommandLong>(frame) else {
                return self.undecodable_command(frame, CommandLong::crc_extra(), from);
            };
            self.command(gimbal, from, &Command::from(&cmd), now);
        } else if id == id_of::<CommandInt>() {
            let Some(cmd) = decode::<CommandInt>(frame) else {
                return self.undecodable_command(frame, CommandInt::crc_extra(), from);
            };
            self.command(gimbal, from, &Command::from(&cmd), now);
        } else if id == id_of::<GlobalPositionInt>() {
            if !frame.checksum_holds(GlobalPositionInt::crc_extra()) {
                return Check::Bad;
            }
            let pos = codec::global_position::decode(frame.payload());
            // Broadcast: the followed autopilot's only (another vehicle's, on a shared
            // link, would move this one's GPS).
            if self.autopilot == Some(from) {
                self.position(gimbal, &pos, now);
            } else {
                bump(&mut self.stats.not_for_us);
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
    pub(super) fn camera_message<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
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
            // Decoded here whatever its type (mavio's refuses a type its dialect does not
            // know): a set of an unknown type is still answered.
            if !frame.checksum_holds(ParamExtSet::crc_extra()) {
                return Check::Bad;
            }
            let m = codec::param_ext::decode_set(frame.payload());
            (camera::Message::ParamSet(m), m.target, false)
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
        let for_camera = (target.0 == self.out.system_id || target.0 == 0 && broadcast_ok)
            && (target.1 == me || target.1 == 0 && broadcast_ok);
        if !for_camera {
            bump(&mut self.stats.not_for_us);
            return Check::Handled;
        }
        self.with_camera(gimbal, now, |camera, config, gimbal, tx| {
            camera.message(config, gimbal, message, from, now, tx)
        });
        Check::Handled
    }

    /// A `COMMAND_LONG` or `COMMAND_INT` whose checksum holds but that `mavio` cannot
    /// decode: a command id or (`COMMAND_INT`) a frame its dialect does not know. Addressed
    /// to the gimbal or the camera, it is answered `UNSUPPORTED`, as PX4 answers, so that
    /// the sender does not wait out its timeouts; broadcast, it may be another's.
    #[inline(never)]
    fn undecodable_command(
        &mut self,
        frame: &ReceivedFrame<'_>,
        crc_extra: u8,
        from: (u8, u8),
    ) -> Check {
        if !frame.checksum_holds(crc_extra) {
            return Check::Bad;
        }
        // Both messages: `command` at 28 (u16), `target_system` at 30, `target_component`
        // at 31 (MAVLink's wire order); MAVLink 2's dropped trailing zeros read as 0.
        let byte = |at: usize| frame.payload().get(at).copied().unwrap_or(0);
        let command = u16::from_le_bytes([byte(28), byte(29)]);
        let (system, component) = (byte(30), byte(31));
        if component == 0 || !self.for_us(system, component) {
            bump(&mut self.stats.not_for_us);
        } else {
            self.ack(component, from, command, MavResult::Unsupported);
        }
        Check::Handled
    }

    pub(super) fn command<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
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
            self.ack(me, from, cmd.command as u16, MavResult::Unsupported);
            return;
        }
        if me == gimbal_id {
            let result = self.gimbal_command(gimbal, cmd, now);
            self.ack(me, from, cmd.command as u16, result);
            // The information follows the ACK.
            if result == MavResult::Accepted && cmd.command == MavCmd::RequestMessage {
                if cmd.requests(id_of::<GimbalDeviceInformation>()) {
                    self.information(gimbal, now);
                } else {
                    self.status(gimbal, now);
                }
            }
        } else {
            let vantage = self.vantage(gimbal, now);
            let acked = self.with_camera(gimbal, now, |camera, config, gimbal, tx| {
                let (result, reply) = camera.command(config, gimbal, cmd, from, now, vantage);
                // The ACK first, then what the command produced.
                tx.out.ack(me, cmd.command as u16, result, from);
                camera.reply(config, gimbal, reply, now, tx);
            });
            if acked.is_some() {
                bump(&mut self.stats.acks);
            }
        }
    }

    /// Commands the gimbal device answers, broadcast or addressed.
    pub(super) fn gimbal_owns(&self, cmd: &Command) -> bool {
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
    pub(super) fn gimbal_owns_addressed(&self, cmd: &Command) -> bool {
        matches!(
            cmd.command,
            MavCmd::DoSetRoiLocation | MavCmd::DoSetRoiNone | MavCmd::PreflightCalibration
        )
    }

    /// A gimbal command's result (the gimbal owns it).
    #[cfg_attr(not(feature = "roi"), allow(unused_variables))]
    pub(super) fn gimbal_command<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
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
    pub(super) fn calibrate<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        cmd: &Command,
    ) -> MavResult {
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
    pub(super) fn addresses_this_gimbal(&self, param1: f32) -> bool {
        param1 == 0.0 || param1 == f32::from(self.config.gimbal_component)
    }

    #[cfg(feature = "roi")]
    /// `MAV_CMD_DO_SET_ROI_LOCATION`: the core's point-at, at the location's height above
    /// mean sea level (the height the vehicle's altitude is pushed in). A height relative
    /// to home needs home's, from GLOBAL_POSITION_INT (alt − relative_alt); a height above
    /// terrain cannot be known here and is refused.
    pub(super) fn roi_location<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &mut Link<Q, T, M>,
        cmd: &Command,
    ) -> MavResult {
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
                // In f64, exact: an autopilot's two i32s can differ by more than an i32.
                f64::from(cmd.z) + (f64::from(alt_mm) - f64::from(rel_mm)) / 1000.0
            }
            _ => return MavResult::Denied,
        };
        let Ok(target) = Position::new(lat, lon, amsl_m) else {
            return MavResult::Denied;
        };
        gimbal.point_at(target);
        self.pose = Pose::Other;
        self.rate_earth = false;
        MavResult::Accepted
    }

    /// `MAV_CMD_SET_MESSAGE_INTERVAL` for the attitude status: µs; −1 stops it, 0 restores
    /// the configured default. Below 1 ms or above a minute is out of range.
    pub(super) fn set_status_interval(&mut self, interval_us: f32, now: Instant) -> MavResult {
        self.status_ms = match Interval::from_us(interval_us) {
            Some(Interval::Stop) => 0,
            Some(Interval::Default) => self.config.attitude_status_ms(),
            Some(Interval::Every(ms)) => ms,
            None => return MavResult::Denied,
        };
        self.next_status = Some(now);
        MavResult::Accepted
    }
}
