//! MAVLink 2 bytes in, frames out; frames in, bytes out. Fixed memory, no I/O.
//!
//! [`FrameReader`] finds frame boundaries in a byte stream split anywhere (the start byte
//! `0xFD`, the payload length, the signature flag) and hands each complete frame, parsed by
//! `mavio`, to the caller, who checks its CRC with the message's `CRC_EXTRA` (only the
//! messages the caller handles are known). A frame whose CRC fails is not consumed whole:
//! the reader drops its start byte and looks for the next start byte inside it, so a
//! corrupt length cannot swallow the frames that follow. MAVLink 1 frames and frames with
//! unknown incompatibility flags are skipped (this bridge speaks MAVLink 2 only).
//!
//! [`Outbox`] holds serialized frames until the transport takes them, whole frames only.

use heapless::Deque;
use mavio::protocol::{Frame, V2};
use mavio::Message;

/// The MAVLink 2 start byte.
pub const STX_V2: u8 = 0xFD;
/// Header bytes before the payload (start byte to message id).
const HEADER_LEN: usize = 10;
/// CRC bytes after the payload.
const CHECKSUM_LEN: usize = 2;
/// Signature bytes after the CRC when the frame is signed.
const SIGNATURE_LEN: usize = 13;
/// Incompatibility flag: the frame is signed.
const IFLAG_SIGNED: u8 = 0x01;
/// The longest MAVLink 2 frame.
pub const MAX_FRAME_LEN: usize = HEADER_LEN + 255 + CHECKSUM_LEN + SIGNATURE_LEN;

/// What the caller found when it checked a frame.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Check {
    /// A message it handles, CRC good.
    Handled,
    /// A message it does not handle (its CRC cannot be checked without its `CRC_EXTRA`).
    Unhandled,
    /// A message it handles whose CRC failed, or whose payload did not decode.
    Bad,
}

/// Counters of a [`FrameReader`], each wrapping at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
pub struct ReaderStats {
    /// Frames handed to the caller and consumed (handled or unhandled).
    pub frames: u32,
    /// Frames the caller found bad (CRC or payload).
    pub bad_frames: u32,
    /// Frames skipped for unknown incompatibility flags (MAVLink 2 frames this bridge cannot
    /// read).
    pub unsupported: u32,
    /// Bytes dropped while looking for a start byte (garbage, MAVLink 1, bad frames' first
    /// bytes).
    pub skipped_bytes: u32,
}

/// An incremental MAVLink 2 frame finder; see the [module docs](self).
#[derive(Clone, Debug)]
pub struct FrameReader {
    buf: [u8; MAX_FRAME_LEN],
    len: usize,
    stats: ReaderStats,
}

impl Default for FrameReader {
    fn default() -> Self {
        Self::new()
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

impl FrameReader {
    /// A reader waiting for a start byte.
    pub const fn new() -> Self {
        FrameReader {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            stats: ReaderStats {
                frames: 0,
                bad_frames: 0,
                unsupported: 0,
                skipped_bytes: 0,
            },
        }
    }

    /// The counters so far.
    pub fn stats(&self) -> ReaderStats {
        self.stats
    }

    /// Bytes of an incomplete frame held now.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Takes bytes in any split; calls `check` with each complete frame, in order.
    pub fn feed(&mut self, mut bytes: &[u8], mut check: impl FnMut(&Frame<V2>) -> Check) {
        while !bytes.is_empty() {
            if self.len == 0 {
                // Look for a start byte; everything before it is skipped.
                let start = bytes
                    .iter()
                    .position(|&b| b == STX_V2)
                    .unwrap_or(bytes.len());
                // A slice is shorter than 2^32 bytes here (it came through a UART buffer);
                // were it not, the counter wraps as every counter does.
                self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(start as u32);
                bytes = bytes.get(start..).unwrap_or(&[]);
                if bytes.is_empty() {
                    return;
                }
            }
            // Copy what the frame in hand still needs (the header first), in one go.
            let want = self.needed().saturating_sub(self.len).max(1);
            let n = want.min(bytes.len()).min(MAX_FRAME_LEN - self.len);
            let (now, rest) = bytes.split_at(n);
            if let Some(dst) = self.buf.get_mut(self.len..self.len + n) {
                dst.copy_from_slice(now);
            }
            self.len += n;
            bytes = rest;
            self.complete(&mut check);
        }
    }

    /// How long the frame in hand is, as far as its header says (the header's length until
    /// it is all here).
    fn needed(&self) -> usize {
        match (self.buf.get(1), self.buf.get(2)) {
            (Some(&payload_len), Some(&iflags)) if self.len >= 3 => {
                let signature = if iflags & IFLAG_SIGNED != 0 {
                    SIGNATURE_LEN
                } else {
                    0
                };
                HEADER_LEN + usize::from(payload_len) + CHECKSUM_LEN + signature
            }
            _ => HEADER_LEN,
        }
    }

    /// Hands out every frame the buffer completes; resyncs after a bad one.
    fn complete(&mut self, check: &mut impl FnMut(&Frame<V2>) -> Check) {
        loop {
            if self.len < HEADER_LEN {
                return;
            }
            if self
                .buf
                .get(2)
                .is_some_and(|&iflags| iflags & !IFLAG_SIGNED != 0)
            {
                self.stats.unsupported = self.stats.unsupported.wrapping_add(1);
                self.resync();
                continue;
            }
            let total = self.needed();
            if self.len < total {
                return;
            }
            let bytes = self.buf.get(..total).unwrap_or(&[]);
            let verdict = match mavio::Receiver::versioned(FrameBytes(bytes), V2).recv() {
                Ok(frame) => check(&frame),
                Err(_) => Check::Bad,
            };
            if verdict == Check::Bad {
                self.stats.bad_frames = self.stats.bad_frames.wrapping_add(1);
                self.resync();
                continue;
            }
            self.stats.frames = self.stats.frames.wrapping_add(1);
            self.drop_front(total);
        }
    }

    /// Drops the first byte and everything up to the next start byte.
    fn resync(&mut self) {
        let next = self
            .buf
            .get(1..self.len)
            .and_then(|rest| rest.iter().position(|&b| b == STX_V2))
            .map_or(self.len, |p| p + 1);
        // `next` <= len <= MAX_FRAME_LEN: the cast is exact.
        self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(next as u32);
        self.drop_front(next);
    }

    fn drop_front(&mut self, n: usize) {
        let n = n.min(self.len);
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }
}

/// Why a message was not queued for sending.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum OutboxError {
    /// `mavio` could not encode it (a message this bridge builds wrongly: a bug).
    Encode,
    /// No room for the whole frame: the transport is not taking bytes fast enough.
    Full,
}

/// Serialized frames waiting for the transport, `N` bytes in all; whole frames only.
#[derive(Clone, Debug)]
pub struct Outbox<const N: usize> {
    bytes: Deque<u8, N>,
    sequence: u8,
}

impl<const N: usize> Default for Outbox<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Outbox<N> {
    /// An empty outbox; the first frame gets sequence number 0.
    pub const fn new() -> Self {
        Outbox {
            bytes: Deque::new(),
            sequence: 0,
        }
    }

    /// Queues `message` from `(system, component)` as one MAVLink 2 frame: all of it or,
    /// when it does not fit, nothing.
    pub fn push(
        &mut self,
        system: u8,
        component: u8,
        message: &dyn Message,
    ) -> Result<(), OutboxError> {
        let frame = Frame::builder()
            .version(V2)
            .sequence(self.sequence)
            .system_id(system)
            .component_id(component)
            .message(message)
            .map_err(|_| OutboxError::Encode)?
            .build();
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = frame.serialize(&mut buf).map_err(|_| OutboxError::Encode)?;
        if N - self.bytes.len() < n {
            return Err(OutboxError::Full);
        }
        for &b in buf.get(..n).unwrap_or(&[]) {
            // Room for all n was checked above.
            let _ = self.bytes.push_back(b);
        }
        self.sequence = self.sequence.wrapping_add(1);
        Ok(())
    }

    /// The bytes to write next (a prefix of what waits); empty when nothing waits.
    pub fn bytes(&self) -> &[u8] {
        self.bytes.as_slices().0
    }

    /// `n` bytes of [`Outbox::bytes`] were written.
    pub fn written(&mut self, n: usize) {
        for _ in 0..n {
            if self.bytes.pop_front().is_none() {
                break;
            }
        }
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
}
