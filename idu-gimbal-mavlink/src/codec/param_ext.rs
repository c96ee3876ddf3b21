//! `PARAM_EXT_SET` (323), received, and `PARAM_EXT_ACK` (324), sent, with the parameter
//! type as its raw byte: `mavio`'s types can only carry a `MAV_PARAM_EXT_TYPE` its dialect
//! knows, and a set of any other type must still be answered (`PARAM_ACK_VALUE_UNSUPPORTED`)
//! rather than left to time out.

use super::{bytes, decode_with, put};

/// `PARAM_EXT_SET`'s full payload length.
pub const SET_LEN: usize = 147;
/// `PARAM_EXT_ACK`'s full payload length.
pub const ACK_LEN: usize = 146;

mod set {
    pub const TARGET_SYSTEM: usize = 0;
    pub const TARGET_COMPONENT: usize = 1;
    pub const PARAM_ID: usize = 2;
    pub const PARAM_VALUE: usize = 18;
    pub const PARAM_TYPE: usize = 146;
}

mod ack {
    pub const PARAM_ID: usize = 0;
    pub const PARAM_VALUE: usize = 16;
    pub const PARAM_TYPE: usize = 144;
    pub const PARAM_RESULT: usize = 145;
}

/// A `PARAM_EXT_SET`, its type as sent.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct ParamSet {
    /// Addressed to (system, component).
    pub target: (u8, u8),
    /// The parameter's name, NUL-padded.
    pub param_id: [u8; 16],
    /// The value's bytes, its type's width used.
    pub param_value: [u8; 128],
    /// `MAV_PARAM_EXT_TYPE`, as sent.
    pub param_type: u8,
}

/// Reads a `PARAM_EXT_SET` payload (MAVLink 2's dropped trailing zeros read as 0).
pub fn decode_set(payload: &[u8]) -> ParamSet {
    decode_with::<SET_LEN, _>(payload, |p| {
        let [system] = bytes(p, set::TARGET_SYSTEM);
        let [component] = bytes(p, set::TARGET_COMPONENT);
        let [param_type] = bytes(p, set::PARAM_TYPE);
        ParamSet {
            target: (system, component),
            param_id: bytes(p, set::PARAM_ID),
            param_value: bytes(p, set::PARAM_VALUE),
            param_type,
        }
    })
}

/// Writes a `PARAM_EXT_ACK` payload into `p`, zeroed, its full length ([`ACK_LEN`];
/// nothing is written into a slice of another length).
pub fn encode_ack(
    param_id: &[u8; 16],
    param_value: &[u8; 128],
    param_type: u8,
    param_result: u8,
    p: &mut [u8],
) {
    let Ok(p) = <&mut [u8; ACK_LEN]>::try_from(p) else {
        return;
    };
    put(p, ack::PARAM_ID, *param_id);
    put(p, ack::PARAM_VALUE, *param_value);
    put(p, ack::PARAM_TYPE, [param_type]);
    put(p, ack::PARAM_RESULT, [param_result]);
}
