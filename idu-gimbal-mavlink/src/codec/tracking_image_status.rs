//! `CAMERA_TRACKING_IMAGE_STATUS` (275), sent: 31 bytes and the 1-byte `camera_device_id`
//! extension.

use mavio::dialects::common::messages::CameraTrackingImageStatus;

use super::put;

/// The full payload's length.
pub const LEN: usize = 32;

mod field {
    pub const POINT_X: usize = 0;
    pub const POINT_Y: usize = 4;
    pub const RADIUS: usize = 8;
    pub const REC_TOP_X: usize = 12;
    pub const REC_TOP_Y: usize = 16;
    pub const REC_BOTTOM_X: usize = 20;
    pub const REC_BOTTOM_Y: usize = 24;
    pub const TRACKING_STATUS: usize = 28;
    pub const TRACKING_MODE: usize = 29;
    pub const TARGET_DATA: usize = 30;
    pub const CAMERA_DEVICE_ID: usize = 31;
}

/// Writes the message's payload into `p`, zeroed, its full length ([`LEN`]; nothing is
/// written into a slice of another length).
pub fn encode(m: &CameraTrackingImageStatus, p: &mut [u8]) {
    let Ok(p) = <&mut [u8; LEN]>::try_from(p) else {
        return;
    };
    put(p, field::POINT_X, m.point_x.to_le_bytes());
    put(p, field::POINT_Y, m.point_y.to_le_bytes());
    put(p, field::RADIUS, m.radius.to_le_bytes());
    put(p, field::REC_TOP_X, m.rec_top_x.to_le_bytes());
    put(p, field::REC_TOP_Y, m.rec_top_y.to_le_bytes());
    put(p, field::REC_BOTTOM_X, m.rec_bottom_x.to_le_bytes());
    put(p, field::REC_BOTTOM_Y, m.rec_bottom_y.to_le_bytes());
    put(p, field::TRACKING_STATUS, [m.tracking_status as u8]);
    put(p, field::TRACKING_MODE, [m.tracking_mode as u8]);
    put(p, field::TARGET_DATA, [m.target_data.bits()]);
    put(p, field::CAMERA_DEVICE_ID, [m.camera_device_id]);
}
