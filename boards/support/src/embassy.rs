//! Between embassy-time and the core's clock, for the embassy boards (`boards/embassy_*`):
//! exact at a tick rate that is a whole number of kHz (the boards' 1 kHz and 1 MHz). At
//! another (32,768 Hz), embassy's `from_millis` rounds down, and a task may wake up to a
//! tick before its deadline's millisecond and poll again until it comes.

use idu_gimbal::link::{Link, Medium};
use idu_gimbal::Instant;

/// The crate's wrapping millisecond tick at embassy's `at`: embassy's u64 millisecond
/// count truncated to 32 bits is exactly a tick that wraps at `u32::MAX` (the truncation is
/// the wrap).
pub fn tick(at: embassy_time::Instant) -> Instant {
    Instant::from_millis(at.as_millis() as u32)
}

/// The embassy instant of the crate's `deadline`, seen from `now` (embassy's) whose tick is
/// `tick(now)`: the start of the deadline's millisecond. `next_deadline` is at or after the
/// tick and less than 2^31 ms ahead, so the wrapping difference is the real distance.
pub fn embassy_at(deadline: Instant, now: embassy_time::Instant) -> embassy_time::Instant {
    let ahead = deadline.millis_since(tick(now));
    embassy_time::Instant::from_millis(now.as_millis() + u64::from(ahead))
}

/// When a task that has just polled `link` at `now` should wake: the link's deadline, or
/// the next millisecond when that deadline is still `now` (a retry: a full queue waiting for
/// the bus to take frames). A timer already due would complete at once, and the task would
/// never yield.
pub fn next_wake<const Q: usize, const T: usize, M: Medium>(
    link: &Link<Q, T, M>,
    now: Instant,
) -> Instant {
    let deadline = link.next_deadline(now);
    if deadline == now {
        now.add_millis(1)
    } else {
        deadline
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use idu_gimbal::Config;

    const WRAP_MS: u64 = 1 << 32;

    /// The tick is embassy's millisecond count modulo 2³².
    #[test]
    fn the_tick_wraps_with_embassy_time() {
        let at = |ms| tick(embassy_time::Instant::from_millis(ms));
        assert_eq!(at(0), Instant::from_millis(0));
        assert_eq!(at(WRAP_MS - 1), Instant::from_millis(u32::MAX));
        assert_eq!(at(WRAP_MS + 5), Instant::from_millis(5));
        assert_eq!(at(3 * WRAP_MS + 7), Instant::from_millis(7));
    }

    /// A deadline ahead of `now` in ticks is as far ahead in embassy time, across the
    /// tick's wrap too.
    #[test]
    fn a_deadline_is_as_far_ahead_in_embassy_time() {
        let now = embassy_time::Instant::from_millis(WRAP_MS + 1_000);
        assert_eq!(
            embassy_at(Instant::from_millis(1_250), now),
            embassy_time::Instant::from_millis(WRAP_MS + 1_250)
        );
        assert_eq!(embassy_at(Instant::from_millis(1_000), now), now);
        // 10 ms before the wrap, a deadline 20 ms after it.
        let now = embassy_time::Instant::from_millis(2 * WRAP_MS - 10);
        assert_eq!(
            embassy_at(Instant::from_millis(20), now),
            embassy_time::Instant::from_millis(2 * WRAP_MS + 20)
        );
    }

    /// A link due now (a fresh one: its schedules run at once) wakes its task a millisecond
    /// later; one whose next deadline is ahead wakes it then.
    #[test]
    fn a_task_wakes_at_the_deadline_or_a_millisecond_on() {
        let link: Link<8, 8> = Link::new(Config::default());
        let now = Instant::from_millis(u32::MAX);
        assert_eq!(link.next_deadline(now), now);
        assert_eq!(next_wake(&link, now), Instant::from_millis(0));
        let mut link: Link<8, 8> = Link::new(Config::default());
        link.poll(now);
        while link.next_transmit().is_some() {
            link.transmit_done(None);
        }
        let deadline = link.next_deadline(now);
        assert_ne!(deadline, now);
        assert_eq!(next_wake(&link, now), deadline);
    }
}
