//! `GLOBAL_POSITION_INT` (33), received: 28 bytes.

use mavio::dialects::common::messages::GlobalPositionInt;

use super::{bytes, decode_with, i32_at, u16_at, u32_at};

/// The full payload's length.
pub const LEN: usize = 28;

mod field {
    pub const TIME_BOOT_MS: usize = 0;
    pub const LAT: usize = 4;
    pub const LON: usize = 8;
    pub const ALT: usize = 12;
    pub const RELATIVE_ALT: usize = 16;
    pub const VX: usize = 20;
    pub const VY: usize = 22;
    pub const VZ: usize = 24;
    pub const HDG: usize = 26;
}

/// The message in `payload` (as received: possibly truncated).
pub fn decode(payload: &[u8]) -> GlobalPositionInt {
    decode_with::<LEN, _>(payload, |p| {
        let i16_at = |at| i16::from_le_bytes(bytes(p, at));
        GlobalPositionInt {
            time_boot_ms: u32_at(p, field::TIME_BOOT_MS),
            lat: i32_at(p, field::LAT),
            lon: i32_at(p, field::LON),
            alt: i32_at(p, field::ALT),
            relative_alt: i32_at(p, field::RELATIVE_ALT),
            vx: i16_at(field::VX),
            vy: i16_at(field::VY),
            vz: i16_at(field::VZ),
            hdg: u16_at(p, field::HDG),
        }
    })
}
