//! Time: the full poll, its idle fast paths, and the next deadline.

use super::*;

impl<const Q: usize, const T: usize, M: Medium> Link<Q, T, M> {
    /// Runs the schedules up to `now`: vehicle pushes, the rate hold and its dead-man, link
    /// health, an aim's closed loop or a point-at, and expiry of partial postbacks.
    ///
    /// When nothing is due and nothing changed since the last poll, this returns after one
    /// comparison.
    ///
    /// A port's [`poll`](crate::Port::poll) runs this itself; called beside it as well, it
    /// leaves the port what the port holds (frames waiting for the hardware, a serial frame
    /// part-written) and what this poll queued, which the port's next poll sends.
    #[inline]
    pub fn poll(&mut self, now: Instant) {
        if self.is_quiet(now) {
            return;
        }
        // The port's hold ends only when the port finds nothing waiting; a full poll sets
        // both intervals, so it is kept here, and taken for what the poll itself queued
        // (a vehicle push, a rate repeat, the dead-man's zero rate), which no port poll
        // follows here to send.
        let held = self.quiet.idle() == 0;
        self.poll_all(now);
        if held || !self.tx.is_empty() {
            self.quiet.hold_idle();
        }
    }

    /// [`Link::poll`] for a port, which releases its own hold after the transmit that
    /// follows.
    #[inline]
    pub(crate) fn poll_for_port(&mut self, now: Instant) {
        if self.is_quiet(now) {
            return;
        }
        self.poll_all(now);
    }

    /// Whether [`Link::poll`] at `now` would have nothing to do: nothing changed since the
    /// last poll and no deadline has come.
    #[inline]
    pub fn is_quiet(&self, now: Instant) -> bool {
        // A clock that went backwards reads as a huge interval: a full poll, never a skip.
        now.millis_since(self.last_poll) < self.quiet.schedules()
    }

    /// Whether [`Link::poll`] at `now` would have nothing to do and no frame waits to be
    /// sent: a driver's idle fast path, one compare for both. (Frames queued outside a
    /// poll end it; the port ends a poll that found nothing waiting with
    /// [`Link::release_idle`].)
    #[inline(always)]
    pub(crate) fn is_idle(&self, now: Instant) -> bool {
        now.millis_since(self.last_poll) < self.quiet.idle()
    }

    /// The driver found nothing waiting after a poll: [`Link::is_idle`] holds again until
    /// the schedules' next deadline or the next frame queued.
    #[inline(always)]
    pub(crate) fn release_idle(&mut self) {
        self.quiet.release_idle();
    }

    /// Something waits to be sent outside the queue (a serial frame part-written): ends
    /// the idle check until the port finds nothing waiting.
    #[inline]
    pub(crate) fn hold_idle(&mut self) {
        self.quiet.hold_idle();
    }

    /// The instant by which [`Link::poll`] must next be called if nothing is received and
    /// nothing else is asked of the link before then, as seen from `now`, the caller's
    /// current time: smoltcp's `poll_at`.
    ///
    /// It is the earliest of the link's deadlines: the vehicle pushes (and vehicle data
    /// going stale), the rate hold's next repeat and its dead-man, the next point-at step,
    /// the expiry of a partial postback, and the link health timeout. It is `now` itself
    /// when a poll is due at once: something changed since the last poll that the schedules
    /// must see (the first vehicle value, a new rate hold, a point-at, a full queue to
    /// retry, ...), a deadline has come, or `now` is behind the last poll. With nothing
    /// scheduled, it is at most 60 s after the last poll.
    ///
    /// Exactly: [`Link::poll`] at every instant from `now` up to, not including, the
    /// deadline does nothing. So an async driver may sleep until the deadline or until a
    /// frame arrives, whichever comes first, and poll then; every call that feeds the link
    /// ([`Link::receive`], [`Link::send`], [`Link::set_rate`], [`Link::set_gps`],
    /// [`Link::point_at`], ...) can move the deadline earlier, so ask again after one.
    ///
    /// Frames waiting for transmission are not a deadline of `poll`, which does not send
    /// them: hand them to the CAN driver while [`Link::has_transmit`] and the driver has
    /// room. ([`Port::next_deadline`](crate::Port::next_deadline), whose `poll` does
    /// transmit, is `now` while frames wait.)
    ///
    /// While a rate hold or point-at has a frame to queue and the transmit queue is full
    /// (the driver takes nothing: a dead bus, full mailboxes), the deadline stays `now`
    /// until room is made. An async loop that sleeps until the deadline should then also
    /// wait for the driver to have room, or sleep at least one tick, so it does not spin
    /// and starve its other tasks (`boards/embassy_stm32f405` does both).
    ///
    /// The result is at or after `now` and less than 2^31 ms ahead of it, whatever the
    /// wrap: the time to sleep is `deadline.millis_since(now)`.
    ///
    /// ```
    /// use idu_gimbal::link::{Config, Link};
    /// use idu_gimbal::wire::vehicle::Gps;
    /// use idu_gimbal::Instant;
    ///
    /// let mut link: Link = Link::new(Config::default());
    /// // Ten milliseconds before the tick wraps.
    /// let t0 = Instant::from_millis(u32::MAX - 9);
    /// link.set_gps(Gps::new(47.0, 8.0).unwrap(), t0);
    /// assert_eq!(link.next_deadline(t0), t0); // the first value: push it at once
    /// link.poll(t0);
    /// while link.next_transmit().is_some() {
    ///     link.transmit_done(None);
    /// }
    /// // The next GPS push, 200 ms later (the data goes stale only after 1000 ms).
    /// assert_eq!(link.next_deadline(t0), Instant::from_millis(190));
    /// assert_eq!(link.next_deadline(t0).millis_since(t0), 200);
    /// ```
    pub fn next_deadline(&self, now: Instant) -> Instant {
        if self.is_quiet(now) {
            // Quiet: `now` is within the interval after the last poll, so this is after it.
            self.last_poll.add_millis(self.quiet.schedules())
        } else {
            now
        }
    }

    /// Makes sure the idle fast path does not skip the poll at `at` (a new deadline): the
    /// quiet interval is cut to end there. Cheaper than a full poll at the next call, and
    /// the same: that poll would find the deadline and cut the interval alike. A deadline
    /// before the last poll (a caller's `now` behind it) ends the interval at once.
    pub(super) fn wake_by(&mut self, at: Instant) {
        let ahead = if at.is_at_or_after(self.last_poll) {
            at.millis_since(self.last_poll)
        } else {
            0
        };
        self.quiet.cut_to(ahead);
    }

    #[inline(never)]
    pub(super) fn poll_all(&mut self, now: Instant) {
        let mut earliest = Earliest {
            now,
            ahead: MAX_QUIET_MS,
        };
        self.assembler.expire(now);
        if let Some(at) = self.assembler.expiry() {
            earliest.offer(at);
        }
        self.poll_rate(now, &mut earliest);
        self.poll_vehicle(now, &mut earliest);
        self.poll_steering(now, &mut earliest);
        if let Some((_, at)) = self.latest {
            if self.status.is_up() && now.is_later_than(at, self.config.link_timeout_ms) {
                self.status.set_up(false);
            }
            if self.status.is_up() {
                earliest
                    .offer(at.add_millis(u32::from(self.config.link_timeout_ms).saturating_add(1)));
            }
        }
        self.last_poll = now;
        self.quiet.set(earliest.ahead);
    }
}
