//! Payload codecs written out for the messages on the bridge's hot paths: the ones received
//! many times a second (`GIMBAL_DEVICE_SET_ATTITUDE`, `AUTOPILOT_STATE_FOR_GIMBAL_DEVICE`,
//! `GLOBAL_POSITION_INT`) and the ones sent on a period (`GIMBAL_DEVICE_ATTITUDE_STATUS`,
//! `HEARTBEAT`, `CAMERA_TRACKING_IMAGE_STATUS`), `COMMAND_ACK` (for any command id, known to
//! `mavio` or not), `PARAM_EXT_SET` and `PARAM_EXT_ACK` (for any parameter type), and `STATUSTEXT` (written in a few stores
//! where `mavio`'s generic encoder took 272 bytes of flash).
//!
//! Why not `mavio`'s generated code for these: it builds a `Payload` (a zeroed 255-byte
//! buffer, the fields written through a generic byte writer, then copied) for every message
//! either way, which on the Cortex-M4 cost about 22 instructions a received byte and most
//! of the 5,100 a status poll took (`BENCHMARKS.md`). Here each payload is the message's
//! own length, on the stack, and its fields are read or written at their offsets. The
//! types stay `mavio`'s (each codec takes or gives `mavio`'s message struct), and so do
//! the message ids and `CRC_EXTRA`s; every other message is still `mavio`'s to encode and
//! decode.
//!
//! The offsets are MAVLink's wire order (fields by size, largest first, then the
//! extensions in the order declared), as the C library pymavlink generates lays them out;
//! `tests/codec.rs` holds every codec to `mavio`'s on arbitrary messages (every bit of
//! every field, NaNs included) and on payloads truncated anywhere, and the MCU bench
//! checks the C library decodes what these encode.
//!
//! Decoding behaves as `mavio`'s does: a truncated payload reads as zeros beyond its end
//! (MAVLink 2 drops trailing zero bytes), bitmask fields keep only the dialect's bits
//! (`from_bits_truncate`), and an enum value outside the dialect refuses the message.

pub mod attitude_status;
pub mod autopilot_state;
pub mod command_ack;
pub mod global_position;
pub mod heartbeat;
pub mod param_ext;
pub mod set_attitude;
pub mod statustext;
pub mod tracking_image_status;

/// Decodes `payload` with `full`, which reads a whole `L`-byte payload: in place when the
/// payload is whole (the common case: the hot messages end in fields that are rarely
/// zero), else from a copy zero-extended to `L` bytes (MAVLink 2 dropped its trailing
/// zeros). Bytes beyond `L` (a newer sender's extensions) are ignored, as `mavio` does.
#[inline(always)]
fn decode_with<const L: usize, T>(payload: &[u8], full: impl Fn(&[u8; L]) -> T) -> T {
    match payload.get(..L).and_then(|p| <&[u8; L]>::try_from(p).ok()) {
        Some(p) => full(p),
        None => {
            let mut p = [0u8; L];
            for (d, &b) in p.iter_mut().zip(payload) {
                *d = b;
            }
            full(&p)
        }
    }
}

/// The `N` bytes at `at` (zeros if they are not all there: never, for the offsets the
/// codecs use, which the compiler then sees).
#[inline(always)]
fn bytes<const N: usize>(p: &[u8], at: usize) -> [u8; N] {
    // Offsets are the codecs' constants, far below usize::MAX: the sum never saturates.
    p.get(at..at.saturating_add(N))
        .and_then(|s| <[u8; N]>::try_from(s).ok())
        .unwrap_or([0; N])
}

#[inline(always)]
fn u16_at(p: &[u8], at: usize) -> u16 {
    u16::from_le_bytes(bytes(p, at))
}

#[inline(always)]
fn u32_at(p: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(bytes(p, at))
}

#[inline(always)]
fn i32_at(p: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(bytes(p, at))
}

#[inline(always)]
fn f32_at(p: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(bytes(p, at))
}

/// The quaternion `[w, x, y, z]` at `at`: four `f32`s in a row.
#[inline(always)]
fn quaternion_at(p: &[u8], at: usize) -> [f32; 4] {
    let [w0, w1, w2, w3, x0, x1, x2, x3, y0, y1, y2, y3, z0, z1, z2, z3] = bytes::<16>(p, at);
    [
        f32::from_le_bytes([w0, w1, w2, w3]),
        f32::from_le_bytes([x0, x1, x2, x3]),
        f32::from_le_bytes([y0, y1, y2, y3]),
        f32::from_le_bytes([z0, z1, z2, z3]),
    ]
}

#[inline(always)]
fn u8_at(p: &[u8], at: usize) -> u8 {
    p.get(at).copied().unwrap_or(0)
}

/// Writes `value`'s bytes at `at` (in bounds for every offset the codecs use).
#[inline(always)]
fn put<const N: usize>(p: &mut [u8], at: usize, value: [u8; N]) {
    // `..N` of what is past `at`: N bytes, so the copy has no length check to fail.
    if let Some(dst) = p.get_mut(at..).and_then(|p| p.get_mut(..N)) {
        dst.copy_from_slice(&value);
    }
}
