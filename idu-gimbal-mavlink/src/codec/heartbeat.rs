//! `HEARTBEAT` (0), sent: 9 bytes.

use mavio::dialects::common::enums::{MavAutopilot, MavModeFlag, MavState, MavType};
use mavio::dialects::common::messages::Heartbeat;

use super::put;

/// The full payload's length.
pub const LEN: usize = 9;

mod field {
    pub const CUSTOM_MODE: usize = 0;
    pub const TYPE: usize = 4;
    pub const AUTOPILOT: usize = 5;
    pub const BASE_MODE: usize = 6;
    pub const SYSTEM_STATUS: usize = 7;
    pub const MAVLINK_VERSION: usize = 8;
}

/// The heartbeat a component of the bridge sends, of type `kind` (`MAV_TYPE_GIMBAL` for the
/// gimbal device, `MAV_TYPE_CAMERA` for the camera): not an autopilot, active, MAVLink 2.
pub const fn of_component(kind: MavType) -> Heartbeat {
    Heartbeat {
        type_: kind,
        autopilot: MavAutopilot::Invalid,
        base_mode: MavModeFlag::empty(),
        custom_mode: 0,
        system_status: MavState::Active,
        mavlink_version: 3,
    }
}

/// Writes the message's payload into `p`, zeroed, its full length ([`LEN`]; nothing is
/// written into a slice of another length).
pub fn encode(m: &Heartbeat, p: &mut [u8]) {
    let Ok(p) = <&mut [u8; LEN]>::try_from(p) else {
        return;
    };
    put(p, field::CUSTOM_MODE, m.custom_mode.to_le_bytes());
    put(p, field::TYPE, [m.type_ as u8]);
    put(p, field::AUTOPILOT, [m.autopilot as u8]);
    put(p, field::BASE_MODE, [m.base_mode.bits()]);
    put(p, field::SYSTEM_STATUS, [m.system_status as u8]);
    put(p, field::MAVLINK_VERSION, [m.mavlink_version]);
}
