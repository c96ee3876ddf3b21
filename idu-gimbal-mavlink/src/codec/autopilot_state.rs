//! `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE` (286), received: 53 bytes and the 4-byte
//! `angular_velocity_z` extension.

use mavio::dialects::common::enums::{EstimatorStatusFlags, MavLandedState};
use mavio::dialects::common::messages::AutopilotStateForGimbalDevice;

use super::{decode_with, f32_at, quaternion_at, u16_at, u32_at, u8_at};

/// The full payload's length.
pub const LEN: usize = 57;

/// The payload's length before the `angular_velocity_z` extension: a payload no longer was
/// sent without the rate, or with a rate of +0.0 (MAVLink 2 drops trailing zeros), which
/// PX4 sends, never setting it.
pub const LEN_WITHOUT_RATE: usize = 53;

mod field {
    pub const TIME_BOOT_US: usize = 0;
    pub const Q: usize = 8;
    pub const Q_ESTIMATED_DELAY_US: usize = 24;
    pub const VX: usize = 28;
    pub const VY: usize = 32;
    pub const VZ: usize = 36;
    pub const V_ESTIMATED_DELAY_US: usize = 40;
    pub const FEED_FORWARD_ANGULAR_VELOCITY_Z: usize = 44;
    pub const ESTIMATOR_STATUS: usize = 48;
    pub const TARGET_SYSTEM: usize = 50;
    pub const TARGET_COMPONENT: usize = 51;
    pub const LANDED_STATE: usize = 52;
    pub const ANGULAR_VELOCITY_Z: usize = 53;
}

/// The message in `payload` (as received: possibly truncated); `None` for a landed state
/// outside the dialect.
pub fn decode(payload: &[u8]) -> Option<AutopilotStateForGimbalDevice> {
    decode_with::<LEN, _>(payload, |p| {
        let time_boot_us = u64::from(u32_at(p, field::TIME_BOOT_US))
            | u64::from(u32_at(p, field::TIME_BOOT_US + 4)) << 32;
        Some(AutopilotStateForGimbalDevice {
            target_system: u8_at(p, field::TARGET_SYSTEM),
            target_component: u8_at(p, field::TARGET_COMPONENT),
            time_boot_us,
            q: quaternion_at(p, field::Q),
            q_estimated_delay_us: u32_at(p, field::Q_ESTIMATED_DELAY_US),
            vx: f32_at(p, field::VX),
            vy: f32_at(p, field::VY),
            vz: f32_at(p, field::VZ),
            v_estimated_delay_us: u32_at(p, field::V_ESTIMATED_DELAY_US),
            feed_forward_angular_velocity_z: f32_at(p, field::FEED_FORWARD_ANGULAR_VELOCITY_Z),
            estimator_status: EstimatorStatusFlags::from_bits_truncate(u16_at(
                p,
                field::ESTIMATOR_STATUS,
            )),
            landed_state: MavLandedState::try_from(u8_at(p, field::LANDED_STATE)).ok()?,
            angular_velocity_z: f32_at(p, field::ANGULAR_VELOCITY_Z),
        })
    })
}
