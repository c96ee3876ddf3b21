//! The rate hold: a rate command repeated until the dead-man ends it with one zero rate.

use super::*;

/// A rate hold: the rate command repeats until the dead-man.
#[derive(Clone, Copy, Debug)]
pub(super) struct RateHold {
    pub(super) rate: Rate,
    pub(super) refreshed: Instant,
    pub(super) next: Instant,
}

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// Starts, changes or refreshes a rate hold on the gimbal: the rate command is repeated
    /// every `rate_repeat_ms` while this is called again within `rate_deadman_ms`. A rate
    /// hold is a pointing command: it ends a point-at.
    ///
    /// Starting a hold or changing its rate queues the command at once; a full queue hands
    /// the rate back and leaves the hold as it was. Refreshing the same rate queues nothing.
    pub fn set_rate(&mut self, rate: Rate, now: Instant) -> Result<(), QueueFull<Rate>> {
        if let Steering::Rate(hold) = &mut self.steering {
            if hold.rate == rate {
                // Only the dead-man moves, later: no need to wake the next poll. (Called at
                // every turn of a main loop, this must not defeat the idle fast path.)
                hold.refreshed = now;
                return Ok(());
            }
        }
        if self
            .tx
            .push_control(
                Command::from(GimbalCommand::Rate(rate)).encode(),
                &mut self.quiet,
            )
            .is_err()
        {
            self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
            return Err(QueueFull(rate));
        }
        self.steering = Steering::Rate(RateHold {
            rate,
            refreshed: now,
            next: now.add_millis(u32::from(self.config.rate_repeat_ms.get())),
        });
        // The new rate supersedes a zero-rate frame still waiting.
        self.tx.cancel_zero_rate();
        self.quiet = quiet::Quiet::NONE;
        Ok(())
    }

    /// Ends a rate hold with one zero-rate command. The zero-rate command needs no queue
    /// slot, so it is never refused: it leaves once no control frame waits (after those
    /// already queued, and any queued before it leaves).
    pub fn stop_rate(&mut self) {
        if let Steering::Rate(_) = self.steering {
            self.end_rate_hold();
        }
    }

    /// Whether a rate hold is active.
    pub fn is_rate_holding(&self) -> bool {
        matches!(self.steering, Steering::Rate(_))
    }

    pub(super) fn end_rate_hold(&mut self) {
        self.steering = Steering::Manual;
        self.tx.mark_zero_rate(&mut self.quiet);
    }

    pub(super) fn poll_rate(&mut self, now: Instant, earliest: &mut Earliest) {
        let Steering::Rate(mut hold) = self.steering else {
            return;
        };
        let deadman = u32::from(self.config.rate_deadman_ms);
        if now.is_later_than(hold.refreshed, self.config.rate_deadman_ms) {
            self.end_rate_hold();
            self.status.raise(Event::RateHoldExpired);
            return;
        }
        if now.is_at_or_after(hold.next) {
            if self
                .tx
                .push_control(
                    Command::from(GimbalCommand::Rate(hold.rate)).encode(),
                    &mut self.quiet,
                )
                .is_ok()
            {
                hold.next = advance(hold.next, u32::from(self.config.rate_repeat_ms.get()), now);
                self.steering = Steering::Rate(hold);
            } else {
                // Try again at the next poll.
                self.stats.queue_full = self.stats.queue_full.wrapping_add(1);
                earliest.offer(now);
            }
        }
        earliest.offer(hold.next);
        earliest.offer(hold.refreshed.add_millis(deadman.saturating_add(1)));
    }
}
