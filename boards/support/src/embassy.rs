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
