//! Frames in, bytes out: serialized MAVLink 2 frames waiting for the transport, whole
//! frames only.
//!
//! A frame is written straight into the buffer: its header, its payload (put in place by
//! the message's codec, [`Outbox::push_with`], or copied) with MAVLink 2's trailing zeros
//! dropped, and its checksum, with the frame reader's table ([`x25`](super::x25)). `mavio`'s frame builder serialized the same bytes
//! (`tests/framing.rs` holds the two equal) through a 255-byte payload and a ~300-byte frame
//! copied twice, with a checksum looked up through `crc-any`: about 3,000 of the 5,100
//! instructions a status poll took on the Cortex-M4.

use mavio::mavspec::rust::spec::MavLinkVersion;
use mavio::Message;

use super::{x25, CHECKSUM_LEN, HEADER_LEN, STX_V2};

/// Why a message was not queued for sending.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum OutboxError {
    /// `mavio` could not encode it (a message this bridge builds wrongly: a bug).
    Encode,
    /// No room for the whole frame: the transport is not taking bytes fast enough.
    Full,
}

/// Serialized frames waiting for the transport, `N` bytes in all; whole frames only.
///
/// The bytes waiting are kept in one piece, `buf[start..end]`, so a frame is written with
/// plain stores in the loop that checksums it and the transport gets everything waiting in
/// one slice. A frame that does not fit after `end` moves what waits to the front first
/// (only when the transport has fallen behind, and at most `N` bytes).
#[derive(Clone, Debug)]
pub struct Outbox<const N: usize> {
    buf: [u8; N],
    start: usize,
    end: usize,
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
            buf: [0; N],
            start: 0,
            end: 0,
            sequence: 0,
        }
    }

    /// Queues `message` from `(system, component)` as one MAVLink 2 frame, its payload
    /// encoded by `mavio`: all of it or, when it does not fit, nothing.
    pub fn push(
        &mut self,
        system: u8,
        component: u8,
        message: &dyn Message,
    ) -> Result<(), OutboxError> {
        let payload = message
            .encode(MavLinkVersion::V2)
            .map_err(|_| OutboxError::Encode)?;
        self.push_payload(
            system,
            component,
            message.id(),
            message.crc_extra(),
            payload.bytes(),
        )
    }

    /// Queues the message `id` with this `CRC_EXTRA` and `payload` (its fields in wire
    /// order, full length or not; trailing zeros are dropped here) from `(system,
    /// component)` as one MAVLink 2 frame: all of it or, when it does not fit, nothing.
    pub fn push_payload(
        &mut self,
        system: u8,
        component: u8,
        id: u32,
        crc_extra: u8,
        payload: &[u8],
    ) -> Result<(), OutboxError> {
        self.push_with(system, component, id, crc_extra, payload.len(), |p| {
            p.copy_from_slice(payload)
        })
    }

    /// Queues the message `id` with this `CRC_EXTRA` from `(system, component)` as one
    /// MAVLink 2 frame whose payload `write` puts in place: it is given the `len` bytes of
    /// the payload, zeroed, and writes the fields in wire order (trailing zeros are dropped
    /// afterwards). All of the frame or, when it does not fit, nothing (and `write` is not
    /// called).
    pub fn push_with(
        &mut self,
        system: u8,
        component: u8,
        id: u32,
        crc_extra: u8,
        len: usize,
        write: impl FnOnce(&mut [u8]),
    ) -> Result<(), OutboxError> {
        // A MAVLink payload has 1 to 255 bytes.
        if !(1..=255).contains(&len) {
            return Err(OutboxError::Encode);
        }
        let frame_len = HEADER_LEN + len + CHECKSUM_LEN;
        if N - self.len() < frame_len {
            return Err(OutboxError::Full);
        }
        if N - self.end < frame_len {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        }
        let Some(frame) = self.buf.get_mut(self.end..self.end + frame_len) else {
            return Err(OutboxError::Full);
        };
        let (head, rest) = frame.split_at_mut(HEADER_LEN);
        let (payload, _) = rest.split_at_mut(len);
        payload.fill(0);
        write(payload);
        // MAVLink 2 drops the payload's trailing zeros (at least one byte stays).
        let sent = payload.iter().rposition(|&b| b != 0).map_or(1, |i| i + 1);
        let [id0, id1, id2, _] = id.to_le_bytes();
        // `sent` <= len <= 255: the cast is exact.
        head.copy_from_slice(&[
            STX_V2,
            sent as u8,
            0, // incompatibility flags: not signed
            0, // compatibility flags
            self.sequence,
            system,
            component,
            id0,
            id1,
            id2,
        ]);
        let checksummed = frame.get(1..HEADER_LEN + sent).unwrap_or(&[]);
        let crc = x25::step(x25::update(x25::INIT, checksummed), crc_extra);
        if let Some(at) = frame.get_mut(HEADER_LEN + sent..HEADER_LEN + sent + CHECKSUM_LEN) {
            at.copy_from_slice(&crc.to_le_bytes());
        }
        self.end += HEADER_LEN + sent + CHECKSUM_LEN;
        self.sequence = self.sequence.wrapping_add(1);
        Ok(())
    }

    /// The bytes to write next (all that wait); empty when nothing waits.
    pub fn bytes(&self) -> &[u8] {
        self.buf.get(self.start..self.end).unwrap_or(&[])
    }

    /// `n` bytes of [`Outbox::bytes`] were written (more than it holds counts as all of
    /// them).
    pub fn written(&mut self, n: usize) {
        self.start += n.min(self.len());
        if self.start == self.end {
            // Empty: start again at the front.
            self.start = 0;
            self.end = 0;
        }
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.start == self.end
    }
}
