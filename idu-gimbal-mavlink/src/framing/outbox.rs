//! Frames in, bytes out: serialized MAVLink 2 frames waiting for the transport, whole
//! frames only.
//!
//! A frame is written straight into the buffer: its header, its payload (put in place by
//! the message's codec, [`Outbox::push_with`], or copied) with MAVLink 2's trailing zeros
//! dropped, and its checksum, with the frame reader's table ([`x25`] module). `mavio`'s frame builder serialized the same bytes
//! (`tests/framing.rs` holds the two equal) through a 255-byte payload and a ~300-byte frame
//! copied twice, with a checksum looked up through `crc-any`: about 3,000 of the 5,100
//! instructions a status poll took on the Cortex-M4.

use mavio::mavspec::rust::spec::MavLinkVersion;
use mavio::Message;

use super::{x25, CHECKSUM_LEN, HEADER_LEN, IFLAG_SIGNED, STX_V2};

/// Why a message was not queued for sending.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum OutboxError {
    /// `mavio` could not encode it (a message this bridge builds wrongly: a bug).
    Encode,
    /// No room for the whole frame: the transport is not taking bytes fast enough.
    Full,
    /// A frame from one component more than the [`COMPONENTS`] the outbox numbers frames
    /// for.
    Components,
}

/// How many components an [`Outbox`] numbers frames for, each on its own (MAVLink's
/// sequence is per component: readers count loss per system and component). The first
/// components to send take the places; a frame from another is refused
/// ([`OutboxError::Components`]). The bridge sends as two, its gimbal and its camera.
pub const COMPONENTS: usize = 4;

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
    /// Each numbered component and its next frame's sequence number, in the order they
    /// first sent.
    sequences: [Option<(u8, u8)>; COMPONENTS],
    /// Signs every frame when set (feature `signing`).
    #[cfg(feature = "signing")]
    signing: Option<crate::signing::Signing>,
}

impl<const N: usize> Default for Outbox<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Outbox<N> {
    /// An empty outbox; each component's first frame gets sequence number 0.
    pub const fn new() -> Self {
        Outbox {
            buf: [0; N],
            start: 0,
            end: 0,
            sequences: [None; COMPONENTS],
            #[cfg(feature = "signing")]
            signing: None,
        }
    }

    /// Signs every frame from now on with `config` (feature `signing`).
    #[cfg(feature = "signing")]
    pub(crate) fn sign_with(&mut self, config: crate::signing::SigningConfig) {
        self.signing = Some(crate::signing::Signing::new(config));
    }

    /// The signing state, when signing.
    #[cfg(feature = "signing")]
    pub(crate) fn signing_mut(&mut self) -> Option<&mut crate::signing::Signing> {
        self.signing.as_mut()
    }

    /// The signing state, when signing.
    #[cfg(feature = "signing")]
    pub(crate) fn signing(&self) -> Option<&crate::signing::Signing> {
        self.signing.as_ref()
    }

    /// The signature block's length on every frame: 13 when signing.
    fn signature_len(&self) -> usize {
        #[cfg(feature = "signing")]
        if self.signing.is_some() {
            return crate::signing::SIGNATURE_LEN;
        }
        0
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
            // `p` is `payload.len()` long; taken as such, the copy has no length check.
            if let Some(dst) = p.get_mut(..payload.len()) {
                dst.copy_from_slice(payload);
            }
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
        // Only `write` is the message's own: the framing around it is one copy for every
        // message, out of line.
        write(self.reserve(component, len)?);
        self.seal(system, component, id, crc_extra, len);
        Ok(())
    }

    /// Where `component`'s sequence number is kept: its place, or the first free one.
    fn place_of(&self, component: u8) -> Result<usize, OutboxError> {
        self.sequences
            .iter()
            .position(|s| s.is_none_or(|(c, _)| c == component))
            .ok_or(OutboxError::Components)
    }

    /// Room for a frame from `component` of a `len`-byte payload at `end`: the payload's
    /// bytes, zeroed.
    #[inline(never)]
    fn reserve(&mut self, component: u8, len: usize) -> Result<&mut [u8], OutboxError> {
        // A MAVLink payload has 1 to 255 bytes.
        if !(1..=255).contains(&len) {
            return Err(OutboxError::Encode);
        }
        self.place_of(component)?;
        // Every length below is at most a frame's 280 bytes or the outbox's N, with
        // `start <= end <= N`: the saturating operations never saturate, and no overflow
        // check is left to panic.
        let frame_len = HEADER_LEN
            .saturating_add(len)
            .saturating_add(CHECKSUM_LEN)
            .saturating_add(self.signature_len());
        if self.room() < frame_len {
            return Err(OutboxError::Full);
        }
        if N.saturating_sub(self.end) < frame_len {
            self.buf.copy_within(self.start..self.end, 0);
            self.end = self.len();
            self.start = 0;
        }
        let payload_at = self.end.saturating_add(HEADER_LEN);
        let payload = self
            .buf
            .get_mut(payload_at..payload_at.saturating_add(len))
            .ok_or(OutboxError::Full)?;
        payload.fill(0);
        Ok(payload)
    }

    /// Finishes the frame [`Outbox::reserve`] made room for, its payload written: the
    /// payload's trailing zeros dropped (MAVLink 2), the header, the checksum, the
    /// signature; the frame queued.
    #[inline(never)]
    fn seal(&mut self, system: u8, component: u8, id: u32, crc_extra: u8, len: usize) {
        let signature_len = self.signature_len();
        // Found by `reserve`.
        let place = self.place_of(component).unwrap_or(0);
        let sequence = self
            .sequences
            .get(place)
            .copied()
            .flatten()
            .map_or(0, |(_, s)| s);
        let Some(frame) = self.buf.get_mut(self.end..) else {
            return;
        };
        let payload = frame
            .get(HEADER_LEN..HEADER_LEN.saturating_add(len))
            .unwrap_or(&[]);
        // At least one byte stays.
        let sent = payload
            .iter()
            .rposition(|&b| b != 0)
            .map_or(1, |i| i.saturating_add(1));
        let [id0, id1, id2, _] = id.to_le_bytes();
        // `sent` <= len <= 255: the cast is exact.
        let header = [
            STX_V2,
            sent as u8,
            // Incompatibility flags: signed or not.
            u8::from(signature_len > 0) * IFLAG_SIGNED,
            0, // compatibility flags
            sequence,
            system,
            component,
            id0,
            id1,
            id2,
        ];
        if let Some(head) = frame.get_mut(..HEADER_LEN) {
            head.copy_from_slice(&header);
        }
        let payload_end = HEADER_LEN.saturating_add(sent);
        let checksummed = frame.get(1..payload_end).unwrap_or(&[]);
        let crc = x25::step(x25::update(x25::INIT, checksummed), crc_extra);
        let body_len = payload_end.saturating_add(CHECKSUM_LEN);
        if let Some(at) = frame
            .get_mut(payload_end..)
            .and_then(|f| f.first_chunk_mut())
        {
            *at = crc.to_le_bytes();
        }
        #[cfg(feature = "signing")]
        if let Some(signing) = self.signing.as_mut() {
            let block = signing.sign(frame.get(..body_len).unwrap_or(&[]));
            if let Some(at) = frame.get_mut(body_len..).and_then(|f| f.first_chunk_mut()) {
                *at = block;
            }
        }
        self.end = self
            .end
            .saturating_add(body_len)
            .saturating_add(signature_len);
        if let Some(s) = self.sequences.get_mut(place) {
            *s = Some((component, sequence.wrapping_add(1)));
        }
    }

    /// The bytes to write next (all that wait); empty when nothing waits.
    pub fn bytes(&self) -> &[u8] {
        self.buf.get(self.start..self.end).unwrap_or(&[])
    }

    /// `n` bytes of [`Outbox::bytes`] were written (more than it holds counts as all of
    /// them).
    pub fn written(&mut self, n: usize) {
        self.start = self.start.saturating_add(n.min(self.len()));
        if self.start == self.end {
            // Empty: start again at the front.
            self.start = 0;
            self.end = 0;
        }
    }

    /// Bytes waiting.
    pub fn len(&self) -> usize {
        // `start <= end`.
        self.end.saturating_sub(self.start)
    }

    /// Bytes there is room for.
    pub fn room(&self) -> usize {
        N.saturating_sub(self.len())
    }

    /// Whether nothing waits.
    pub fn is_empty(&self) -> bool {
        self.start == self.end
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame of message 1 with a `len`-byte payload of `fill` (non-zero: not trimmed).
    fn push(out: &mut Outbox<64>, len: usize, fill: u8) -> Result<(), OutboxError> {
        out.push_with(1, 1, 1, 0, len, |p| p.fill(fill))
    }

    #[test]
    fn a_frame_that_does_not_fit_is_refused_whole() {
        let mut out = Outbox::<64>::new();
        // 12 + 40 = 52 bytes, then 12 + 1 = 13 do not fit in the 12 left.
        push(&mut out, 40, 7).unwrap();
        assert_eq!(push(&mut out, 1, 7), Err(OutboxError::Full));
        assert_eq!(out.len(), 52);
        // Exactly the room left fits.
        let mut small = Outbox::<64>::new();
        push(&mut small, 40, 7).unwrap();
        small.written(1);
        assert_eq!(push(&mut small, 1, 7), Ok(()));
        assert_eq!(small.len(), 51 + 13);
    }

    #[test]
    fn what_waits_moves_to_the_front_when_the_end_is_full() {
        let mut out = Outbox::<64>::new();
        push(&mut out, 40, 7).unwrap();
        let first = out.bytes().to_vec();
        // The transport takes 30 bytes: 22 wait at 30..52; a 25-byte frame does not fit
        // after them (12 left) but fits in all (42 free).
        out.written(30);
        push(&mut out, 13, 9).unwrap();
        assert_eq!(out.len(), 22 + 25);
        let bytes = out.bytes();
        assert_eq!(&bytes[..22], &first[30..]);
        assert_eq!(bytes[22], STX_V2);
        assert_eq!(usize::from(bytes[23]), 13);
        assert!(bytes[32..45].iter().all(|&b| b == 9));
    }

    #[test]
    fn written_past_what_waits_empties_it_and_nothing_is_trimmed_to_nothing() {
        let mut out = Outbox::<64>::new();
        // An all-zero payload keeps one byte (MAVLink 2).
        out.push_with(1, 1, 1, 0, 9, |_| {}).unwrap();
        assert_eq!(out.len(), 13);
        out.written(100);
        assert!(out.is_empty());
        assert!(out.bytes().is_empty());
        // Payloads of 0 or over 255 bytes are not MAVLink.
        assert_eq!(
            out.push_with(1, 1, 1, 0, 0, |_| {}),
            Err(OutboxError::Encode)
        );
        let mut big = Outbox::<600>::new();
        assert_eq!(
            big.push_with(1, 1, 1, 0, 256, |_| {}),
            Err(OutboxError::Encode)
        );
        assert_eq!(big.push_with(1, 1, 1, 0, 255, |p| p.fill(1)), Ok(()));
        assert_eq!(big.len(), 267);
    }
}
