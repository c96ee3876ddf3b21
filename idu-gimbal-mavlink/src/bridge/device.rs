//! The gimbal device's own messages: its heartbeats (and the camera's), its information,
//! and the attitude status from the latest postback.

use idu_gimbal::wire::postback::GimbalType;
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{
    GimbalDeviceCapFlags, GimbalDeviceErrorFlags, MavSeverity, MavType,
};
use mavio::dialects::common::messages::{
    GimbalDeviceAttitudeStatus, GimbalDeviceInformation, Heartbeat, Statustext,
};

use idu_gimbal::wire::control::Pitch;

use super::State;
use crate::codec;
use crate::status;
use crate::tx::name;
use idu_gimbal::link::aim::AimState;
use idu_gimbal::link::{Link, Medium};

/// The yaw motor's range either side of the nose, degrees: the postback's ±170.00°, or
/// ±325.00° on the 3.5× models (the document's Motor_psi scope,
/// [`GimbalType::motor_yaw_limit_cdeg`]); ±170° until a postback names the model.
pub fn yaw_limit_deg(t: Option<GimbalType>) -> f32 {
    f32::from(t.unwrap_or_default().motor_yaw_limit_cdeg()) / 100.0
}

/// Which of an aim's troubles a `STATUSTEXT` has said (see [`State::tell_aim`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub(crate) struct AimTold {
    at_yaw_limit: bool,
    not_reached: bool,
}

/// What the gimbal device can do (`GIMBAL_DEVICE_INFORMATION.cap_flags`): two axes, pitch and
/// yaw, each locked or (yaw) following, a yaw in the earth frame, neutral and retract; no
/// roll axis, no endless yaw, no RC inputs.
const CAP_FLAGS: GimbalDeviceCapFlags = GimbalDeviceCapFlags::HAS_NEUTRAL
    .union(GimbalDeviceCapFlags::HAS_RETRACT)
    .union(GimbalDeviceCapFlags::HAS_PITCH_AXIS)
    .union(GimbalDeviceCapFlags::HAS_PITCH_LOCK)
    .union(GimbalDeviceCapFlags::HAS_YAW_AXIS)
    .union(GimbalDeviceCapFlags::HAS_YAW_FOLLOW)
    .union(GimbalDeviceCapFlags::HAS_YAW_LOCK)
    .union(GimbalDeviceCapFlags::SUPPORTS_YAW_IN_EARTH_FRAME);

impl State {
    /// Says in a `STATUSTEXT` (severity warning, from the gimbal device) when the aim held
    /// begins to need the yaw beyond the motor's travel, or is not reached: the failure
    /// flags carry the first (`AT_YAW_LIMIT`), but no flag the second, and ground stations
    /// show a status text to the pilot (QGroundControl as a message, ArduPilot and PX4
    /// forward it). Once each time it begins; looked at with each status and each
    /// heartbeat (so also with the status stopped), a text the outbox had no room for at
    /// the next look.
    fn tell_aim(&mut self, aim: Option<AimState>) {
        let now = AimTold {
            at_yaw_limit: aim.is_some_and(|a| a.at_yaw_limit),
            not_reached: aim.is_some_and(|a| a.not_reached),
        };
        // A trouble that has ended is told again when it begins again.
        self.aim_told.not_reached &= now.not_reached;
        self.aim_told.at_yaw_limit &= now.at_yaw_limit;
        // The text says how many re-commands the link makes.
        const _: () = assert!(idu_gimbal::link::aim::ATTEMPTS == 3);
        if now.not_reached && !self.aim_told.not_reached {
            self.aim_told.not_reached = self.warn("Gimbal: setpoint not reached, re-sent 3 times");
        }
        if now.at_yaw_limit && !self.aim_told.at_yaw_limit {
            self.aim_told.at_yaw_limit =
                self.warn("Gimbal: setpoint beyond yaw travel, held at limit");
        }
    }

    /// A warning `STATUSTEXT` from the gimbal device; whether the outbox took it.
    fn warn(&mut self, text: &str) -> bool {
        let message = Statustext {
            severity: MavSeverity::Warning,
            text: name(text),
            id: 0,
            chunk_seq: 0,
        };
        self.out.send_encoded::<Statustext>(
            self.config.gimbal_component,
            codec::statustext::LEN,
            |p| codec::statustext::encode(&message, p),
        )
    }

    /// The heartbeats, when due: the gimbal device's and, with one, the camera's once its
    /// identity is known (`camera_known`: the postback gave the gimbal type). Ground
    /// stations read a camera's identity once, at its first heartbeat, and name its cached
    /// definition after it (QGroundControl's `QGCCameraManager`), so the camera is not
    /// announced under a provisional one.
    pub(super) fn send_heartbeats<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &Link<Q, T, M>,
        now: Instant,
    ) {
        if !self.next_heartbeat.is_none_or(|t| now.is_at_or_after(t)) {
            return;
        }
        // The camera's identity is its gimbal type's: asked only when a heartbeat is due.
        let camera_known = gimbal.gimbal_type().is_some();
        self.next_heartbeat = Some(now.add_millis(self.config.heartbeat.millis()));
        // With the status stopped, the aim's troubles are still told.
        self.tell_aim(gimbal.aim_state());
        let hb = codec::heartbeat::of_component(MavType::Gimbal);
        self.out.send_encoded::<Heartbeat>(
            self.config.gimbal_component,
            codec::heartbeat::LEN,
            |p| codec::heartbeat::encode(&hb, p),
        );
        if let (Some(camera), true) = (self.camera_component(), camera_known) {
            let hb = codec::heartbeat::of_component(MavType::Camera);
            self.out
                .send_encoded::<Heartbeat>(camera, codec::heartbeat::LEN, |p| {
                    codec::heartbeat::encode(&hb, p)
                });
        }
    }

    pub(super) fn information<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &Link<Q, T, M>,
        now: Instant,
    ) {
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
            cap_flags: CAP_FLAGS,
            custom_cap_flags: 0,
            // No roll axis: unknown, as the message says to give it.
            roll_min: f32::NAN,
            roll_max: f32::NAN,
            pitch_min: Pitch::MIN_DEG.to_radians(),
            pitch_max: Pitch::MAX_DEG.to_radians(),
            yaw_min: -yaw_limit,
            yaw_max: yaw_limit,
            gimbal_device_id: 0,
        };
        self.out.send(self.config.gimbal_component, &info);
    }

    pub(super) fn status<const Q: usize, const T: usize, M: Medium>(
        &mut self,
        gimbal: &Link<Q, T, M>,
        now: Instant,
    ) {
        let latest = gimbal.latest_postback(now).map(|(p, _)| p);
        let held = status::Held {
            pose: self.pose,
            earth_yaw: self.holds_earth_yaw(gimbal),
        };
        let mut failure = GimbalDeviceErrorFlags::empty();
        if !gimbal.is_link_up() {
            failure |= GimbalDeviceErrorFlags::COMMS_ERROR;
        }
        let aim = gimbal.aim_state();
        if aim.is_some_and(|a| a.at_yaw_limit) {
            failure |= GimbalDeviceErrorFlags::AT_YAW_LIMIT;
        }
        // The motor angle now, not at the postback (up to 500 ms old): QGroundControl and
        // ArduPilot add the vehicle's heading now to the status's yaw. `delta_yaw`, the
        // heading now, then relates the two frames now (`q_earth = q_delta_yaw · q_vehicle`).
        let heading = self.vehicle.yaw(now);
        let turned = match (self.postback_heading(gimbal, now), heading) {
            (Some(then), Some(now)) => then - now,
            _ => 0.0,
        };
        let q = latest.map_or([f32::NAN; 4], |p| status::attitude_turned(&p, turned));
        let flags = status::flags(held);
        self.tell_aim(aim);
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
            delta_yaw: heading.unwrap_or(f32::NAN),
            delta_yaw_velocity: heading.and(self.vehicle.yaw_rate(now)).unwrap_or(f32::NAN),
            gimbal_device_id: 0,
        };
        self.out.send_encoded::<GimbalDeviceAttitudeStatus>(
            self.config.gimbal_component,
            codec::attitude_status::LEN,
            |p| codec::attitude_status::encode(&status, p),
        );
    }
}
