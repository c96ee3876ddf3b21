//! `GIMBAL_DEVICE_SET_ATTITUDE` (284), received: 32 bytes.

use mavio::dialects::common::enums::GimbalDeviceFlags;
use mavio::dialects::common::messages::GimbalDeviceSetAttitude;

use super::{decode_with, f32_at, quaternion_at, u16_at, u8_at};

/// The full payload's length.
pub const LEN: usize = 32;

mod field {
    pub const Q: usize = 0;
    pub const ANGULAR_VELOCITY_X: usize = 16;
    pub const ANGULAR_VELOCITY_Y: usize = 20;
    pub const ANGULAR_VELOCITY_Z: usize = 24;
    pub const FLAGS: usize = 28;
    pub const TARGET_SYSTEM: usize = 30;
    pub const TARGET_COMPONENT: usize = 31;
}

/// The message in `payload` (as received: possibly truncated).
pub fn decode(payload: &[u8]) -> GimbalDeviceSetAttitude {
    decode_with::<LEN, _>(payload, |p| GimbalDeviceSetAttitude {
        target_system: u8_at(p, field::TARGET_SYSTEM),
        target_component: u8_at(p, field::TARGET_COMPONENT),
        flags: GimbalDeviceFlags::from_bits_truncate(u16_at(p, field::FLAGS)),
        q: quaternion_at(p, field::Q),
        angular_velocity_x: f32_at(p, field::ANGULAR_VELOCITY_X),
        angular_velocity_y: f32_at(p, field::ANGULAR_VELOCITY_Y),
        angular_velocity_z: f32_at(p, field::ANGULAR_VELOCITY_Z),
    })
}
