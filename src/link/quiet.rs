//! The idle fast paths' intervals: how long after the last full poll nothing needs doing.
//!
//! Two intervals, each at most [`MAX_QUIET_MS`] (below 2^16), share
//! one word, so that either check is the word and the last poll's time loaded as a pair
//! and one compare:
//! - the schedules' (low half): no deadline comes before it ends, so [`Link::poll`] may
//!   skip ([`Link::is_quiet`], [`Link::next_deadline`]);
//! - the driver's (high half): the same, and nothing waits to be sent, so a driver whose
//!   poll also transmits may skip its transmit check too. It is 0 from the moment a frame
//!   is queued between polls, or queued again after the CAN driver refused it, until the
//!   driver finds the queue empty and releases it. (What a full poll queues, the same
//!   driver poll sends or queues again.)
//!
//! The driver's interval is always the schedules' or 0 (every change keeps that), so
//! skipping by it never skips a schedule.
//!
//! [`Link::poll`]: super::Link::poll
//! [`Link::is_quiet`]: super::Link::is_quiet
//! [`Link::next_deadline`]: super::Link::next_deadline

use super::MAX_QUIET_MS;

const HALF: u32 = 0xFFFF;
const _: () = assert!(MAX_QUIET_MS <= HALF, "an interval fits half a word");

/// See the [module docs](self).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Quiet(u32);

impl Quiet {
    /// Both intervals 0: the next poll is a full one.
    pub(crate) const NONE: Quiet = Quiet(0);

    /// The schedules' interval, ms.
    #[inline(always)]
    pub(crate) fn schedules(self) -> u32 {
        self.0 & HALF
    }

    /// The driver's interval, ms.
    #[inline(always)]
    pub(crate) fn idle(self) -> u32 {
        self.0 >> 16
    }

    /// After a full poll: nothing is due for `ms`, and the driver's interval is the same.
    /// (Frames the poll queued leave in the same driver poll; one the CAN driver refuses
    /// is queued again, which holds the driver's interval.)
    pub(crate) fn set(&mut self, ms: u32) {
        let ms = ms.min(MAX_QUIET_MS);
        self.0 = ms | ms << 16;
    }

    /// A deadline `ms` after the last poll: both intervals end there at the latest.
    #[inline]
    pub(crate) fn cut_to(&mut self, ms: u32) {
        if ms < self.schedules() {
            // The driver's interval is the schedules' or 0 (held): it stays so.
            self.0 = if self.idle() == 0 { ms } else { ms | ms << 16 };
        }
    }

    /// A frame was queued: the driver's interval ends at once.
    #[inline]
    pub(crate) fn hold_idle(&mut self) {
        self.0 &= HALF;
    }

    /// The driver found nothing waiting: its interval is the schedules' again.
    #[inline]
    pub(crate) fn release_idle(&mut self) {
        self.0 = self.schedules() | self.schedules() << 16;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halves_stay_apart_and_the_driver_s_is_never_longer() {
        let mut q = Quiet::NONE;
        q.set(70_000);
        assert_eq!((q.schedules(), q.idle()), (60_000, 60_000), "bounded");
        q.hold_idle();
        assert_eq!((q.schedules(), q.idle()), (60_000, 0));
        q.release_idle();
        assert_eq!((q.schedules(), q.idle()), (60_000, 60_000));
        q.cut_to(1_000);
        assert_eq!((q.schedules(), q.idle()), (1_000, 1_000));
        q.hold_idle();
        assert_eq!((q.schedules(), q.idle()), (1_000, 0));
        q.cut_to(100_000);
        assert_eq!(
            (q.schedules(), q.idle()),
            (1_000, 0),
            "a later deadline cuts nothing"
        );
        q.cut_to(7);
        assert_eq!((q.schedules(), q.idle()), (7, 0));
        q.release_idle();
        assert_eq!((q.schedules(), q.idle()), (7, 7));
    }
}
