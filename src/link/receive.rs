//! Receiving: one frame at a time from CAN, or a whole postback from the serial stream;
//! the link's health and the latest postback follow.

use super::*;

/// What the CAN controller says of a received frame's identifier.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RxId {
    /// A data frame with this 29-bit extended ID (a `u32` converts to this).
    Extended(u32),
    /// A standard (11-bit) ID or a remote frame: never for this node, only counted.
    Other,
}

impl From<u32> for RxId {
    fn from(id: u32) -> Self {
        RxId::Extended(id)
    }
}

impl<const Q: usize, const T: usize> Link<Q, T, Can> {
    /// Takes a received frame: the one way in from CAN. `id` is the frame's 29-bit ID (a
    /// `u32`), or [`RxId::Other`] for a standard-ID or remote frame, which is only
    /// counted. The drivers take a faster way in for the postback's frames, with the same
    /// effect.
    #[inline]
    pub fn receive(&mut self, id: impl Into<RxId>, data: &[u8], now: Instant) {
        match id.into() {
            RxId::Extended(ids::POSTBACK) => self.receive_postback_frame(data, now),
            _ => self.receive_ignored(),
        }
    }
}

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// Takes a received data frame whose ID the caller has found to be
    /// [`ids::POSTBACK`]: [`Link::receive`] without the ID check, for a driver that
    /// rejects foreign frames itself before anything else.
    pub(crate) fn receive_postback_frame(&mut self, data: &[u8], now: Instant) {
        match <&[u8; 8]>::try_from(data) {
            Ok(d) => self.receive_postback_u64(now, u64::from_le_bytes(*d)),
            Err(_) => self.assembler.malformed(),
        }
    }

    /// [`Link::receive_postback_frame`] for a frame whose length is not 8: counted as
    /// malformed. Out of line, taking only the link: a driver's receive loop then keeps
    /// nothing in registers for it.
    #[cold]
    #[inline(never)]
    pub(crate) fn receive_malformed(&mut self) {
        self.assembler.malformed();
    }

    /// [`Link::receive_postback_frame`] for a frame of 8 bytes (every good one), its data
    /// read as a little-endian `u64`: passed in two registers, so that a driver need not
    /// copy its frame to memory. Out of line: the driver's poll then keeps few registers,
    /// which is what an idle poll pays for.
    #[inline(never)]
    pub(crate) fn receive_postback_u64(&mut self, now: Instant, data: u64) {
        let held = self.assembler.pending() != 0;
        if self.assembler.push(&data.to_le_bytes(), now) {
            self.complete_postback(now);
        } else if !held {
            // A window that starts brings its expiry deadline; while it holds frames the
            // deadline only moves later (a frame too late or too early empties it), so a
            // poll woken for the first is never too late for the others.
            if let Some(at) = self.assembler.expiry() {
                self.wake_by(at);
            }
        }
    }

    /// The assembler's window is full: the CRC decides. Out of line, so that the three
    /// frames before it pay nothing for its registers.
    #[inline(never)]
    pub(super) fn complete_postback(&mut self, now: Instant) {
        if let Some(p) = self.assembler.complete() {
            self.receive_postback(p, now);
        }
    }

    /// Takes a whole postback that arrived in one piece, as on the serial link, where the
    /// stream parser has already checked its header, length byte and CRC: counted here, as
    /// the assembler counts the postbacks it completes from CAN frames. Out of line: the
    /// serial port's byte loop then keeps none of the link's state in registers.
    #[inline(never)]
    pub(crate) fn receive_whole_postback(&mut self, postback: Postback, now: Instant) {
        self.stats.whole_postbacks = self.stats.whole_postbacks.wrapping_add(1);
        self.receive_postback(postback, now);
    }

    /// Takes a postback checked whole: the link's health, the latest postback, the event.
    pub(super) fn receive_postback(&mut self, postback: Postback, now: Instant) {
        // The health deadline follows this postback: earlier than the one the idle fast
        // path knows of when the link was down (none) or `now` is behind the last postback.
        // While the link is up the fast path wakes for the last postback's deadline (the
        // full poll offers it, or this call did when the link came up), and a postback at
        // or after that one only moves it later: no need to cut the interval then.
        let later =
            self.status.is_up() && self.latest.is_some_and(|(_, at)| now.is_at_or_after(at));
        if !later {
            self.wake_by(now.add_millis(u32::from(self.config.link_timeout_ms).saturating_add(1)));
        }
        self.latest = Some((postback, now));
        self.status.set_up(true);
        self.status.raise(Event::Postback);
    }

    /// Counts a received frame that cannot be for this node (a standard ID or a remote
    /// frame); the port calls it for what it does not pass to [`Link::receive`].
    pub(crate) fn receive_ignored(&mut self) {
        self.stats.ignored_frames = self.stats.ignored_frames.wrapping_add(1);
    }

    /// Whether a valid postback arrived within the link timeout (as of the last poll).
    pub fn is_link_up(&self) -> bool {
        self.status.is_up()
    }

    /// The latest valid postback and its age in milliseconds at `now`, the wrapping
    /// [`Instant::millis_since`] its stamp (so `now` at or after the receive that took it).
    pub fn latest_postback(&self, now: Instant) -> Option<(Postback, u32)> {
        self.latest.map(|(p, at)| (p, now.millis_since(at)))
    }

    /// The gimbal model as last reported.
    pub fn gimbal_type(&self) -> Option<GimbalType> {
        self.latest.map(|(p, _)| p.gimbal_type)
    }
}
