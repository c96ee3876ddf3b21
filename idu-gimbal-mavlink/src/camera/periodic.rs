//! A message the camera sends unasked, every so many milliseconds.

use idu_gimbal::Instant;

/// When a message is next due, at the period set.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Periodic {
    /// The period, ms; 0: not sent unasked.
    period_ms: u32,
    next: Option<Instant>,
}

impl Periodic {
    /// Every `period_ms` from `now` (0: no longer).
    pub(crate) fn set(&mut self, period_ms: u32, now: Instant) {
        self.period_ms = period_ms;
        self.next = Some(now);
    }

    /// Whether the message is due at `now`.
    pub(crate) fn due(&self, now: Instant) -> bool {
        self.period_ms > 0 && self.next.is_none_or(|t| now.is_at_or_after(t))
    }

    /// The message was sent at `now` (asked for or due): the next a period on.
    pub(crate) fn sent(&mut self, now: Instant) {
        if self.period_ms > 0 {
            self.next = Some(now.add_millis(self.period_ms));
        }
    }
}
