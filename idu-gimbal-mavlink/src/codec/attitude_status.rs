//! `GIMBAL_DEVICE_ATTITUDE_STATUS` (285), sent: 40 bytes and the 9 bytes of its extensions
//! (`delta_yaw`, `delta_yaw_velocity`, `gimbal_device_id`).

use mavio::dialects::common::messages::GimbalDeviceAttitudeStatus;

use super::put;

/// The full payload's length.
pub const LEN: usize = 49;

mod field {
    pub const TIME_BOOT_MS: usize = 0;
    pub const Q: usize = 4;
    pub const ANGULAR_VELOCITY_X: usize = 20;
    pub const ANGULAR_VELOCITY_Y: usize = 24;
    pub const ANGULAR_VELOCITY_Z: usize = 28;
    pub const FAILURE_FLAGS: usize = 32;
    pub const FLAGS: usize = 36;
    pub const TARGET_SYSTEM: usize = 38;
    pub const TARGET_COMPONENT: usize = 39;
    pub const DELTA_YAW: usize = 40;
    pub const DELTA_YAW_VELOCITY: usize = 44;
    pub const GIMBAL_DEVICE_ID: usize = 48;
}

/// Writes the message's payload into `p`, zeroed, its full length ([`LEN`]; nothing is
/// written into a slice of another length).
pub fn encode(m: &GimbalDeviceAttitudeStatus, p: &mut [u8]) {
    let Ok(p) = <&mut [u8; LEN]>::try_from(p) else {
        return;
    };
    put(p, field::TIME_BOOT_MS, m.time_boot_ms.to_le_bytes());
    for (at, q) in [field::Q, field::Q + 4, field::Q + 8, field::Q + 12]
        .into_iter()
        .zip(m.q)
    {
        put(p, at, q.to_le_bytes());
    }
    put(
        p,
        field::ANGULAR_VELOCITY_X,
        m.angular_velocity_x.to_le_bytes(),
    );
    put(
        p,
        field::ANGULAR_VELOCITY_Y,
        m.angular_velocity_y.to_le_bytes(),
    );
    put(
        p,
        field::ANGULAR_VELOCITY_Z,
        m.angular_velocity_z.to_le_bytes(),
    );
    // A uint32_t on the wire; mavio keeps the flags in 16 bits (none is higher).
    put(
        p,
        field::FAILURE_FLAGS,
        u32::from(m.failure_flags.bits()).to_le_bytes(),
    );
    put(p, field::FLAGS, m.flags.bits().to_le_bytes());
    put(p, field::TARGET_SYSTEM, [m.target_system]);
    put(p, field::TARGET_COMPONENT, [m.target_component]);
    put(p, field::DELTA_YAW, m.delta_yaw.to_le_bytes());
    put(
        p,
        field::DELTA_YAW_VELOCITY,
        m.delta_yaw_velocity.to_le_bytes(),
    );
    put(p, field::GIMBAL_DEVICE_ID, [m.gimbal_device_id]);
}
