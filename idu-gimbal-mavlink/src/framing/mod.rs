//! MAVLink 2 bytes in, frames out; frames in, bytes out. Fixed memory, no I/O.
//!
//! - [`FrameReader`] finds frame boundaries in a byte stream split anywhere and hands each
//!   complete frame to the caller as a [`ReceivedFrame`], a view of its bytes.
//! - [`ReceivedFrame::decode`] checks the frame's CRC with the message's `CRC_EXTRA` (only
//!   the messages the caller handles are known) and decodes the payload with `mavio`.
//! - [`Outbox`] holds serialized frames until the transport takes them, whole frames only.
//!
//! # Why received frames are not `mavio::Frame`s
//!
//! Building a `mavio::Frame` for every received frame (`mavio::Receiver`) and checking it
//! with `Frame::validate_checksum_with_crc_extra` cost 62.7 guest instructions a byte on
//! the Cortex-M4 (`qemu_bench_mavlink`): 40.9 for the parse, which zeroes and copies a
//! 270-byte body and a 255-byte payload and moves the ~300-byte frame, and 21.8 for the
//! checksum, which serializes the header again and looks each byte up through `crc-any`'s
//! table enum. That alone was over the bridge's goal of 60 a byte for the whole bridge,
//! and more than the C MAVLink library's parse and decode take (47.4, `BENCHMARKS.md`).
//! Instead the reader takes the checksum (CRC-16/MCRF4XX, MAVLink's "X.25") in the same
//! loop that copies each byte in, and [`ReceivedFrame`] reads the header fields where
//! MAVLink 2 puts them. `CRC_EXTRA` and message ids come from `mavio`'s message specs;
//! payloads are decoded by `mavio`'s generated code, but for the few messages received many
//! times a second ([`crate::codec`]). `tests/framing.rs` holds every field, every checksum
//! verdict and every decoded message to `mavio`'s own parse of the same bytes
//! ([`ReceivedFrame::to_frame`]), for valid, damaged and garbage streams split anywhere,
//! and every frame the [`Outbox`] writes to `mavio`'s serialization of the same message.

mod frame;
mod outbox;
mod reader;
mod x25;

pub use frame::{DecodeError, ReceivedFrame};
pub use outbox::{Outbox, OutboxError, COMPONENTS};
pub use reader::{Check, FrameReader, ReaderStats};

/// The MAVLink 2 start byte.
pub const STX_V2: u8 = 0xFD;
/// Header bytes before the payload (start byte to message id).
pub(crate) const HEADER_LEN: usize = 10;
/// CRC bytes after the payload.
pub(crate) const CHECKSUM_LEN: usize = 2;
/// Signature bytes after the CRC when the frame is signed.
pub(crate) const SIGNATURE_LEN: usize = 13;
/// Incompatibility flag: the frame is signed.
pub(crate) const IFLAG_SIGNED: u8 = 0x01;
/// The longest MAVLink 2 frame.
pub const MAX_FRAME_LEN: usize = HEADER_LEN + 255 + CHECKSUM_LEN + SIGNATURE_LEN;
