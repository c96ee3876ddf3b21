//! Time as the caller's wrapping millisecond tick.
//!
//! The crate never reads a clock: every call that needs the time takes an [`Instant`].
//! An `Instant` wraps around after `u32::MAX` milliseconds (about 49.7 days); comparisons
//! are made on the wrapping difference, so they stay correct across the wrap as long as
//! the two instants compared are less than 2^31 ms (about 24.8 days) apart.
//!
//! ```
//! use idu_gimbal::Instant;
//! let before = Instant::from_millis(u32::MAX - 10);
//! let after = before.add_millis(30); // wrapped to 19
//! assert_eq!(after.as_millis(), 19);
//! assert_eq!(after.millis_since(before), 30);
//! assert!(after.is_at_or_after(before));
//! assert!(!before.is_at_or_after(after));
//! ```

/// A point on the caller's monotonic millisecond clock, wrapping at `u32::MAX`.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Instant(u32);

impl Instant {
    /// The instant whose tick reads `millis`.
    pub const fn from_millis(millis: u32) -> Self {
        Instant(millis)
    }

    /// The raw tick, in milliseconds.
    pub const fn as_millis(self) -> u32 {
        self.0
    }

    /// Milliseconds from `earlier` to `self`, wrapping.
    ///
    /// If `earlier` is in fact later than `self`, the result is a huge number (the wrapped
    /// difference); use [`Instant::is_at_or_after`] to order two instants.
    pub const fn millis_since(self, earlier: Instant) -> u32 {
        self.0.wrapping_sub(earlier.0)
    }

    /// The instant `millis` after `self`, wrapping.
    pub const fn add_millis(self, millis: u32) -> Instant {
        Instant(self.0.wrapping_add(millis))
    }

    /// Whether `self` is at or after `other`, assuming they are less than 2^31 ms apart.
    pub const fn is_at_or_after(self, other: Instant) -> bool {
        // The wrapping difference read as signed: non-negative means "not before".
        (self.0.wrapping_sub(other.0) as i32) >= 0
    }

    /// Whether `self` is more than `millis` after `stamp`, the two read as less than 2^31 ms
    /// apart (as [`Instant::is_at_or_after`] reads them): an instant before `stamp` (a
    /// stamp taken from a clock read a little after `self`) is not. For a deadline the
    /// caller's polls keep within 2^31 ms of the clock.
    ///
    /// ```
    /// use idu_gimbal::Instant;
    /// let stamp = Instant::from_millis(u32::MAX - 99);
    /// assert!(!Instant::from_millis(400).is_later_than(stamp, 500)); // 500 after
    /// assert!(Instant::from_millis(401).is_later_than(stamp, 500)); // 501 after
    /// assert!(!Instant::from_millis(u32::MAX - 100).is_later_than(stamp, 500)); // before
    /// ```
    pub const fn is_later_than(self, stamp: Instant, millis: u16) -> bool {
        (self.0.wrapping_sub(stamp.0) as i32) > millis as i32
    }

    /// Whether `self` and `other` are at most `millis` apart, whichever is later: how a
    /// stamp is told fresh at `now` when it may be a little ahead of it (a stamp taken from
    /// a clock read after the caller's `now`). A stamp older than 2^31 ms is not taken for
    /// one ahead, as [`Instant::is_at_or_after`] would: it is within `millis` again only in
    /// the `millis` either side of a whole 2^32 ms (49.7 days).
    ///
    /// ```
    /// use idu_gimbal::Instant;
    /// let now = Instant::from_millis(5);
    /// assert!(now.is_within(Instant::from_millis(u32::MAX - 994), 1000)); // 1000 ago
    /// assert!(now.is_within(Instant::from_millis(7), 1000)); // 2 ahead
    /// assert!(!now.is_within(Instant::from_millis(5 + (1 << 31)), 1000)); // 2^31 ago
    /// ```
    pub const fn is_within(self, other: Instant, millis: u32) -> bool {
        self.millis_since(other) <= millis || other.millis_since(self) <= millis
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn ordering_holds_across_the_wrap(start: u32, delta in 0u32..(1 << 31)) {
            let a = Instant::from_millis(start);
            let b = a.add_millis(delta);
            prop_assert!(b.is_at_or_after(a));
            prop_assert_eq!(b.millis_since(a), delta);
            if delta != 0 {
                prop_assert!(!a.is_at_or_after(b));
            }
        }

        #[test]
        fn later_than_is_the_signed_difference(start: u32, delta in -(1i32 << 30)..(1 << 30), limit: u16) {
            let stamp = Instant::from_millis(start);
            let now = Instant::from_millis(start.wrapping_add_signed(delta));
            prop_assert_eq!(now.is_later_than(stamp, limit), delta > i32::from(limit));
        }

        #[test]
        fn within_is_the_distance_either_way_round(start: u32, delta: u32, limit: u32) {
            let a = Instant::from_millis(start);
            let b = a.add_millis(delta);
            let distance = delta.min(delta.wrapping_neg());
            prop_assert_eq!(a.is_within(b, limit), distance <= limit);
            prop_assert_eq!(b.is_within(a, limit), distance <= limit);
        }
    }
}
