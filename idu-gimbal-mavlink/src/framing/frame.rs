//! A complete MAVLink 2 frame as received: a view of its bytes.

use core::fmt;

use mavio::mavspec::rust::spec::{MavLinkVersion, MessageSpecStatic};
use mavio::protocol::{Frame, Payload, V2};

use super::{x25, HEADER_LEN, IFLAG_SIGNED};

/// Why [`ReceivedFrame::decode`] gave no message.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// The frame carries another message (its id is given).
    OtherMessage(u32),
    /// The checksum over the frame and the message's `CRC_EXTRA` does not hold: the frame
    /// is corrupt, or the sender's definition of the message differs.
    Checksum,
    /// The checksum holds but `mavio` could not decode the payload (an enum or flag value
    /// outside the dialect).
    Payload,
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeError::OtherMessage(id) => write!(f, "the frame carries message id {id}"),
            DecodeError::Checksum => {
                f.write_str("checksum mismatch (with the message's CRC_EXTRA)")
            }
            DecodeError::Payload => {
                f.write_str("payload does not decode (a value outside the dialect)")
            }
        }
    }
}

/// A complete MAVLink 2 frame, as [`FrameReader`](super::FrameReader) hands it out: its
/// length fits its header, its CRC is not checked yet (that needs the message's
/// `CRC_EXTRA`: [`ReceivedFrame::decode`], [`ReceivedFrame::checksum_holds`]).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub struct ReceivedFrame<'a> {
    /// The whole frame: header, payload, checksum and the signature if any. At least
    /// `HEADER_LEN + payload length + CHECKSUM_LEN` bytes, as the reader checked.
    bytes: &'a [u8],
    /// The checksum over `bytes[1..HEADER_LEN + payload length]`, taken as the bytes came
    /// in; the message's `CRC_EXTRA` completes it.
    crc: u16,
}

/// Header field offsets in a MAVLink 2 frame.
mod field {
    pub const LEN: usize = 1;
    pub const INCOMPAT_FLAGS: usize = 2;
    pub const SEQ: usize = 4;
    pub const SYSID: usize = 5;
    pub const COMPID: usize = 6;
    pub const MSGID: usize = 7;
}

impl<'a> ReceivedFrame<'a> {
    /// The view of a frame the reader has checked to be whole (`bytes` holds the header,
    /// the payload its length byte gives, the checksum and, when signed, the signature),
    /// with the checksum of its header and payload.
    pub(super) fn new(bytes: &'a [u8], crc: u16) -> Self {
        ReceivedFrame { bytes, crc }
    }

    fn byte(&self, at: usize) -> u8 {
        self.bytes.get(at).copied().unwrap_or(0)
    }

    /// The frame's bytes, from the start byte to the end of the signature (if signed).
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Sequence number.
    pub fn sequence(&self) -> u8 {
        self.byte(field::SEQ)
    }

    /// Sending system.
    pub fn system_id(&self) -> u8 {
        self.byte(field::SYSID)
    }

    /// Sending component.
    pub fn component_id(&self) -> u8 {
        self.byte(field::COMPID)
    }

    /// Message id (24 bits).
    pub fn message_id(&self) -> u32 {
        u32::from_le_bytes([
            self.byte(field::MSGID),
            self.byte(field::MSGID + 1),
            self.byte(field::MSGID + 2),
            0,
        ])
    }

    /// Whether the frame carries a signature (not verified here).
    pub fn is_signed(&self) -> bool {
        self.byte(field::INCOMPAT_FLAGS) & IFLAG_SIGNED != 0
    }

    fn payload_end(&self) -> usize {
        HEADER_LEN + usize::from(self.byte(field::LEN))
    }

    /// The payload as sent (MAVLink 2 drops trailing zero bytes).
    pub fn payload(&self) -> &'a [u8] {
        self.bytes
            .get(HEADER_LEN..self.payload_end())
            .unwrap_or(&[])
    }

    /// The checksum the frame carries.
    pub fn checksum(&self) -> u16 {
        let at = self.payload_end();
        u16::from_le_bytes([self.byte(at), self.byte(at.saturating_add(1))])
    }

    /// Whether the checksum holds for a message with this `CRC_EXTRA`.
    pub fn checksum_holds(&self, crc_extra: u8) -> bool {
        x25::step(self.crc, crc_extra) == self.checksum()
    }

    /// The message `M` the frame carries, when it is an `M` and its checksum holds with
    /// `M`'s `CRC_EXTRA`; decoded by `mavio`.
    pub fn decode<M>(&self) -> Result<M, DecodeError>
    where
        M: MessageSpecStatic + for<'p> TryFrom<&'p Payload>,
    {
        let spec = M::spec();
        let id = self.message_id();
        if id != spec.id() {
            return Err(DecodeError::OtherMessage(id));
        }
        if !self.checksum_holds(spec.crc_extra()) {
            return Err(DecodeError::Checksum);
        }
        let payload = Payload::new(id, self.payload(), MavLinkVersion::V2);
        M::try_from(&payload).map_err(|_| DecodeError::Payload)
    }

    /// The frame parsed by `mavio` (slower: a copy of ~300 bytes), e.g. to re-serialize it
    /// or to decode it as a whole dialect; `None` only if `mavio` refuses it.
    pub fn to_frame(&self) -> Option<Frame<V2>> {
        mavio::Receiver::versioned(FrameBytes(self.bytes), V2)
            .recv()
            .ok()
    }
}

/// `mavio`'s reader trait over the bytes of one complete frame.
struct FrameBytes<'a>(&'a [u8]);

impl mavio::io::Read<mavio::error::IoError> for FrameBytes<'_> {
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), mavio::error::IoError> {
        let Some((head, rest)) = self.0.split_at_checked(buf.len()) else {
            return Err(mavio::error::IoErrorKind::UnexpectedEof.into());
        };
        buf.copy_from_slice(head);
        self.0 = rest;
        Ok(())
    }
}
