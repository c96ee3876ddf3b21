//! The gimbal device's own messages: its heartbeats (and the camera's), its information,
//! and the attitude status from the latest postback.

use idu_gimbal::wire::postback::GimbalType;
use idu_gimbal::Instant;
use mavio::dialects::common::enums::{
    GimbalDeviceCapFlags, GimbalDeviceErrorFlags, MavAutopilot, MavModeFlag, MavState, MavType,
};
use mavio::dialects::common::messages::{
    GimbalDeviceAttitudeStatus, GimbalDeviceInformation, Heartbeat,
};

use super::{name, State, PITCH_MAX_DEG, PITCH_MIN_DEG};
use crate::codec;
use crate::gimbal::GimbalControl;
use crate::status;

/// The yaw motor's range either side of the nose, degrees: the postback's ±170.00°, or
/// ±325.00° on the 3.5× models (the document's Motor_psi scope).
pub fn yaw_limit_deg(t: Option<GimbalType>) -> f32 {
    match t {
        Some(GimbalType::Zoom3_5x | GimbalType::DualLight3_5x) => 325.0,
        _ => 170.0,
    }
}

impl State {
    /// The heartbeats, when due: the gimbal device's and, with one, the camera's.
    pub(super) fn send_heartbeats(&mut self, now: Instant) {
        if !self.next_heartbeat.is_none_or(|t| now.is_at_or_after(t)) {
            return;
        }
        self.next_heartbeat = Some(now.add_millis(self.config.heartbeat_ms.max(1)));
        let hb = Heartbeat {
            type_: MavType::Gimbal,
            autopilot: MavAutopilot::Invalid,
            base_mode: MavModeFlag::empty(),
            custom_mode: 0,
            system_status: MavState::Active,
            mavlink_version: 3,
        };
        self.send_encoded::<Heartbeat>(self.config.gimbal_component, codec::heartbeat::LEN, |p| {
            codec::heartbeat::encode(&hb, p)
        });
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

    pub(super) fn information<G: GimbalControl>(&mut self, gimbal: &G, now: Instant) {
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

    pub(super) fn status<G: GimbalControl>(&mut self, gimbal: &G, now: Instant) {
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
}
