//! Finding MAVLink 2 frames in a byte stream split anywhere: [`FrameReader`].

use super::{
    x25, ReceivedFrame, CHECKSUM_LEN, HEADER_LEN, IFLAG_SIGNED, MAX_FRAME_LEN, SIGNATURE_LEN,
    STX_V2,
};

/// What the caller found when it checked a frame.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Check {
    /// A message it handles, CRC good.
    Handled,
    /// A message it does not handle (its CRC cannot be checked without its `CRC_EXTRA`).
    Unhandled,
    /// A message it handles whose CRC failed, or whose payload did not decode.
    Bad,
    /// It cannot act on the frame now (no room for its answer): the reader keeps the frame
    /// whole, takes no more bytes, and offers it first at the next call
    /// ([`FrameReader::is_waiting`]).
    Wait,
}

/// Counters of a [`FrameReader`], each wrapping at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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

/// An incremental MAVLink 2 frame finder.
///
/// It reads the start byte `0xFD`, the payload length and the signature flag to find where
/// each frame ends, and hands each complete frame to the caller, who checks its CRC with
/// the message's `CRC_EXTRA` (only the messages the caller handles are known). A frame
/// whose CRC fails is not consumed whole: the reader drops its start byte and looks for the
/// next start byte inside it, so a corrupt length cannot swallow the frames that follow.
/// A message the caller does not know cannot be checked: taken whole, one whose length was
/// changed in transit takes in up to 280 bytes after it, and whatever frames they held go
/// uncounted (the bridge checks every message it acts on; the others pass it unchecked).
/// MAVLink 1 frames and frames with unknown incompatibility flags are skipped (this bridge
/// speaks MAVLink 2 only).
///
/// The checksum runs in the loop that copies each byte in (over the header after the start
/// byte, and the payload), so a frame is read once; the caller adds its message's
/// `CRC_EXTRA` ([`ReceivedFrame::checksum_holds`]).
#[derive(Clone, Debug)]
pub struct FrameReader {
    buf: [u8; MAX_FRAME_LEN],
    /// Bytes of the frame in hand; `buf[0]` is its start byte when `len > 0`.
    len: usize,
    /// Bytes to hold before there is something to look at: the header's length until the
    /// header is whole, then the frame's. `len < need` between calls.
    need: usize,
    /// Where the checksummed bytes end: the header's end until the header is whole, then
    /// the payload's.
    crc_end: usize,
    /// The checksum over `buf[1..len.min(crc_end)]`.
    crc: u16,
    stats: ReaderStats,
}

impl Default for FrameReader {
    fn default() -> Self {
        Self::new()
    }
}

impl FrameReader {
    /// A reader waiting for a start byte.
    pub const fn new() -> Self {
        FrameReader {
            buf: [0; MAX_FRAME_LEN],
            len: 0,
            need: HEADER_LEN,
            crc_end: HEADER_LEN,
            crc: x25::INIT,
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

    /// Bytes held now: of an incomplete frame, or of a whole one waiting ([`Check::Wait`]).
    pub fn pending(&self) -> usize {
        self.len
    }

    /// Whether a whole frame waits for the caller ([`Check::Wait`]): the next
    /// [`FrameReader::feed`] offers it first, and takes no bytes while it waits.
    pub fn is_waiting(&self) -> bool {
        // Between calls `len < need`, but for a whole frame kept back.
        self.len > 0 && self.len >= self.need
    }

    /// Forgets what is held, counting nothing: for a caller who offers those bytes again
    /// (a datagram's, after [`Check::Wait`]).
    pub fn clear(&mut self) {
        self.drop_front(self.len);
    }

    /// Takes bytes in any split; calls `check` with each complete frame, in order. Returns
    /// how many bytes it took: all of them, or, when `check` said [`Check::Wait`], those up
    /// to the end of the frame that waits; offer the rest again after it is taken.
    pub fn feed(
        &mut self,
        mut bytes: &[u8],
        mut check: impl FnMut(&ReceivedFrame<'_>) -> Check,
    ) -> usize {
        let given = bytes.len();
        loop {
            if self.len == 0 {
                // Look for a start byte; everything before it is skipped.
                let start = bytes
                    .iter()
                    .position(|&b| b == STX_V2)
                    .unwrap_or(bytes.len());
                // A slice is shorter than 2^32 bytes here (it came through a UART buffer);
                // were it not, the counter wraps as every counter does.
                self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(start as u32);
                // The bytes after the start byte; none found, all were skipped.
                let Some((_, rest)) = bytes.get(start..).and_then(<[u8]>::split_first) else {
                    return given;
                };
                // The start byte is not checksummed.
                if let Some(first) = self.buf.first_mut() {
                    *first = STX_V2;
                }
                self.len = 1;
                self.crc = x25::INIT;
                bytes = rest;
            }
            // Copy what the frame in hand still needs (the header first), in one go,
            // checksumming up to the payload's end. `len <= need <= MAX_FRAME_LEN` here
            // (equal for a frame kept waiting: nothing to copy).
            let n = self.need.saturating_sub(self.len).min(bytes.len());
            let (now, rest) = bytes.split_at(n);
            let covered = self.crc_end.saturating_sub(self.len).min(n);
            // `len + n <= need <= MAX_FRAME_LEN`: the sum never saturates.
            #[allow(clippy::arithmetic_side_effects)]
            let end = self.len + n;
            if let Some(dst) = self.buf.get_mut(self.len..end) {
                let (dst_crc, dst_plain) = dst.split_at_mut(covered);
                let (src_crc, src_plain) = now.split_at(covered);
                self.crc = x25::copy_update(self.crc, dst_crc, src_crc);
                // The checksum and signature bytes: at most 15, too few for a memcpy call
                // to pay.
                for (d, &b) in dst_plain.iter_mut().zip(src_plain) {
                    *d = b;
                }
            }
            self.len = end;
            bytes = rest;
            // A whole frame: the one just completed, or one kept waiting since the last call
            // (offered first, before any new byte is taken).
            if self.len >= self.need && !self.complete(&mut check) {
                // `rest` is what is left of `bytes`: the difference cannot underflow.
                return given.saturating_sub(bytes.len());
            }
            if bytes.is_empty() {
                return given;
            }
        }
    }

    /// Ends a datagram (MAVLink on UDP carries whole frames, one or more a datagram): a frame
    /// still incomplete can never be finished, so its start byte is dropped and what
    /// follows it is searched again, until nothing is held. Frames found in that tail are
    /// handed to `check` as by [`FrameReader::feed`]; every dropped byte is counted in
    /// [`ReaderStats::skipped_bytes`]. The next datagram then starts clean, whatever this
    /// one held. When `check` says [`Check::Wait`], the frame waiting stays
    /// ([`FrameReader::is_waiting`]): its bytes are the last [`FrameReader::pending`] of the
    /// datagram.
    pub fn end_datagram(&mut self, mut check: impl FnMut(&ReceivedFrame<'_>) -> Check) {
        if self.is_waiting() && !self.complete(&mut check) {
            return;
        }
        while self.len > 0 {
            self.resync();
            if self.len > 0 && !self.complete(&mut check) {
                return;
            }
        }
    }

    /// How long the frame in hand is, as far as its header says (the header's length until
    /// it is all here), and where its checksummed bytes end.
    fn extent(&self) -> (usize, usize) {
        match (self.buf.get(1), self.buf.get(2)) {
            (Some(&payload_len), Some(&iflags)) if self.len >= HEADER_LEN => {
                let signature = if iflags & IFLAG_SIGNED != 0 {
                    SIGNATURE_LEN
                } else {
                    0
                };
                let payload_end = HEADER_LEN + usize::from(payload_len);
                // At most MAX_FRAME_LEN: the sum never saturates.
                let total = payload_end
                    .saturating_add(CHECKSUM_LEN)
                    .saturating_add(signature);
                (total, payload_end)
            }
            _ => (HEADER_LEN, HEADER_LEN),
        }
    }

    /// Hands out every frame the buffer completes; resyncs after a bad one. False when a
    /// frame waits ([`Check::Wait`]).
    fn complete(&mut self, check: &mut impl FnMut(&ReceivedFrame<'_>) -> Check) -> bool {
        loop {
            if self.len >= HEADER_LEN
                && self
                    .buf
                    .get(2)
                    .is_some_and(|&iflags| iflags & !IFLAG_SIGNED != 0)
            {
                self.stats.unsupported = self.stats.unsupported.wrapping_add(1);
                self.resync();
                continue;
            }
            let (total, crc_end) = self.extent();
            self.need = total;
            self.crc_end = crc_end;
            if self.len < total {
                return true;
            }
            let bytes = self.buf.get(..total).unwrap_or(&[]);
            match check(&ReceivedFrame::new(bytes, self.crc)) {
                Check::Wait => return false,
                Check::Bad => {
                    self.stats.bad_frames = self.stats.bad_frames.wrapping_add(1);
                    self.resync();
                    continue;
                }
                Check::Handled | Check::Unhandled => {}
            }
            self.stats.frames = self.stats.frames.wrapping_add(1);
            self.drop_front(total);
        }
    }

    /// Drops a bad frame's start byte, and what follows up to the next start byte.
    fn resync(&mut self) {
        self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(1);
        self.drop_front(1);
    }

    /// Drops the first `n` bytes (a frame handed out, or a bad frame's start byte), then
    /// every byte before the next start byte, counted as skipped: what is left starts a
    /// frame (or is empty). Its checksum is taken again; bytes are left over only after a
    /// bad or unsupported frame.
    fn drop_front(&mut self, n: usize) {
        if n >= self.len {
            // The common case, a frame that ended what was held: nothing to search.
            self.len = 0;
            self.need = HEADER_LEN;
            self.crc_end = HEADER_LEN;
            self.crc = x25::INIT;
            return;
        }
        self.drop_front_and_search(n);
    }

    #[inline(never)]
    fn drop_front_and_search(&mut self, n: usize) {
        let n = n.min(self.len);
        let rest = self.buf.get(n..self.len).unwrap_or(&[]);
        let skip = rest.iter().position(|&b| b == STX_V2).unwrap_or(rest.len());
        // `skip` <= MAX_FRAME_LEN: the cast is exact.
        self.stats.skipped_bytes = self.stats.skipped_bytes.wrapping_add(skip as u32);
        // `n + skip <= len`: what is left starts at the next start byte.
        let start = n.saturating_add(skip);
        self.len = self.len.saturating_sub(start);
        self.need = HEADER_LEN;
        self.crc_end = HEADER_LEN;
        self.crc = x25::INIT;
        if self.len > 0 {
            self.buf
                .copy_within(start..start.saturating_add(self.len), 0);
            let (_, crc_end) = self.extent();
            self.crc_end = crc_end;
            self.crc = x25::update(
                x25::INIT,
                self.buf.get(1..self.len.min(crc_end)).unwrap_or(&[]),
            );
        }
    }
}
